//! Skinning, posed once per frame: glTF skins read (and malformed ones rejected by
//! name), the CPU twin against an independent evaluation of `SimpleSkin` (a file nobody
//! here wrote), every posed vertex inside its instance's culling sphere, the GPU's
//! posed vertices equal to the twin's, and one skinning pass per frame whatever the rig.

mod support;

use glam::{DAffine3, DQuat, DVec3, Quat, Vec3};
use rand::{Rng, SeedableRng};
use stereocull::renderer::{Renderer, RendererOptions};
use stereocull::scene::Scene;
use stereocull::scene_spec;
use stereocull::skin::skin_vertex;

fn simple_skin() -> Scene {
    let path = support::gltf_sample("SimpleSkin", "gltf");
    scene_spec::load(path.to_str().unwrap()).unwrap()
}

/// SimpleSkin's posed vertices in world space at `time`, evaluated here from the file
/// with the gltf crate's own reader, in f64: glTF's definition, the weighted sum of
/// each joint's world transform times its inverse bind matrix.
fn simple_skin_reference(time: f64) -> Vec<DVec3> {
    let path = support::gltf_sample("SimpleSkin", "gltf");
    let (document, buffers, _) = gltf::import(path).unwrap();
    let get = |b: gltf::Buffer| Some(&buffers[b.index()].0[..]);
    let channel = document
        .animations()
        .next()
        .unwrap()
        .channels()
        .next()
        .unwrap();
    let reader = channel.reader(get);
    let times: Vec<f64> = reader.read_inputs().unwrap().map(f64::from).collect();
    let rotations: Vec<DQuat> = match reader.read_outputs().unwrap() {
        gltf::animation::util::ReadOutputs::Rotations(r) => r
            .into_f32()
            .map(|q| Quat::from_array(q).as_dquat())
            .collect(),
        _ => unreachable!("SimpleSkin rotates its second joint"),
    };
    let t = time % times[times.len() - 1];
    let k = times
        .iter()
        .rposition(|&x| x <= t)
        .unwrap()
        .min(times.len() - 2);
    let u = (t - times[k]) / (times[k + 1] - times[k]);
    // The file's keys are unit to 4 digits (0.707): glTF rotations are unit.
    let rotation = rotations[k].slerp(rotations[k + 1], u).normalize();
    // nodes[0] (the mesh, at the origin) holds joint nodes[1] (up 1 m), which holds
    // joint nodes[2] (the animated rotation).
    let joint1 = DAffine3::from_translation(DVec3::Y);
    let joint2 = joint1 * DAffine3::from_quat(rotation);
    let skin = document.skins().next().unwrap();
    let inverse_binds: Vec<DAffine3> = (skin.reader(get).read_inverse_bind_matrices().unwrap())
        .map(|m| DAffine3::from_mat4(glam::Mat4::from_cols_array_2d(&m).as_dmat4()))
        .collect();
    let joints = [joint1 * inverse_binds[0], joint2 * inverse_binds[1]];
    let primitive = document
        .meshes()
        .next()
        .unwrap()
        .primitives()
        .next()
        .unwrap();
    let reader = primitive.reader(get);
    let positions = reader.read_positions().unwrap();
    let influences = reader.read_joints(0).unwrap().into_u16();
    let weights = reader.read_weights(0).unwrap().into_f32();
    (positions.zip(influences).zip(weights))
        .map(|((p, j), w)| {
            let p = Vec3::from(p).as_dvec3();
            (0..4)
                .map(|k| joints[j[k] as usize].transform_point3(p) * w[k] as f64)
                .sum()
        })
        .collect()
}

/// Every skinned vertex of `scene` posed by the CPU twin, in world space, per skin.
fn posed_world(scene: &Scene) -> Vec<Vec<Vec3>> {
    let skins = &scene.skins;
    (skins.skins.iter())
        .map(|s| {
            let world = scene.instances[s.instance as usize].world_from_local;
            let range = s.vertices.start as usize..s.vertices.end as usize;
            (skins.vertices[range].iter())
                .map(|v| {
                    world.transform_point3(Vec3::from(skin_vertex(v, &skins.joint_matrices).0))
                })
                .collect()
        })
        .collect()
}

