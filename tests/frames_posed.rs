//! Two frames per submission with content posed apart: node animations, skins and the
//! second frame's own edits, each frame posed on the CPU in its own sync
//! (`Renderer::sync`, then `Renderer::sync_next`). Each frame must be the frame drawn
//! alone at its time; the grown spheres keep the GPU and CPU culls byte-identical; what
//! the second frame cannot change alone is refused.

mod support;

use glam::{Affine3A, Vec3, Vec4};
use image::{RgbaImage, imageops};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use stereocull::device::Gpu;
use stereocull::error::Error;
use stereocull::live::LiveScene;
use stereocull::readback::read_rgba8;
use stereocull::renderer::{CullMode, OcclusionMode, PosingMode, Renderer, RendererOptions, grown};
use stereocull::rig::Rig;
use stereocull::scene::{Instance, Scene};
use stereocull::scene_spec;
use support::{PLACED, assert_images_match, gpu, sized};

const DT: f32 = 0.2;

fn options(cull: CullMode, frames: u32) -> RendererOptions {
    RendererOptions {
        cull,
        occlusion: OcclusionMode::Off,
        frames_per_submit: frames,
        dt: DT,
        ..Default::default()
    }
}

/// The second frame's own edits, made on `live` after its pose.
type Edit<'a> = &'a dyn Fn(&mut LiveScene);

/// One submission of two frames of `live`: posed at `time`, synced, posed at
/// `time + DT` and edited by `second`, synced as the second frame's. Returns each
/// display's two images.
fn render_pair(
    gpu: &Gpu,
    renderer: &mut Renderer,
    live: &mut LiveScene,
    (rig, time): (&Rig, f32),
    second: Edit,
) -> Vec<(RgbaImage, RgbaImage)> {
    let (device, queue) = (&gpu.device, &gpu.queue);
    live.pose(time).unwrap();
    renderer.sync(device, queue, live).unwrap();
    live.pose(time + DT).unwrap();
    second(live);
    renderer.sync_next(device, queue, live).unwrap();
    let targets = renderer.create_targets(device);
    renderer
        .prepare_pair(queue, (rig, time), (rig, time + DT))
        .unwrap();
    let mut encoder = device.create_command_encoder(&Default::default());
    let views: Vec<_> = targets.iter().map(|t| t.views()).collect();
    renderer.encode(&mut encoder, &views, None).unwrap();
    queue.submit([encoder.finish()]);
    (targets.iter())
        .map(|t| {
            let both = read_rgba8(device, queue, &t.color).unwrap();
            let (w, h) = (both.width() / 2, both.height());
            let half = |x| imageops::crop_imm(&both, x, 0, w, h).to_image();
            (half(0), half(w))
        })
        .collect()
}

/// Each frame of a pair (`got`) against the frame drawn alone at its time (`want`),
/// and the two frames alone more than `apart` pixels apart, where `apart` is not 0
/// (what moved between them: a pair whose views all read one pose fails a comparison).
fn assert_pair(
    label: &str,
    got: (&RgbaImage, &RgbaImage),
    want: (&RgbaImage, &RgbaImage),
    apart: usize,
) {
    assert_images_match(&format!("{label}-now"), got.0, want.0, PLACED);
    assert_images_match(&format!("{label}-next"), got.1, want.1, PLACED);
    let moved = (want.0.pixels().zip(want.1.pixels())).filter(|(p, q)| p != q);
    assert!(
        apart == 0 || moved.count() > apart,
        "{label}: the frames alone barely differ"
    );
}

/// `scene` as one frame draws it alone at `time`.
fn alone(gpu: &Gpu, scene: &Scene, rig: &Rig, cull: CullMode, time: f32) -> Vec<RgbaImage> {
    let mut posed = scene.clone();
    posed.pose(time);
    support::render_at(gpu, &posed, rig, options(cull, 1), time).unwrap()
}

fn load(spec: &str) -> Scene {
    scene_spec::load(spec).unwrap()
}

fn sample(name: &str, ext: &str) -> Scene {
    load(support::gltf_sample(name, ext).to_str().unwrap())
}

