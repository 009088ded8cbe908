// Draw-pipeline prelude for foveated stereo with CLIP_DISTANCES: four views of
// different sizes share the target, so each view's triangles are clipped at all four
// edges of its own viewport (a shorter view has empty target rows below it).
enable clip_distances;

struct VertexOutput {
    @builtin(position) position: vec4<f32>,
    @builtin(clip_distances) edges: array<f32, 4>,
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

fn set_view_clip(out: ptr<function, VertexOutput>, d: Decoded) {
    (*out).edges = array(d.edges.x, d.edges.y, d.edges.z, d.edges.w);
}

const DISCARD_OUTSIDE_VIEWPORT: bool = false;
