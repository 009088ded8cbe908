// The draw pipeline of the instanced path and of the per-instance modes. Stereo
// (VIEWS = 2): instance_index >> 1 is the slot in the visible list and instance_index & 1
// the eye, whose half of the double-wide target the clip-space placement selects;
// foveated stereo (VIEWS = 4) the same with / 4 and % 4 and four viewports of their own
// sizes. Mono (VIEWS = 1): the slot is the instance index and the eye is eye[0] of the
// context, drawn into its view's viewport by the pass (classic modes).

@vertex
fn vs_main(v: VertexInput, @builtin(instance_index) instance_index: u32) -> VertexOutput {
    let at = decode_instance(instance_index, VIEWS);
    return vertex(v, at.x, at.y, VIEWS >= 2u);
}

// Every view's context says where its pixels lie: its viewport of the shared target,
// or (the classic modes, one view per context) the viewport its pass set.
@fragment
fn fs_main(in: FragmentInput) -> @location(0) vec4<f32> {
    let eye = in.ids.x;
    return fragment(in, eye, display.eye[eye].viewport);
}
