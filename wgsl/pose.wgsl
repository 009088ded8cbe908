// The frame's posing pass (src/pose_tables.rs, src/renderer/frame/pose.rs): once per
// frame, before the skinning pass and every cull, from the frame context's time alone.
// Three entry points, dispatched in order: `locals` samples each node's channels,
// `worlds` composes each node's world transform, `targets` writes each posed
// instance's move (the moves scatter's edit, applied by that scatter right after) and
// each skin's joint matrices. The CPU twin is posing::Posing::node_worlds,
// skinning::Skin::pose_joints and scene::Scene::world_sphere, the same steps (a node's
// world product associated from the node up, not from the root down: no chain kept per
// invocation); tests/gpu_posing.rs compares them. Transforms are the rows of 3x4
// affines.

struct PoseNode {
    parent: u32,
    first_channel: u32,
    channels: u32,
    unused: u32,
    root_from: array<vec4<f32>, 3>,
    translation: vec4<f32>,
    rotation: vec4<f32>,
    scale: vec4<f32>,
}

struct PoseChannel {
    // 0 translation, 1 rotation, 2 scale.
    property: u32,
    // 0 step, 1 linear, 2 cubic spline.
    interpolation: u32,
    first_key: u32,
    keys: u32,
    first_value: u32,
    offset: f32,
    speed: f32,
    duration: f32,
}

struct PoseTarget {
    // VACANT: a void edit, nothing posed.
    slot: u32,
    // An instance on a node: the node; a skin: its first joint.
    node: u32,
    // A skin's joints; 0 for an instance on a node.
    joints: u32,
    joint_base: u32,
    bounds: vec4<f32>,
    node_from_local: array<vec4<f32>, 3>,
    orbit: f32,
    bob: f32,
    unused: array<u32, 2>,
}

struct SkinJoint {
    node: u32,
    unused: array<u32, 3>,
    inverse_bind: array<vec4<f32>, 3>,
    bounds: vec4<f32>,
}

struct Edits {
    header: EditHeader,
    list: array<MoveEdit>,
}

alias Rows = array<vec4<f32>, 3>;

const ROOT: u32 = 0xffffffffu;

// Bindings: POSE_BINDINGS in src/shaders/bindings.rs.

// Invocations per row of the node and the target dispatches (x workgroups times
// POSE_GROUP: a dispatch's y spreads past the device's limit per dimension).
struct PoseParams {
    node_row: u32,
    target_row: u32,
    // The counts (the buffers may be longer).
    nodes: u32,
    targets: u32,
    // Seconds after the frame's time: a two-frame submission's second pose is dt ahead.
    ahead: f32,
}


// Clip time: the pose's time (the frame's, or the second frame's of two) at the clip's
// pace and phase, looped over its duration (Clip::looped: rem_euclid). The sum is the
// second frame's time to the bit: the CPU adds the same two f32.
fn clip_time(c: PoseChannel) -> f32 {
    let t = (frame.time + params.ahead) * c.speed + c.offset;
    if (c.duration <= 0.0) {
        return 0.0;
    }
    let r = t - c.duration * trunc(t / c.duration);
    return select(r, r + c.duration, r < 0.0);
}

fn key_value(c: PoseChannel, k: u32) -> vec4<f32> {
    let per_key = select(1u, 3u, c.interpolation == 2u);
    let middle = select(0u, 1u, c.interpolation == 2u);
    return values[c.first_value + per_key * k + middle];
}

// glam's Quat::slerp: the shorter arc; nearly equal ends lerped and normalized.
fn slerp(a: vec4<f32>, b_in: vec4<f32>, u: f32) -> vec4<f32> {
    var b = b_in;
    var d = dot(a, b);
    if (d < 0.0) {
        b = -b;
        d = -d;
    }
    if (d > 1.0 - 1.1920929e-7) {
        return normalize(a + (b - a) * u);
    }
    let theta = acos(d);
    let x = sin(theta * (1.0 - u));
    let y = sin(theta * u);
    return (a * x + b * y) * (1.0 / sin(theta));
}

