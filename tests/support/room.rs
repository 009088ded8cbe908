//! The authoring of the built-in room: a furnished room at real scale, with objects
//! from an arm's length to ten meters away so that stereo depth reads. The library only
//! embeds the written file (`assets/room.glb`); `tests/default_scene.rs` checks that the
//! file is what this writes (`STEREOCULL_RECORD=1` rewrites it).

use glam::{Affine3A, Quat, Vec3, Vec4};
use serde_json::json;
use stereocull::scene::{Animation, Instance, Scene};
use stereocull::shapes::{self, Shape};

const CUBE: u32 = 0;
const SPHERE: u32 = 1;
const CYLINDER: u32 = 2;
const TORUS: u32 = 3;

/// The room in front of the `hmd` viewer at (0, 1.6, 2) looking down -Z.
pub fn room() -> Scene {
    let mut scene = Scene::default();
    let shapes: [Shape; 4] = [
        shapes::cuboid(Vec3::splat(0.5)),
        shapes::sphere(0.5, 24, 16),
        shapes::cylinder(0.5, 1.0, 24),
        shapes::torus(0.35, 0.15, 32, 16),
    ];
    for (shape, name) in shapes.iter().zip(["cube", "sphere", "cylinder", "torus"]) {
        scene.add_mesh(name, &shape.vertices, &shape.indices);
    }
    let mut put = |mesh, scale: Vec3, rotation: Quat, at: Vec3, rgb: [f32; 3]| {
        scene.instances.push(Instance {
            world_from_local: Affine3A::from_scale_rotation_translation(scale, rotation, at),
            mesh,
            color: Vec4::new(rgb[0], rgb[1], rgb[2], 1.0),
            material: None,
            animation: Animation::NONE,
        });
    };
    let q = Quat::IDENTITY;
    let (wall, floor) = ([0.75, 0.72, 0.68], [0.45, 0.38, 0.32]);
    put(
        CUBE,
        Vec3::new(8.0, 0.1, 14.0),
        q,
        Vec3::new(0.0, -0.05, -3.0),
        floor,
    );
    put(
        CUBE,
        Vec3::new(8.0, 3.0, 0.1),
        q,
        Vec3::new(0.0, 1.5, -10.0),
        wall,
    );
    put(
        CUBE,
        Vec3::new(0.1, 3.0, 14.0),
        q,
        Vec3::new(-4.0, 1.5, -3.0),
        wall,
    );
    put(
        CUBE,
        Vec3::new(0.1, 3.0, 14.0),
        q,
        Vec3::new(4.0, 1.5, -3.0),
        wall,
    );
    // A table an arm's length ahead, with things on it.
    let wood = [0.55, 0.33, 0.18];
    put(
        CUBE,
        Vec3::new(1.6, 0.05, 0.9),
        q,
        Vec3::new(0.0, 0.75, 0.6),
        wood,
    );
    for (x, z) in [(-0.7, 0.25), (0.7, 0.25), (-0.7, 0.95), (0.7, 0.95)] {
        put(
            CYLINDER,
            Vec3::new(0.06, 0.75, 0.06),
            q,
            Vec3::new(x, 0.375, z),
            wood,
        );
    }
    put(
        SPHERE,
        Vec3::splat(0.2),
        q,
        Vec3::new(-0.3, 0.875, 0.7),
        [0.9, 0.2, 0.15],
    );
    put(
        CUBE,
        Vec3::splat(0.18),
        Quat::from_rotation_y(0.6),
        Vec3::new(0.35, 0.865, 0.5),
        [0.2, 0.5, 0.9],
    );
    // Floating close to the eyes: the strongest disparity in the scene.
    put(
        TORUS,
        Vec3::splat(0.25),
        Quat::from_rotation_x(1.2),
        Vec3::new(0.12, 1.45, 1.2),
        [0.95, 0.75, 0.1],
    );
    // Pillars down both sides, each with a ball, out to ten meters.
    for k in 0..6 {
        let z = -0.5 - 1.8 * k as f32;
        for x in [-2.8f32, 2.8] {
            let hue = k as f32 / 6.0;
            put(
                CYLINDER,
                Vec3::new(0.3, 2.0, 0.3),
                q,
                Vec3::new(x, 1.0, z),
                [0.6, 0.6, 0.65],
            );
            put(
                SPHERE,
                Vec3::splat(0.4),
                q,
                Vec3::new(x, 2.2, z),
                [0.3 + 0.6 * hue, 0.8 - 0.5 * hue, 0.4],
            );
        }
    }
    // Crates stacked at the far wall.
    for (i, (x, y)) in [(-1.0, 0.4), (0.0, 0.4), (1.0, 0.4), (-0.5, 1.2), (0.5, 1.2)]
        .iter()
        .enumerate()
    {
        let turn = Quat::from_rotation_y(0.2 * i as f32);
        put(
            CUBE,
            Vec3::splat(0.8),
            turn,
            Vec3::new(*x, *y, -9.0),
            [0.65, 0.5, 0.3],
        );
    }
    scene
}

