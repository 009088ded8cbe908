// Pass 1 of 3 per display: test every instance's world sphere against the display
// frustum (never per eye) and record its flag plus its prefix within the workgroup.

@group(0) @binding(0) var<uniform> display: DisplayContext;
@group(0) @binding(1) var<uniform> params: CullParams;
@group(0) @binding(2) var<storage, read> spheres: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> local_prefix: array<u32>;
@group(0) @binding(6) var<storage, read_write> block_sums: array<u32>;

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
