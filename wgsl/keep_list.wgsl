// A kept frame's changed tiles listed for the tile pass's indirect draw
// (src/draw/keep_tiles.rs): each invocation takes one word of the display's bits and
// appends its set tiles' indices, so the pass draws triangles for changed tiles only.
// The order of the list is free: the tiles do not overlap.

@compute @workgroup_size(LIST_GROUP)
fn list_tiles(@builtin(global_invocation_id) id: vec3<u32>) {
    // The draw comes cleared: six corners per instance.
    if (id.x == 0u) {
        draw.vertex_count = 6u;
    }
    let rows = (tiles.height + TILE - 1u) / TILE;
    if (id.x >= (tiles.cols * rows + 31u) / 32u) {
        return;
    }
    var bits = tiles.words[id.x];
    var at = atomicAdd(&draw.instance_count, countOneBits(bits));
    while (bits != 0u) {
        list[at] = id.x * 32u + firstTrailingBit(bits);
        bits &= bits - 1u;
        at++;
    }
}
