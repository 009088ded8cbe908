//! Posing on the GPU (`RendererOptions::posing = PosingMode::Gpu`, `wgsl/pose.wgsl`):
//! the pose pass against its CPU twin (the CPU posing) on random animated trees and on
//! the crowd, the culls it feeds against the CPU reference, live edits (removes,
//! inserts, engine-supplied joints), and what crosses the bus.

mod support;

use glam::{Affine3A, Quat, Vec3, Vec4};
use rand::{Rng, SeedableRng};
use stereocull::live::LiveScene;
use stereocull::pose::{Channel, Clip, Interpolation, NodeInstance, PoseNode, Property, Trs};
use stereocull::records::InstanceRecord;
use stereocull::renderer::{CullMode, PosingMode, Renderer, RendererOptions};
use stereocull::scene::Scene;
use stereocull::scene_spec;

fn gpu_posing() -> RendererOptions {
    RendererOptions {
        posing: PosingMode::Gpu,
        ..support::frustum_only()
    }
}

/// A random quaternion of unit length.
fn unit_quat(rng: &mut impl Rng) -> Quat {
    let axis = Vec3::new(rng.random(), rng.random(), rng.random()) - 0.5;
    Quat::from_axis_angle(axis.normalize_or(Vec3::Y), rng.random_range(-3.0..3.0))
}

/// A random channel of `property` on `node`: 1 to 6 keys at random gaps, each
/// interpolation, values of the property's kind (cubic splines with random tangents).
fn random_channel(rng: &mut rand_pcg::Pcg64Mcg, node: u32, property: Property) -> Channel {
    let interpolation = [
        Interpolation::Step,
        Interpolation::Linear,
        Interpolation::CubicSpline,
    ][rng.random_range(0..3)];
    let keys = rng.random_range(1..7);
    let mut t = rng.random_range(-0.5..0.5);
    let times: Vec<f32> = (0..keys)
        .map(|_| {
            t += rng.random_range(0.1..1.0);
            t
        })
        .collect();
    let value = |rng: &mut rand_pcg::Pcg64Mcg| match property {
        Property::Translation => Vec3::new(rng.random(), rng.random(), rng.random())
            .map(|c| 4.0 * c - 2.0)
            .extend(0.0),
        Property::Rotation => Vec4::from(unit_quat(rng)),
        Property::Scale => Vec3::new(rng.random(), rng.random(), rng.random())
            .map(|c| 0.5 + c)
            .extend(0.0),
    };
    let per_key = if interpolation == Interpolation::CubicSpline {
        3
    } else {
        1
    };
    let values = (0..keys * per_key)
        .map(|k| match (per_key, k % 3) {
            (3, 0 | 2) => value(rng) * 0.3,
            _ => value(rng),
        })
        .collect();
    Channel {
        node,
        property,
        interpolation,
        times,
        values,
    }
}

/// Random trees of posed nodes (parents first, roots placed in front of the viewer),
/// three clips of random channels at their own offsets and speeds, and cubes hanging
/// on random nodes.
fn random_animated_scene(seed: u64) -> Scene {
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(seed);
    let mut scene = support::cubes(&[], 2);
    let nodes = 24;
    for n in 0..nodes {
        let parent = (n > 0 && rng.random_bool(0.75)).then(|| rng.random_range(0..n));
        let root_from = match parent {
            Some(_) => Affine3A::IDENTITY,
            None => Affine3A::from_rotation_translation(
                unit_quat(&mut rng),
                Vec3::new(
                    rng.random_range(-3.0..3.0),
                    1.5,
                    rng.random_range(-9.0..-3.0),
                ),
            ),
        };
        let rest = Trs {
            translation: Vec3::new(rng.random(), rng.random(), rng.random()) - 0.5,
            rotation: unit_quat(&mut rng),
            scale: Vec3::splat(rng.random_range(0.7..1.3)),
        };
        scene.posing.nodes.push(PoseNode {
            parent,
            root_from,
            rest,
        });
    }
    for c in 0..3 {
        let properties = [Property::Translation, Property::Rotation, Property::Scale];
        let channels = (0..6)
            .map(|_| {
                let property = properties[rng.random_range(0..3)];
                let node = rng.random_range(0..nodes);
                random_channel(&mut rng, node, property)
            })
            .collect();
        scene.posing.clips.push(Clip {
            name: format!("clip {c}"),
            channels,
            offset: rng.random_range(0.0..2.0),
            speed: rng.random_range(0.5..1.5),
        });
    }
    for i in 0..30 {
        let node_from_local = Affine3A::from_scale_rotation_translation(
            Vec3::splat(rng.random_range(0.2..0.6)),
            unit_quat(&mut rng),
            Vec3::new(rng.random(), rng.random(), rng.random()) - 0.5,
        );
        scene.posing.instances.push(NodeInstance {
            instance: i,
            node: rng.random_range(0..nodes),
            node_from_local,
        });
        let mut instance = support::cubes(&[(Vec3::ZERO, 0)], 1).instances[0];
        instance.mesh = rng.random_range(0..2);
        scene.instances.push(instance);
    }
    scene.pose(0.0);
    scene
}

