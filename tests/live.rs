//! Live scenes: random edit sequences (fixed seeds) against a plain model of the scene,
//! with GPU and CPU culling checked byte for byte against the CPU reference of the model
//! at the live scene's places every few frames (and, as sets per draw, against the
//! model laid out afresh); inserts take their mesh's lowest vacant place; typed errors
//! for bad handles and non-finite edits; and a moved instance drawn exactly where a
//! freshly built scene draws it.

mod support;

use encase::ShaderType;
use glam::{Affine3A, Quat, Vec3, Vec4};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use stereocull::Error;
use stereocull::contexts::{DisplayContext, FrameContext};
use stereocull::cull::cpu;
use stereocull::cull::rig::RigView;
use stereocull::device::Gpu;
use stereocull::live::{Handle, LiveScene};
use stereocull::places::Places;
use stereocull::readback::read_rgba8;
use stereocull::records::CullLayout;
use stereocull::renderer::{
    CullMode, FrameStats, Renderer, RendererOptions, StereoMode, SyncStats, frame_lod,
};
use stereocull::rig::Rig;
use stereocull::scene::{Animation, Instance, MAX_LODS, Scene};
use stereocull::shapes;
use support::{Tolerance, assert_images_match, frustum_only, gpu, reference_culls};

const MESHES: u32 = 5;

const VACANT: Instance = LiveScene::VACANT_INSTANCE;

fn empty_scene() -> Scene {
    let mut scene = Scene::default();
    for k in 0..MESHES {
        let s = shapes::family(k);
        scene.add_mesh(format!("shape{k}"), &s.vertices, &s.indices);
    }
    scene
}

/// `n` random instances of the meshes in turn.
fn random_scene(rng: &mut Pcg64Mcg, n: u32) -> Scene {
    let mut scene = empty_scene();
    scene.instances = (0..n).map(|k| random_instance(rng, k % MESHES)).collect();
    scene
}

/// Somewhere within a few meters of the hmd viewer at (0, 1.6, 2), in view or not.
fn random_instance(rng: &mut Pcg64Mcg, mesh: u32) -> Instance {
    Instance {
        world_from_local: random_transform(rng),
        mesh,
        color: Vec4::new(rng.random(), rng.random(), rng.random(), 1.0),
        material: None,
        animation: Animation::NONE,
    }
}

/// A third of them 20 times as far (up to 200 m), where coarser levels of detail start.
fn random_transform(rng: &mut Pcg64Mcg) -> Affine3A {
    let spread = if rng.random_bool(0.3) { 20.0 } else { 1.0 };
    let at = Vec3::new(0.0, 1.6, 2.0)
        + spread
            * Vec3::new(
                rng.random_range(-8.0..8.0),
                rng.random_range(-3.6..3.4),
                rng.random_range(-12.0..4.0),
            );
    let turn = Quat::from_rotation_y(rng.random_range(0.0..6.3));
    Affine3A::from_scale_rotation_translation(Vec3::splat(rng.random_range(0.2..1.5)), turn, at)
}

/// The model: what each slot holds, kept by the test without stereocull.
struct Model {
    slots: Vec<Option<Instance>>,
    handles: Vec<Option<Handle>>,
}

impl Model {
    fn scene(&self, meshes: &Scene) -> Scene {
        let mut scene = meshes.clone();
        scene.instances = self.slots.iter().map(|s| s.unwrap_or(VACANT)).collect();
        scene
    }

    fn live(&self) -> Vec<usize> {
        (0..self.slots.len())
            .filter(|&s| self.slots[s].is_some())
            .collect()
    }
}

