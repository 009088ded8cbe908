// Pass 3 of 3 per display: every visible instance writes its id to its slot. Slots
// ascend with cull position, so each mesh's ids are contiguous and ascending.
// Bindings (all cull passes share them): CULL_BINDINGS in src/shaders.rs.

@compute @workgroup_size(WORKGROUP_SIZE)
fn compact(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    let block = wid.y * params.groups_x + wid.x;
    let k = block * WORKGROUP_SIZE + local;
    if (k >= params.instance_count) {
        return;
    }
    let entry = local_prefix[k];
    if ((entry & VISIBLE_BIT) != 0u) {
        visible[block_sums[block] + (entry & ~VISIBLE_BIT)] = order[k];
    }
}
