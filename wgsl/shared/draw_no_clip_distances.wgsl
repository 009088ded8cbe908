// Draw-pipeline prelude without CLIP_DISTANCES (and for mono, which needs none): a
// fragment of a view outside that view's viewport (for stereo, its eye's half) is
// discarded instead.

struct VertexOutput {
    @builtin(position) position: vec4<f32>,
    @location(0) normal: vec3<f32>,
    // (eye, instance, material) in one location: lavapipe's multiview misroutes
    // clipped triangles as varyings grow.
    @location(1) @interpolate(flat) ids: vec3<u32>,
    @location(2) uv: vec2<f32>,
    // World tangent and handedness, for normal maps.
    @location(3) tangent: vec4<f32>,
}

fn set_view_clip(out: ptr<function, VertexOutput>, d: Decoded) {}

const DISCARD_OUTSIDE_VIEWPORT: bool = VIEWS >= 2u;