/// One random edit on both the live scene and the model; `moves` only moves and
/// recolors.
fn edit(rng: &mut Pcg64Mcg, live: &mut LiveScene, model: &mut Model, moves: bool) {
    let present = model.live();
    let kind = match moves {
        true => rng.random_range(3..8),
        false => rng.random_range(0..11),
    };
    match kind {
        // Inserts (more likely while the scene is small): into the lowest vacant slot,
        // and the mesh's lowest vacant place (or a new layout when it has none).
        0..=2 => {
            let mesh = rng.random_range(0..MESHES);
            let inst = random_instance(rng, mesh);
            let place = lowest_vacant_place(live.places(), mesh);
            let h = live.insert(inst).unwrap();
            let slot = h.slot() as usize;
            let lowest_vacant = model.slots.iter().position(Option::is_none);
            assert_eq!(Some(slot), lowest_vacant.or(Some(model.slots.len())));
            let (start, len) = live.places().range(mesh);
            let now = live.places().of_slots()[slot];
            assert!(
                (start..start + len).contains(&now),
                "within its mesh's places"
            );
            if let Some(place) = place {
                assert_eq!(now, place, "the mesh's lowest vacant place");
            }
            if slot == model.slots.len() {
                model.slots.push(None);
                model.handles.push(None);
            }
            model.slots[slot] = Some(inst);
            model.handles[slot] = Some(h);
        }
        3..=6 if !present.is_empty() => {
            let slot = present[rng.random_range(0..present.len())];
            let t = random_transform(rng);
            live.set_transform(model.handles[slot].unwrap(), t).unwrap();
            model.slots[slot].as_mut().unwrap().world_from_local = t;
        }
        7 if !present.is_empty() => {
            let slot = present[rng.random_range(0..present.len())];
            let c = Vec4::new(rng.random(), 0.5, 0.25, 1.0);
            live.set_color(model.handles[slot].unwrap(), c).unwrap();
            model.slots[slot].as_mut().unwrap().color = c;
        }
        8..=9 if !present.is_empty() => {
            let slot = present[rng.random_range(0..present.len())];
            let h = model.handles[slot].take().unwrap();
            let removed = live.remove(h).unwrap();
            assert_eq!(Some(removed), model.slots[slot].take());
            // The handle is dead now, and stays dead after its slot is reused.
            assert!(matches!(live.get(h), Err(Error::BadHandle(_))));
        }
        // A respawn: removed, and an instance of the same mesh inserted (into that slot
        // when it is the lowest vacant: then the cull order stays and only edits go up).
        10 if !present.is_empty() => {
            let slot = present[rng.random_range(0..present.len())];
            let mesh = model.slots[slot].unwrap().mesh;
            live.remove(model.handles[slot].take().unwrap()).unwrap();
            model.slots[slot] = None;
            let inst = random_instance(rng, mesh);
            let h = live.insert(inst).unwrap();
            let at = h.slot() as usize;
            if at == model.slots.len() {
                model.slots.push(None);
                model.handles.push(None);
            }
            model.slots[at] = Some(inst);
            model.handles[at] = Some(h);
        }
        _ => {}
    }
}

/// The lowest vacant place of `mesh`, if it has one.
fn lowest_vacant_place(places: &Places, mesh: u32) -> Option<u32> {
    let (start, len) = places.range(mesh);
    (start..start + len).find(|&p| places.slots()[p as usize] == Places::VACANT)
}

