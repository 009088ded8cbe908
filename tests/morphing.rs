//! Morph targets: a test file with two targets (positions, normals, tangents) on two
//! nodes, their weights animated linearly and by cubic splines, and SimpleSkin (written
//! by nobody here) given a target of its own. The GPU's morphed vertices equal the CPU
//! twin's, once per frame, skinned ones after the morph; every sampled pose stays inside
//! its culling sphere.

mod support;

use base64::Engine;
use glam::{Vec3, Vec4};
use serde_json::json;
use stereocull::morph::{MorphVertex, Morphs, morph_vertex};
use stereocull::renderer::{Renderer, RendererOptions};
use stereocull::scene::Scene;
use stereocull::scene_spec;
use stereocull::skin::skin_vertex;
use support::morph::SIDE;

/// SimpleSkin with one target on its mesh (each vertex pushed out along x by its
/// height), its weight animated from 0 to 1 over the skin's own 5.5 s.
fn morphed_skin() -> Scene {
    let path = support::gltf_sample("SimpleSkin", "gltf");
    let mut json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let heights: Vec<f32> = vec![0.0, 0.0, 0.5, 0.5, 1.0, 1.0, 1.5, 1.5, 2.0, 2.0];
    let offsets: Vec<[f32; 3]> = heights.iter().map(|h| [0.25 * h, 0.0, 0.0]).collect();
    let keys = [0.0f32, 5.5, 0.0, 1.0];
    let bytes: Vec<u8> = [
        bytemuck::cast_slice::<_, u8>(&offsets),
        bytemuck::cast_slice(&keys),
    ]
    .concat();
    let uri = format!(
        "data:application/gltf-buffer;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&bytes)
    );
    let buffer = json["buffers"].as_array().unwrap().len();
    json["buffers"]
        .as_array_mut()
        .unwrap()
        .push(json!({"uri": uri, "byteLength": bytes.len()}));
    let view = json["bufferViews"].as_array().unwrap().len();
    json["bufferViews"]
        .as_array_mut()
        .unwrap()
        .push(json!({"buffer": buffer, "byteLength": bytes.len()}));
    let accessor = json["accessors"].as_array().unwrap().len();
    json["accessors"].as_array_mut().unwrap().extend([
        json!({"bufferView": view, "componentType": 5126, "count": 10, "type": "VEC3"}),
        json!({"bufferView": view, "byteOffset": 120, "componentType": 5126, "count": 2, "type": "SCALAR", "min": [0], "max": [5.5]}),
        json!({"bufferView": view, "byteOffset": 128, "componentType": 5126, "count": 2, "type": "SCALAR"}),
    ]);
    json["meshes"][0]["primitives"][0]["targets"] = json!([{"POSITION": accessor}]);
    json["meshes"][0]["weights"] = json!([0.0]);
    let animation = &mut json["animations"][0];
    let sampler = animation["samplers"].as_array().unwrap().len();
    animation["samplers"]
        .as_array_mut()
        .unwrap()
        .push(json!({"input": accessor + 1, "output": accessor + 2, "interpolation": "LINEAR"}));
    animation["channels"]
        .as_array_mut()
        .unwrap()
        .push(json!({"sampler": sampler, "target": {"node": 0, "path": "weights"}}));
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("morphed-skin.gltf");
    std::fs::write(&out, json.to_string()).unwrap();
    scene_spec::load(out.to_str().unwrap()).unwrap()
}

/// What the morph writes for `v` at the scene's current weights.
fn morphed(morphs: &Morphs, v: &MorphVertex) -> ([f32; 3], [f32; 3], [i8; 4]) {
    morph_vertex(v, &morphs.deltas, &morphs.weights)
}

fn assert_close(g: [f32; 3], c: [f32; 3], what: &str) {
    for (g, c) in g.iter().zip(c) {
        assert!(
            (g - c).abs() <= 1e-6 * (1.0 + c.abs()),
            "{what}: {g} against {c}"
        );
    }
}

