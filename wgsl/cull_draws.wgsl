// Pass 2 of 3 per display, one workgroup: per level of detail, finest first, turn the
// level's block sums into block prefixes (after every finer level's instances), then
// build one draw per mesh with visible instances at that level, packed in ascending
// mesh id after the finer levels' draws; zero the rest and write the counts.
// Deterministic: no atomics anywhere.
// Bindings (all cull passes share them): CULL_BINDINGS in src/shaders.rs.

// Visible instances of `level` before cull position `pos`, plus every finer level's
// (pos may equal the instance count, which gives `total`).
fn visible_before(level: u32, pos: u32, total: u32) -> u32 {
    let n = params.instance_count;
    if (pos >= n) {
        return total;
    }
    let blocks = (n + WORKGROUP_SIZE - 1u) / WORKGROUP_SIZE;
    return block_sums[level * blocks + pos / WORKGROUP_SIZE] + (local_prefix[level * n + pos] & ~VISIBLE_BIT);
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn draws_main(@builtin(local_invocation_index) local: u32) {
    let blocks = (params.instance_count + WORKGROUP_SIZE - 1u) / WORKGROUP_SIZE;
    var carry = 0u;
    var packed = 0u;
    for (var level = 0u; level < params.lod_levels; level++) {
        let first_block = level * blocks;
        for (var base = 0u; base < blocks; base += WORKGROUP_SIZE) {
            let b = base + local;
            var sum = 0u;
            if (b < blocks) {
                sum = block_sums[first_block + b];
            }
            let scan = workgroup_exclusive_scan(local, sum);
            if (b < blocks) {
                block_sums[first_block + b] = carry + scan.x;
            }
            carry += scan.y;
        }
        let total = carry;
        storageBarrier();
        packed += pack_draws(level, total, packed, local);
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
fn pack_draws(level: u32, total: u32, packed: u32, local: u32) -> u32 {
    var written = 0u;
    for (var base = 0u; base < params.mesh_count; base += WORKGROUP_SIZE) {
        let m = base + local;
        var count = 0u;
        var offset = 0u;
        if (m < params.mesh_count) {
            let mesh = meshes[m];
            offset = visible_before(level, mesh.cull_start, total);
            count = visible_before(level, mesh.cull_start + mesh.cull_count, total) - offset;
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
