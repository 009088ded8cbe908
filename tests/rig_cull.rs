//! The rig cull (`stereocull::cull::rig`): one set of dispatches culls every view of the
//! frame that culls over every instance (by its frustum, or in an occlusion phase). On
//! random rigs of 1 to 12 displays (stereo, mono, foveated, head-mounted and
//! world-fixed, with LOD, blended bins, the far layer, the inset cull and occlusion),
//! its buffers are byte for byte the CPU culler's and each view's own dispatches'; its
//! images are exactly theirs; and the frame's dispatch count follows a formula in which
//! displays count only by groups (of 16 views; of 8 displays for the pyramids).

mod support;

use rand::{Rng, SeedableRng};
use stereocull::cull::rig::MAX_RIG_VIEWS;
use stereocull::cull::{CullJob, CullOutput};
use stereocull::device::Gpu;
use stereocull::procedural;
use stereocull::records::CullLayout;
use stereocull::renderer::{
    CoarseMode, CullMode, FramePlan, OcclusionMode, Renderer, RendererOptions,
};
use stereocull::rig::Rig;
use stereocull::scene::Scene;
use stereocull::shaders::PYRAMID_SET_DEPTHS;
use support::{frustum_only, gpu};

/// `displays` displays drawn at random (fixed `seed`) from every preset's (a CAVE's
/// walls are world-fixed, the others head-mounted; mono panels, a foveated display),
/// renamed apart, at 32 x 32 pixels per view, the viewer turned at random.
fn mixed_rig(displays: usize, seed: u64) -> Rig {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    let pool: Vec<_> = ["hmd", "cave", "hmd-peripheral", "hmd-foveated"]
        .iter()
        .flat_map(|p| Rig::preset(p).unwrap().displays)
        .collect();
    let mut rig = Rig::preset("cave").unwrap();
    rig.viewer.yaw_deg = rng.random_range(-180.0..180.0);
    rig.viewer.pitch_deg = rng.random_range(-30.0..30.0);
    rig.displays = (0..displays)
        .map(|k| {
            let mut d = pool[rng.random_range(0..pool.len())].clone();
            d.name = format!("d{k}");
            d.resolution = [32, 32];
            d
        })
        .collect();
    rig
}

/// Every view's cull outputs after one frame: per display its own (with occlusion its
/// early phase), its far layer's, its inset pair's and its late phase's (where it has
/// them).
fn culls(gpu: &Gpu, renderer: &Renderer, rig: &Rig) -> Vec<Option<CullOutput>> {
    let d = renderer.diagnostics(&gpu.device, &gpu.queue);
    (0..rig.displays.len())
        .flat_map(|i| {
            [
                Some(d.cull(i).unwrap()),
                d.far_cull(i).unwrap(),
                d.inset_cull(i).unwrap(),
                d.late_cull(i).unwrap(),
            ]
        })
        .collect()
}

fn options(cull: CullMode, rig_cull: bool, k: u64) -> RendererOptions {
    RendererOptions {
        cull,
        rig_cull,
        lod: k.is_multiple_of(2),
        far_layer: k % 3 != 1,
        inset_cull: k % 2 == 1,
        // The head-mounted displays' lens masks cull too.
        visibility_mask: k % 4 < 2,
        coarse_cull: CoarseMode::Off,
        // Every third rig culls by occlusion: its late phases are the rig cull's
        // second part.
        occlusion: match k % 3 {
            0 => OcclusionMode::On,
            _ => OcclusionMode::Off,
        },
        ..frustum_only()
    }
}

/// A scene of 3,000 instances around the rig, its meshes in every material bin.
fn scene(seed: u64) -> Scene {
    support::with_random_bins(procedural::scene(3_000, 9, seed), seed)
}

