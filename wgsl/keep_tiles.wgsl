// A kept frame's changed tiles cleared before they are redrawn (src/draw/keep_tiles.rs):
// each tile two triangles, their corners placed in the display's target on the CPU, at
// the far plane (depth 1, what a cleared pass holds) in the clear color. Everything
// outside them keeps what the last frame drew.

@vertex
fn vs_main(@builtin(vertex_index) vertex: u32) -> @builtin(position) vec4<f32> {
    return vec4<f32>(corners[vertex], 1.0, 1.0);
}

@fragment
fn fs_main() -> @location(0) vec4<f32> {
    return CLEAR_COLOR;
}
