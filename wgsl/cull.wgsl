// Pass 1 of 3 per display: test every instance's world sphere (or those of the blocks
// the frame's coarse cull listed for this display) against the display frustum (never
// per eye), choose its level of detail from the viewer, and record, for the level this z slice handles, its
// flag plus its prefix within the workgroup.
// Bindings (all cull passes share them): CULL_BINDINGS in src/shaders/bindings.rs.

@compute @workgroup_size(WORKGROUP_SIZE)
fn cull(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let block = wid.y * groups.x + wid.x;
    let level = wid.z;
    let n = cull_count();
    let j = block * WORKGROUP_SIZE + local;
    var flag = 0u;
    if (j < n) {
        let k = cull_position(j);
        if (k < params.instance_count) {
            let s = spheres_at(k);
            if (sphere_in_planes(display.planes, s) && in_split(s) && lod_level(k) == level) {
                flag = 1u;
            }
        }
    }
    let scan = workgroup_exclusive_scan(local, flag);
    if (j < n) {
        local_prefix[level * n + j] = scan.x | select(0u, VISIBLE_BIT, flag == 1u);
    }
    let blocks = (n + WORKGROUP_SIZE - 1u) / WORKGROUP_SIZE;
    if (local == 0u && block < blocks) {
        block_sums[level * blocks + block] = scan.y;
    }
}