// Channel::sample: held before the first key and after the last.
fn sample(c: PoseChannel, t: f32) -> vec4<f32> {
    let last = c.keys - 1u;
    if (t <= times[c.first_key]) {
        return key_value(c, 0u);
    }
    if (t >= times[c.first_key + last]) {
        return key_value(c, last);
    }
    // The key at or before t: the count of keys at or before t, less one.
    var lo = 0u;
    var hi = c.keys;
    while (lo < hi) {
        let mid = (lo + hi) / 2u;
        if (times[c.first_key + mid] <= t) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    let k = lo - 1u;
    let t0 = times[c.first_key + k];
    let dt = times[c.first_key + k + 1u] - t0;
    let u = (t - t0) / dt;
    if (c.interpolation == 0u) {
        return key_value(c, k);
    }
    if (c.interpolation == 1u) {
        if (c.property == 1u) {
            return slerp(key_value(c, k), key_value(c, k + 1u), u);
        }
        let a = key_value(c, k);
        return a + (key_value(c, k + 1u) - a) * u;
    }
    let out_tangent = values[c.first_value + 3u * k + 2u];
    let in_tangent = values[c.first_value + 3u * (k + 1u)];
    let u2 = u * u;
    let u3 = u2 * u;
    return key_value(c, k) * (2.0 * u3 - 3.0 * u2 + 1.0)
        + out_tangent * (dt * (u3 - 2.0 * u2 + u))
        + key_value(c, k + 1u) * (-2.0 * u3 + 3.0 * u2)
        + in_tangent * (dt * (u3 - u2));
}

// Affine3A::from_scale_rotation_translation, as rows.
fn trs_rows(t: vec3<f32>, q: vec4<f32>, s: vec3<f32>) -> Rows {
    let x2 = q.x + q.x;
    let y2 = q.y + q.y;
    let z2 = q.z + q.z;
    let xx = q.x * x2;
    let xy = q.x * y2;
    let xz = q.x * z2;
    let yy = q.y * y2;
    let yz = q.y * z2;
    let zz = q.z * z2;
    let wx = q.w * x2;
    let wy = q.w * y2;
    let wz = q.w * z2;
    let x_axis = vec3(1.0 - (yy + zz), xy + wz, xz - wy) * s.x;
    let y_axis = vec3(xy - wz, 1.0 - (xx + zz), yz + wx) * s.y;
    let z_axis = vec3(xz + wy, yz - wx, 1.0 - (xx + yy)) * s.z;
    return Rows(
        vec4(x_axis.x, y_axis.x, z_axis.x, t.x),
        vec4(x_axis.y, y_axis.y, z_axis.y, t.y),
        vec4(x_axis.z, y_axis.z, z_axis.z, t.z),
    );
}

// a * b of two affines.
fn mul(a: Rows, b: Rows) -> Rows {
    var out: Rows;
    for (var r = 0u; r < 3u; r++) {
        let x = a[r];
        out[r] = b[0] * x.x + b[1] * x.y + b[2] * x.z + vec4(0.0, 0.0, 0.0, x.w);
    }
    return out;
}

fn point(m: Rows, p: vec3<f32>) -> vec3<f32> {
    let h = vec4(p, 1.0);
    return vec3(dot(m[0], h), dot(m[1], h), dot(m[2], h));
}

// The longest of the linear part's axes (columns).
fn stretch(m: Rows) -> f32 {
    let x = vec3(m[0].x, m[1].x, m[2].x);
    let y = vec3(m[0].y, m[1].y, m[2].y);
    let z = vec3(m[0].z, m[1].z, m[2].z);
    return max(length(x), max(length(y), length(z)));
}

@compute @workgroup_size(POSE_GROUP)
fn locals_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let n = id.x + id.y * params.node_row;
    if (n >= params.nodes) {
        return;
    }
    let node = nodes[n];
    var t = node.translation.xyz;
    var q = node.rotation;
    var s = node.scale.xyz;
    for (var i = 0u; i < node.channels; i++) {
        let c = channels[node.first_channel + i];
        let v = sample(c, clip_time(c));
        switch c.property {
            case 0u: { t = v.xyz; }
            case 1u: { q = normalize(v); }
            default: { s = v.xyz; }
        }
    }
    locals[n] = trs_rows(t, q, s);
}