#[test]
fn the_rig_cull_matches_the_cpu_and_each_views_own_cull_on_random_rigs() {
    let gpu = gpu();
    let mut masked = 0;
    for displays in 1..=12 {
        let k = displays as u64;
        let rig = mixed_rig(displays, k);
        let scene = scene(k);
        masked += dropped_by_masks(&scene, &rig, &options(CullMode::Gpu, true, k));
        let rig_cull = support::one_frame(&gpu, &scene, &rig, options(CullMode::Gpu, true, k));
        let own = support::one_frame(&gpu, &scene, &rig, options(CullMode::Gpu, false, k));
        let cpu = support::one_frame(&gpu, &scene, &rig, options(CullMode::Cpu, true, k));
        let got = culls(&gpu, &rig_cull, &rig);
        assert!(
            got.iter().flatten().any(|c| !c.visible.is_empty()),
            "{displays} displays: something visible"
        );
        assert!(
            got == culls(&gpu, &own, &rig),
            "{displays} displays: own culls"
        );
        assert!(
            got == culls(&gpu, &cpu, &rig),
            "{displays} displays: CPU culls"
        );
    }
    assert!(masked > 0, "the lens masks dropped nothing");
}

/// Instances the displays' lens masks drop from their culls' frustums in `rig`'s plan.
fn dropped_by_masks(scene: &Scene, rig: &Rig, options: &RendererOptions) -> usize {
    let plan = FramePlan::new(rig, options, false, 0.0).unwrap();
    let spheres = CullLayout::new(scene).spheres;
    (plan.jobs().iter())
        .map(|job| {
            let frustum = CullJob {
                hidden: None,
                tiles: None,
                ..*job
            };
            (spheres.iter())
                .filter(|&&s| frustum.keeps(s) && !job.keeps(s))
                .count()
        })
        .sum()
}

/// The rig's cull skips a member's sphere tests for a span whose box fails the
/// member's block test (the coarse cull's guarantee, per span): on rigs anywhere within
/// a million meters and scenes from a tenth of a millimeter to a hundred meters, out to
/// two thousand kilometers, it keeps exactly what the CPU keeps.
#[test]
fn the_rig_cull_keeps_what_the_cpu_keeps_far_from_the_origin() {
    let gpu = gpu();
    for (k, rig) in support::presets_and_random_rigs(5).into_iter().enumerate() {
        let scene = support::extreme_scene(&rig, 20_000, 5, 90 + k as u64);
        let options = |cull| RendererOptions {
            cull,
            lod: true,
            coarse_cull: CoarseMode::Off,
            ..frustum_only()
        };
        let got = support::one_frame(&gpu, &scene, &rig, options(CullMode::Gpu));
        let want = support::one_frame(&gpu, &scene, &rig, options(CullMode::Cpu));
        let got = culls(&gpu, &got, &rig);
        assert!(
            got.iter().flatten().any(|c| !c.visible.is_empty()),
            "rig {k}"
        );
        assert!(got == culls(&gpu, &want, &rig), "rig {k}");
    }
}

/// The frame's cull dispatches on the GPU without occlusion or the coarse cull: three
/// (four with blended bins) per group of [`MAX_RIG_VIEWS`] views, all at the frame
/// level; none per display.
fn formula(views: usize, blended: bool) -> u32 {
    let per_group = 3 + u32::from(blended);
    views.div_ceil(MAX_RIG_VIEWS) as u32 * per_group
}

#[test]
fn the_frames_dispatches_do_not_grow_with_the_displays() {
    let gpu = gpu();
    for (displays, far_layer) in [(1, false), (5, false), (12, false), (12, true)] {
        let rig = mixed_rig(displays, 40 + displays as u64);
        let scene = scene(7);
        let options = RendererOptions {
            far_layer,
            inset_cull: true,
            coarse_cull: CoarseMode::Off,
            ..frustum_only()
        };
        let mut renderer = Renderer::new(&gpu.device, &scene, &rig, options).unwrap();
        let targets = renderer.create_targets(&gpu.device);
        let stats = renderer
            .submit_frame(&gpu.device, &gpu.queue, &rig, 0.0, &targets)
            .unwrap();
        let d = renderer.diagnostics(&gpu.device, &gpu.queue);
        let far = (0..displays).filter(|&i| d.far_cull(i).unwrap().is_some());
        let insets = (0..displays).filter(|&i| d.inset_cull(i).unwrap().is_some());
        let views = displays + far.count() + insets.count();
        let want = formula(views, true);
        assert_eq!(
            stats.dispatch_levels.frame, want,
            "{displays} displays, {views} views"
        );
        assert_eq!(stats.dispatch_levels.display, 0, "{displays} displays");
        assert_eq!(stats.dispatches, want);
    }
}

