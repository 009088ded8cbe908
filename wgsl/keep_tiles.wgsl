// A kept frame's changed tiles cleared before they are redrawn (src/draw/keep_tiles.rs):
// an instance of two triangles per changed tile (listed by keep_list.wgsl), at the far
// plane (depth 1, what a cleared pass holds) in the clear color. Everything outside the
// changed tiles keeps what the last frame drew.

const CORNERS = array(vec2(0u, 0u), vec2(1u, 0u), vec2(0u, 1u), vec2(0u, 1u), vec2(1u, 0u), vec2(1u, 1u));

@vertex
fn vs_main(@builtin(vertex_index) vertex: u32, @builtin(instance_index) instance: u32) -> @builtin(position) vec4<f32> {
    let t = list[instance];
    let size = vec2(tiles.width, tiles.height);
    let px = vec2<f32>(min((vec2(t % tiles.cols, t / tiles.cols) + CORNERS[vertex]) * TILE, size));
    let target_size = vec2<f32>(size);
    return vec4<f32>(px.x / target_size.x * 2.0 - 1.0, 1.0 - px.y / target_size.y * 2.0, 1.0, 1.0);
}

@fragment
fn fs_main() -> @location(0) vec4<f32> {
    return CLEAR_COLOR;
}