/// Culls one frame with `renderer` after syncing `live`, and compares every display's
/// buffers with the CPU reference culling of the model at the live scene's places, and
/// each draw's visible ids as a set with the model laid out afresh.
fn check(
    gpu: &Gpu,
    renderer: &mut Renderer,
    live: &mut LiveScene,
    want: &Scene,
    what: &str,
) -> SyncStats {
    let rig = Rig::preset("hmd").unwrap();
    let synced = renderer.sync(&gpu.device, &gpu.queue, live).unwrap();
    assert_eq!(
        live.scene().instances,
        want.instances,
        "{what}: the live scene is the model"
    );
    let targets = renderer.create_targets(&gpu.device);
    renderer
        .submit_frame(&gpu.device, &gpu.queue, &rig, 0.0, &targets)
        .unwrap();
    let lod = match renderer.options().lod {
        false => cpu::FrameLod::OFF,
        true => frame_lod(&rig, &rig.resolve().unwrap(), MAX_LODS as u32),
    };
    let jobs = rig.cull_jobs().unwrap();
    let at_places = CullLayout::with_places(want, live.places());
    let reference = cpu::cull_many_lod(&at_places, &jobs, &lod);
    let afresh = cpu::cull_many_lod(&CullLayout::new(want), &jobs, &lod);
    for (d, (reference, afresh)) in reference.into_iter().zip(afresh).enumerate() {
        let got = renderer
            .diagnostics(&gpu.device, &gpu.queue)
            .cull(d)
            .unwrap();
        assert_eq!(got.draw_count, reference.draw_count, "{what}: draw count");
        assert_eq!(got.draws, reference.draws, "{what}: draws");
        assert!(got.visible == reference.visible, "{what}: visible ids");
        // Laid out afresh, a blended bin has fewer places (no room), so its range of
        // zeros is shorter, and ids sit at other slots of the visible list (place order
        // is not id order after removes): the packed draws are the same but for where
        // they start in the list, and their ids are compared below.
        let packed = |out: &stereocull::cull::CullOutput| {
            (out.packed_draws())
                .map(|d| {
                    (
                        d.index_count,
                        d.instance_count,
                        d.first_index,
                        d.base_vertex,
                    )
                })
                .collect::<Vec<_>>()
        };
        assert_eq!(
            packed(&got),
            packed(&afresh),
            "{what}: draws of the model afresh"
        );
        assert_eq!(
            per_draw_sets(&got),
            per_draw_sets(&afresh),
            "{what}: visible sets"
        );
    }
    synced
}

/// Each draw's visible ids, sorted.
fn per_draw_sets(out: &stereocull::cull::CullOutput) -> Vec<Vec<u32>> {
    out.packed_draws()
        .map(|d| {
            let views = 2;
            let first = (d.first_instance / views) as usize;
            let count = (d.instance_count / views) as usize;
            let mut ids = out.visible[first..first + count].to_vec();
            ids.sort_unstable();
            ids
        })
        .collect()
}

/// Random edit sequences from an empty scene: inserts into it, moves, recolors, removes
/// (also of a mesh's last instance), slots reused after removal. Every third frame, a
/// GPU-culled and a CPU-culled renderer sync the same changes and must both match the
/// model's reference cull; two of the four sequences with levels of detail on, two with
/// materials of every alpha mode (sorted glass, whose ranges grow with the places).
#[test]
fn edit_sequences_keep_gpu_and_cpu_culls_identical_to_the_model() {
    let gpu = gpu();
    let rig = support::sized("hmd", 32, 32);
    for (seed, lod) in [(0u64, false), (1, false), (2, true), (3, true)] {
        let meshes = match seed % 2 {
            0 => empty_scene(),
            _ => support::with_random_bins(empty_scene(), seed),
        };
        let glass = stereocull::bins::Bins::of(&meshes).first_blend_bin() != u32::MAX;
        assert_eq!(
            glass,
            seed % 2 == 1,
            "seed {seed}: glass in the odd sequences"
        );
        let mut rng = Pcg64Mcg::seed_from_u64(seed);
        let mut model = Model {
            slots: Vec::new(),
            handles: Vec::new(),
        };
        let mut live = LiveScene::new(meshes.clone());
        let mut renderers = [CullMode::Gpu, CullMode::Cpu].map(|cull| {
            let options = RendererOptions {
                cull,
                lod,
                ..frustum_only()
            };
            Renderer::new(&gpu.device, &meshes, &rig, options).unwrap()
        });
        let mut sparse_places = 0;
        for frame in 0..24 {
            for _ in 0..rng.random_range(1..40) {
                edit(&mut rng, &mut live, &mut model, false);
            }
            if frame % 3 != 2 {
                continue;
            }
            // Inserts and removes, then moves alone: both ways of syncing.
            for moves in [false, true] {
                if moves {
                    for _ in 0..rng.random_range(1..30) {
                        edit(&mut rng, &mut live, &mut model, true);
                    }
                }
                let want = model.scene(&meshes);
                let mut copy = live.clone();
                let pairs = renderers.iter_mut().zip([&mut live, &mut copy]);
                for (k, (renderer, scene)) in pairs.enumerate() {
                    let what = format!("seed {seed} frame {frame} moves {moves} renderer {k}");
                    let synced = check(&gpu, renderer, scene, &want, &what);
                    if moves && !model.live().is_empty() {
                        assert!(!synced.reloaded && synced.moved > 0, "{what}: {synced:?}");
                    }
                    if !synced.reloaded && synced.placed > 0 {
                        sparse_places += 1;
                    }
                }
            }
        }
        assert!(
            !model.live().is_empty(),
            "seed {seed}: the sequence ends with instances"
        );
        assert!(
            sparse_places > 0,
            "seed {seed}: inserts and removes went up as place edits"
        );
        if lod {
            // The far instances were drawn at coarser levels, or the LOD runs prove little.
            let (want, rig) = (model.scene(&meshes), Rig::preset("hmd").unwrap());
            let lod = frame_lod(&rig, &rig.resolve().unwrap(), MAX_LODS as u32);
            let jobs = rig.cull_jobs().unwrap();
            let with = cpu::cull_many_lod(&CullLayout::new(&want), &jobs, &lod);
            let finest: Vec<u32> = want.meshes.iter().map(|m| m.first_index).collect();
            let coarse = with[0].draws[..with[0].draw_count as usize]
                .iter()
                .filter(|d| !finest.contains(&d.first_index))
                .count();
            assert!(coarse > 0, "seed {seed}: no coarser level drawn");
        }
    }
}