#[test]
fn simple_skin_is_read_with_its_joints_weights_and_bind_matrices() {
    let scene = simple_skin();
    assert_eq!(scene.skins.skins.len(), 1);
    let skin = &scene.skins.skins[0];
    assert_eq!(skin.joints.len(), 2);
    assert_eq!(skin.vertices, 0..10);
    let mesh = scene.instances[skin.instance as usize].mesh;
    let base = scene.meshes[mesh as usize].base_vertex as u32;
    let targets: Vec<u32> = scene.skins.vertices.iter().map(|v| v.destination).collect();
    assert_eq!(targets, (base..base + 10).collect::<Vec<_>>());
    assert_eq!(
        skin.inverse_binds[1].translation,
        glam::Vec3A::new(-0.5, -1.0, 0.0)
    );
    for v in &scene.skins.vertices {
        assert!((v.weights.iter().sum::<f32>() - 1.0).abs() < 1e-6);
    }
    // The top vertices move with joint 1 (the second) alone, so its sphere holds them.
    assert!(skin.joint_bounds.iter().all(|b| b.w >= 0.0));
}

/// At random times the twin's posed vertices, placed by the instance's transform, are
/// where glTF's definition puts them, and inside the instance's culling sphere.
#[test]
fn simple_skin_poses_where_gltf_defines_and_inside_its_sphere() {
    let mut scene = simple_skin();
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(5);
    let mut moved = 0.0f64;
    for _ in 0..20 {
        let time: f32 = rng.random_range(0.0..11.0);
        scene.pose(time);
        let got = &posed_world(&scene)[0];
        let want = simple_skin_reference(time as f64);
        for (g, w) in got.iter().zip(&want) {
            assert!(
                (g.as_dvec3() - *w).length() < 1e-5,
                "t = {time}: {g} against {w}"
            );
        }
        moved = moved.max((want[9] - simple_skin_reference(0.0)[9]).length());
        let instance = &scene.instances[scene.skins.skins[0].instance as usize];
        let sphere = scene.world_sphere(instance);
        for p in got {
            assert!(
                p.distance(sphere.truncate()) <= sphere.w,
                "t = {time}: {p} outside {sphere}"
            );
        }
    }
    assert!(moved > 0.5, "the joint moves the top vertices ({moved} m)");
}

/// The skinned instance's culling sphere follows the pose: with the skeleton's root
/// joint carried 100 m away, every posed vertex lies there, outside the rest pose's
/// sphere and inside the instance's.
#[test]
fn the_culling_sphere_is_the_posed_one_not_the_rest_one() {
    let mut scene = simple_skin();
    scene.pose(1.2);
    let rest = scene.world_sphere(&scene.instances[0]);
    let root = scene.skins.skins[0].joints[0] as usize;
    scene.posing.nodes[root].rest.translation += Vec3::new(100.0, 0.0, 0.0);
    scene.pose(1.2);
    let sphere = scene.world_sphere(&scene.instances[0]);
    for p in &posed_world(&scene)[0] {
        assert!(p.distance(rest.truncate()) > rest.w, "{p} moved away");
        assert!(
            p.distance(sphere.truncate()) <= sphere.w,
            "{p} outside {sphere}"
        );
    }
}

