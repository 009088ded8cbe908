// Shared by every draw pipeline: the vertex transform and the shading. Bindings:
// DRAW_BINDINGS in src/shaders.rs.

struct VertexInput {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
}

// Normals transform by the cofactor matrix (inverse transpose times determinant),
// sign-corrected so that mirroring transforms keep normals outward.
fn world_normal(rows: array<vec4<f32>, 3>, n: vec3<f32>) -> vec3<f32> {
    let m = transpose(mat3x3(rows[0].xyz, rows[1].xyz, rows[2].xyz));
    let cofactor = mat3x3(cross(m[1], m[2]), cross(m[2], m[0]), cross(m[0], m[1]));
    return sign(dot(m[0], cross(m[1], m[2]))) * (cofactor * n);
}

const PI: f32 = 3.14159265358979;

// Rotation by `angle` radians about +Y (the instance's spin, in its local space).
fn spin(angle: f32) -> mat3x3<f32> {
    let c = cos(angle);
    let s = sin(angle);
    return mat3x3(vec3(c, 0.0, -s), vec3(0.0, 1.0, 0.0), vec3(s, 0.0, c));
}

// Transforms visible slot `slot` for eye `eye`, animated by the frame's time;
// `double_wide` remaps x into that eye's half of a 2W-wide target.
fn vertex(v: VertexInput, slot: u32, eye: u32, double_wide: bool) -> VertexOutput {
    let inst = instances[visible[slot]];
    let spun = spin(inst.spin * frame.time);
    let local = vec4(spun * v.position, 1.0);
    let rows = inst.world_from_local;
    var world = vec3(dot(rows[0], local), dot(rows[1], local), dot(rows[2], local));
    world.y += inst.bob * sin(PI * frame.time);
    let e = display.eye[eye];
    var clip = e.clip_from_view * (e.view_from_world * vec4(world, 1.0));

    var out: VertexOutput;
    if (double_wide) {
        // Exact two-viewport remap: x' = x/2 -+ w/2 lands where a W-wide viewport would.
        let x_eye = clip.x;
        clip.x = 0.5 * clip.x + select(0.5, -0.5, eye == 0u) * clip.w;
        set_seam_distance(&out, select(clip.w + x_eye, clip.w - x_eye, eye == 0u));
    }
    out.position = clip;
    out.world_position = world;
    out.normal = world_normal(rows, spun * v.normal);
    out.color = unpack4x8unorm(inst.color);
    out.eye = eye;
    return out;
}

// The fragment stage gets its own input: naga rejects clip_distances in it.
struct FragmentInput {
    @builtin(position) position: vec4<f32>,
    @location(0) world_position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) color: vec4<f32>,
    @location(3) @interpolate(flat) eye: u32,
}

const LIGHT_DIRECTION: vec3<f32> = vec3(0.37139068, 0.74278135, 0.55708601);

@fragment
fn fs_main(in: FragmentInput) -> @location(0) vec4<f32> {
    if (DISCARD_OTHER_HALF && ((in.position.x < display.resolution.x) != (in.eye == 0u))) {
        discard;
    }
    // Specular from this eye's own position, not the viewer's: the eye context.
    let to_eye = normalize(display.eye[in.eye].position - in.world_position);
    var n = normalize(in.normal);
    if (dot(n, to_eye) < 0.0) {
        n = -n;
    }
    let diffuse = max(dot(n, LIGHT_DIRECTION), 0.0);
    let half_vector = normalize(LIGHT_DIRECTION + to_eye);
    let specular = 0.3 * pow(max(dot(n, half_vector), 0.0), 48.0);
    return vec4(in.color.rgb * (0.25 + 0.75 * diffuse) + vec3(specular), 1.0);
}
