// The frame's shadow pass (src/renderer/frame/shadow.rs; the light's view comes from
// src/shadow.rs), once per frame before any display: depth only, from the light's cull
// outputs, the light's view in the display context's eye 0.
// Bindings: DRAW_BINDINGS in src/shaders/bindings.rs (group 0).

@vertex
fn vs_main(v: VertexInput, @builtin(instance_index) instance_index: u32) -> @builtin(position) vec4<f32> {
    return decode(v, instance_index, 0u, false).clip;
}