/// Bad handles (removed, or from another scene) and non-finite edits are typed errors,
/// and nothing changes: the scene and its pending changes are as before.
#[test]
fn bad_handles_and_non_finite_edits_are_errors_that_change_nothing() {
    let mut live = LiveScene::new(empty_scene());
    let mut rng = Pcg64Mcg::seed_from_u64(7);
    let kept = live.insert(random_instance(&mut rng, 1)).unwrap();
    let gone = live.insert(random_instance(&mut rng, 2)).unwrap();
    live.remove(gone).unwrap();
    let _ = live.take_changes();
    let mut other = LiveScene::new(empty_scene());
    let foreign = (0..3)
        .map(|_| other.insert(random_instance(&mut rng, 0)).unwrap())
        .last()
        .unwrap();
    let before = live.scene().instances.clone();
    let t = random_transform(&mut rng);
    for bad in [gone, foreign] {
        assert!(matches!(
            live.set_transform(bad, t),
            Err(Error::BadHandle(_))
        ));
        assert!(matches!(
            live.set_color(bad, Vec4::ONE),
            Err(Error::BadHandle(_))
        ));
        assert!(matches!(live.remove(bad), Err(Error::BadHandle(_))));
        assert!(matches!(live.get(bad), Err(Error::BadHandle(_))));
    }
    let mut nan = t;
    nan.translation.y = f32::NAN;
    let mut infinite = t;
    infinite.matrix3.x_axis.x = f32::INFINITY;
    for broken in [nan, infinite] {
        assert!(matches!(
            live.set_transform(kept, broken),
            Err(Error::NonFinite(_))
        ));
        let inst = Instance {
            world_from_local: broken,
            ..random_instance(&mut rng, 0)
        };
        assert!(matches!(live.insert(inst), Err(Error::NonFinite(_))));
    }
    let nan_color = Vec4::new(f32::NAN, 0.0, 0.0, 1.0);
    assert!(matches!(
        live.set_color(kept, nan_color),
        Err(Error::NonFinite(_))
    ));
    let bad_mesh = random_instance(&mut rng, MESHES);
    assert!(matches!(live.insert(bad_mesh), Err(Error::InvalidScene(_))));
    assert_eq!(live.scene().instances, before);
    assert!(live.take_changes().is_empty(), "nothing pending");
    // The removed slot is reused by the next insert; the old handle stays dead.
    let reused = live.insert(random_instance(&mut rng, 3)).unwrap();
    assert_eq!(reused.slot(), gone.slot());
    assert!(matches!(live.get(gone), Err(Error::BadHandle(_))));
    assert!(live.get(reused).is_ok());
}

