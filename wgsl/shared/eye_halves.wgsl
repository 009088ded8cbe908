// Full-screen passes over a double-wide target, one instance per eye: a triangle over
// clip x, y in [-1, 1], then x moved into the instance's eye's half (the far layer's
// composite and a foveated display's composite).

struct EyeHalf {
    @builtin(position) position: vec4<f32>,
    @location(0) @interpolate(flat) eye: u32,
}

@vertex
fn vs_main(@builtin(vertex_index) v: u32, @builtin(instance_index) eye: u32) -> EyeHalf {
    let xy = vec2(f32((v << 1u) & 2u), f32(v & 2u)) * 2.0 - 1.0;
    let x = 0.5 * xy.x + select(0.5, -0.5, eye == 0u);
    return EyeHalf(vec4(x, xy.y, 0.0, 1.0), eye);
}
