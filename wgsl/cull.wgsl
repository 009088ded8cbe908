// Pass 1 of 3 per display: test every instance's world sphere against the display
// frustum (never per eye) and record its flag plus its prefix within the workgroup.
// Bindings (all cull passes share them): CULL_BINDINGS in src/shaders.rs.

@compute @workgroup_size(WORKGROUP_SIZE)
fn cull(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    let block = wid.y * params.groups_x + wid.x;
    let k = block * WORKGROUP_SIZE + local;
    var flag = 0u;
    if (k < params.instance_count && sphere_in_planes(display.planes, spheres[k])) {
        flag = 1u;
    }
    let scan = workgroup_exclusive_scan(local, flag);
    if (k < params.instance_count) {
        local_prefix[k] = scan.x | select(0u, VISIBLE_BIT, flag == 1u);
    }
    if (local == 0u) {
        block_sums[block] = scan.y;
    }
}