#[test]
fn the_file_reads_two_targets_their_defaults_and_both_animations() {
    let mut scene = support::morph::morph_scene();
    let morphs = &scene.morphs;
    assert_eq!(morphs.morphs.len(), 2, "one morph per node");
    assert_eq!(morphs.vertices.len(), 2 * SIDE * SIDE);
    assert_eq!(morphs.deltas.len(), 2 * 2 * SIDE * SIDE);
    assert_eq!(morphs.morphs[0].defaults, [0.25, 0.0], "the mesh's weights");
    assert_eq!(morphs.morphs[1].defaults, [0.5, 0.25], "the node's own");
    assert_ne!(
        scene.instances[0].mesh, scene.instances[1].mesh,
        "a mesh per node"
    );
    // Linear: halfway between keys 1 (1, 0.5) and 2 (0.2, 1).
    scene.pose(1.5);
    assert_eq!(&scene.morphs.weights[..2], &[0.6, 0.75]);
    // The cubic spline at its start is its first key's value.
    scene.pose(0.0);
    assert_eq!(&scene.morphs.weights[2..], &[0.0, 0.0]);
    scene.pose(0.75);
    assert!(
        scene.morphs.weights[2] > 0.5,
        "the out-tangent pushes the weight up early"
    );
}

/// The GPU's morphed vertices, read back after a frame, equal the CPU twin's at that
/// frame's time: positions and normals within a few ulps of their magnitudes (the same
/// operations in the same order, but a GPU may fuse a multiply and an add), tangents
/// within a byte's rounding. One morph pass runs per frame, whatever the displays.
#[test]
fn the_gpu_morphs_what_the_cpu_twin_morphs_once_per_frame() {
    let gpu = support::gpu();
    let scene = support::morph::morph_scene();
    for (preset, time) in [("hmd", 0.4), ("cave", 0.7), ("hmd-peripheral", 1.9)] {
        let rig = support::sized(preset, 32, 32);
        let mut renderer =
            Renderer::new(&gpu.device, &scene, &rig, RendererOptions::default()).unwrap();
        let targets = renderer.create_targets(&gpu.device);
        renderer
            .submit_frame(&gpu.device, &gpu.queue, &rig, time, &targets)
            .unwrap();
        let morphs = (renderer.passes().iter())
            .filter(|p| p.name == "morph")
            .count();
        assert_eq!(morphs, 1, "{preset}: one morph pass per frame");
        assert_eq!(renderer.morphed_vertices(), 2 * (SIDE * SIDE) as u32);
        let drawn = renderer
            .diagnostics(&gpu.device, &gpu.queue)
            .vertices()
            .unwrap();
        let mut cpu = scene.morphs.clone();
        cpu.set_time(time);
        let mut moved = 0.0f32;
        for v in &cpu.vertices {
            let (position, normal, tangent) = morphed(&cpu, v);
            let g = drawn[v.destination as usize];
            assert_close(g.position, position, preset);
            assert_close(g.normal, normal, preset);
            for (g, c) in g.tangent.iter().zip(tangent) {
                assert!(g.abs_diff(c) <= 1, "{preset}: tangent {g} against {c}");
            }
            moved = moved.max(Vec3::from(position).distance(Vec3::from(v.position)));
        }
        assert!(
            moved > 0.05,
            "{preset}: the targets move the grid ({moved} m)"
        );
    }
}

/// Every pose the weights reach over both animations (sampled every 10 ms) stays inside
/// its mesh's culling sphere, which is larger than the rest pose's. Without the growth
/// the bulge leaves it (checked: the grid's rest sphere is flat).
#[test]
fn every_sampled_pose_stays_in_the_culling_sphere() {
    let mut scene = support::morph::morph_scene();
    // The flat grid's sphere: its half diagonal.
    let flat = std::f32::consts::FRAC_1_SQRT_2;
    for i in 0..=200 {
        scene.pose(i as f32 * 0.01);
        for v in &scene.morphs.vertices {
            let (p, _, _) = morphed(&scene.morphs, v);
            let mesh = (scene.meshes.iter())
                .find(|m| {
                    let at = v.destination as i32 - m.base_vertex;
                    at >= 0 && (at as usize) < SIDE * SIDE
                })
                .unwrap();
            let b: Vec4 = mesh.bounds;
            let d = Vec3::from(p).distance(b.truncate());
            assert!(d <= b.w, "t {}: {d} outside {}", i as f32 * 0.01, b.w);
            assert!(b.w > flat * 1.01, "the sphere grew");
        }
    }
}

