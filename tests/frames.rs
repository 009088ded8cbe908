//! Two frames per submission ("dt multiview"): each display's eyes at two times and two
//! poses as four views of one target, drawn by one multi-draw from one cull. Each frame
//! must be the frame drawn alone at its time and pose; the GPU and CPU culls must agree
//! byte for byte; what cannot join is refused.

mod support;

use image::{RgbaImage, imageops};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use stereocull::cull::cpu;
use stereocull::device::Gpu;
use stereocull::error::Error;
use stereocull::readback::read_rgba8;
use stereocull::records::CullLayout;
use stereocull::renderer::{
    CullMode, FramePlan, OcclusionMode, Renderer, RendererOptions, StereoMode,
};
use stereocull::rig::Rig;
use stereocull::scene::{Animation, Scene};
use stereocull::scene_spec;
use support::{PLACED, assert_images_match, gpu, sized};

/// Seconds between the frames: long enough that spinning instances visibly turn.
const DT: f32 = 0.25;

fn options(cull: CullMode, frames: u32) -> RendererOptions {
    RendererOptions {
        cull,
        mode: StereoMode::Instanced,
        occlusion: OcclusionMode::Off,
        frames_per_submit: frames,
        dt: DT,
        ..Default::default()
    }
}

/// A procedural scene whose every third instance spins and bobs (random rates, fixed
/// seed): the draw animates them from each view's time.
fn animated_scene() -> Scene {
    let mut scene = scene_spec::load("procedural:4000:8").unwrap();
    let mut rng = Pcg64Mcg::seed_from_u64(41);
    for instance in scene.instances.iter_mut().step_by(3) {
        instance.animation = Animation {
            spin: rng.random_range(1.0..4.0),
            bob: rng.random_range(0.05..0.3),
        };
    }
    scene
}

/// The viewer a tracker predicts `DT` later: turned and stepped.
fn moved(rig: &Rig) -> Rig {
    let mut next = rig.clone();
    next.viewer.yaw_deg += 4.0;
    next.viewer.pitch_deg -= 1.5;
    next.viewer.position[0] += 0.08;
    next.viewer.position[2] -= 0.05;
    next
}

/// One submission of two frames: each display's target read back, split into the first
/// frame's image and the second's.
fn render_pair(
    gpu: &Gpu,
    scene: &Scene,
    (now, next): (&Rig, &Rig),
    options: RendererOptions,
    time: f32,
) -> (Renderer, Vec<(RgbaImage, RgbaImage)>) {
    let mut renderer = Renderer::new(&gpu.device, scene, now, options).unwrap();
    let targets = renderer.create_targets(&gpu.device);
    (renderer)
        .prepare_pair(&gpu.queue, (now, time), (next, time + DT))
        .unwrap();
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    let views: Vec<_> = targets.iter().map(|t| t.views()).collect();
    renderer.encode(&mut encoder, &views, None).unwrap();
    gpu.queue.submit([encoder.finish()]);
    let images = (targets.iter())
        .map(|t| {
            let both = read_rgba8(&gpu.device, &gpu.queue, &t.color).unwrap();
            let (w, h) = (both.width() / 2, both.height());
            let half = |x| imageops::crop_imm(&both, x, 0, w, h).to_image();
            (half(0), half(w))
        })
        .collect();
    (renderer, images)
}

#[test]
fn each_frame_of_a_pair_is_the_frame_drawn_alone_at_its_time_and_pose() {
    let gpu = gpu();
    let scene = animated_scene();
    for preset in ["hmd", "cave"] {
        let now = sized(preset, 96, 80);
        let next = moved(&now);
        let time = 0.5;
        for cull in [CullMode::Gpu, CullMode::Cpu] {
            let (_, pair) = render_pair(&gpu, &scene, (&now, &next), options(cull, 2), time);
            let alone = |rig: &Rig, t: f32| {
                support::render_at(&gpu, &scene, rig, options(cull, 1), t).unwrap()
            };
            let first = alone(&now, time);
            let second = alone(&next, time + DT);
            for (d, ((a, b), (want_a, want_b))) in
                pair.iter().zip(first.iter().zip(&second)).enumerate()
            {
                let name = format!("frames-{preset}-{cull:?}-{d}");
                assert_images_match(&format!("{name}-now"), a, want_a, PLACED);
                assert_images_match(&format!("{name}-next"), b, want_b, PLACED);
                // The frames differ (the pose and the animations moved): a pair drawn
                // at one time and pose would fail here.
                let apart = a.pixels().zip(b.pixels()).filter(|(p, q)| p != q).count();
                assert!(
                    apart > (a.width() * a.height() / 50) as usize,
                    "{name}: the two frames are nearly the same ({apart} pixels apart)"
                );
            }
        }
    }
}

