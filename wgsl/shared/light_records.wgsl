// A light as the shaders read it (LightRecord in src/lights.rs), and the views buffer
// (`light_views`: the light count, each slice's starting depth, then per display its
// combined frustum's view and projection matrices, column by column). Shared by the
// draw pipelines (wgsl/shared/lights.wgsl) and the cluster pass
// (wgsl/light_clusters.wgsl).

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

fn light_count() -> u32 {
    return light_views[0];
}

// The view depth where slice k starts (k = CLUSTER_Z: where the last ends).
fn slice_start(k: u32) -> f32 {
    return bitcast<f32>(light_views[1u + k]);
}

// Display `slot`'s view (m = 0) or projection (m = 1) matrix.
fn cluster_matrix(slot: u32, m: u32) -> mat4x4<f32> {
    let at = LIGHT_HEADER_WORDS + slot * LIGHT_VIEW_WORDS + 16u * m;
    var c: array<vec4<f32>, 4>;
    for (var i = 0u; i < 4u; i++) {
        let w = at + 4u * i;
        c[i] = bitcast<vec4<f32>>(vec4(light_views[w], light_views[w + 1u], light_views[w + 2u], light_views[w + 3u]));
    }
    return mat4x4(c[0], c[1], c[2], c[3]);
}

// The view depths at which a fragment's slice index changes: slice 0 below
// CLUSTER_NEAR, then exponential to CLUSTER_FAR, the last slice beyond it.
fn slice_of(depth: f32) -> u32 {
    if (!(depth >= CLUSTER_NEAR)) {
        return 0u;
    }
    let t = log(depth / CLUSTER_NEAR) / log(CLUSTER_FAR / CLUSTER_NEAR);
    return min(1u + u32(t * f32(CLUSTER_Z - 2u)), CLUSTER_Z - 1u);
}