/// The rows of `m` as an instance record holds them.
fn rows(m: &Affine3A) -> [[f32; 4]; 3] {
    stereocull::scene::affine_rows(m)
}

/// Whether two transforms' rows agree within `tolerance` of the larger entry of the
/// reference row (at least 1: translations in meters).
fn close(gpu: &[[f32; 4]; 3], cpu: &[[f32; 4]; 3], tolerance: f32) -> bool {
    gpu.iter().zip(cpu).all(|(g, c)| {
        let scale = c.iter().fold(1.0f32, |m, x| m.max(x.abs()));
        g.iter()
            .zip(c)
            .all(|(a, b)| (a - b).abs() <= tolerance * scale)
    })
}

/// One GPU-posed frame of `scene` at `time`: the renderer, and its instance records
/// read back.
fn gpu_posed(
    gpu: &stereocull::device::Gpu,
    scene: &Scene,
    rig: &stereocull::rig::Rig,
    time: f32,
) -> (Renderer, Vec<InstanceRecord>) {
    let mut renderer = Renderer::new(&gpu.device, scene, rig, gpu_posing()).unwrap();
    let targets = renderer.create_targets(&gpu.device);
    renderer
        .submit_frame(&gpu.device, &gpu.queue, rig, time, &targets)
        .unwrap();
    let records = renderer
        .diagnostics(&gpu.device, &gpu.queue)
        .instance_records()
        .unwrap();
    (renderer, records)
}

/// `scene` with its instances at the transforms of `records`.
fn at_transforms(scene: &Scene, records: &[InstanceRecord]) -> Scene {
    let mut at = scene.clone();
    for (instance, record) in at.instances.iter_mut().zip(records) {
        let [x, y, z] = record.world_from_local;
        let m = glam::Mat4::from_cols_array_2d(&[x, y, z, [0.0, 0.0, 0.0, 1.0]]).transpose();
        instance.world_from_local = Affine3A::from_mat4(m);
    }
    at
}

/// The spheres the pose pass wrote are the CPU's (`Scene::world_sphere`) of the
/// transforms it wrote, within two ulps: a GPU may fuse the squared lengths' multiplies
/// and adds (lavapipe matches exactly).
fn assert_spheres_are_the_cpus_of(
    renderer: &Renderer,
    gpu: &stereocull::device::Gpu,
    records: &[InstanceRecord],
    scene: &Scene,
) {
    let at = at_transforms(scene, records);
    let spheres = (renderer.diagnostics(&gpu.device, &gpu.queue).spheres())
        .unwrap()
        .unwrap();
    for (k, (g, instance)) in spheres.iter().zip(&at.instances).enumerate() {
        let c = at.world_sphere(instance).to_array();
        assert!(
            g.iter()
                .zip(c)
                .all(|(a, b)| (a - b).abs() <= 2.0 * f32::EPSILON * b.abs()),
            "instance {k}'s sphere {g:?}, the CPU's of its transform {c:?}"
        );
    }
}

/// The tolerance of GPU posing against the CPU's, per entry and relative to the row's
/// magnitude: the pass does the CPU's steps in its order, but WGSL's `sin` and `acos`
/// (slerp) promise only about 2^-11 absolute, and a GPU may fuse multiplies and adds
/// down a chain of a few transforms. Wrong posing (another time, order or key) is off
/// by tenths.
const POSE_TOLERANCE: f32 = 4e-3;

