// Each display's light clusters, once per frame for both eyes (src/lights.rs is the
// CPU twin, cluster_bits: the same operations in the same order): one invocation per
// cluster, the display the dispatch's z. A cluster's box in the display's view space
// holds its tile of normalized device coordinates between its slice's depths (the
// slices' starts come from the CPU, after the light count); a light's bit is set where
// its sphere of influence touches the box.
// Bindings: LIGHT_CLUSTER_BINDINGS in src/shaders/binding_lists.rs.

fn word_f32(i: u32) -> f32 {
    return bitcast<f32>(light_clusters[i]);
}

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

@compute @workgroup_size(64)
fn clusters(@builtin(global_invocation_id) id: vec3<u32>) {
    let c = id.x;
    if (c >= CLUSTERS) {
        return;
    }
    let region = LIGHT_HEADER_WORDS + id.z * LIGHT_DISPLAY_WORDS;
    let view_from_world = cluster_matrix(region);
    let p = cluster_matrix(region + 16u);
    let x = c % CLUSTER_X;
    let y = (c / CLUSTER_X) % CLUSTER_Y;
    let k = c / (CLUSTER_X * CLUSTER_Y);
    let d0 = word_f32(1u + k);
    let d1 = word_f32(2u + k);
    let xs = across(ndc(x, CLUSTER_X), ndc(x + 1u, CLUSTER_X), p[0].x, p[2].x, d0, d1);
    let ys = across(ndc(y, CLUSTER_Y), ndc(y + 1u, CLUSTER_Y), p[1].y, p[2].y, d0, d1);
    let lo = vec3(xs.x, ys.x, -d1);
    let hi = vec3(xs.y, ys.y, -d0);
    let count = light_clusters[0];
    let out = region + LIGHT_MATRIX_WORDS + c * CLUSTER_WORDS;
    for (var w = 0u; w < CLUSTER_WORDS; w++) {
        var bits = 0u;
        for (var b = 0u; b < 32u; b++) {
            let i = 32u * w + b;
            if (i < count && touches(lights[i], view_point(view_from_world, lights[i].position), lo, hi)) {
                bits |= 1u << b;
            }
        }
        light_clusters[out + w] = bits;
    }
}

fn touches(l: LightRecord, center: vec3<f32>, lo: vec3<f32>, hi: vec3<f32>) -> bool {
    if (l.kind == 0u) {
        return false;
    }
    if (l.kind == 3u) {
        return true;
    }
    let d = center - clamp(center, lo, hi);
    return d.x * d.x + d.y * d.y + d.z * d.z <= l.range * l.range;
}
