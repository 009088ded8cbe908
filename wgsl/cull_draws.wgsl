// Pass 2 of 3 per display, one workgroup: turn the block sums into block prefixes,
// then build one draw per mesh with visible instances, packed in ascending mesh id,
// zero the rest, and write the counts. Deterministic: no atomics anywhere.
// Bindings (all cull passes share them): CULL_BINDINGS in src/shaders.rs.

// Visible instances before cull position `pos` (pos may equal the instance count).
fn visible_before(pos: u32, total: u32) -> u32 {
    if (pos >= params.instance_count) {
        return total;
    }
    return block_sums[pos / WORKGROUP_SIZE] + (local_prefix[pos] & ~VISIBLE_BIT);
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn draws_main(@builtin(local_invocation_index) local: u32) {
    let blocks = (params.instance_count + WORKGROUP_SIZE - 1u) / WORKGROUP_SIZE;
    var carry = 0u;
    for (var base = 0u; base < blocks; base += WORKGROUP_SIZE) {
        let b = base + local;
        var sum = 0u;
        if (b < blocks) {
            sum = block_sums[b];
        }
        let scan = workgroup_exclusive_scan(local, sum);
        if (b < blocks) {
            block_sums[b] = carry + scan.x;
        }
        carry += scan.y;
    }
    let total = carry;
    storageBarrier();

    var packed = 0u;
    for (var base = 0u; base < params.mesh_count; base += WORKGROUP_SIZE) {
        let m = base + local;
        var count = 0u;
        var offset = 0u;
        if (m < params.mesh_count) {
            let mesh = meshes[m];
            offset = visible_before(mesh.cull_start, total);
            count = visible_before(mesh.cull_start + mesh.cull_count, total) - offset;
        }
        let scan = workgroup_exclusive_scan(local, select(0u, 1u, count > 0u));
        if (count > 0u) {
            let mesh = meshes[m];
            draws[packed + scan.x] = DrawArgs(
                mesh.index_count,
                display.instances_per_object * count,
                mesh.first_index,
                mesh.base_vertex,
                display.instances_per_object * offset,
            );
        }
        packed += scan.y;
    }
    for (var d = packed + local; d < params.mesh_count; d += WORKGROUP_SIZE) {
        draws[d] = DrawArgs(0u, 0u, 0u, 0, 0u);
    }
    if (local == 0u) {
        counts[0] = packed;
        counts[1] = total;
    }
}