/// The GPU's posed vertices, read back after a frame, equal the CPU twin's: positions
/// and normals within a few ulps of their magnitudes (the pass and the twin do the same
/// operations in the same order, but a GPU may fuse a multiply and an add), tangents
/// within a byte's rounding. One skinning pass runs per frame on every preset.
#[test]
fn the_gpu_skins_what_the_cpu_twin_skins_once_per_frame() {
    let gpu = support::gpu();
    for preset in ["hmd", "cave", "hmd-peripheral"] {
        let mut scene = simple_skin();
        scene.pose(1.7);
        let rig = support::sized(preset, 32, 32);
        let options = RendererOptions::default();
        let mut renderer = Renderer::new(&gpu.device, &scene, &rig, options).unwrap();
        let targets = renderer.create_targets(&gpu.device);
        renderer
            .submit_frame(&gpu.device, &gpu.queue, &rig, 1.7, &targets)
            .unwrap();
        let skins = renderer
            .passes()
            .iter()
            .filter(|p| p.name == "skin")
            .count();
        assert_eq!(skins, 1, "{preset}: one skinning pass per frame");
        assert_eq!(renderer.skinned_vertices(), 10);
        let drawn = renderer
            .diagnostics(&gpu.device, &gpu.queue)
            .vertices()
            .unwrap();
        for v in &scene.skins.vertices {
            let (position, normal, tangent) = skin_vertex(v, &scene.skins.joint_matrices);
            let gpu_v = drawn[v.destination as usize];
            for (g, c) in gpu_v
                .position
                .iter()
                .zip(position)
                .chain(gpu_v.normal.iter().zip(normal))
            {
                assert!(
                    (g - c).abs() <= 1e-6 * (1.0 + c.abs()),
                    "{preset}: {g} against {c}"
                );
            }
            for (g, c) in gpu_v.tangent.iter().zip(tangent) {
                assert!(g.abs_diff(c) <= 1, "{preset}: tangent {g} against {c}");
            }
        }
    }
}

/// Drawn: SimpleSkin bent (1.2 s: its upper joint turned 90 degrees) differs from its
/// rest pose, but its base row, whose vertices the lower joint alone holds, does not
/// move: the bent strip still ends on the same image row, unchanged there.
#[test]
fn the_image_changes_where_the_joint_moves() {
    let gpu = support::gpu();
    let mut rig = support::sized("hmd", 64, 64);
    rig.viewer.position = [0.0, 1.0, 3.0];
    let draw = |time: f32| {
        let mut scene = simple_skin();
        scene.pose(time);
        let options = RendererOptions {
            shadows: false,
            ..support::frustum_only()
        };
        support::render(&gpu, &scene, &rig, options)
            .unwrap()
            .remove(0)
    };
    let (rest, bent) = (draw(0.0), draw(1.2));
    let background = *rest.get_pixel(0, 0);
    let base = (rest.enumerate_pixels())
        .filter(|(_, _, p)| **p != background)
        .map(|(_, y, _)| y)
        .max()
        .expect("the strip is drawn");
    let changed: Vec<u32> = (rest.enumerate_pixels().zip(bent.pixels()))
        .filter(|((_, _, a), b)| a != b)
        .map(|((_, y, _), _)| y)
        .collect();
    assert!(
        changed.len() > 50,
        "the bend shows ({} pixels)",
        changed.len()
    );
    assert!(
        changed.iter().all(|&y| y < base),
        "the base row {base} stays put"
    );
    let bent_base = (bent.enumerate_pixels())
        .filter(|(_, _, p)| **p != background)
        .map(|(_, y, _)| y)
        .max();
    assert_eq!(
        bent_base,
        Some(base),
        "the bent strip stands on the same row"
    );
}

/// A skin whose file is wrong is an error naming what is wrong.
#[test]
fn malformed_skins_are_errors_naming_the_part() {
    let path = support::gltf_sample("SimpleSkin", "gltf");
    let original: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    let import = |json: &serde_json::Value| {
        let bytes = json.to_string();
        let err = stereocull::gltf_import::import_bytes(
            bytes.as_bytes(),
            None,
            std::path::Path::new("skin.gltf"),
        );
        err.err().map(|e| e.to_string()).unwrap_or_default()
    };
    let mut one_joint = original.clone();
    one_joint["skins"][0]["joints"] = serde_json::json!([1]);
    let err = import(&one_joint);
    assert!(
        err.contains("JOINTS_0: joint 1 is past skins[0]'s 1 joints"),
        "{err}"
    );
    let mut few_binds = original.clone();
    few_binds["accessors"][4]["count"] = serde_json::json!(1);
    let err = import(&few_binds);
    assert!(
        err.contains("skins[0].inverseBindMatrices: 1 matrices for 2 joints"),
        "{err}"
    );
    let mut nan_weight = original.clone();
    let uri = nan_weight["buffers"][1]["uri"].as_str().unwrap().to_owned();
    let (head, data) = uri.split_once(',').unwrap();
    use base64::Engine;
    let mut bytes = base64::engine::general_purpose::STANDARD
        .decode(data)
        .unwrap();
    bytes[160..164].copy_from_slice(&f32::NAN.to_le_bytes());
    let data = base64::engine::general_purpose::STANDARD.encode(bytes);
    nan_weight["buffers"][1]["uri"] = format!("{head},{data}").into();
    let err = import(&nan_weight);
    assert!(
        err.contains("WEIGHTS_0: vertex 0 has weights [NaN"),
        "{err}"
    );
}