/// Only the time differs between the frames (the viewer holds still): what moves is
/// the animated instances alone, drawn at each view's own time.
#[test]
fn a_still_viewer_sees_the_animations_move_between_the_frames() {
    let gpu = gpu();
    let scene = animated_scene();
    let rig = sized("hmd", 96, 80);
    let time = 1.25;
    let (_, pair) = render_pair(&gpu, &scene, (&rig, &rig), options(CullMode::Gpu, 2), time);
    let second =
        support::render_at(&gpu, &scene, &rig, options(CullMode::Gpu, 1), time + DT).unwrap();
    let first = support::render_at(&gpu, &scene, &rig, options(CullMode::Gpu, 1), time).unwrap();
    assert_images_match("frames-still-now", &pair[0].0, &first[0], PLACED);
    assert_images_match("frames-still-next", &pair[0].1, &second[0], PLACED);
    let moved = first[0]
        .pixels()
        .zip(second[0].pixels())
        .filter(|(p, q)| p != q)
        .count();
    assert!(moved > 200, "the animations barely moved: {moved} pixels");
}

/// One cull keeps what any of the four views may see, the same on the GPU as on the
/// CPU; each visible object is drawn four times.
#[test]
fn the_gpu_and_cpu_culls_of_a_pair_are_the_same_bytes() {
    let gpu = gpu();
    let scene = animated_scene();
    for preset in ["hmd", "cave"] {
        let now = sized(preset, 64, 64);
        let next = moved(&now);
        let (renderer, _) =
            render_pair(&gpu, &scene, (&now, &next), options(CullMode::Gpu, 2), 0.0);
        let plan = FramePlan::pair(
            (&now, 0.0),
            (&next, DT),
            &options(CullMode::Gpu, 2),
            renderer.coarse_cull(),
        )
        .unwrap();
        let want = cpu::cull_many(&CullLayout::new(&scene), &plan.jobs());
        let got = support::read_culls(&gpu, &renderer, &now);
        for (d, (got, want)) in got.iter().zip(&want).enumerate() {
            assert!(
                !want.visible.is_empty(),
                "{preset} display {d}: nothing visible"
            );
            support::assert_same_cull(&format!("{preset} display {d}"), got, want);
            let instances: u32 = want.draws.iter().map(|d| d.instance_count).sum();
            assert_eq!(
                instances,
                4 * want.visible.len() as u32,
                "{preset} display {d}: four views per object"
            );
        }
        let (cpu_renderer, _) =
            render_pair(&gpu, &scene, (&now, &next), options(CullMode::Cpu, 2), 0.0);
        let from_cpu = support::read_culls(&gpu, &cpu_renderer, &now);
        for (d, (got, want)) in from_cpu.iter().zip(&want).enumerate() {
            support::assert_same_cull(&format!("{preset} display {d}, CPU cull"), got, want);
        }
    }
}

/// The lens's hidden area masks each frame's eyes alike: each frame of a pair is the
/// frame drawn alone with the mask (its corners keep the clear color), and the pair's
/// cull, which drops what all four views' masks hide, is the CPU twin's to the byte.
#[test]
fn the_lens_mask_masks_both_frames_and_culls_what_all_four_views_hide() {
    let gpu = gpu();
    let scene = animated_scene();
    let now = sized("hmd", 96, 80);
    let next = moved(&now);
    let masked = |cull, frames| RendererOptions {
        visibility_mask: true,
        ..options(cull, frames)
    };
    for cull in [CullMode::Gpu, CullMode::Cpu] {
        let (renderer, pair) = render_pair(&gpu, &scene, (&now, &next), masked(cull, 2), 0.5);
        let first = support::render_at(&gpu, &scene, &now, masked(cull, 1), 0.5).unwrap();
        let second = support::render_at(&gpu, &scene, &next, masked(cull, 1), 0.5 + DT).unwrap();
        assert_images_match("frames-mask-now", &pair[0].0, &first[0], PLACED);
        assert_images_match("frames-mask-next", &pair[0].1, &second[0], PLACED);
        let alone = Renderer::new(&gpu.device, &scene, &now, masked(cull, 1)).unwrap();
        assert_eq!(renderer.masked_pixels(), 2 * alone.masked_pixels());
        let plan =
            FramePlan::pair((&now, 0.5), (&next, 0.5 + DT), &masked(cull, 2), false).unwrap();
        let area = plan.displays[0]
            .hidden
            .as_ref()
            .expect("the pair's hidden area");
        assert_eq!(
            area.count, 4,
            "every view of both frames must hide a dropped sphere"
        );
        let want = cpu::cull_many(&CullLayout::new(&scene), &plan.jobs());
        let unmasked = cpu::cull_many(
            &CullLayout::new(&scene),
            &FramePlan::pair((&now, 0.5), (&next, 0.5 + DT), &options(cull, 2), false)
                .unwrap()
                .jobs(),
        );
        assert!(
            want[0].visible.len() < unmasked[0].visible.len(),
            "the mask culls nothing here"
        );
        let got = support::read_culls(&gpu, &renderer, &now);
        support::assert_same_cull(&format!("masked pair, {cull:?} cull"), &got[0], &want[0]);
    }
}

