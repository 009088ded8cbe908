// The draw pipeline of two frames per submission whose second frame is posed apart
// (node animations, skins, morph targets, the second frame's own edits: see
// src/renderer/second_frame.rs): the instanced path's (wgsl/draw.wgsl), whose first
// frame's views read the first frame's pose. Its records are group 3 and its vertices
// locations 6 to 8, both copied after the first frame's passes and before the second
// frame's rewrite the live ones. The second frame's views read the live ones. What
// one frame has and the other not (a second frame's insert or remove) has a vacant
// record in the other's records.

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
    let second = display.eye[at.y].time_ahead > 0.0;
    var input = v;
    var inst = instances_at(id);
    if (!second) {
        input.position = first_position;
        input.normal = first_normal;
        input.tangent = first_tangent;
        inst = previous_instances_at(id);
    }
    var out = vertex_of(decode_record(input, id, inst, at.y, double_wide), double_wide);
    // A vacant record: the instance is the other frame's alone (inserted in the
    // second, or removed in it). Every vertex outside the clip volume: no pixel.
    if (inst.mesh == VACANT_MESH) {
        out.position = vec4(2.0, 2.0, 2.0, 1.0);
    }
    return out;
}

@fragment
fn fs_main(in: FragmentInput) -> @location(0) vec4<f32> {
    let eye = in.ids.x;
    return fragment(in, eye, display.eye[eye].viewport);
}
