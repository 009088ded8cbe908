// Shared by the built-in draw pipelines: their vertex output and shading, on top of
// the decode (wgsl/shared/decode.wgsl). Vertices pass on only what the fragment stage
// cannot find itself: the software rasterizers we profile on (lavapipe) set up every
// varying of every triangle, and most triangles of a large scene cover a pixel or none.
// The fragment stage reads the instance's color from its record and rebuilds its world
// position from the depth buffer's coordinates.

fn vertex(v: VertexInput, slot: u32, eye: u32, double_wide: bool) -> VertexOutput {
    return vertex_of(decode(v, slot, eye, double_wide), double_wide);
}

fn vertex_of(d: Decoded, double_wide: bool) -> VertexOutput {
    var out: VertexOutput;
    if (double_wide) {
        set_view_clip(&out, d);
    }
    out.position = d.clip;
    out.normal_u = vec4(d.world_normal, d.uv.x);
    out.ids = vec4(d.eye, d.instance, d.material, u32(d.world_tangent.w < 0.0));
    out.tangent_v = vec4(d.world_tangent.xyz, d.uv.y);
    set_second_uv(&out, d);
    return out;
}

// The fragment stage gets its own input: naga rejects clip_distances in it.
struct FragmentInput {
    @builtin(position) position: vec4<f32>,
    @location(0) normal_u: vec4<f32>,
    @location(1) @interpolate(flat) ids: vec4<u32>,
    @location(2) tangent_v: vec4<f32>,
    // SECOND_UV
    // MOTION
}

// What a material sees of one fragment: a caller's `fn material(s: Surface) ->
// vec4<f32>` (RendererOptions::material) replaces `shade` (its alpha is read by
// blended materials only); `display.eye[s.eye]` is the eye's context, `frame` the
// frame's (its light: `frame.light_direction`, and `light_reaching(s.world_position,
// normal)` for the shadow map). `pbr_inputs(s)` reads the material's textures and
// factors (wgsl/shared/pbr.wgsl) and `pbr_shade(s, p)` lights them as `shade` does.
struct Surface {
    world_position: vec3<f32>,
    // Interpolated, not normalized.
    normal: vec3<f32>,
    // The instance record's color (for glTF, the material's base color factor);
    // base_color(s) multiplies in the base color texture.
    color: vec4<f32>,
    eye: u32,
    instance: u32,
    // Texture coordinates, and the material (materials[s.material]).
    uv: vec2<f32>,
    material: u32,
    // World tangent (interpolated, not normalized) and handedness in w: the bitangent
    // is sign(w) * cross(normal, tangent).
    tangent: vec4<f32>,
    // The second texture coordinates: the slots in materials[s.material].second_uv
    // read them (zero in a bin whose materials read one set).
    uv1: vec2<f32>,
}

// The surface's color times its material's base color texture, if any.
fn base_color(s: Surface) -> vec4<f32> {
    return base_color_at(s.color, vec4(s.uv, s.uv1), s.material);
}

// How much of the frame's light reaches world position `p` (facing `n`, unit): 1 lit,
// 0 in shadow, from a 3 x 3 percentage-closer filter over the frame's shadow map (each
// tap bilinear, so 4 x 4 texels weigh in), taken a texel and a half along the normal
// so that surfaces do not shadow themselves. 1 outside the map and without shadows.
fn light_reaching(p: vec3<f32>, n: vec3<f32>) -> f32 {
    if (frame.shadows == 0u) {
        return 1.0;
    }
    let m = frame.light_from_world;
    let size = vec2<f32>(textureDimensions(shadow_map));
    let texel = 2.0 / (length(vec3(m[0].x, m[1].x, m[2].x)) * size.x);
    let clip = m * vec4(p + n * (1.5 * texel), 1.0);
    let uv = vec2(clip.x * 0.5 + 0.5, 0.5 - clip.y * 0.5);
    if (any(uv < vec2(0.0)) || any(uv > vec2(1.0)) || clip.z > 1.0) {
        return 1.0;
    }
    var lit = 0.0;
    for (var y = -1; y <= 1; y++) {
        for (var x = -1; x <= 1; x++) {
            let at = uv + vec2(f32(x), f32(y)) / size;
            lit += textureSampleCompareLevel(shadow_map, shadow_sampler, at, clip.z);
        }
    }
    return lit / 9.0;
}

// The fragment stage of every built-in pipeline, for view `eye` (its entry point says
// where the view comes from), whose pixels are `viewport` (x, y, width, height) of the
// target.
fn fragment(in: FragmentInput, eye: u32, viewport: vec4<f32>) -> vec4<f32> {
    let p = in.position.xy;
    if (DISCARD_OUTSIDE_VIEWPORT && (any(p < viewport.xy) || any(p >= viewport.xy + viewport.zw))) {
        discard;
    }
    let color = instance_color(in.ids.y, eye);
    let world = world_position(in.position, eye, viewport);
    let uv = vec2(in.normal_u.w, in.tangent_v.w);
    // Handedness is the provoking vertex's: constant across a triangle in practice
    // (a mirrored uv seam splits its vertices).
    let tangent = vec4(in.tangent_v.xyz, select(1.0, -1.0, in.ids.w == 1u));
    let s = Surface(world, in.normal_u.xyz, color, eye, in.ids.y, uv, in.ids.z, tangent, second_uv(in));
    // The bin's alpha mode (ALPHA_MODE, src/bins.rs): only cutout pipelines discard,
    // so the opaque ones keep early depth testing.
    if (ALPHA_MODE == 1u && !ALPHA_TO_COVERAGE && base_color(s).a < materials[s.material].alpha_cutoff) {
        discard;
    }
    let shaded = surface_color(s);
    if (ALPHA_MODE == 2u) {
        return shaded;
    }
    if (ALPHA_MODE == 1u && ALPHA_TO_COVERAGE) {
        return vec4(shaded.rgb, coverage(base_color(s).a, materials[s.material].alpha_cutoff));
    }
    return vec4(shaded.rgb, 1.0);
}

// A cutout's alpha under MSAA, for alpha to coverage: the cutoff's edge sharpened to
// about a pixel wide (0 below, 1 above), so the samples split where the cutoff falls.
// The width is capped at COVERAGE_WIDTH: a texture sample's derivative is unreliable
// where a 2 x 2 quad crosses a triangle edge (lavapipe's helper lanes read alpha 0
// there: fwidth reached 0.75 on a smooth texture), and an uncapped width would let
// such a pixel half cover a hole.
const COVERAGE_WIDTH: f32 = 0.25;

fn coverage(alpha: f32, cutoff: f32) -> f32 {
    return clamp((alpha - cutoff) / clamp(fwidth(alpha), 1e-4, COVERAGE_WIDTH) + 0.5, 0.0, 1.0);
}

// The world position under a fragment of view `eye` drawn into `viewport`: its pixel
// and depth back through the view's projection (world_from_clip, composed in f64 on the
// CPU).
fn world_position(frag: vec4<f32>, eye: u32, viewport: vec4<f32>) -> vec3<f32> {
    let size = viewport.zw;
    let at = frag.xy - viewport.xy;
    let ndc = vec2(at.x / size.x * 2.0 - 1.0, 1.0 - at.y / size.y * 2.0);
    let world = display.eye[eye].world_from_clip * vec4(ndc, frag.z, 1.0);
    return world.xyz / world.w;
}
