// Draw-pipeline prelude for foveated stereo with CLIP_DISTANCES: four views of
// different sizes share the target, so each view's triangles are clipped at all four
// edges of its own viewport (a shorter view has empty target rows below it).
enable clip_distances;

struct VertexOutput {
    @builtin(position) position: vec4<f32>,
    @builtin(clip_distances) edges: array<f32, 4>,
    @location(0) normal: vec3<f32>,
    // (eye, instance, material) in one location: lavapipe's multiview misroutes
    // clipped triangles as varyings grow.
    @location(1) @interpolate(flat) ids: vec3<u32>,
    @location(2) uv: vec2<f32>,
    // World tangent and handedness, for normal maps.
    @location(3) tangent: vec4<f32>,
}

fn set_view_clip(out: ptr<function, VertexOutput>, d: Decoded) {
    (*out).edges = array(d.edges.x, d.edges.y, d.edges.z, d.edges.w);
}

const DISCARD_OUTSIDE_VIEWPORT: bool = false;
