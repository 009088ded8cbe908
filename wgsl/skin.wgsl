// The frame's skinning pass (src/skinning.rs, once per frame before every draw): each
// invocation moves one skinned vertex by its four joints' matrices blended by weight,
// and writes its position, normal and tangent into its instance's own mesh in the one
// vertex buffer every display, eye and shadow draws from. The CPU twin is
// skinning::skin_vertex, the same operations in the same order.

struct SkinVertex {
    position: array<f32, 3>,
    normal: array<f32, 3>,
    // Snorm8x4: tangent and handedness.
    tangent: u32,
    // Four u16 joint indices into the skin's joints, two to a word.
    joints: array<u32, 2>,
    weights: array<f32, 4>,
    joint_base: u32,
    destination: u32,
}

struct SkinParams {
    vertices: u32,
    // Invocations per row of the dispatch (workgroups in x times the workgroup size).
    row: u32,
}

// Bindings: SKIN_BINDINGS in src/shaders/bindings.rs; `vertices` holds the scene's
// vertices (scene::Vertex), twelve words each.

const VERTEX_WORDS: u32 = 12u;
const TANGENT_WORD: u32 = 9u;

fn joint_of(v: SkinVertex, k: u32) -> u32 {
    return (v.joints[k / 2u] >> (16u * (k % 2u))) & 0xffffu;
}

@compute @workgroup_size(64)
fn skin(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x + id.y * params.row;
    if (i >= params.vertices) {
        return;
    }
    let v = rest[i];
    var blended = array<vec4<f32>, 3>(vec4(0.0), vec4(0.0), vec4(0.0));
    for (var k = 0u; k < 4u; k++) {
        let m = joints[v.joint_base + joint_of(v, k)];
        for (var r = 0u; r < 3u; r++) {
            blended[r] += m[r] * v.weights[k];
        }
    }
    let p = vec4(v.position[0], v.position[1], v.position[2], 1.0);
    let position = vec3(dot(blended[0], p), dot(blended[1], p), dot(blended[2], p));
    let linear = transpose(mat3x3(blended[0].xyz, blended[1].xyz, blended[2].xyz));
    let a = linear[0];
    let b = linear[1];
    let c = linear[2];
    let cofactor = mat3x3(cross(b, c), cross(c, a), cross(a, b));
    let n = vec3(v.normal[0], v.normal[1], v.normal[2]);
    let normal = sign(dot(a, cross(b, c))) * (cofactor * n);
    let t = unpack4x8snorm(v.tangent);
    let along = linear * t.xyz;
    let unit = select(vec3(0.0), normalize(along), dot(along, along) > 0.0);
    let out = v.destination * VERTEX_WORDS;
    vertices[out] = bitcast<u32>(position.x);
    vertices[out + 1u] = bitcast<u32>(position.y);
    vertices[out + 2u] = bitcast<u32>(position.z);
    vertices[out + 3u] = bitcast<u32>(normal.x);
    vertices[out + 4u] = bitcast<u32>(normal.y);
    vertices[out + 5u] = bitcast<u32>(normal.z);
    vertices[out + TANGENT_WORD] = pack4x8snorm(vec4(unit, t.w));
}
