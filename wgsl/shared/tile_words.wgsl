// A display's changed tiles as the tile pass reads them (src/draw/keep_tiles.rs): its
// grid, mirrored by TileGrid (bytemuck), then the tiles' bits.
struct TileWords {
    // Tiles per row, and the target's pixels.
    cols: u32,
    width: u32,
    height: u32,
    // Bit t % 32 of word t / 32: tile t (row-major) changed.
    words: array<u32>,
}

// The tile pass's indirect draw (wgpu's DrawIndirectArgs): six corners per changed
// tile, an instance each, counted by keep_list.wgsl.
struct TileDraw {
    vertex_count: u32,
    instance_count: atomic<u32>,
    first_vertex: u32,
    first_instance: u32,
}
