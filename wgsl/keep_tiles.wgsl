// A kept frame's changed tiles cleared before they are redrawn (src/draw/keep_tiles.rs):
// one instance of two triangles per tile of the display's target, placed from the
// tile's bit (marked on the GPU or written from the CPU), at the far plane (depth 1,
// what a cleared pass holds) in the clear color. An unchanged tile's triangles lie
// outside the clip volume: everything outside the changed tiles keeps what the last
// frame drew.

// Mirrored by TileGrid in src/draw/keep_tiles.rs (bytemuck), then the tiles' bits.
struct TileWords {
    // Tiles per row, and the target's pixels.
    cols: u32,
    width: u32,
    height: u32,
    // Bit t % 32 of word t / 32: tile t (row-major) changed.
    words: array<u32>,
}

const CORNERS = array(vec2(0u, 0u), vec2(1u, 0u), vec2(0u, 1u), vec2(0u, 1u), vec2(1u, 0u), vec2(1u, 1u));

@vertex
fn vs_main(@builtin(vertex_index) vertex: u32, @builtin(instance_index) t: u32) -> @builtin(position) vec4<f32> {
    if (((tiles.words[t / 32u] >> (t % 32u)) & 1u) == 0u) {
        return vec4<f32>(2.0, 2.0, 2.0, 1.0);
    }
    let size = vec2(tiles.width, tiles.height);
    let px = vec2<f32>(min((vec2(t % tiles.cols, t / tiles.cols) + CORNERS[vertex]) * TILE, size));
    let target_size = vec2<f32>(size);
    return vec4<f32>(px.x / target_size.x * 2.0 - 1.0, 1.0 - px.y / target_size.y * 2.0, 1.0, 1.0);
}

@fragment
fn fs_main() -> @location(0) vec4<f32> {
    return CLEAR_COLOR;
}