/// An instance moved between two frames is drawn exactly where a scene built fresh with
/// it at the new place draws it; a frame with no edits uploads nothing per instance.
#[test]
fn a_moved_instance_renders_like_a_fresh_scene_with_it_there() {
    let gpu = gpu();
    let rig = support::sized("hmd", 120, 100);
    let mut rng = Pcg64Mcg::seed_from_u64(3);
    let scene = random_scene(&mut rng, 40);
    let ahead = Affine3A::from_translation(Vec3::new(0.2, 1.5, -1.5));
    for mode in [StereoMode::Instanced, StereoMode::MultiPass] {
        let options = RendererOptions {
            mode,
            cull: support::cull_for(mode),
            ..frustum_only()
        };
        let mut live = LiveScene::new(scene.clone());
        let handles = live.handles();
        let mut renderer = Renderer::new(&gpu.device, &scene, &rig, options.clone()).unwrap();
        let targets = renderer.create_targets(&gpu.device);
        renderer
            .submit_frame(&gpu.device, &gpu.queue, &rig, 0.0, &targets)
            .unwrap();
        live.set_transform(handles[7], ahead).unwrap();
        let synced = renderer.sync(&gpu.device, &gpu.queue, &mut live).unwrap();
        let header = size_of::<stereocull::records::EditHeader>() as u64;
        assert_eq!((synced.moved, synced.bytes_uploaded), (1, header + 56));
        let frame = renderer
            .submit_frame(&gpu.device, &gpu.queue, &rig, 0.0, &targets)
            .unwrap();
        let moved = read_rgba8(&gpu.device, &gpu.queue, &targets[0].color).unwrap();
        let mut fresh = scene.clone();
        fresh.instances[7].world_from_local = ahead;
        let want = support::render(&gpu, &fresh, &rig, options)
            .unwrap()
            .remove(0);
        // Exact on any CPU: the scatter writes the same record rows a fresh upload holds,
        // and the same pipeline draws the same draws.
        assert_images_match(
            &format!("moved-{}", mode.name()),
            &moved,
            &want,
            Tolerance::EXACT,
        );
        // Nothing changed since: the sync uploads nothing, the frame only its contexts.
        let idle = renderer.sync(&gpu.device, &gpu.queue, &mut live).unwrap();
        assert_eq!(idle, SyncStats::default());
        let still = renderer
            .submit_frame(&gpu.device, &gpu.queue, &rig, 0.0, &targets)
            .unwrap();
        assert_eq!(
            still.dispatches + 1,
            frame.dispatches,
            "the scatter dispatch is gone"
        );
        if mode == StereoMode::Instanced {
            // The frame and display contexts and the display's record in the rig cull,
            // nothing per instance.
            let contexts = FrameContext::min_size().get()
                + DisplayContext::min_size().get()
                + RigView::min_size().get();
            assert_eq!(still.bytes_uploaded, contexts, "{still:?}");
        }
    }
}

/// A live random scene of 3,000 instances (from `seed`) on a 32 x 32 `cave`, and a
/// GPU-culling renderer of it.
fn live_on_cave(gpu: &Gpu, seed: u64) -> (Rig, Pcg64Mcg, LiveScene, Renderer) {
    let rig = support::sized("cave", 32, 32);
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let scene = random_scene(&mut rng, 3000);
    let renderer = Renderer::new(&gpu.device, &scene, &rig, frustum_only()).unwrap();
    (rig, rng, LiveScene::new(scene), renderer)
}

/// Submits a frame and checks every display's GPU cull against the CPU reference of
/// the live scene; returns the frame's figures.
fn frame_matches_reference(
    gpu: &Gpu,
    renderer: &mut Renderer,
    live: &LiveScene,
    rig: &Rig,
) -> FrameStats {
    let targets = renderer.create_targets(&gpu.device);
    let frame = renderer
        .submit_frame(&gpu.device, &gpu.queue, rig, 0.0, &targets)
        .unwrap();
    for (d, reference) in reference_culls(live.scene(), rig).into_iter().enumerate() {
        let got = renderer
            .diagnostics(&gpu.device, &gpu.queue)
            .cull(d)
            .unwrap();
        assert!(got == reference, "display {d}");
    }
    frame
}

