// Each display's light clusters, once per frame for both eyes: one invocation per
// light, the display the dispatch's z (the records were cleared before). A light
// tests the clusters of the slices its sphere's depth range reaches (a slice wider on
// each side for the rounding of the logarithm; a box of another slice lies wholly
// nearer or farther than the sphere) and each cluster's box
// exactly as src/lights.rs's twin tests every cluster (cluster_box, touches: the same
// operations in the same order), setting its bit and the bit word's summary bit with
// atomic ors, whose order does not matter.
// Bindings: LIGHT_CLUSTER_BINDINGS in src/shaders/binding_lists.rs.

fn view_point(m: mat4x4<f32>, p: vec3<f32>) -> vec3<f32> {
    return vec3(
        m[0].x * p.x + m[1].x * p.y + m[2].x * p.z + m[3].x,
        m[0].y * p.x + m[1].y * p.y + m[2].y * p.z + m[3].y,
        m[0].z * p.x + m[1].z * p.y + m[2].z * p.z + m[3].z,
    );
}

fn ndc(i: u32, n: u32) -> f32 {
    return 2.0 * f32(i) / f32(n) - 1.0;
}

// The least and greatest of the four corners' coordinate across (x or y).
fn across(n0: f32, n1: f32, scale: f32, shift: f32, d0: f32, d1: f32) -> vec2<f32> {
    let a = d0 * (n0 + shift) / scale;
    let b = d0 * (n1 + shift) / scale;
    let c = d1 * (n0 + shift) / scale;
    let d = d1 * (n1 + shift) / scale;
    return vec2(min(min(a, b), min(c, d)), max(max(a, b), max(c, d)));
}

struct Box {
    lo: vec3<f32>,
    hi: vec3<f32>,
}

// Cluster c's box in the display's view space (projection p).
fn cluster_box(c: u32, p: mat4x4<f32>) -> Box {
    let x = c % CLUSTER_X;
    let y = (c / CLUSTER_X) % CLUSTER_Y;
    let k = c / (CLUSTER_X * CLUSTER_Y);
    let d0 = slice_start(k);
    let d1 = slice_start(k + 1u);
    let xs = across(ndc(x, CLUSTER_X), ndc(x + 1u, CLUSTER_X), p[0].x, p[2].x, d0, d1);
    let ys = across(ndc(y, CLUSTER_Y), ndc(y + 1u, CLUSTER_Y), p[1].y, p[2].y, d0, d1);
    return Box(vec3(xs.x, ys.x, -d1), vec3(xs.y, ys.y, -d0));
}

fn touches(l: LightRecord, center: vec3<f32>, b: Box) -> bool {
    if (l.kind == 0u) {
        return false;
    }
    if (l.kind == 3u) {
        return true;
    }
    let d = center - clamp(center, b.lo, b.hi);
    return d.x * d.x + d.y * d.y + d.z * d.z <= l.range * l.range;
}

@compute @workgroup_size(64)
fn clusters(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i >= light_count()) {
        return;
    }
    let l = lights[i];
    let view_from_world = cluster_matrix(id.z, 0u);
    let p = cluster_matrix(id.z, 1u);
    let center = view_point(view_from_world, l.position);
    var ks = vec2(0u, CLUSTER_Z - 1u);
    if (l.kind == 0u) {
        return;
    }
    if (l.kind != 3u) {
        let near = -center.z - l.range;
        let far = -center.z + l.range;
        if (far < 0.0) {
            return;
        }
        ks = vec2(max(slice_of(near), 1u) - 1u, min(slice_of(far) + 1u, CLUSTER_Z - 1u));
    }
    let region = id.z * LIGHT_DISPLAY_WORDS;
    let w = i / 32u;
    let bit = 1u << (i % 32u);
    let summary = 1u << (w % 32u);
    let per_slice = CLUSTER_X * CLUSTER_Y;
    for (var c = ks.x * per_slice; c < (ks.y + 1u) * per_slice; c++) {
        if (touches(l, center, cluster_box(c, p))) {
            let at = region + c * CLUSTER_RECORD_WORDS;
            atomicOr(&light_clusters[at + CLUSTER_WORDS / 32u + w], bit);
            atomicOr(&light_clusters[at + w / 32u], summary);
        }
    }
}
