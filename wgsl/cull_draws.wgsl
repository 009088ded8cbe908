// Pass 3 of 4 per display, one workgroup: per level of detail, finest first, turn the
// level's group totals into group prefixes (after every finer level's instances), then
// build one draw per mesh with visible instances at that level, packed in ascending
// mesh id after the finer levels' draws; zero the rest and write the counts. It walks
// group totals (one per WORKGROUP_SIZE * SPAN positions), never every span.
// Deterministic: no atomics anywhere.
// Bindings (all cull passes share them): CULL_BINDINGS in src/shaders/bindings.rs.

@compute @workgroup_size(WORKGROUP_SIZE)
fn draws_main(@builtin(local_invocation_index) local: u32) {
    let n = workgroup_cull_count(local);
    let groups = group_count(span_count(n));
    var carry = 0u;
    var packed = 0u;
    for (var level = 0u; level < params.lod_levels; level++) {
        carry = prefix_groups(group_slot(n, level, 0u), groups, carry, local);
        let total = carry;
        storageBarrier();
        packed += pack_draws(level, n, total, packed, local);
        storageBarrier();
    }
    let slots = params.mesh_count * params.lod_levels;
    for (var d = packed + local; d < slots; d += WORKGROUP_SIZE) {
        draws[d] = DrawArgs(0u, 0u, 0u, 0, 0u);
    }
    if (local == 0u) {
        counts[0] = packed;
        counts[1] = carry;
    }
}

// Writes `level`'s draws from draws[packed] on, in ascending mesh id; returns how many.
// `n` is what the passes ran over, `total` the visible count up to this level.
fn pack_draws(level: u32, n: u32, total: u32, packed: u32, local: u32) -> u32 {
    var written = 0u;
    for (var base = 0u; base < params.mesh_count; base += WORKGROUP_SIZE) {
        let m = base + local;
        var count = 0u;
        var offset = 0u;
        if (m < params.mesh_count) {
            let range = mesh_range(m);
            offset = flagged_before(level, range.x, n, total);
            count = flagged_before(level, range.x + range.y, n, total) - offset;
        }
        let scan = workgroup_exclusive_scan(local, select(0u, 1u, count > 0u));
        if (count > 0u) {
            let mesh = meshes[m];
            let lod = lods[m * MAX_LODS + level];
            draws[packed + written + scan.x] = DrawArgs(
                lod.index_count,
                display.instances_per_object * count,
                lod.first_index,
                mesh.base_vertex,
                display.instances_per_object * offset,
            );
        }
        written += scan.y;
    }
    return written;
}