/// The pair's display frustum holds every eye of both frames, and only the second
/// frame's views lie ahead in time.
#[test]
fn a_pairs_plan_holds_both_frames_eyes_and_times_its_views() {
    let now = sized("hmd", 64, 64);
    let next = moved(&now);
    let plan = FramePlan::pair(
        (&now, 2.0),
        (&next, 2.0 + DT),
        &options(CullMode::Gpu, 2),
        false,
    )
    .unwrap();
    let display = &plan.resolved.displays[0];
    let frustum = stereocull::frustum::Frustum {
        planes: display.planes,
    };
    for (e, eye) in display.eyes.iter().enumerate() {
        for corner in eye.corners() {
            assert!(
                frustum.contains_point(corner.as_vec3()),
                "eye {e}'s corner {corner} is outside"
            );
        }
    }
    let context = &plan.displays[0].context;
    assert_eq!((context.views, context.instances_per_object), (4, 4));
    let ahead: Vec<f32> = context.eye.iter().map(|e| e.time_ahead).collect();
    assert_eq!(ahead, [0.0, 0.0, DT, DT]);
    assert_eq!(plan.frame.time, 2.0);
    // One frame per submission keeps every view at the frame's time.
    let single = FramePlan::new(&now, &options(CullMode::Gpu, 1), false, 2.0).unwrap();
    assert!(
        single.displays[0]
            .context
            .eye
            .iter()
            .all(|e| e.time_ahead == 0.0)
    );
}

#[test]
fn what_cannot_join_two_frames_is_refused_with_its_reason() {
    let gpu = gpu();
    let scene = scene_spec::load("procedural:200:4").unwrap();
    let hmd = sized("hmd", 32, 32);
    let refused =
        |scene: &Scene, rig: &Rig, options: RendererOptions, why: &str| match Renderer::new(
            &gpu.device,
            scene,
            rig,
            options,
        ) {
            Err(Error::Unsupported(m)) => assert!(m.contains(why), "{why}: {m}"),
            Err(e) => panic!("{why}: {e}"),
            Ok(_) => panic!("{why}: not refused"),
        };
    let two = options(CullMode::Gpu, 2);
    let with = |f: fn(&mut RendererOptions)| {
        let mut o = two.clone();
        f(&mut o);
        o
    };
    refused(
        &scene,
        &hmd,
        with(|o| o.occlusion = OcclusionMode::On),
        "early phase",
    );
    refused(&scene, &hmd, with(|o| o.far_layer = true), "far layer");
    refused(
        &scene,
        &hmd,
        with(|o| o.motion_vectors = true),
        "motion vectors",
    );
    refused(&scene, &hmd, with(|o| o.frames_per_submit = 3), "1 or 2");
    refused(&scene, &hmd, with(|o| o.dt = 0.0), "positive");
    let classic = RendererOptions {
        mode: StereoMode::MultiPass,
        cull: CullMode::Cpu,
        ..two.clone()
    };
    refused(&scene, &hmd, classic, "one at a time");
    refused(&scene, &sized("hmd-foveated", 32, 32), two.clone(), "eight");
    // A renderer of one frame per submission takes no pair.
    let mut one = Renderer::new(&gpu.device, &scene, &hmd, options(CullMode::Gpu, 1)).unwrap();
    let pair = one.prepare_pair(&gpu.queue, (&hmd, 0.0), (&hmd, DT));
    assert!(
        matches!(pair, Err(Error::Unsupported(_))),
        "{:?}",
        pair.err()
    );
    // A latch would replace both frames' pose by one.
    let mut renderer = Renderer::new(&gpu.device, &scene, &hmd, two).unwrap();
    renderer.prepare(&gpu.queue, &hmd, 0.0).unwrap();
    assert!(matches!(
        renderer.latch(&gpu.queue, &hmd),
        Err(Error::Unsupported(_))
    ));
}
