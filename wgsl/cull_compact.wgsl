// Pass 3 of 3 per display: every visible instance writes its id to its slot, one z
// slice per level of detail. Slots ascend with cull position within a (level, mesh)
// group, so each draw's ids are contiguous and ascending.
// Bindings (all cull passes share them): CULL_BINDINGS in src/shaders/bindings.rs.

@compute @workgroup_size(WORKGROUP_SIZE)
fn compact(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let block = wid.y * groups.x + wid.x;
    let level = wid.z;
    let n = cull_count();
    let j = block * WORKGROUP_SIZE + local;
    if (j >= n) {
        return;
    }
    let blocks = (n + WORKGROUP_SIZE - 1u) / WORKGROUP_SIZE;
    let entry = local_prefix[level * n + j];
    if ((entry & VISIBLE_BIT) != 0u) {
        visible[block_sums[level * blocks + block] + (entry & ~VISIBLE_BIT)] = order[cull_position(j)];
    }
}