/// Each frame of a pair equals the frame drawn alone at its time, for a node
/// animation (BoxAnimated), a skin (SimpleSkin) and a walking crowd (skins and node
/// animations), on `hmd` and `cave`, culled on the GPU and on the CPU.
#[test]
fn posed_content_is_drawn_at_each_frames_time() {
    let gpu = gpu();
    let mut rng = Pcg64Mcg::seed_from_u64(43);
    let scenes = [
        ("box", sample("BoxAnimated", "glb"), [0.0, 1.0, 6.0], "hmd"),
        ("skin", sample("SimpleSkin", "gltf"), [0.5, 1.0, 3.0], "hmd"),
        ("crowd", load("crowd:40:4"), [0.0, 1.6, 0.0], "hmd"),
        ("crowd", load("crowd:40:4"), [0.0, 1.6, 0.0], "cave"),
    ];
    for (name, scene, viewer, preset) in scenes {
        let mut rig = sized(preset, 96, 80);
        rig.viewer.position = viewer;
        let time = rng.random_range(0.2..2.0);
        for cull in [CullMode::Gpu, CullMode::Cpu] {
            let mut live = LiveScene::new(scene.clone());
            let mut renderer =
                Renderer::new(&gpu.device, live.scene(), &rig, options(cull, 2)).unwrap();
            let pair = render_pair(&gpu, &mut renderer, &mut live, (&rig, time), &|_| {});
            let first = alone(&gpu, &scene, &rig, cull, time);
            let second = alone(&gpu, &scene, &rig, cull, time + DT);
            for (d, ((a, b), (want_a, want_b))) in
                pair.iter().zip(first.iter().zip(&second)).enumerate()
            {
                let label = format!("posed-{name}-{preset}-{cull:?}-{d}");
                let apart = if d == 0 { 20 } else { 0 };
                assert_pair(&label, (a, b), (want_a, want_b), apart);
            }
        }
    }
}

/// Morph targets are morphed for each frame at its time: the grid of
/// `support::morph`, its weights played by a linear and a cubic animation, GPU and CPU
/// culls, against each frame drawn alone.
#[test]
fn morph_targets_are_morphed_at_each_frames_time() {
    let gpu = gpu();
    let scene = support::morph::morph_scene();
    let mut rig = sized("hmd", 96, 80);
    rig.viewer.position = [0.0, 0.5, 2.2];
    for cull in [CullMode::Gpu, CullMode::Cpu] {
        let mut live = LiveScene::new(scene.clone());
        let mut renderer =
            Renderer::new(&gpu.device, live.scene(), &rig, options(cull, 2)).unwrap();
        let pair = render_pair(&gpu, &mut renderer, &mut live, (&rig, 0.9), &|_| {});
        let morphs = (renderer.passes().iter()).filter(|p| p.name == "morph");
        assert_eq!(morphs.count(), 2, "one morph pass per frame");
        let first = alone(&gpu, &scene, &rig, cull, 0.9);
        let second = alone(&gpu, &scene, &rig, cull, 0.9 + DT);
        let label = format!("morph-{cull:?}");
        let (got, want) = ((&pair[0].0, &pair[0].1), (&first[0], &second[0]));
        assert_pair(&label, got, want, 20);
    }
}

/// Posed on the GPU, the pose pass poses the second frame `dt` ahead: each frame of the
/// pair equals the GPU-posed frame drawn alone at its time (BoxAnimated on `hmd`, a
/// crowd on `hmd` and `cave`), and every posed sphere holds both frames' poses.
#[test]
fn the_pose_pass_poses_each_frame_at_its_time() {
    let gpu = gpu();
    let posing = |frames| RendererOptions {
        posing: PosingMode::Gpu,
        ..options(CullMode::Gpu, frames)
    };
    let scenes = [
        ("box", sample("BoxAnimated", "glb"), [0.0, 1.0, 6.0], "hmd"),
        ("crowd", load("crowd:40:4"), [0.0, 1.6, 0.0], "hmd"),
        ("crowd", load("crowd:40:4"), [0.0, 1.6, 0.0], "cave"),
    ];
    let mut rng = Pcg64Mcg::seed_from_u64(46);
    for (name, scene, viewer, preset) in scenes {
        let mut rig = sized(preset, 96, 80);
        rig.viewer.position = viewer;
        let time = rng.random_range(0.2..2.0);
        let mut renderer = Renderer::new(&gpu.device, &scene, &rig, posing(2)).unwrap();
        let targets = renderer.create_targets(&gpu.device);
        renderer
            .prepare_pair(&gpu.queue, (&rig, time), (&rig, time + DT))
            .unwrap();
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let views: Vec<_> = targets.iter().map(|t| t.views()).collect();
        renderer.encode(&mut encoder, &views, None).unwrap();
        gpu.queue.submit([encoder.finish()]);
        let alone = |t| support::render_at(&gpu, &scene, &rig, posing(1), t).unwrap();
        let (first, second) = (alone(time), alone(time + DT));
        for (d, target) in targets.iter().enumerate() {
            let both = read_rgba8(&gpu.device, &gpu.queue, &target.color).unwrap();
            let (w, h) = (both.width() / 2, both.height());
            let half = |x| imageops::crop_imm(&both, x, 0, w, h).to_image();
            let label = format!("gpu-posed-{name}-{preset}-{d}");
            let (now, next) = (half(0), half(w));
            let apart = if d == 0 { 20 } else { 0 };
            assert_pair(&label, (&now, &next), (&first[d], &second[d]), apart);
        }
        // Each posed sphere holds the first pose's sphere and the second's.
        let spheres = |t: f32| {
            let mut posed = scene.clone();
            posed.pose(t);
            (posed.instances.iter())
                .map(|i| posed.world_sphere(i))
                .collect::<Vec<_>>()
        };
        let (at_first, at_second) = (spheres(time), spheres(time + DT));
        let read = renderer.diagnostics(&gpu.device, &gpu.queue).spheres();
        for (k, s) in read.unwrap().unwrap().iter().enumerate() {
            let s = Vec4::from(*s);
            let holds = |o: Vec4| s.truncate().distance(o.truncate()) + o.w <= s.w * 1.0001;
            assert!(
                holds(at_first[k]) && holds(at_second[k]),
                "{name} {preset}: instance {k}'s sphere {s} misses a pose"
            );
        }
    }
}