/// Random trees, clips of every interpolation on every property, random times: every
/// instance (each hangs on a node) stands where the CPU posing puts it, with the
/// CPU's sphere of where it stands.
#[test]
fn the_pose_pass_matches_the_cpu_posing_on_random_trees() {
    let gpu = support::gpu();
    let rig = support::sized("hmd", 32, 32);
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(77);
    for seed in 0..4 {
        let scene = random_animated_scene(seed);
        let time = rng.random_range(-1.0..6.0);
        let (renderer, records) = gpu_posed(&gpu, &scene, &rig, time);
        let mut cpu = scene.clone();
        cpu.pose(time);
        let mut moved = 0;
        for (k, (record, instance)) in records.iter().zip(&cpu.instances).enumerate() {
            let want = rows(&instance.world_from_local);
            assert!(
                close(&record.world_from_local, &want, POSE_TOLERANCE),
                "seed {seed}, t {time}: instance {k}: GPU {:?}, CPU {want:?}",
                record.world_from_local
            );
            moved += usize::from(instance.world_from_local != scene.instances[k].world_from_local);
        }
        assert!(
            moved > 10,
            "seed {seed}: the clips move most instances ({moved})"
        );
        assert_spheres_are_the_cpus_of(&renderer, &gpu, &records, &scene);
    }
}

/// The crowd, GPU-posed at random times: the figures' transforms and joint matrices
/// match the CPU posing; every skinned vertex (as the GPU skinned it, placed by the
/// GPU's transform) lies inside the culling sphere of that transform; the spheres the
/// pass wrote are the CPU's of its transforms; and the GPU cull equals the CPU reference cull of the scene at the GPU's transforms
/// byte for byte.
#[test]
fn the_pose_pass_poses_the_crowd_as_the_cpu_does() {
    let gpu = support::gpu();
    let scene = scene_spec::load("crowd:120:6").unwrap();
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(5);
    for preset in ["hmd", "cave"] {
        let rig = support::sized(preset, 32, 32);
        let time = rng.random_range(0.0..20.0);
        let (renderer, records) = gpu_posed(&gpu, &scene, &rig, time);
        let mut cpu = scene.clone();
        cpu.pose(time);
        let diagnostics = renderer.diagnostics(&gpu.device, &gpu.queue);
        let joints = diagnostics.joint_matrices().unwrap().unwrap();
        let joint_scale = 4.0;
        for (g, c) in joints.iter().zip(&cpu.skins.joint_matrices) {
            assert!(
                close(g, c, POSE_TOLERANCE * joint_scale),
                "{preset}: joint {g:?} against {c:?}"
            );
        }
        let vertices = diagnostics.vertices().unwrap();
        let at_gpu = at_transforms(&scene, &records);
        for (skin, instance) in scene.skins.skins.iter().zip(&at_gpu.instances) {
            let sphere = at_gpu.world_sphere(instance);
            for v in &scene.skins.vertices[skin.vertices.start as usize..skin.vertices.end as usize]
            {
                let local = Vec3::from(vertices[v.destination as usize].position);
                let world = instance.world_from_local.transform_point3(local);
                assert!(
                    world.distance(sphere.truncate()) <= sphere.w,
                    "{preset}: a vertex of instance {} outside its sphere",
                    skin.instance
                );
            }
        }
        assert_spheres_are_the_cpus_of(&renderer, &gpu, &records, &scene);
        let gpu_culls = support::read_culls(&gpu, &renderer, &rig);
        assert_eq!(
            gpu_culls,
            support::reference_culls(&at_gpu, &rig),
            "{preset}"
        );
        assert!(
            gpu_culls.iter().any(|c| !c.visible.is_empty()),
            "{preset}: figures seen"
        );
    }
}

/// One pose pass per frame, before the skinning pass, on every preset; a walking
/// frame uploads what a frozen crowd's frame does (the contexts: no moves, no joints).
#[test]
fn one_pose_pass_per_frame_and_only_the_time_goes_up() {
    let gpu = support::gpu();
    let scene = scene_spec::load("crowd:30:2").unwrap();
    for preset in ["hmd", "cave", "hmd-peripheral"] {
        let rig = support::sized(preset, 32, 32);
        let mut renderer = Renderer::new(&gpu.device, &scene, &rig, gpu_posing()).unwrap();
        let targets = renderer.create_targets(&gpu.device);
        let mut live = LiveScene::new(scene.clone());
        let mut uploads = Vec::new();
        for frame in 0..3 {
            let synced = renderer.sync(&gpu.device, &gpu.queue, &mut live).unwrap();
            let stats = renderer
                .submit_frame(&gpu.device, &gpu.queue, &rig, frame as f32 * 0.1, &targets)
                .unwrap();
            uploads.push(synced.bytes_uploaded + stats.bytes_uploaded);
        }
        let names: Vec<&str> = renderer.passes().iter().map(|p| p.name).collect();
        let pose = names.iter().position(|n| *n == "pose");
        let skin = names.iter().position(|n| *n == "skin");
        assert_eq!(
            names.iter().filter(|n| **n == "pose").count(),
            1,
            "{preset}: {names:?}"
        );
        assert!(pose < skin, "{preset}: posed before skinned: {names:?}");
        let mut frozen = Renderer::new(&gpu.device, &scene, &rig, support::frustum_only()).unwrap();
        let mut frozen_uploads = 0;
        for _ in 0..2 {
            let stats = frozen
                .submit_frame(&gpu.device, &gpu.queue, &rig, 0.0, &targets)
                .unwrap();
            frozen_uploads = stats.bytes_uploaded;
        }
        assert_eq!(uploads[1..], [frozen_uploads; 2], "{preset}");
    }
}