@compute @workgroup_size(POSE_GROUP)
fn worlds_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let n = id.x + id.y * params.node_row;
    if (n >= params.nodes) {
        return;
    }
    // Composed from the node up: each ancestor's local transform applied on the left,
    // then the root's placement (the CPU composes from the root down: the same
    // product, associated the other way).
    var world = locals[n];
    var at = n;
    for (var depth = 1u; depth < MAX_DEPTH; depth++) {
        let parent = nodes[at].parent;
        if (parent == ROOT) {
            break;
        }
        at = parent;
        world = mul(locals[at], world);
    }
    world = mul(nodes[at].root_from, world);
    worlds[n] = world;
}

// Scene::world_sphere's radius for a transform `m` of the target's mesh, with the
// rounding slack of its center.
fn move_of(posed: PoseTarget, m: Rows) -> MoveEdit {
    let x = vec3(m[0].x, m[1].x, m[2].x);
    let y = vec3(m[0].y, m[1].y, m[2].y);
    let z = vec3(m[0].z, m[1].z, m[2].z);
    let scale = sqrt(max(dot(x, x), max(dot(y, y), dot(z, z))));
    let radius = (posed.bounds.w + posed.orbit) * scale + posed.bob;
    let c = point(m, posed.bounds.xyz);
    let slack = ROUNDING_SLACK * (abs(c.x) + abs(c.y) + abs(c.z) + radius);
    var rows: array<f32, 12>;
    for (var r = 0u; r < 3u; r++) {
        for (var k = 0u; k < 4u; k++) {
            rows[4u * r + k] = m[r][k];
        }
    }
    return MoveEdit(posed.slot, rows, radius + slack);
}

// The smallest sphere around spheres a and b (skinning::enclose).
fn enclose(a: vec4<f32>, b: vec4<f32>) -> vec4<f32> {
    let d = distance(b.xyz, a.xyz);
    if (d + b.w <= a.w) {
        return a;
    }
    if (d + a.w <= b.w) {
        return b;
    }
    let radius = 0.5 * (d + a.w + b.w);
    let toward = (b.xyz - a.xyz) / d;
    return vec4(a.xyz + toward * (radius - a.w), radius);
}

// A skin's pose (Skin::pose_joints): the sphere around its joints' posed spheres, the
// transform that maps its rest sphere onto it, and the joint matrices in that
// transform's local space.
fn pose_skin(posed: PoseTarget) -> MoveEdit {
    var sphere = vec4(0.0);
    var any = false;
    for (var j = 0u; j < posed.joints; j++) {
        let joint = skin_joints[posed.node + j];
        if (joint.bounds.w < 0.0) {
            continue;
        }
        let m = worlds[joint.node];
        let s = vec4(point(m, joint.bounds.xyz), joint.bounds.w * stretch(m));
        sphere = select(s, enclose(sphere, s), any);
        any = true;
    }
    let slack = (max(abs(sphere.x), max(abs(sphere.y), abs(sphere.z))) + sphere.w) / 65536.0;
    sphere.w += slack;
    let rest = posed.bounds;
    let scale = select(1.0, sphere.w / rest.w, rest.w > 0.0);
    let move_by = sphere.xyz - rest.xyz * scale;
    let world_from_local = Rows(
        vec4(scale, 0.0, 0.0, move_by.x),
        vec4(0.0, scale, 0.0, move_by.y),
        vec4(0.0, 0.0, scale, move_by.z),
    );
    let inverse = 1.0 / scale;
    let local_from_world = Rows(
        vec4(inverse, 0.0, 0.0, -move_by.x * inverse),
        vec4(0.0, inverse, 0.0, -move_by.y * inverse),
        vec4(0.0, 0.0, inverse, -move_by.z * inverse),
    );
    for (var j = 0u; j < posed.joints; j++) {
        let joint = skin_joints[posed.node + j];
        let world_joint = mul(worlds[joint.node], joint.inverse_bind);
        joint_matrices[posed.joint_base + j] = mul(local_from_world, world_joint);
    }
    return move_of(posed, world_from_local);
}

@compute @workgroup_size(POSE_GROUP)
fn targets_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x + id.y * params.target_row;
    if (i >= params.targets) {
        return;
    }
    let posed = targets[i];
    if (posed.slot == VACANT) {
        edits.list[i].slot = VACANT;
        return;
    }
    if (posed.joints == 0u) {
        let m = mul(worlds[posed.node], posed.node_from_local);
        edits.list[i] = move_of(posed, m);
    } else {
        edits.list[i] = pose_skin(posed);
    }
}