/// The crowd: every posed vertex of random figures at random times lies inside its
/// instance's culling sphere (fails if the bounds ignore the pose: the swinging limbs
/// leave the rest pose's sphere), the figures walk out of phase, and the GPU poses
/// what the twin poses.
#[test]
fn crowd_figures_stay_inside_their_spheres_at_any_time() {
    let mut scene = scene_spec::load("crowd:40:3").unwrap();
    assert_eq!(scene.skins.skins.len(), 40);
    assert!(scene.skins.skins[0].joints.len() >= 10, "tens of joints");
    let rest: Vec<_> = (scene.instances.iter())
        .map(|i| scene.world_sphere(i))
        .collect();
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(8);
    let mut left_rest = 0;
    for _ in 0..12 {
        scene.pose(rng.random_range(0.0..30.0));
        for (s, posed) in scene.skins.skins.iter().zip(posed_world(&scene)) {
            let instance = &scene.instances[s.instance as usize];
            let sphere = scene.world_sphere(instance);
            for p in &posed {
                assert!(
                    p.distance(sphere.truncate()) <= sphere.w,
                    "{p} outside {sphere}"
                );
            }
            let was = rest[s.instance as usize];
            left_rest += usize::from(posed.iter().any(|p| p.distance(was.truncate()) > was.w));
        }
    }
    assert!(left_rest > 0, "limbs swing out of the rest sphere");
    // Out of phase: two figures' knees do not bend alike.
    let knees: Vec<f32> = (scene.skins.joint_matrices.chunks(stereocull::crowd::JOINTS))
        .map(|m| m[12][1][2])
        .collect();
    assert!(knees.windows(2).any(|w| (w[0] - w[1]).abs() > 1e-3));
}

/// Every stereo mode draws the crowd posed alike, with tests/images.rs's tolerances for
/// still scenes: the classic modes draw each eye into its own viewport, where a vertex
/// can round a hair from the double-wide remap (2 levels, 0.05 % of the pixels beyond:
/// seen here, 3 pixels one level off), and lavapipe's multiview clips triangles that
/// cross the near plane a pixel differently (2 levels, 0.3 %).
#[test]
fn every_stereo_mode_draws_the_same_posed_crowd() {
    use stereocull::renderer::StereoMode;
    let gpu = support::gpu();
    let mut scene = scene_spec::load("crowd:60:5").unwrap();
    scene.pose(0.7);
    let mut rig = support::sized("hmd", 96, 80);
    rig.viewer.position = [0.0, 1.6, 0.0];
    let draw = |mode: StereoMode| {
        let options = RendererOptions {
            mode,
            cull: support::cull_for(mode),
            ..support::frustum_only()
        };
        support::render(&gpu, &scene, &rig, options)
            .unwrap()
            .remove(0)
    };
    let reference = draw(StereoMode::Instanced);
    let background = *reference.get_pixel(0, 0);
    assert!(
        reference.pixels().filter(|p| **p != background).count() > 300,
        "figures drawn"
    );
    for mode in StereoMode::ALL {
        let tolerance = match mode {
            StereoMode::Multiview => support::Tolerance {
                levels: 2,
                share: 0.003,
            },
            _ => support::Tolerance {
                levels: 2,
                share: 0.0005,
            },
        };
        support::assert_images_match(
            &format!("crowd-{}", mode.name()),
            &draw(mode),
            &reference,
            tolerance,
        );
    }
}