/// Live edits under GPU posing: a removed figure's slot, filled by another instance,
/// keeps that instance where it was put; a figure whose joints the engine supplies
/// keeps the engine's pose (the pass no longer poses it); the others walk on.
#[test]
fn removed_and_engine_posed_figures_are_left_alone() {
    let gpu = support::gpu();
    let scene = scene_spec::load("crowd:12:4").unwrap();
    let rig = support::sized("hmd", 32, 32);
    let mut renderer = Renderer::new(&gpu.device, &scene, &rig, gpu_posing()).unwrap();
    let targets = renderer.create_targets(&gpu.device);
    let mut live = LiveScene::new(scene.clone());
    let handles = live.handles();
    let removed = live.remove(handles[3]).unwrap();
    let placed = Affine3A::from_translation(Vec3::new(0.5, 1.0, -4.0));
    let filler = live
        .insert(stereocull::scene::Instance {
            world_from_local: placed,
            ..removed
        })
        .unwrap();
    assert_eq!(
        filler.slot(),
        handles[3].slot(),
        "the lowest vacant slot is reused"
    );
    let joint_worlds: Vec<Affine3A> = (0..stereocull::crowd::JOINTS)
        .map(|j| Affine3A::from_translation(Vec3::new(1.0, j as f32 * 0.1, -5.0)))
        .collect();
    live.set_joints(handles[5], &joint_worlds).unwrap();
    let engine_pose = live.scene().skins.joint_matrices.clone();
    let engine_place = live.scene().instances[handles[5].slot() as usize].world_from_local;
    for frame in 0..3 {
        renderer.sync(&gpu.device, &gpu.queue, &mut live).unwrap();
        renderer
            .submit_frame(&gpu.device, &gpu.queue, &rig, 0.3 + frame as f32, &targets)
            .unwrap();
    }
    let diagnostics = renderer.diagnostics(&gpu.device, &gpu.queue);
    let records = diagnostics.instance_records().unwrap();
    let joints = diagnostics.joint_matrices().unwrap().unwrap();
    assert_eq!(
        records[handles[3].slot() as usize].world_from_local,
        rows(&placed)
    );
    let skin = &scene.skins.skins[5];
    let range = skin.joint_base as usize..skin.joint_base as usize + skin.joints.len();
    assert_eq!(joints[range.clone()], engine_pose[range]);
    assert_eq!(
        records[handles[5].slot() as usize].world_from_local,
        rows(&engine_place)
    );
    let mut cpu = scene.clone();
    cpu.pose(2.3);
    let walker = handles[7].slot() as usize;
    assert!(close(
        &records[walker].world_from_local,
        &rows(&cpu.instances[walker].world_from_local),
        POSE_TOLERANCE
    ));
}

/// GPU posing writes the culling spheres on the GPU: a CPU cull cannot read them, and
/// the renderer says so rather than cull stale spheres.
#[test]
fn gpu_posing_with_a_cpu_cull_is_an_error() {
    let gpu = support::gpu();
    let scene = scene_spec::load("crowd:3:1").unwrap();
    let rig = support::sized("hmd", 16, 16);
    let options = RendererOptions {
        cull: CullMode::Cpu,
        ..gpu_posing()
    };
    let err = Renderer::new(&gpu.device, &scene, &rig, options)
        .err()
        .expect("refused")
        .to_string();
    assert!(err.contains("--posing cpu or --cull gpu"), "{err}");
}

/// The pose pass's tables hold a walk's keys once however many figures play it (each
/// at its own phase, in a clip of its own): `crowd:N`'s keys do not grow with N.
#[test]
fn figures_share_the_walk_keys_in_the_pose_tables() {
    use stereocull::pose_tables::PoseTables;
    let tables = |n: u32| {
        let scene = scene_spec::load(&format!("crowd:{n}:3")).unwrap();
        PoseTables::new(&scene, |_| true).unwrap().unwrap()
    };
    let (few, many) = (tables(2), tables(40));
    assert_eq!(many.channels.len(), 20 * few.channels.len());
    assert_eq!(
        (many.times.len(), many.values.len()),
        (few.times.len(), few.values.len())
    );
    assert!(!few.times.is_empty());
}