/// Edits given for the second frame alone reach it and not the first: instances
/// moved out of view and recolored after the first frame's sync.
#[test]
fn the_second_frames_own_edits_reach_it_alone() {
    let gpu = gpu();
    let scene = load("procedural:600:6");
    let rig = sized("hmd", 96, 80);
    let mut rng = Pcg64Mcg::seed_from_u64(44);
    let picks: Vec<u32> = (0..60)
        .map(|_| rng.random_range(0..scene.instances.len() as u32))
        .collect();
    let edit_second = |live: &mut LiveScene| {
        let handles = live.handles();
        for (k, &slot) in picks.iter().enumerate() {
            let handle = handles[slot as usize];
            let at = live.scene().instances[slot as usize].world_from_local;
            let shifted = Affine3A::from_translation(Vec3::new(0.0, 0.6, 0.0)) * at;
            match k % 2 {
                0 => live.set_transform(handle, shifted).unwrap(),
                _ => live
                    .set_color(handle, Vec4::new(1.0, 0.0, 1.0, 1.0))
                    .unwrap(),
            }
        }
    };
    let mut edited = scene.clone();
    let mut shown = LiveScene::new(scene.clone());
    edit_second(&mut shown);
    edited.instances = shown.scene().instances.clone();
    for cull in [CullMode::Gpu, CullMode::Cpu] {
        let mut live = LiveScene::new(scene.clone());
        let mut renderer =
            Renderer::new(&gpu.device, live.scene(), &rig, options(cull, 2)).unwrap();
        let pair = render_pair(&gpu, &mut renderer, &mut live, (&rig, 0.0), &edit_second);
        let first = alone(&gpu, &scene, &rig, cull, 0.0);
        let second = alone(&gpu, &edited, &rig, cull, DT);
        let label = format!("second-edits-{cull:?}");
        let (got, want) = ((&pair[0].0, &pair[0].1), (&first[0], &second[0]));
        assert_pair(&label, got, want, 100);
    }
}

