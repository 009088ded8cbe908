// The frame level, before any display's cull (src/cull/coarse.rs): every instance is
// tested once against the frame frustum, and the candidates, as cull positions in
// ascending order with each mesh's range among them, are what every display's passes
// then run over, dispatched indirectly from their count. Three entry points, in
// dispatch order: coarse_cull, coarse_ranges (one workgroup), coarse_compact.
// Bindings: CULL_BINDINGS in group 0, COARSE_BINDINGS in group 1 (src/shaders/bindings.rs).

// The CPU twin is CoarseCull::test: same operations, same order, no fma.
fn coarse_test(s: vec4<f32>) -> bool {
    let reach = s.w * frame.coarse_inflation + frame.coarse_slack * (abs(s.x) + abs(s.y) + abs(s.z));
    for (var i = 0u; i < 6u; i++) {
        let p = frame.coarse_planes[i];
        if (p.x * s.x + p.y * s.y + p.z * s.z + p.w < -reach) {
            return false;
        }
    }
    return true;
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn coarse_cull(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let block = wid.y * groups.x + wid.x;
    let n = params.instance_count;
    let k = block * WORKGROUP_SIZE + local;
    var flag = 0u;
    if (k < n && coarse_test(spheres_at(k))) {
        flag = 1u;
    }
    let scan = workgroup_exclusive_scan(local, flag);
    if (k < n) {
        local_prefix[k] = scan.x | select(0u, VISIBLE_BIT, flag == 1u);
    }
    let blocks = (n + WORKGROUP_SIZE - 1u) / WORKGROUP_SIZE;
    if (local == 0u && block < blocks) {
        block_sums[block] = scan.y;
    }
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn coarse_ranges(@builtin(local_invocation_index) local: u32) {
    let n = params.instance_count;
    let blocks = (n + WORKGROUP_SIZE - 1u) / WORKGROUP_SIZE;
    let total = prefix_blocks(0u, blocks, 0u, local);
    storageBarrier();
    for (var m = local; m < params.mesh_count; m += WORKGROUP_SIZE) {
        let mesh = meshes[m];
        let start = flagged_before(0u, mesh.cull_start, n, total);
        let end = flagged_before(0u, mesh.cull_start + mesh.cull_count, n, total);
        candidate_ranges[m] = vec2(start, end - start);
    }
    if (local == 0u) {
        candidate_count[0] = total;
        // The display passes' grid: x within the device's limit, y the rest.
        let needed = (total + WORKGROUP_SIZE - 1u) / WORKGROUP_SIZE;
        let x = min(needed, params.max_groups);
        coarse_args[0] = x;
        coarse_args[1] = select(0u, (needed + x - 1u) / x, x > 0u);
        coarse_args[2] = params.lod_levels;
    }
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn coarse_compact(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let block = wid.y * groups.x + wid.x;
    let k = block * WORKGROUP_SIZE + local;
    if (k >= params.instance_count) {
        return;
    }
    let entry = local_prefix[k];
    if ((entry & VISIBLE_BIT) != 0u) {
        candidates[block_sums[block] + (entry & ~VISIBLE_BIT)] = k;
    }
}
