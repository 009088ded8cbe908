//! Late latching (`Renderer::latch`): a frame prepared and recorded at one pose, then
//! latched at another before its submit, is the frame planned and drawn at the latched
//! pose, exactly, image and culls alike, however far the pose moved.

mod support;

use image::RgbaImage;
use stereocull::cull::CullOutput;
use stereocull::device::Gpu;
use stereocull::renderer::{CoarseMode, CullMode, OcclusionMode, Renderer, RendererOptions};
use stereocull::rig::Rig;
use stereocull::scene::Scene;

/// Every pose-dependent choice on: levels of detail, the coarse cull, the far layer,
/// shadows, occlusion, and lights (clusters per display).
fn everything() -> RendererOptions {
    RendererOptions {
        lod: true,
        coarse_cull: CoarseMode::On,
        far_layer: true,
        shadows: true,
        occlusion: OcclusionMode::On,
        sample_count: 1,
        ..RendererOptions::default()
    }
}

fn scene() -> Scene {
    let mut scene = stereocull::scene_spec::load("city:3000:5").unwrap();
    stereocull::procedural::scatter_lights(&mut scene, 24, 3);
    scene
}

/// One frame of a renderer made for `made`, prepared and recorded at `planned`; latched
/// at `latched` when given. Its images and every display's cull. (A renderer sizes its
/// far layers for the rig it is made with, for its life: both frames compared come
/// from renderers made alike.)
fn frame(
    gpu: &Gpu,
    scene: &Scene,
    (made, planned, latched): (&Rig, &Rig, Option<&Rig>),
    options: RendererOptions,
) -> (Vec<RgbaImage>, Vec<CullOutput>) {
    let mut renderer = Renderer::new(&gpu.device, scene, made, options).unwrap();
    let targets = renderer.create_targets(&gpu.device);
    renderer.prepare(&gpu.queue, planned, 0.5).unwrap();
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    let views: Vec<_> = targets.iter().map(|t| t.views()).collect();
    renderer.encode(&mut encoder, &views, None).unwrap();
    if let Some(latched) = latched {
        renderer.latch(&gpu.queue, latched).unwrap();
    }
    gpu.queue.submit([encoder.finish()]);
    let rig = latched.unwrap_or(planned);
    let images = (targets.iter())
        .map(|t| stereocull::readback::read_rgba8(&gpu.device, &gpu.queue, &t.color).unwrap())
        .collect();
    (images, support::read_culls(gpu, &renderer, rig))
}

/// `rig` moved by `meters` along x and turned by `degrees`.
fn moved(rig: &Rig, meters: f32, degrees: f32) -> Rig {
    let mut moved = rig.clone();
    moved.viewer.position[0] += meters;
    moved.viewer.yaw_deg += degrees;
    moved.viewer.pitch_deg -= degrees / 4.0;
    moved
}

#[test]
fn a_latched_frame_is_the_frame_planned_at_the_latched_pose() {
    let gpu = support::gpu();
    let scene = scene();
    for preset in ["hmd", "cave", "hmd-foveated"] {
        let planned = support::sized(preset, 48, 40);
        for (meters, degrees) in [(0.03, 2.0), (0.6, 60.0)] {
            let latched = moved(&planned, meters, degrees);
            // The far latch through mapped staging, the near one through the queue's.
            let late_latch = meters > 0.1;
            let what = format!("{preset}, {meters} m and {degrees} degrees, late {late_latch}");
            let options = RendererOptions {
                late_latch,
                ..everything()
            };
            let (images, culls) =
                frame(&gpu, &scene, (&planned, &planned, Some(&latched)), options);
            let (at_b, culls_b) = frame(&gpu, &scene, (&planned, &latched, None), everything());
            assert_eq!(culls, culls_b, "{what}: culls");
            // Exact on any CPU: one renderer's pipelines, the same culls (checked above),
            // the same contexts; only when they were written differs.
            for (i, (a, b)) in images.iter().zip(&at_b).enumerate() {
                let name = format!("latch-{preset}-{i}-{meters}");
                support::assert_images_match(&name, a, b, support::Tolerance::EXACT);
            }
            // The control: the frame as planned differs from the latched one.
            let (unlatched, _) = frame(&gpu, &scene, (&planned, &planned, None), everything());
            assert!(unlatched != images, "{what}: latching changed nothing");
        }
    }
}