/// Where posing runs does not change the image: the crowd posed on the GPU at random
/// times draws what the CPU-posed crowd draws, on `hmd` and `cave`, and so does
/// BoxAnimated's node animation. Both draw with the same pipelines; only the posed
/// transforms and joint matrices differ, in their last bits (the posings' rounding, see
/// POSE_TOLERANCE: measured here far below it), so a vertex can land a hair apart and
/// flip an edge pixel or round its shading a level: 2 levels, 0.1 % of the pixels beyond.
#[test]
fn gpu_and_cpu_posing_draw_the_same_images() {
    let gpu = support::gpu();
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(12);
    let tolerance = support::Tolerance {
        levels: 2,
        share: 0.001,
    };
    let crowd = scene_spec::load("crowd:60:5").unwrap();
    let boxes =
        scene_spec::load(support::gltf_sample("BoxAnimated", "glb").to_str().unwrap()).unwrap();
    for (name, scene, preset, viewer) in [
        ("crowd", &crowd, "hmd", [0.0, 1.6, 0.0]),
        ("crowd", &crowd, "cave", [0.0, 1.6, 0.0]),
        ("box", &boxes, "hmd", [0.0, 1.0, 6.0]),
    ] {
        let mut rig = support::sized(preset, 96, 80);
        rig.viewer.position = viewer;
        let time = rng.random_range(0.0..4.0);
        let mut cpu_posed = scene.clone();
        cpu_posed.pose(time);
        let on_cpu =
            support::render_at(&gpu, &cpu_posed, &rig, support::frustum_only(), time).unwrap();
        let on_gpu = support::render_at(&gpu, scene, &rig, gpu_posing(), time).unwrap();
        for (d, (g, c)) in on_gpu.iter().zip(&on_cpu).enumerate() {
            let background = *c.get_pixel(0, 0);
            let drawn = c.pixels().filter(|p| **p != background).count();
            let label = format!("posing-{name}-{preset}-{d}");
            support::assert_images_match(&label, g, c, tolerance);
            assert!(d > 0 || drawn > 100, "{label}: drawn ({drawn} pixels)");
        }
    }
}

/// A live scene reallocated (it gained a mesh) while a removed figure's slot stands
/// vacant: the renderer builds the pose pass again from the live scene as it is, the
/// vacant slot posed by nothing, an instance of the new mesh where it was put, and the
/// figures left walk on.
#[test]
fn a_reallocation_rebuilds_the_pose_pass_from_the_live_scene() {
    let gpu = support::gpu();
    let scene = scene_spec::load("crowd:8:6").unwrap();
    let rig = support::sized("hmd", 32, 32);
    let mut renderer = Renderer::new(&gpu.device, &scene, &rig, gpu_posing()).unwrap();
    let targets = renderer.create_targets(&gpu.device);
    let mut live = LiveScene::new(scene.clone());
    let handles = live.handles();
    live.remove(handles[2]).unwrap();
    let cube = stereocull::shapes::cuboid(Vec3::splat(0.2));
    let mesh = live.add_mesh("cube", &cube.vertices, &cube.indices);
    let placed = Affine3A::from_translation(Vec3::new(0.0, 1.0, -3.0));
    let synced = renderer.sync(&gpu.device, &gpu.queue, &mut live).unwrap();
    assert!(synced.reallocated, "a new mesh: everything uploaded again");
    assert!(!live.occupied(2), "the removed figure's slot stays vacant");
    let mut cube_instance = support::cubes(&[(Vec3::ZERO, 0)], 1).instances[0];
    cube_instance.mesh = mesh;
    cube_instance.world_from_local = placed;
    let new = live.insert(cube_instance).unwrap();
    renderer.sync(&gpu.device, &gpu.queue, &mut live).unwrap();
    let time = 1.3;
    renderer
        .submit_frame(&gpu.device, &gpu.queue, &rig, time, &targets)
        .unwrap();
    let records = (renderer
        .diagnostics(&gpu.device, &gpu.queue)
        .instance_records())
    .unwrap();
    assert_eq!(records[new.slot() as usize].world_from_local, rows(&placed));
    let mut cpu = scene.clone();
    cpu.pose(time);
    for h in handles.iter().filter(|h| h.slot() != 2) {
        let slot = h.slot() as usize;
        let want = rows(&cpu.instances[slot].world_from_local);
        assert!(
            close(&records[slot].world_from_local, &want, POSE_TOLERANCE),
            "figure {slot}"
        );
    }
}