/// Two syncs before a frame: the second's edits join the first's in one dispatch (an
/// instance moved in both keeps its last move), also when they outgrow the edits buffer.
#[test]
fn edits_of_two_syncs_before_a_frame_merge() {
    let gpu = gpu();
    let (rig, mut rng, mut live, mut renderer) = live_on_cave(&gpu, 11);
    let handles = live.handles();
    for &h in handles.iter().step_by(7).take(10) {
        live.set_transform(h, random_transform(&mut rng)).unwrap();
    }
    renderer.sync(&gpu.device, &gpu.queue, &mut live).unwrap();
    for &h in handles.iter().step_by(3) {
        live.set_transform(h, random_transform(&mut rng)).unwrap();
    }
    let second = renderer.sync(&gpu.device, &gpu.queue, &mut live).unwrap();
    assert_eq!(second.moved, 1000);
    let frame = frame_matches_reference(&gpu, &mut renderer, &live, &rig);
    assert_eq!(
        frame.dispatches,
        1 + 3,
        "one scatter for both syncs, the rig cull's three for the five walls"
    );
}

/// A move staged by one sync, then its instance removed before the frame (some slots
/// taken again by inserts): the second sync voids the staged move, so the vacated
/// place stays vacant (a stale move would put the removed instance's sphere back) and a
/// reinserted slot gets its new transform. GPU culls equal the reference's.
#[test]
fn a_move_staged_then_removed_before_the_frame_is_void() {
    let gpu = gpu();
    let (rig, mut rng, mut live, mut renderer) = live_on_cave(&gpu, 12);
    let moved: Vec<Handle> = live.handles().into_iter().step_by(5).collect();
    for &h in &moved {
        live.set_transform(h, random_transform(&mut rng)).unwrap();
    }
    renderer.sync(&gpu.device, &gpu.queue, &mut live).unwrap();
    for (k, &h) in moved.iter().enumerate().filter(|(k, _)| k % 2 == 0) {
        let mut inst = live.remove(h).unwrap();
        if k % 4 == 0 {
            inst.world_from_local = random_transform(&mut rng);
            live.insert(inst).unwrap();
        }
    }
    let second = renderer.sync(&gpu.device, &gpu.queue, &mut live).unwrap();
    assert!(second.placed > 0 && !second.reloaded, "{second:?}");
    frame_matches_reference(&gpu, &mut renderer, &live, &rig);
    let visible: usize = (0..5)
        .map(|d| {
            renderer
                .diagnostics(&gpu.device, &gpu.queue)
                .cull(d)
                .unwrap()
                .visible
                .len()
        })
        .sum();
    assert!(visible > 1000, "{visible} visible");
}

fn options_for(cull: CullMode) -> RendererOptions {
    RendererOptions {
        cull,
        ..frustum_only()
    }
}