/// Writes `scene` as a GLB: one glTF mesh per (mesh, color) pair, sharing the mesh's
/// accessors, and one node per instance in id order, so that importing it gives the
/// same instances in the same order.
pub fn to_glb(scene: &Scene) -> Vec<u8> {
    let mut bin = Vec::new();
    let mut views = Vec::new();
    let mut accessors = Vec::new();
    let mut push = |bytes: &[u8], target: u32, accessor: serde_json::Value| {
        views.push(json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": bytes.len(), "target": target}));
        bin.extend_from_slice(bytes);
        let mut a = accessor;
        a["bufferView"] = json!(views.len() - 1);
        accessors.push(a);
        accessors.len() - 1
    };
    let mut primitives = Vec::new();
    for mesh in &scene.meshes {
        let first = mesh.base_vertex as usize;
        let indices = &scene.indices
            [mesh.first_index as usize..(mesh.first_index + mesh.index_count) as usize];
        let count = *indices.iter().max().unwrap_or(&0) as usize + 1;
        let verts = &scene.vertices[first..first + count];
        let positions: Vec<[f32; 3]> = verts.iter().map(|v| v.position).collect();
        let normals: Vec<[f32; 3]> = verts.iter().map(|v| v.normal).collect();
        let (min, max) = bounds(&positions);
        let p = push(
            bytemuck::cast_slice(&positions),
            34962,
            json!({"componentType": 5126, "count": count, "type": "VEC3", "min": min, "max": max}),
        );
        let n = push(
            bytemuck::cast_slice(&normals),
            34962,
            json!({"componentType": 5126, "count": count, "type": "VEC3"}),
        );
        let i = push(
            bytemuck::cast_slice(indices),
            34963,
            json!({"componentType": 5125, "count": indices.len(), "type": "SCALAR"}),
        );
        primitives.push((p, n, i));
    }
    let mut materials: Vec<[f32; 4]> = Vec::new();
    let mut meshes: Vec<(u32, usize)> = Vec::new();
    let mut nodes = Vec::new();
    for inst in &scene.instances {
        let color = inst.color.to_array();
        let material = materials
            .iter()
            .position(|c| *c == color)
            .unwrap_or_else(|| {
                materials.push(color);
                materials.len() - 1
            });
        let key = (inst.mesh, material);
        let mesh = meshes.iter().position(|k| *k == key).unwrap_or_else(|| {
            meshes.push(key);
            meshes.len() - 1
        });
        let matrix = glam::Mat4::from(inst.world_from_local).to_cols_array();
        nodes.push(json!({"mesh": mesh, "matrix": matrix}));
    }
    let json = json!({
        "asset": {"version": "2.0", "generator": "stereocull default_scene"},
        "scene": 0,
        "scenes": [{"nodes": (0..nodes.len()).collect::<Vec<_>>()}],
        "nodes": nodes,
        "meshes": meshes.iter().map(|&(m, mat)| {
            let (p, n, i) = primitives[m as usize];
            json!({"name": scene.meshes[m as usize].name, "primitives": [{"attributes": {"POSITION": p, "NORMAL": n}, "indices": i, "material": mat}]})
        }).collect::<Vec<_>>(),
        "materials": materials.iter().map(|c| json!({"pbrMetallicRoughness": {"baseColorFactor": c}})).collect::<Vec<_>>(),
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": views,
        "accessors": accessors,
    });
    glb(json.to_string().into_bytes(), bin)
}

fn bounds(points: &[[f32; 3]]) -> ([f32; 3], [f32; 3]) {
    let min = points.iter().fold([f32::MAX; 3], |a, p| {
        std::array::from_fn(|i| a[i].min(p[i]))
    });
    let max = points.iter().fold([f32::MIN; 3], |a, p| {
        std::array::from_fn(|i| a[i].max(p[i]))
    });
    (min, max)
}

/// The GLB container: header, JSON chunk (space-padded), BIN chunk (zero-padded).
fn glb(mut json: Vec<u8>, mut bin: Vec<u8>) -> Vec<u8> {
    json.resize(json.len().next_multiple_of(4), b' ');
    bin.resize(bin.len().next_multiple_of(4), 0);
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    for word in [
        0x4654_6c67u32,
        2,
        total as u32,
        json.len() as u32,
        0x4e4f_534a,
    ] {
        out.extend_from_slice(&word.to_le_bytes());
    }
    out.extend_from_slice(&json);
    for word in [bin.len() as u32, 0x004e_4942] {
        out.extend_from_slice(&word.to_le_bytes());
    }
    out.extend_from_slice(&bin);
    out
}