/// The crowd walking and a few instances moved for the second frame alone: the GPU
/// cull and the CPU cull of the pair are the same bytes, on `hmd` and `cave`, and every
/// sphere the second frame moved is the grown one, about its first-frame center.
#[test]
fn the_gpu_and_cpu_culls_of_a_posed_pair_are_the_same_bytes() {
    let gpu = gpu();
    let scene = load("crowd:60:5");
    let moved: Vec<u32> = vec![2, 17, 33];
    let edit_second = |live: &mut LiveScene| {
        let handles = live.handles();
        for &slot in &moved {
            let at = live.scene().instances[slot as usize].world_from_local;
            let step = Affine3A::from_translation(Vec3::new(0.3, 0.0, -0.4)) * at;
            live.set_transform(handles[slot as usize], step).unwrap();
        }
    };
    for preset in ["hmd", "cave"] {
        let mut rig = sized(preset, 64, 64);
        rig.viewer.position = [0.0, 1.6, 0.0];
        let culls = [CullMode::Gpu, CullMode::Cpu].map(|cull| {
            let mut live = LiveScene::new(scene.clone());
            let mut renderer =
                Renderer::new(&gpu.device, live.scene(), &rig, options(cull, 2)).unwrap();
            render_pair(&gpu, &mut renderer, &mut live, (&rig, 0.7), &edit_second);
            (renderer, live)
        });
        let [(on_gpu, live), (on_cpu, _)] = &culls;
        let got = support::read_culls(&gpu, on_gpu, &rig);
        let want = support::read_culls(&gpu, on_cpu, &rig);
        let seen: usize = want.iter().map(|c| c.visible.len()).sum();
        assert!(seen > 20, "{preset}: {seen} visible");
        for (d, (got, want)) in got.iter().zip(&want).enumerate() {
            support::assert_same_cull(&format!("{preset} display {d}"), got, want);
        }
        let spheres = (on_gpu.diagnostics(&gpu.device, &gpu.queue).spheres())
            .unwrap()
            .unwrap();
        let first = {
            let mut posed = scene.clone();
            posed.pose(0.7);
            posed
        };
        let scene_now = live.scene();
        for &slot in &moved {
            let want = grown(
                first.world_sphere(&first.instances[slot as usize]),
                scene_now.world_sphere(&scene_now.instances[slot as usize]),
            );
            let got = Vec4::from(spheres[slot as usize]);
            assert_eq!(got, want, "{preset}: slot {slot}'s sphere");
        }
    }
}

/// Instances inserted and removed for the second frame alone: the first frame draws
/// the scene before them, the second after, and the removes reach the cull order at
/// the next sync (the next pair's first frame no longer draws them). GPU and CPU culls
/// are the same bytes throughout.
#[test]
fn the_second_frames_inserts_and_removes_reach_it_alone() {
    let gpu = gpu();
    let scene = load("procedural:600:6");
    let rig = sized("hmd", 96, 80);
    let mut rng = Pcg64Mcg::seed_from_u64(47);
    let mut picks: Vec<usize> = (0..scene.instances.len()).collect();
    for k in 0..40 {
        picks.swap(k, rng.random_range(k..scene.instances.len()));
    }
    let (gone, copied) = (&picks[..20], &picks[20..40]);
    // The inserts first: a remove's place would be the next insert's.
    let edit_second = |live: &mut LiveScene| {
        let handles = live.handles();
        // Copies of other instances, raised: new places of their meshes.
        for &slot in copied {
            let mut copy = live.scene().instances[slot];
            copy.world_from_local =
                Affine3A::from_translation(Vec3::new(0.2, 0.5, 0.0)) * copy.world_from_local;
            live.insert(copy).unwrap();
        }
        for &slot in gone {
            live.remove(handles[slot]).unwrap();
        }
    };
    // The scene each frame draws alone (vacant slots dropped).
    let drawn = |live: &LiveScene| {
        let mut s = live.scene().clone();
        s.instances.retain(|i| i.mesh != Instance::VACANT_MESH);
        s
    };
    let mut culls = Vec::new();
    for cull in [CullMode::Gpu, CullMode::Cpu] {
        // Room for the inserts: the scene with a vacant place per mesh and more slots.
        let mut live = LiveScene::new(scene.clone());
        // Placed apart from the inserts (a first frame's view that drew a stale record
        // of a slot the second frame fills would show it).
        let spares: Vec<_> = (copied.iter())
            .map(|&s| {
                let mut spare = live.scene().instances[s];
                let down = Affine3A::from_translation(Vec3::new(-0.3, -0.4, 0.0));
                spare.world_from_local = down * spare.world_from_local;
                spare
            })
            .collect();
        let extra: Vec<_> = spares.iter().map(|&i| live.insert(i).unwrap()).collect();
        let mut renderer =
            Renderer::new(&gpu.device, live.scene(), &rig, options(cull, 2)).unwrap();
        // Laid out with the spares (their inserts restructured the order); removed
        // after, their records stay in the renderer's buffer.
        renderer.sync(&gpu.device, &gpu.queue, &mut live).unwrap();
        for h in extra {
            live.remove(h).unwrap();
        }
        let before = drawn(&live);
        let pair = render_pair(&gpu, &mut renderer, &mut live, (&rig, 0.0), &edit_second);
        let after = drawn(&live);
        let first = alone(&gpu, &before, &rig, cull, 0.0);
        let second = alone(&gpu, &after, &rig, cull, DT);
        let label = format!("second-inserts-{cull:?}");
        let (got, want) = ((&pair[0].0, &pair[0].1), (&first[0], &second[0]));
        assert_pair(&label, got, want, 100);
        culls.push(support::read_culls(&gpu, &renderer, &rig));
        // The next pair: the removes have reached the cull order.
        let next = render_pair(&gpu, &mut renderer, &mut live, (&rig, 2.0 * DT), &|_| {});
        let want = alone(&gpu, &after, &rig, cull, 2.0 * DT);
        assert_images_match(&format!("{label}-later"), &next[0].0, &want[0], PLACED);
        let later = support::read_culls(&gpu, &renderer, &rig);
        let kept = (gone.iter()).filter(|&&s| later[0].visible.contains(&(s as u32)));
        assert_eq!(
            kept.count(),
            0,
            "{label}: removed instances left in the cull"
        );
        culls.push(later);
    }
    for (k, (got, want)) in culls[..2].iter().zip(&culls[2..]).enumerate() {
        support::assert_same_cull(&format!("pair {k}"), &got[0], &want[0]);
    }
}

