// Pass 1 of 4 per display: test every instance's world sphere (or those of the blocks
// the frame's coarse cull listed for this display) against the display frustum (never
// per eye), choose its level of detail from the viewer, and write its entry (one word,
// whatever the number of levels: see ENTRY_VISIBLE in cull_math.wgsl) plus, per span of
// SPAN positions and level, the span's visible count. Each sphere is read once.
// Bindings (all cull passes share them): CULL_BINDINGS in src/shaders/bindings.rs.

@compute @workgroup_size(WORKGROUP_SIZE)
fn cull(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let n = cull_count();
    let j = (wid.y * groups.x + wid.x) * WORKGROUP_SIZE + local;
    var visible = false;
    var level = 0u;
    if (j < n) {
        let k = cull_position(j);
        if (k < params.instance_count) {
            let s = spheres_at(k);
            visible = sphere_in_planes(display.planes, s) && in_split(s);
            if (visible) {
                level = lod_level(k, s);
            }
        }
    }
    // One 8-bit count per level in one word: a span's counts reach SPAN = 128 at most.
    let scan = segmented_exclusive_scan(local, select(0u, 1u << (8u * level), visible), SPAN);
    if (j >= n) {
        return;
    }
    entries[j] = narrow_fields(scan.x) | (level << ENTRY_LEVEL_SHIFT) | select(0u, ENTRY_VISIBLE, visible);
    if (j % SPAN == 0u) {
        let spans = span_count(n);
        for (var l = 0u; l < params.lod_levels; l++) {
            span_sums[l * spans + j / SPAN] = (scan.y >> (8u * l)) & 0xffu;
        }
    }
}
