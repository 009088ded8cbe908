// Draw-pipeline prelude without CLIP_DISTANCES (and for mono, which needs none): a
// stereo fragment outside its eye's half is discarded instead.

struct VertexOutput {
    @builtin(position) position: vec4<f32>,
    @location(0) normal: vec3<f32>,
    // (eye, instance, material) in one location: lavapipe's multiview misroutes
    // clipped triangles as varyings grow.
    @location(1) @interpolate(flat) ids: vec3<u32>,
    @location(2) uv: vec2<f32>,
}

fn set_seam_distance(out: ptr<function, VertexOutput>, distance: f32) {}

const DISCARD_OTHER_HALF: bool = VIEWS == 2u;
