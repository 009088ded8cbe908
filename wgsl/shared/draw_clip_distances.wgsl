// Draw-pipeline prelude for stereo with CLIP_DISTANCES: the hardware clips each eye's
// triangles at the seam of the double-wide target.
enable clip_distances;

struct VertexOutput {
    @builtin(position) position: vec4<f32>,
    @builtin(clip_distances) seam: array<f32, 1>,
    @location(0) normal: vec3<f32>,
    // (eye, instance, material) in one location: lavapipe's multiview misroutes
    // clipped triangles as varyings grow.
    @location(1) @interpolate(flat) ids: vec3<u32>,
    @location(2) uv: vec2<f32>,
    // World tangent and handedness, for normal maps.
    @location(3) tangent: vec4<f32>,
}

fn set_view_clip(out: ptr<function, VertexOutput>, d: Decoded) {
    (*out).seam[0] = d.seam;
}

const DISCARD_OUTSIDE_VIEWPORT: bool = false;
