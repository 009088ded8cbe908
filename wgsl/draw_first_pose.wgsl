// The draw pipeline of two frames per submission whose second frame is posed apart
// (node animations, skins, morph targets, the second frame's own edits: see
// src/renderer/second_frame.rs): the instanced path's (wgsl/draw.wgsl), whose first
// frame's views read the first frame's pose. Its records are group 3 and its vertices
// locations 6 to 8, both copied after the first frame's passes and before the second
// frame's rewrite the live ones. The second frame's views read the live ones.

@vertex
fn vs_main(
    v: VertexInput,
    @location(6) first_position: vec3<f32>,
    @location(7) first_normal: vec3<f32>,
    @location(8) first_tangent: vec4<f32>,
    @builtin(instance_index) instance_index: u32,
) -> VertexOutput {
    let at = decode_instance(instance_index, VIEWS);
    let id = visible[at.x];
    let double_wide = VIEWS >= 2u;
    // The second frame's views lie ahead of the frame context's time (dt > 0).
    if (display.eye[at.y].time_ahead > 0.0) {
        return vertex_of(decode_record(v, id, instances_at(id), at.y, double_wide), double_wide);
    }
    var first = v;
    first.position = first_position;
    first.normal = first_normal;
    first.tangent = first_tangent;
    let inst = previous_instances_at(id);
    return vertex_of(decode_record(first, id, inst, at.y, double_wide), double_wide);
}

@fragment
fn fs_main(in: FragmentInput) -> @location(0) vec4<f32> {
    let eye = in.ids.x;
    return fragment(in, eye, display.eye[eye].viewport);
}
