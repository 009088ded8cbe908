// The frame's morph pass (src/morphing.rs, once per frame before the skinning pass and
// every draw): each invocation moves one morphed vertex from its rest by every target's
// offsets times the target's weight, and writes its position, normal and tangent into
// the one vertex buffer every display, eye and shadow draws from, or, for a skinned
// mesh, into the skin's rest vertex, which the skinning pass moves next. The CPU twin is
// morphing::morph_vertex, the same operations in the same order.

struct MorphVertex {
    position: array<f32, 3>,
    normal: array<f32, 3>,
    // Snorm8x4: tangent and handedness.
    tangent: u32,
    first_delta: u32,
    first_weight: u32,
    targets: u32,
    destination: u32,
    skinned: u32,
}

struct MorphDelta {
    position: array<f32, 3>,
    normal: array<f32, 3>,
    tangent: array<f32, 3>,
}

struct MorphParams {
    vertices: u32,
    // Invocations per row of the dispatch (workgroups in x times the workgroup size).
    row: u32,
}

// Bindings: MORPH_BINDINGS in src/shaders/binding_lists.rs. `vertices` holds the
// scene's vertices (scene::Vertex, twelve words each), `skin_rest` the skins' rest
// vertices (skinning::SkinVertex, fifteen words each).

const VERTEX_WORDS: u32 = 12u;
const VERTEX_TANGENT: u32 = 9u;
const SKIN_WORDS: u32 = 15u;
const SKIN_TANGENT: u32 = 6u;

fn vec3_of(a: array<f32, 3>) -> vec3<f32> {
    return vec3(a[0], a[1], a[2]);
}

@compute @workgroup_size(64)
fn morph(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x + id.y * params.row;
    if (i >= params.vertices) {
        return;
    }
    let v = rest[i];
    var position = vec3_of(v.position);
    var normal = vec3_of(v.normal);
    let t = unpack4x8snorm(v.tangent);
    var tangent = t.xyz;
    for (var k = 0u; k < v.targets; k++) {
        let w = weights[v.first_weight + k];
        let d = deltas[v.first_delta + k];
        position += vec3_of(d.position) * w;
        normal += vec3_of(d.normal) * w;
        tangent += vec3_of(d.tangent) * w;
    }
    let unit = select(vec3(0.0), normalize(tangent), dot(tangent, tangent) > 0.0);
    let packed = pack4x8snorm(vec4(unit, t.w));
    if (v.skinned != 0u) {
        let out = v.destination * SKIN_WORDS;
        write_skin(out, position, normal);
        skin_rest[out + SKIN_TANGENT] = packed;
    } else {
        let out = v.destination * VERTEX_WORDS;
        write_vertex(out, position, normal);
        vertices[out + VERTEX_TANGENT] = packed;
    }
}

fn write_vertex(out: u32, p: vec3<f32>, n: vec3<f32>) {
    vertices[out] = bitcast<u32>(p.x);
    vertices[out + 1u] = bitcast<u32>(p.y);
    vertices[out + 2u] = bitcast<u32>(p.z);
    vertices[out + 3u] = bitcast<u32>(n.x);
    vertices[out + 4u] = bitcast<u32>(n.y);
    vertices[out + 5u] = bitcast<u32>(n.z);
}

fn write_skin(out: u32, p: vec3<f32>, n: vec3<f32>) {
    skin_rest[out] = bitcast<u32>(p.x);
    skin_rest[out + 1u] = bitcast<u32>(p.y);
    skin_rest[out + 2u] = bitcast<u32>(p.z);
    skin_rest[out + 3u] = bitcast<u32>(n.x);
    skin_rest[out + 4u] = bitcast<u32>(n.y);
    skin_rest[out + 5u] = bitcast<u32>(n.z);
}