/// SimpleSkin morphed, then skinned: the GPU writes the morphed rest into the skin's
/// rest vertices and the skinning pass moves it, equal to the CPU twins run in that
/// order; every posed, morphed vertex stays in the instance's culling sphere.
#[test]
fn a_morphed_skin_is_morphed_before_it_is_skinned() {
    let gpu = support::gpu();
    let mut scene = morphed_skin();
    assert_eq!(scene.morphs.vertices.len(), 10);
    assert!(scene.morphs.vertices.iter().all(|v| v.skinned == 1));
    for time in [0.0, 2.0, 4.5] {
        scene.pose(time);
        let rig = support::sized("hmd", 32, 32);
        let mut renderer =
            Renderer::new(&gpu.device, &scene, &rig, RendererOptions::default()).unwrap();
        let targets = renderer.create_targets(&gpu.device);
        renderer
            .submit_frame(&gpu.device, &gpu.queue, &rig, time, &targets)
            .unwrap();
        let names: Vec<&str> = renderer.passes().iter().map(|p| p.name).collect();
        let (morph, skin) = (
            names.iter().position(|n| *n == "morph"),
            names.iter().position(|n| *n == "skin"),
        );
        assert!(morph.unwrap() < skin.unwrap(), "{names:?}");
        let drawn = renderer
            .diagnostics(&gpu.device, &gpu.queue)
            .vertices()
            .unwrap();
        let world = scene.world_sphere(&scene.instances[0]);
        let placed = scene.instances[0].world_from_local;
        for (m, rest) in scene.morphs.vertices.iter().zip(&scene.skins.vertices) {
            let (position, normal, tangent) = morphed(&scene.morphs, m);
            let morphed_rest = stereocull::skin::SkinVertex {
                position,
                normal,
                tangent,
                ..*rest
            };
            let (p, n, _) = skin_vertex(&morphed_rest, &scene.skins.joint_matrices);
            let g = drawn[rest.destination as usize];
            assert_close(g.position, p, "skinned position");
            assert_close(g.normal, n, "skinned normal");
            let at = placed.transform_point3(Vec3::from(p));
            assert!(
                at.distance(world.truncate()) <= world.w,
                "t {time}: {at} outside {world}"
            );
        }
        let top = Vec3::from(drawn[scene.skins.vertices[8].destination as usize].position);
        let plain = skin_vertex(&scene.skins.vertices[8], &scene.skins.joint_matrices).0;
        if time > 0.0 {
            let moved = top.distance(Vec3::from(plain));
            assert!(
                moved > 0.05,
                "t {time}: the target moves the top row {moved} m"
            );
        }
    }
}

/// An engine's own weights replace a morph's animation from the next frame, the GPU
/// equal to the CPU twin with them; weights past what the culling sphere holds (the
/// file's largest, or 1) and the wrong count are errors naming the bound.
#[test]
fn an_engine_sets_its_own_weights_within_the_bound() {
    let gpu = support::gpu();
    let scene = support::morph::morph_scene();
    let rig = support::sized("hmd", 32, 32);
    let options = RendererOptions::default();
    let mut renderer = Renderer::new(&gpu.device, &scene, &rig, options).unwrap();
    let targets = renderer.create_targets(&gpu.device);
    let e = renderer
        .set_morph_weights(0, &[5.0, 0.0])
        .unwrap_err()
        .to_string();
    assert!(e.contains("past"), "{e}");
    assert!(renderer.set_morph_weights(0, &[0.5]).is_err());
    renderer.set_morph_weights(0, &[-0.5, 0.75]).unwrap();
    renderer
        .submit_frame(&gpu.device, &gpu.queue, &rig, 1.3, &targets)
        .unwrap();
    let drawn = renderer
        .diagnostics(&gpu.device, &gpu.queue)
        .vertices()
        .unwrap();
    let mut cpu = scene.morphs.clone();
    cpu.set_time(1.3);
    cpu.set_weights(0, &[-0.5, 0.75]).unwrap();
    for v in &cpu.vertices {
        let (position, normal, _) = morphed(&cpu, v);
        let g = drawn[v.destination as usize];
        assert_close(g.position, position, "set weights");
        assert_close(g.normal, normal, "set weights");
    }
    assert_eq!(&cpu.weights[..2], &[-0.5, 0.75]);
}
