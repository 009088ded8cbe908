//! A glTF file of morph targets written here: a grid on two nodes whose weights play
//! two animations (`tests/morphing.rs` says what each target does).

use serde_json::json;

use super::glb::write_glb;

/// The grid's vertices a side.
pub const SIDE: usize = 4;

fn grid() -> (Vec<[f32; 3]>, Vec<u16>) {
    let positions = (0..SIDE * SIDE)
        .map(|i| {
            let (x, y) = ((i % SIDE) as f32, (i / SIDE) as f32);
            [x / 3.0, y / 3.0, 0.0]
        })
        .collect();
    let mut indices = Vec::new();
    for y in 0..SIDE - 1 {
        for x in 0..SIDE - 1 {
            let a = (y * SIDE + x) as u16;
            let (b, c, d) = (a + 1, a + SIDE as u16, a + SIDE as u16 + 1);
            indices.extend([a, b, d, a, d, c]);
        }
    }
    (positions, indices)
}

/// A 4 x 4 grid with normals, tangents and two targets (0 bulges it and bends its
/// normals; 1 shears it and turns its tangents), drawn by two nodes: node 0's weights
/// play linearly over 2 s, node 1's by a cubic spline whose tangents overshoot its keys.
pub fn morph_file() -> Vec<u8> {
    let (positions, indices) = grid();
    let n = positions.len();
    let bulge: Vec<[f32; 3]> = (positions.iter())
        .map(|p| {
            let z = 0.3 * (std::f32::consts::PI * p[0]).sin() * (std::f32::consts::PI * p[1]).sin();
            [0.0, 0.0, z]
        })
        .collect();
    let bent: Vec<[f32; 3]> = positions
        .iter()
        .map(|p| [-0.2 * p[0], 0.1 * p[1], 0.0])
        .collect();
    let shear: Vec<[f32; 3]> = positions.iter().map(|p| [0.2 * p[1], -0.1, 0.0]).collect();
    let turned = vec![[0.0f32, 0.3, 0.1]; n];
    let normals = vec![[0.0f32, 0.0, 1.0]; n];
    let tangents = vec![[1.0f32, 0.0, 0.0, 1.0]; n];
    let linear_times = [0.0f32, 1.0, 2.0];
    let linear_weights = [0.0f32, 0.0, 1.0, 0.5, 0.2, 1.0];
    let cubic_times = [0.0f32, 1.5];
    let cubic_weights = [
        0.0f32, 0.0, 0.0, 0.0, 2.0, -1.0, 1.0, 1.0, 1.0, 0.5, 0.0, 0.0,
    ];
    let cubic = [cubic_times.as_slice(), &cubic_weights].concat();
    let mut bin = Vec::new();
    let mut views = Vec::new();
    let mut push = |bytes: &[u8]| {
        views.push(json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": bytes.len()}));
        bin.extend_from_slice(bytes);
        while bin.len() % 4 != 0 {
            bin.push(0);
        }
        views.len() - 1
    };
    let chunks: [&[u8]; 11] = [
        bytemuck::cast_slice(&positions),
        bytemuck::cast_slice(&normals),
        bytemuck::cast_slice(&tangents),
        bytemuck::cast_slice(&indices),
        bytemuck::cast_slice(&bulge),
        bytemuck::cast_slice(&bent),
        bytemuck::cast_slice(&shear),
        bytemuck::cast_slice(&turned),
        bytemuck::cast_slice(&linear_times),
        bytemuck::cast_slice(&linear_weights),
        bytemuck::cast_slice(&cubic),
    ];
    let v: Vec<usize> = chunks.iter().map(|c| push(c)).collect();
    let vec3 = |view: usize| json!({"bufferView": view, "componentType": 5126, "count": n, "type": "VEC3"});
    let json = json!({
        "asset": {"version": "2.0"},
        "scene": 0, "scenes": [{"nodes": [0, 1]}],
        "nodes": [
            {"mesh": 0, "translation": [-1.0, 0.0, 0.0]},
            {"mesh": 0, "translation": [1.0, 0.0, 0.0], "weights": [0.5, 0.25]}
        ],
        "meshes": [{"weights": [0.25, 0.0], "primitives": [{
            "attributes": {"POSITION": 0, "NORMAL": 1, "TANGENT": 2}, "indices": 3,
            "targets": [{"POSITION": 4, "NORMAL": 5}, {"POSITION": 6, "TANGENT": 7}]}]}],
        "animations": [
            {"channels": [{"sampler": 0, "target": {"node": 0, "path": "weights"}}],
             "samplers": [{"input": 8, "output": 9, "interpolation": "LINEAR"}]},
            {"channels": [{"sampler": 0, "target": {"node": 1, "path": "weights"}}],
             "samplers": [{"input": 10, "output": 11, "interpolation": "CUBICSPLINE"}]}
        ],
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": views,
        "accessors": [
            {"bufferView": v[0], "componentType": 5126, "count": n, "type": "VEC3",
             "min": [0, 0, 0], "max": [1, 1, 0]},
            vec3(v[1]),
            {"bufferView": v[2], "componentType": 5126, "count": n, "type": "VEC4"},
            {"bufferView": v[3], "componentType": 5123, "count": indices.len(), "type": "SCALAR"},
            vec3(v[4]), vec3(v[5]), vec3(v[6]), vec3(v[7]),
            {"bufferView": v[8], "componentType": 5126, "count": 3, "type": "SCALAR",
             "min": [0], "max": [2]},
            {"bufferView": v[9], "componentType": 5126, "count": 6, "type": "SCALAR"},
            {"bufferView": v[10], "componentType": 5126, "count": 2, "type": "SCALAR",
             "min": [0], "max": [1.5]},
            {"bufferView": v[10], "byteOffset": 8, "componentType": 5126, "count": 12, "type": "SCALAR"}
        ]
    });
    write_glb(&json, &bin)
}

/// [`morph_file`]'s scene, loaded as a file is.
pub fn morph_scene() -> stereocull::scene::Scene {
    super::load_bytes("morph.glb", &morph_file())
}
