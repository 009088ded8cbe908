// The draw pipeline with motion vectors (src/motion.rs): the instanced path's
// (wgsl/draw.wgsl), with the vertex's previous position (location 6: the previous
// frame's vertices) carried to the fragment as a clip position, and a second target
// for the pixel's motion.

struct DrawOutput {
    @location(0) color: vec4<f32>,
    @location(1) motion: vec2<f32>,
}

@vertex
fn vs_main(
    v: VertexInput,
    @location(6) previous_position: vec3<f32>,
    @builtin(instance_index) instance_index: u32,
) -> VertexOutput {
    let at = decode_instance(instance_index, VIEWS);
    var out = vertex(v, at.x, at.y, VIEWS >= 2u);
    out.previous_clip = previous_clip(previous_position, at.x, at.y);
    return out;
}

@fragment
fn fs_main(in: FragmentInput) -> DrawOutput {
    let eye = in.ids.x;
    let viewport = display.eye[eye].viewport;
    let motion = pixel_motion(in.position.xy, in.previous_clip, viewport);
    return DrawOutput(fragment(in, eye, viewport), motion);
}
