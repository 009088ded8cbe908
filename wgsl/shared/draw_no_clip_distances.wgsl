// Draw-pipeline prelude without CLIP_DISTANCES (and for mono, which needs none): a
// fragment of a view outside that view's viewport (for stereo, its eye's half) is
// discarded instead.

struct VertexOutput {
    @builtin(position) position: vec4<f32>,
    // Three locations, packed (normal_u: world normal and u; tangent_v: world tangent
    // and v; ids: eye, instance, material and the tangent's handedness as 0 or 1):
    // lavapipe's multiview misroutes clipped triangles as varyings grow (a fourth
    // location for the tangent dropped a wall's edge from the second view).
    @location(0) normal_u: vec4<f32>,
    @location(1) @interpolate(flat) ids: vec4<u32>,
    @location(2) tangent_v: vec4<f32>,
    // SECOND_UV
    // MOTION
}

fn set_view_clip(out: ptr<function, VertexOutput>, d: Decoded) {}

const DISCARD_OUTSIDE_VIEWPORT: bool = VIEWS >= 2u;
