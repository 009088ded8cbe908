// The stereo decode, public for engines that draw the cull outputs with pipelines of
// their own (Renderer::draw_display_with_own_pipeline): which instance and eye an
// instance_index means, the instance's animated world transform, the eye's clip
// position remapped into its half of a double-wide target, and the seam distance.
// Bindings: DRAW_BINDINGS in src/shaders/bindings.rs (group 0).

struct VertexInput {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    // The mesh's material (MaterialRecord index).
    @location(3) material: u32,
    // Local tangent (xyz) and handedness (w): the bitangent is w * cross(normal, tangent).
    @location(4) tangent: vec4<f32>,
    // The second texture coordinates, for materials that read two sets.
    @location(5) uv1: vec2<f32>,
}

// Normals transform by the cofactor matrix (inverse transpose times determinant),
// sign-corrected so that mirroring transforms keep normals outward.
fn world_normal(rows: array<vec4<f32>, 3>, n: vec3<f32>) -> vec3<f32> {
    let m = transpose(mat3x3(rows[0].xyz, rows[1].xyz, rows[2].xyz));
    let cofactor = mat3x3(cross(m[1], m[2]), cross(m[2], m[0]), cross(m[0], m[1]));
    return sign(dot(m[0], cross(m[1], m[2]))) * (cofactor * n);
}

// Tangents transform as directions; a mirroring transform flips the handedness, since
// world_normal keeps normals outward.
fn world_tangent(rows: array<vec4<f32>, 3>, t: vec4<f32>) -> vec4<f32> {
    let m = transpose(mat3x3(rows[0].xyz, rows[1].xyz, rows[2].xyz));
    let mirrored = sign(dot(m[0], cross(m[1], m[2])));
    return vec4(m * t.xyz, t.w * mirrored);
}

const PI: f32 = 3.14159265358979;

// Rotation by `angle` radians about +Y (the instance's spin, in its local space).
fn spin(angle: f32) -> mat3x3<f32> {
    let c = cos(angle);
    let s = sin(angle);
    return mat3x3(vec3(c, 0.0, -s), vec3(0.0, 1.0, 0.0), vec3(s, 0.0, c));
}

// (slot in the visible list, view) of an instance_index when one draw covers `views`
// views: instance_index / views the slot and instance_index % views the view (for
// stereo, instance_index >> 1 and & 1; foveated stereo has 4 views).
fn decode_instance(instance_index: u32, views: u32) -> vec2<u32> {
    if (views == 2u) {
        return vec2(instance_index >> 1u, instance_index & 1u);
    }
    if (views == 4u) {
        return vec2(instance_index >> 2u, instance_index & 3u);
    }
    return vec2(instance_index, 0u);
}

// The instance's spin at `time`. Most instances do not animate: the branch spares
// them a sin and cos per vertex.
fn spin_at(inst: InstanceRecord, time: f32) -> mat3x3<f32> {
    if (inst.spin != 0.0) {
        return spin(inst.spin * time);
    }
    return mat3x3(vec3(1.0, 0.0, 0.0), vec3(0.0, 1.0, 0.0), vec3(0.0, 0.0, 1.0));
}

// Local position `spun` (already spun) placed in the world by the instance's
// transform, and its bob at `time`.
fn placed_at(inst: InstanceRecord, spun: vec3<f32>, time: f32) -> vec3<f32> {
    let local = vec4(spun, 1.0);
    let rows = inst.world_from_local;
    var world = vec3(dot(rows[0], local), dot(rows[1], local), dot(rows[2], local));
    if (inst.bob != 0.0) {
        world.y += inst.bob * sin(PI * time);
    }
    return world;
}

// Local position `local` of the instance, animated at `time`, in the world.
fn animated(inst: InstanceRecord, local: vec3<f32>, time: f32) -> vec3<f32> {
    return placed_at(inst, spin_at(inst, time) * local, time);
}

struct Decoded {
    // The eye's clip position; in a double-wide target already in that eye's half.
    clip: vec4<f32>,
    // Distance inside the eye's half (>= 0 keeps the vertex's side), for
    // @builtin(clip_distances)[0]; 1 when not double-wide.
    seam: f32,
    // Distances inside the view's own clip rectangle (left, right, bottom, top edges;
    // >= 0 inside), for clip distances where views of several sizes share a target.
    edges: vec4<f32>,
    world_position: vec3<f32>,
    world_normal: vec3<f32>,
    // The instance record's color, unpacked.
    color: vec4<f32>,
    // The instance id (its slot).
    instance: u32,
    // The view: 0 left, 1 right, 2 and 3 the left and right insets of a foveated
    // display (display.eye[eye] is its context).
    eye: u32,
    uv: vec2<f32>,
    material: u32,
    // World tangent and handedness (world_tangent).
    world_tangent: vec4<f32>,
    uv1: vec2<f32>,
}

// Visible slot `slot` for view `eye`, animated at its frame's time; `double_wide`
// places the view's clip space into its viewport of the shared target (for stereo,
// that eye's half of a 2W-wide target).
fn decode(v: VertexInput, slot: u32, eye: u32, double_wide: bool) -> Decoded {
    let id = visible[slot];
    return decode_record(v, id, instances_at(id), eye, double_wide);
}

// decode of instance `id` as record `inst` holds it (a two-frame submission's first
// frame reads a copy of the records: wgsl/draw_first_pose.wgsl).
fn decode_record(v: VertexInput, id: u32, inst: InstanceRecord, eye: u32, double_wide: bool) -> Decoded {
    let e = display.eye[eye];
    // The view's own frame: a two-frame submission's second frame lies ahead.
    let time = frame.time + e.time_ahead;
    let spun = spin_at(inst, time);
    let rows = inst.world_from_local;
    let world = placed_at(inst, spun * v.position, time);
    var clip = e.clip_from_world * vec4(world, 1.0);
    var seam = 1.0;
    let edges = vec4(clip.w + clip.x, clip.w - clip.x, clip.w + clip.y, clip.w - clip.y);
    if (double_wide) {
        // For stereo exactly x' = x/2 -+ w/2: where a W-wide viewport would land it.
        let p = e.placement;
        clip = vec4(clip.x * p.x + clip.w * p.y, clip.y * p.z + clip.w * p.w, clip.zw);
        seam = select(edges.x, edges.y, eye == 0u);
    }
    let normal = world_normal(rows, spun * v.normal);
    let true_eye = eye + display.first_eye;
    let color = unpack4x8unorm(inst.color);
    let material = select(inst.material, v.material, inst.material == 0xffffffffu);
    let tangent = world_tangent(rows, vec4(spun * v.tangent.xyz, v.tangent.w));
    return Decoded(clip, seam, edges, world, normal, color, id, true_eye, v.uv, material, tangent, v.uv1);
}
