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