#[test]
fn latching_needs_the_gpu_cull_and_a_prepared_frame() {
    let gpu = support::gpu();
    let scene = scene();
    let rig = support::sized("hmd", 32, 32);
    let options = RendererOptions {
        cull: CullMode::Cpu,
        ..RendererOptions::default()
    };
    let mut cpu = Renderer::new(&gpu.device, &scene, &rig, options).unwrap();
    cpu.prepare(&gpu.queue, &rig, 0.0).unwrap();
    let error = cpu.latch(&gpu.queue, &rig).unwrap_err().to_string();
    assert!(error.contains("GPU cull"), "{error}");
    let mut unprepared =
        Renderer::new(&gpu.device, &scene, &rig, RendererOptions::default()).unwrap();
    let error = unprepared.latch(&gpu.queue, &rig).unwrap_err().to_string();
    assert!(error.contains("after prepare"), "{error}");
    let cave = support::sized("cave", 32, 32);
    let mut gpu_cull =
        Renderer::new(&gpu.device, &scene, &rig, RendererOptions::default()).unwrap();
    gpu_cull.prepare(&gpu.queue, &rig, 0.0).unwrap();
    assert!(
        gpu_cull.latch(&gpu.queue, &cave).is_err(),
        "a rig of other displays"
    );
}

/// With late latching each frame's staging is mapped before the pose is sampled and
/// closed by the latch, then mapped again for a later frame: a run of frames, each
/// latched at its own pose, draws what frames planned at those poses draw.
#[test]
fn late_latched_frames_in_a_row_are_the_frames_planned_at_their_poses() {
    let gpu = support::gpu();
    let scene = scene();
    let planned = support::sized("hmd", 48, 40);
    let late = RendererOptions {
        late_latch: true,
        ..everything()
    };
    let mut latching = Renderer::new(&gpu.device, &scene, &planned, late).unwrap();
    let mut planning = Renderer::new(&gpu.device, &scene, &planned, everything()).unwrap();
    let (latching_targets, planning_targets) = (
        latching.create_targets(&gpu.device),
        planning.create_targets(&gpu.device),
    );
    for k in 0..4 {
        let pose = moved(&planned, 0.05 * k as f32, 7.0 * k as f32);
        let time = 0.5 + k as f32 / 90.0;
        latching.prepare(&gpu.queue, &planned, time).unwrap();
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let views: Vec<_> = latching_targets.iter().map(|t| t.views()).collect();
        latching.encode(&mut encoder, &views, None).unwrap();
        latching.latch(&gpu.queue, &pose).unwrap();
        let error = latching.latch(&gpu.queue, &pose).unwrap_err().to_string();
        assert!(error.contains("latches once"), "{error}");
        gpu.queue.submit([encoder.finish()]);
        (planning.submit_frame(&gpu.device, &gpu.queue, &pose, time, &planning_targets)).unwrap();
        for (i, (a, b)) in latching_targets.iter().zip(&planning_targets).enumerate() {
            let read = |t: &stereocull::renderer::DisplayTarget| {
                stereocull::readback::read_rgba8(&gpu.device, &gpu.queue, &t.color).unwrap()
            };
            // Exact on any CPU: the same pipelines, contexts and history (each frame's
            // occlusion starts from the last frame's visibility, the same in both).
            let name = format!("late-latch-row-{k}-{i}");
            support::assert_images_match(&name, &read(a), &read(b), support::Tolerance::EXACT);
        }
    }
}

/// Late latching latches every frame, so it asks what a latch does of the renderer.
#[test]
fn late_latching_is_refused_where_a_latch_would_be() {
    let gpu = support::gpu();
    let scene = scene();
    let rig = support::sized("hmd", 32, 32);
    let refused = [
        RendererOptions {
            cull: CullMode::Cpu,
            ..RendererOptions::default()
        },
        RendererOptions {
            keep_unchanged: stereocull::keep::KeepUnchanged::On,
            ..RendererOptions::default()
        },
        RendererOptions {
            frames_per_submit: 2,
            ..RendererOptions::default()
        },
    ];
    for options in refused {
        let what = format!("{:?} {:?}", options.cull, options.keep_unchanged);
        let options = RendererOptions {
            late_latch: true,
            ..options
        };
        let error = Renderer::new(&gpu.device, &scene, &rig, options).err();
        let error = error.map(|e| e.to_string()).unwrap_or_default();
        assert!(error.contains("late latching"), "{what}: {error}");
    }
}