/// With occlusion, the late phases are a second part of the rig cull, and every
/// display's pyramids are one set of dispatches per [`PYRAMID_SET_DEPTHS`] displays
/// (one dispatch each at 32 x 32: five levels): the frame's dispatches are the
/// formula's for the first part's views, the pyramids' and the formula's for the late
/// phases, recorded after every display's early draw; none at the display level.
#[test]
fn the_late_culls_and_pyramids_are_one_set_of_dispatches() {
    let gpu = gpu();
    for displays in [1, 5, 12, 20] {
        let rig = mixed_rig(displays, 60 + displays as u64);
        let options = RendererOptions {
            occlusion: OcclusionMode::On,
            coarse_cull: CoarseMode::Off,
            ..Default::default()
        };
        let mut renderer = Renderer::new(&gpu.device, &scene(5), &rig, options).unwrap();
        let targets = renderer.create_targets(&gpu.device);
        let mut stats = Default::default();
        // The second frame's early phases keep what the first drew.
        for _ in 0..2 {
            stats = renderer
                .submit_frame(&gpu.device, &gpu.queue, &rig, 0.0, &targets)
                .unwrap();
        }
        let d = renderer.diagnostics(&gpu.device, &gpu.queue);
        let late = (0..displays).filter(|&i| d.late_cull(i).unwrap().is_some());
        let late = late.count();
        assert!(late > 0, "{displays} displays: none occludes");
        let what = format!("{displays} displays, {late} late");
        let pyramids = late.div_ceil(PYRAMID_SET_DEPTHS) as u32;
        let frame = formula(displays, true) + pyramids + formula(late, true);
        assert_eq!(stats.dispatch_levels.frame, frame, "{what}");
        assert_eq!(stats.dispatch_levels.display, 0, "{what}");
        let names: Vec<_> = renderer.passes().iter().map(|p| p.name).collect();
        let first = |name: &str| names.iter().position(|n| *n == name).unwrap();
        let last = |name: &str| names.iter().rposition(|n| *n == name).unwrap();
        assert!(last("draw") < first("pyramid"), "{what}: {names:?}");
        assert!(
            first("pyramid") < first("rig_late_cull"),
            "{what}: {names:?}"
        );
        assert!(
            first("rig_late_cull") < first("late_draw"),
            "{what}: {names:?}"
        );
    }
}

#[test]
fn the_rig_cull_draws_the_images_each_views_own_cull_draws() {
    let gpu = gpu();
    for displays in [3, 12] {
        let k = displays as u64;
        let rig = mixed_rig(displays, 80 + k);
        let scene = scene(k);
        let with = support::render(&gpu, &scene, &rig, options(CullMode::Gpu, true, k)).unwrap();
        let without =
            support::render(&gpu, &scene, &rig, options(CullMode::Gpu, false, k)).unwrap();
        // Exact: the same pipelines draw the same draws from the same buffers' bytes in
        // the same order; only where the culls ran differs.
        for (d, (a, b)) in with.iter().zip(&without).enumerate() {
            assert!(a == b, "{displays} displays: display {d}'s image differs");
        }
    }
}

#[test]
fn the_twelve_display_rig_file_runs() {
    let gpu = gpu();
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/rigs/ring-12.json");
    let mut rig = Rig::load(path).unwrap();
    assert_eq!(rig.displays.len(), 12);
    for d in &mut rig.displays {
        d.resolution = [32, 32];
    }
    let scene = scene(12);
    let gpu_culled = support::one_frame(&gpu, &scene, &rig, options(CullMode::Gpu, true, 0));
    let cpu_culled = support::one_frame(&gpu, &scene, &rig, options(CullMode::Cpu, true, 0));
    let got = culls(&gpu, &gpu_culled, &rig);
    assert!(got == culls(&gpu, &cpu_culled, &rig));
    // A wall's views (with occlusion, its first frame draws all it sees late).
    let drawn =
        |views: &[Option<CullOutput>]| views.iter().flatten().any(|c| !c.visible.is_empty());
    assert!(got.chunks(4).filter(|views| drawn(views)).count() >= 6);
}