/// Respawns (an instance removed and one of the same mesh inserted, as `--churn` does)
/// take the place just vacated: they go up as place edits, moves and record rewrites,
/// not as a new order, and the culls still equal the model's, GPU and CPU. An insert
/// into a mesh without a vacant place (the scene came tight) lays the order out again,
/// with room; inserts and removes after that are sparse again.
#[test]
fn respawns_are_sparse_edits() {
    let gpu = gpu();
    let mut rng = Pcg64Mcg::seed_from_u64(44);
    for cull in [CullMode::Gpu, CullMode::Cpu] {
        let scene = random_scene(&mut rng, 2000);
        let mut live = LiveScene::new(scene.clone());
        let options = RendererOptions {
            cull,
            ..frustum_only()
        };
        let mut renderer =
            Renderer::new(&gpu.device, &scene, &Rig::preset("hmd").unwrap(), options).unwrap();
        let mut handles = live.handles();
        for frame in 0..3 {
            for k in 0..50 {
                let i = (frame * 97 + k * 31) % handles.len();
                let mut inst = live.remove(handles[i]).unwrap();
                inst.world_from_local = random_transform(&mut rng);
                inst.color = Vec4::new(rng.random(), rng.random(), 0.5, 1.0);
                handles[i] = live.insert(inst).unwrap();
            }
            let want = live.scene().clone();
            let synced = check(
                &gpu,
                &mut renderer,
                &mut live,
                &want,
                &format!("{cull:?} frame {frame}"),
            );
            assert!(!synced.reloaded, "{cull:?}: {synced:?}");
            assert_eq!(synced.moved, 50);
        }
        // The records went up through the records scatter: the image is a fresh scene's.
        let rig = Rig::preset("hmd").unwrap();
        let draw = |r: &mut Renderer| {
            let targets = r.create_targets(&gpu.device);
            r.submit_frame(&gpu.device, &gpu.queue, &rig, 0.0, &targets)
                .unwrap();
            read_rgba8(&gpu.device, &gpu.queue, &targets[0].color).unwrap()
        };
        let fresh = &mut Renderer::new(&gpu.device, live.scene(), &rig, options_for(cull)).unwrap();
        // Exact on any CPU: the same records and culls, drawn by the same pipelines.
        assert_images_match(
            &format!("respawned-{cull:?}"),
            &draw(&mut renderer),
            &draw(fresh),
            Tolerance::EXACT,
        );
        let inst = live.remove(handles[0]).unwrap();
        let other = (inst.mesh + 1) % MESHES;
        live.insert(Instance {
            mesh: other,
            ..inst
        })
        .unwrap();
        let want = live.scene().clone();
        let synced = check(&gpu, &mut renderer, &mut live, &want, "another mesh");
        assert!(synced.reloaded, "{synced:?}");
        for (k, &h) in handles.iter().skip(1).take(20).enumerate() {
            let inst = live.remove(h).unwrap();
            let mesh = (inst.mesh + 1 + k as u32 % 2) % MESHES;
            live.insert(Instance { mesh, ..inst }).unwrap();
        }
        let want = live.scene().clone();
        let synced = check(&gpu, &mut renderer, &mut live, &want, "inserts after");
        assert!(
            !synced.reloaded && (1..=40).contains(&synced.placed),
            "{synced:?}"
        );
    }
}

/// A live scene gains a mesh and syncs before any instance of it (the renderer uploads
/// everything again), then instances of it come in (some into vacated slots): every
/// sync keeps the GPU culls equal to the reference's. The cull order got the new mesh's
/// range when the mesh was added, not at its first instance.
#[test]
fn a_mesh_added_to_a_live_scene_syncs_before_and_after_its_instances() {
    let gpu = gpu();
    let (rig, mut rng, mut live, mut renderer) = live_on_cave(&gpu, 13);
    for &h in live.handles().iter().step_by(9) {
        live.remove(h).unwrap();
    }
    // One freed slot taken again: its generation goes up.
    live.insert(random_instance(&mut rng, 0)).unwrap();
    let shape = stereocull::shapes::cuboid(Vec3::splat(0.3));
    let mesh = live.add_mesh("late box", &shape.vertices, &shape.indices);
    let synced = renderer.sync(&gpu.device, &gpu.queue, &mut live).unwrap();
    assert!(synced.reallocated, "{synced:?}");
    // The new buffers start from the live scene's records, generations included.
    let want = live.instance_records();
    assert!(want.iter().any(|r| r.generation > 0));
    let on_gpu = (renderer.diagnostics(&gpu.device, &gpu.queue))
        .instance_records()
        .unwrap();
    let bytes =
        |r: &[stereocull::records::InstanceRecord]| bytemuck::cast_slice::<_, u8>(r).to_vec();
    assert_eq!(bytes(&on_gpu[..want.len()]), bytes(&want));
    frame_matches_reference(&gpu, &mut renderer, &live, &rig);
    for _ in 0..500 {
        live.insert(random_instance(&mut rng, mesh)).unwrap();
    }
    renderer.sync(&gpu.device, &gpu.queue, &mut live).unwrap();
    frame_matches_reference(&gpu, &mut renderer, &live, &rig);
    let scene = live.scene();
    let seen = (reference_culls(scene, &rig).iter())
        .flat_map(|c| c.visible.iter())
        .filter(|&&slot| scene.instances[slot as usize].mesh == mesh)
        .count();
    assert!(seen > 0, "instances of the new mesh are drawn");
}
