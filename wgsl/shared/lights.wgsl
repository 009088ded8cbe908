// Punctual lights, shaded through the display's clusters (src/lights.rs says how the
// clusters are built and why one grid serves both eyes). Composed into the draw
// pipelines after light_records.wgsl, with group 2's `lights` and `light_clusters`
// (a display's region is its cull_slot's).

// The first word of the record of the cluster holding world point `p` in display
// `slot`'s grid: from the point, whichever eye draws it.
fn cluster_record_at(p: vec3<f32>, slot: u32) -> u32 {
    let view = cluster_matrix(slot, 0u) * vec4(p, 1.0);
    let clip = cluster_matrix(slot, 1u) * view;
    let ndc = clip.xy / clip.w;
    let cells = vec2(f32(CLUSTER_X), f32(CLUSTER_Y));
    let tile = vec2<u32>(clamp((ndc * 0.5 + 0.5) * cells, vec2(0.0), cells - 1.0));
    let k = slice_of(-view.z);
    let cluster = (k * CLUSTER_Y + tile.y) * CLUSTER_X + tile.x;
    return slot * LIGHT_DISPLAY_WORDS + cluster * CLUSTER_RECORD_WORDS;
}

// What light `l` brings to world point `p`: the direction toward it (xyz) and its
// radiance there, as `light_at` in src/pbr.rs.
fn light_at(l: LightRecord, p: vec3<f32>) -> array<vec3<f32>, 2> {
    if (l.kind == 3u) {
        return array(-l.direction, l.color);
    }
    let to = l.position - p;
    let d2 = max(dot(to, to), 1e-8);
    let d = sqrt(d2);
    let toward = to / d;
    let q = d2 / (l.range * l.range);
    let window = clamp(1.0 - q * q, 0.0, 1.0);
    var falloff = window * window / d2;
    if (l.kind == 2u) {
        let a = clamp(dot(l.direction, -toward) * l.cone_scale + l.cone_offset, 0.0, 1.0);
        falloff *= a * a;
    }
    return array(toward, l.color * falloff);
}

// Every light of the fragment's cluster (the summary names the bit words that hold
// any), shaded like the frame's light but without a shadow. Nothing without lights (a
// uniform branch).
fn lights_shading(s: Surface, p: Pbr, v: vec3<f32>) -> vec3<f32> {
    var sum = vec3(0.0);
    if (light_count() == 0u) {
        return sum;
    }
    let at = cluster_record_at(s.world_position, display.cull_slot);
    let words = at + CLUSTER_WORDS / 32u;
    for (var u = 0u; u < CLUSTER_WORDS / 32u; u++) {
        var used = light_clusters[at + u];
        while (used != 0u) {
            let w = 32u * u + firstTrailingBit(used);
            used &= used - 1u;
            var bits = light_clusters[words + w];
            while (bits != 0u) {
                let i = 32u * w + firstTrailingBit(bits);
                bits &= bits - 1u;
                let l = light_at(lights[i], s.world_position);
                let b = brdf(p, v, l[0]);
                sum += b.xyz * (l[1] * b.w);
            }
        }
    }
    return sum;
}
