// The multiview pipeline: one view per instance (counts not doubled); the hardware runs
// each draw once per layer of a two-layer target and view_index picks the eye.

@vertex
fn vs_main(
    v: VertexInput,
    @builtin(instance_index) instance_index: u32,
    @builtin(view_index) view_index: u32,
) -> VertexOutput {
    return vertex(v, instance_index, view_index, false);
}

// The eye from view_index here too, not from the flat varying: lavapipe (Mesa 22.3)
// hands some fragments of clipped triangles the other view's value.
@fragment
fn fs_main(in: FragmentInput, @builtin(view_index) view_index: u32) -> @location(0) vec4<f32> {
    return fragment(in, view_index + display.first_eye, vec4(0.0, 0.0, display.resolution));
}
