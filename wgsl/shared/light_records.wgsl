// A light as the shaders read it (LightRecord in src/lights.rs), and the matrices of
// the clusters buffer (`light_clusters`: word 0 the light count, then each slice's
// starting depth, then per display its combined frustum's view and projection
// matrices, column by column, and each cluster's bits). Shared by the draw pipelines
// (wgsl/shared/lights.wgsl) and the cluster pass (wgsl/light_clusters.wgsl).

struct LightRecord {
    position: vec3<f32>,
    range: f32,
    color: vec3<f32>,
    // 0 none, 1 point, 2 spot, 3 directional.
    kind: u32,
    direction: vec3<f32>,
    cone_scale: f32,
    cone_offset: f32,
}

fn cluster_matrix(at: u32) -> mat4x4<f32> {
    var m: array<vec4<f32>, 4>;
    for (var c = 0u; c < 4u; c++) {
        let w = at + 4u * c;
        m[c] = vec4(
            bitcast<f32>(light_clusters[w]),
            bitcast<f32>(light_clusters[w + 1u]),
            bitcast<f32>(light_clusters[w + 2u]),
            bitcast<f32>(light_clusters[w + 3u]),
        );
    }
    return mat4x4(m[0], m[1], m[2], m[3]);
}

