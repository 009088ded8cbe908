// A display's passes after the frame's coarse cull: the positions of the blocks listed
// for its slot, ascending (the last block's may run past the instances:
// cull_position then passes instance_count). Reads CANDIDATE_BINDINGS (group 1), which
// the coarse passes wrote.

fn cull_count() -> u32 {
    return candidate_count[display.cull_slot];
}

fn cull_position(j: u32) -> u32 {
    let listed = block_list[display.cull_slot * block_count() + j / BLOCK];
    return listed * BLOCK + j % BLOCK;
}

// Mesh m's (start, count) among what the passes run over.
fn mesh_range(m: u32) -> vec2<u32> {
    return candidate_ranges[display.cull_slot * params.mesh_count + m];
}