/// An engine that animates itself hands one figure's joint transforms to the live
/// scene: that figure's joint matrices and transform become what posing at the same
/// time gives, the others stay, only its joints (and its move) go up at the sync, and
/// the GPU skins it with them.
#[test]
fn engine_supplied_joints_pose_one_figure_sparsely() {
    use stereocull::live::LiveScene;
    let gpu = support::gpu();
    let scene = scene_spec::load("crowd:6:2").unwrap();
    let rig = support::sized("hmd", 32, 32);
    let options = RendererOptions::default();
    let mut renderer = Renderer::new(&gpu.device, &scene, &rig, options).unwrap();
    let targets = renderer.create_targets(&gpu.device);
    let mut live = LiveScene::new(scene.clone());
    let skin = scene.skins.skins[2].clone();
    let worlds = scene.posing.node_worlds(0.8);
    let joint_worlds: Vec<_> = skin.joints.iter().map(|&j| worlds[j as usize]).collect();
    let handle = live.handles()[skin.instance as usize];
    live.set_joints(handle, &joint_worlds).unwrap();
    let synced = renderer.sync(&gpu.device, &gpu.queue, &mut live).unwrap();

    let mut posed = scene.clone();
    posed.pose(0.8);
    let (start, end) = (
        skin.joint_base as usize,
        skin.joint_base as usize + skin.joints.len(),
    );
    let matrices = &live.scene().skins.joint_matrices;
    assert_eq!(matrices[start..end], posed.skins.joint_matrices[start..end]);
    assert_eq!(
        matrices[..start],
        scene.skins.joint_matrices[..start],
        "the others stay"
    );
    let instance = skin.instance as usize;
    assert_eq!(live.scene().instances[instance], posed.instances[instance]);
    let joint_bytes = (skin.joints.len() * 48) as u64;
    assert_eq!(synced.moved, 1);
    assert!(synced.bytes_uploaded >= joint_bytes && synced.bytes_uploaded < 2 * joint_bytes);

    renderer
        .submit_frame(&gpu.device, &gpu.queue, &rig, 0.0, &targets)
        .unwrap();
    let drawn = renderer
        .diagnostics(&gpu.device, &gpu.queue)
        .vertices()
        .unwrap();
    let range = skin.vertices.start as usize..skin.vertices.end as usize;
    for v in &live.scene().skins.vertices[range] {
        let (position, _, _) = skin_vertex(v, matrices);
        let gpu_position = drawn[v.destination as usize].position;
        for (g, c) in gpu_position.iter().zip(position) {
            assert!((g - c).abs() <= 1e-6 * (1.0 + c.abs()), "{g} against {c}");
        }
    }
    let err = live
        .set_joints(handle, &joint_worlds[..3])
        .unwrap_err()
        .to_string();
    assert!(err.contains("3 joint transforms for a skin of 17"), "{err}");
}

/// Culling a moving body: a live crowd posed frame after frame (the skinned figures'
/// transforms and spheres going up as edits), the GPU cull's buffers equal the CPU
/// reference cull of the same posed scene byte for byte, on `hmd` and `cave`.
#[test]
fn gpu_and_cpu_culls_agree_on_a_walking_crowd() {
    use stereocull::live::LiveScene;
    let gpu = support::gpu();
    let scene = scene_spec::load("crowd:300:9").unwrap();
    for preset in ["hmd", "cave"] {
        let rig = support::sized(preset, 32, 32);
        let options = support::frustum_only();
        let mut renderer = Renderer::new(&gpu.device, &scene, &rig, options).unwrap();
        let targets = renderer.create_targets(&gpu.device);
        let mut live = LiveScene::new(scene.clone());
        for frame in 0..4 {
            let time = frame as f32 * 0.37;
            live.pose(time).unwrap();
            renderer.sync(&gpu.device, &gpu.queue, &mut live).unwrap();
            renderer
                .submit_frame(&gpu.device, &gpu.queue, &rig, time, &targets)
                .unwrap();
            let gpu_culls = support::read_culls(&gpu, &renderer, &rig);
            let cpu_culls = support::reference_culls(live.scene(), &rig);
            assert_eq!(gpu_culls, cpu_culls, "{preset}, frame {frame}");
            assert!(
                gpu_culls.iter().any(|c| !c.visible.is_empty()),
                "{preset}: figures seen"
            );
        }
    }
}