/// A second frame's move grows the sphere the one cull tests: about the first frame's
/// center, just large enough to hold the second frame's sphere too.
#[test]
fn a_grown_sphere_holds_both_frames_spheres() {
    let mut rng = Pcg64Mcg::seed_from_u64(45);
    for _ in 0..1000 {
        let mut sphere = || {
            let c = Vec3::new(
                rng.random_range(-50.0..50.0),
                rng.random_range(-5.0..5.0),
                rng.random_range(-50.0..50.0),
            );
            c.extend(rng.random_range(0.01..3.0))
        };
        let (first, second) = (sphere(), sphere());
        let g = grown(first, second);
        assert_eq!(g.truncate(), first.truncate(), "the first frame's center");
        let holds = |s: Vec4| s.truncate().distance(g.truncate()) + s.w <= g.w;
        assert!(holds(first) && holds(second), "{first} {second}: {g}");
        let reach = first.truncate().distance(second.truncate()) + second.w;
        assert!(g.w <= first.w.max(reach) * 1.00001, "not much larger");
    }
}

/// The second frame's sync refuses what both frames share, and leaves the live
/// scene's changes for the next sync; a renderer of one frame has no second frame.
#[test]
fn what_the_second_frame_cannot_change_alone_is_refused() {
    let gpu = gpu();
    let scene = load("procedural:200:4");
    let rig = sized("hmd", 32, 32);
    let (device, queue) = (&gpu.device, &gpu.queue);
    let mut live = LiveScene::new(scene.clone());
    let mut renderer =
        Renderer::new(device, live.scene(), &rig, options(CullMode::Gpu, 2)).unwrap();
    renderer.sync(device, queue, &mut live).unwrap();
    // A remove, and an insert into the place it emptied: the first frame still draws
    // the removed instance there.
    let removed = live.remove(live.handles()[3]).unwrap();
    live.insert(removed).unwrap();
    match renderer.sync_next(device, queue, &mut live) {
        Err(Error::Unsupported(m)) => assert!(m.contains("a remove emptied"), "{m}"),
        other => panic!("a place emptied and filled in the second frame: {other:?}"),
    }
    assert!(
        !live.pending_changes().removed.is_empty(),
        "the refused changes stay for the next sync"
    );
    renderer.sync(device, queue, &mut live).unwrap();
    // Past the renderer's room (every place taken: the order is laid out again).
    live.insert(removed).unwrap();
    match renderer.sync_next(device, queue, &mut live) {
        Err(Error::Unsupported(m)) => assert!(m.contains("out again"), "{m}"),
        other => panic!("an insert past the room in the second frame: {other:?}"),
    }
    let mut one = Renderer::new(device, live.scene(), &rig, options(CullMode::Gpu, 1)).unwrap();
    assert!(matches!(
        one.sync_next(device, queue, &mut live),
        Err(Error::Unsupported(_))
    ));
    let skinned = sample("SimpleSkin", "gltf");
    let refused = |options: RendererOptions, why: &str| match Renderer::new(
        device, &skinned, &rig, options,
    ) {
        Err(Error::Unsupported(m)) => assert!(m.contains(why), "{why}: {m}"),
        Err(e) => panic!("{why}: {e}"),
        Ok(_) => panic!("{why}: not refused"),
    };
    let shadows = RendererOptions {
        shadows: true,
        ..options(CullMode::Gpu, 2)
    };
    refused(shadows, "--shadows off");
}
