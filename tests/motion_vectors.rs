//! Motion vectors (`RendererOptions::motion_vectors`, `src/motion.rs`) against their CPU
//! twin: every covered pixel's motion read back equals the motion of the surface point
//! its depth gives (`motion::motion_at`) under the motion that point is known to have:
//! the head's alone over a static scene; a moved instance's, a spinning one's, a
//! GPU-posed glTF node's and a skinned figure's own; a newcomer's none. Pixels no
//! surface covers hold zero. Warping a frame by the next frame's vectors comes close to
//! the next frame. What the renderer cannot do with them is refused.

mod support;

use glam::{Affine3A, DVec2, DVec3, Quat, Vec3};
use stereocull::device::Gpu;
use stereocull::live::LiveScene;
use stereocull::motion::{PreviousFrame, motion_at, pixel_of};
use stereocull::readback::{read_depth, read_motion, read_rgba8};
use stereocull::renderer::{
    DisplayTarget, FramePlan, OcclusionMode, PosingMode, Renderer, RendererOptions, StereoMode,
};
use stereocull::rig::Rig;
use stereocull::scene::{Animation, Instance, Scene};
use stereocull::{Error, scene_spec};

const SIZE: u32 = 96;

/// How far the GPU's motion may be from the twin's, in pixels: `ABSOLUTE` plus
/// `RELATIVE` of the motion. The half float target keeps 11 significant bits
/// (2^-11 relative); the twin rebuilds each point from the depth buffer's f32 value,
/// whose rounding moves the point along its ray by up to about 2^-24 of the depth
/// range (millimeters at tens of meters, hundredths of a pixel of parallax here); the
/// rasterizer's f32 interpolation of the previous clip position errs by about 1e-4
/// pixels. Both bounds sit well above those sums and far below any wrong source of
/// motion (a missing one is whole pixels here).
const ABSOLUTE: f64 = 0.02;
const RELATIVE: f64 = 1.0 / 512.0;

fn options() -> RendererOptions {
    RendererOptions {
        motion_vectors: true,
        // One phase: occlusion moves what is drawn when, never a pixel's motion.
        occlusion: OcclusionMode::Off,
        ..Default::default()
    }
}

fn rig(position: [f32; 3], yaw: f32, pitch: f32) -> Rig {
    let mut rig = support::sized("hmd", SIZE, SIZE);
    rig.viewer.position = position;
    rig.viewer.yaw_deg = yaw;
    rig.viewer.pitch_deg = pitch;
    rig
}

/// One frame read back: each pixel's motion and depth, and the contexts the twin
/// measures with (the frame's plan, carrying the previous frame's matrices).
struct Drawn {
    motion: Vec<[f32; 2]>,
    depth: Vec<f32>,
    color: image::RgbaImage,
    plan: FramePlan,
}

/// A renderer's frames at given poses and times, each measured from the one before.
struct Frames {
    gpu: Gpu,
    renderer: Renderer,
    targets: Vec<DisplayTarget>,
    previous: Option<PreviousFrame>,
}

impl Frames {
    fn new(scene: &Scene, rig: &Rig, options: RendererOptions) -> Frames {
        let gpu = support::gpu();
        let renderer = Renderer::new(&gpu.device, scene, rig, options).unwrap();
        let targets = renderer.create_targets(&gpu.device);
        Frames {
            gpu,
            renderer,
            targets,
            previous: None,
        }
    }

    fn draw(&mut self, rig: &Rig, time: f32) -> Drawn {
        let (device, queue) = (&self.gpu.device, &self.gpu.queue);
        let mut plan = self.renderer.plan(rig, time).unwrap();
        if let Some(previous) = &self.previous {
            plan.measure_from(previous);
        }
        self.previous = Some(plan.as_previous());
        let targets = &self.targets;
        (self.renderer)
            .submit_frame(device, queue, rig, time, targets)
            .unwrap();
        let target = &targets[0];
        let motion = target.motion.as_ref().expect("a motion target");
        Drawn {
            motion: read_motion(device, queue, motion).unwrap(),
            depth: read_depth(device, queue, &target.depth).unwrap().1,
            color: read_rgba8(device, queue, &target.color).unwrap(),
            plan,
        }
    }

    fn sync(&mut self, live: &mut LiveScene) {
        let (device, queue) = (&self.gpu.device, &self.gpu.queue);
        self.renderer.sync(device, queue, live).unwrap();
    }
}

/// Where a surface point `p` of the current frame stood in the previous one.
type Previously<'a> = &'a dyn Fn(DVec3) -> DVec3;

const STILL: Previously = &|p| p;

/// Checks every pixel of `drawn`: the background holds zero; a covered pixel's motion
/// matches the twin's under one of `candidates` (else the test fails, naming it).
/// Returns how many pixels each candidate matches.
fn matches(drawn: &Drawn, candidates: &[Previously]) -> Vec<usize> {
    let width = 2 * SIZE;
    let mut counts = vec![0; candidates.len()];
    for (i, (&[mx, my], &depth)) in drawn.motion.iter().zip(&drawn.depth).enumerate() {
        let (x, y) = (i as u32 % width, i as u32 / width);
        let gpu = DVec2::new(mx as f64, my as f64);
        if depth >= 1.0 {
            assert_eq!(gpu, DVec2::ZERO, "background pixel ({x}, {y}) moves");
            continue;
        }
        let eye = &drawn.plan.displays[0].context.eye[(x >= SIZE) as usize];
        let pixel = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
        let twins: Vec<DVec2> = (candidates.iter())
            .map(|c| motion_at(eye, (pixel, depth), c))
            .collect();
        let close = |t: &DVec2| (gpu - *t).length() <= ABSOLUTE + RELATIVE * t.length();
        let found: Vec<usize> = (0..twins.len()).filter(|&k| close(&twins[k])).collect();
        assert!(
            !found.is_empty(),
            "pixel ({x}, {y}) at depth {depth}: {gpu} matches none of {twins:?}"
        );
        for k in found {
            counts[k] += 1;
        }
    }
    counts
}

/// A point moved by `to` from where `from` had it: its previous place.
fn rigid(from: Affine3A, to: Affine3A) -> impl Fn(DVec3) -> DVec3 {
    let back = from * to.inverse();
    move |p| back.transform_point3(p.as_vec3()).as_dvec3()
}

/// Cubes ahead of the hmd viewer at (0, 1.6, 2), a meter or more apart.
fn cubes() -> Scene {
    let at = |x: f32, y: f32, z: f32| (Vec3::new(x, y, z), 0);
    support::cubes(
        &[
            at(-1.2, 1.6, -0.5),
            at(0.0, 1.9, -1.0),
            at(1.2, 1.3, -0.5),
            at(0.3, 0.8, 0.0),
        ],
        1,
    )
}

/// A head that moves and turns over a static scene: every pixel moves as its point
/// reprojects, the analytic motion of the head alone.
#[test]
fn a_turning_head_gives_each_pixel_its_reprojection() {
    let scene = scene_spec::load("procedural:400:6:7").unwrap();
    let now = rig([0.0, 1.6, 2.0], 0.0, 0.0);
    let mut frames = Frames::new(&scene, &now, options());
    // The same time twice: the scene's animations stand still.
    frames.draw(&rig([0.06, 1.58, 2.04], 4.0, -2.5), 1.0);
    let drawn = frames.draw(&now, 1.0);
    let [still] = matches(&drawn, &[STILL])[..] else {
        unreachable!()
    };
    let covered = drawn.depth.iter().filter(|&&d| d < 1.0).count();
    assert_eq!(still, covered);
    assert!(
        covered > (SIZE * SIZE) as usize / 2,
        "{covered} pixels covered"
    );
    let largest = (drawn.motion.iter()).fold(0.0f32, |m, v| m.max(v[0].abs()).max(v[1].abs()));
    assert!(largest > 3.0, "a 4 degree turn moves pixels by {largest}");
}

/// A moved instance moves by its move, a spinning one by its spin between the two
/// times, the rest by the head's motion alone; an instance inserted into a slot freed
/// this frame has no previous transform: it moves as if it had stood there, never from
/// where the slot's last occupant stood.
#[test]
fn moved_spinning_and_new_instances_move_as_they_did() {
    let mut scene = cubes();
    scene.instances[1].animation = Animation {
        spin: 2.0,
        ..Animation::NONE
    };
    let mut live = LiveScene::new(scene.clone());
    let handles = live.handles();
    let view = rig([0.0, 1.6, 2.0], 0.0, 0.0);
    let mut frames = Frames::new(live.scene(), &view, options());
    frames.draw(&rig([0.02, 1.6, 2.0], 1.0, 0.0), 0.5);

    // A move a frame earlier: the previous transform is the last frame's, not the
    // first one's.
    let first = scene.instances[0].world_from_local;
    let was = Affine3A::from_translation(Vec3::new(-0.1, 0.0, 0.1)) * first;
    live.set_transform(handles[0], was).unwrap();
    frames.sync(&mut live);
    frames.draw(&rig([0.01, 1.6, 2.0], 0.5, 0.0), 0.55);
    let moved = Affine3A::from_translation(Vec3::new(0.15, -0.1, 0.05)) * was;
    live.set_transform(handles[0], moved).unwrap();
    let gone = live.remove(handles[2]).unwrap();
    let newcomer = Instance {
        world_from_local: Affine3A::from_translation(Vec3::new(-0.4, 1.2, 0.3)),
        ..gone
    };
    let inserted = live.insert(newcomer).unwrap();
    assert_eq!(
        inserted.slot(),
        handles[2].slot(),
        "the freed slot is reused"
    );
    frames.sync(&mut live);
    let drawn = frames.draw(&view, 0.6);

    let spin = |t: f32| Quat::from_rotation_y(2.0 * t);
    let spun_at = |t| scene.instances[1].world_from_local * Affine3A::from_quat(spin(t));
    let stale = rigid(gone.world_from_local, newcomer.world_from_local);
    let counts = matches(
        &drawn,
        &[
            STILL,
            &rigid(was, moved),
            &rigid(spun_at(0.55), spun_at(0.6)),
            &stale,
        ],
    );
    assert!(counts[1] > 100 && counts[2] > 100, "{counts:?}");
    // The newcomer is in view (its center's pixel shows it), and none of its pixels
    // came from its slot's last occupant.
    let eye = &drawn.plan.displays[0].context.eye[0];
    let center = newcomer.world_from_local.translation.as_dvec3();
    let p = pixel_of(eye.clip_from_world, eye.viewport, center).unwrap();
    let at = (p.y as u32 * 2 * SIZE + p.x as u32) as usize;
    let seen = stereocull::motion::world_at(eye, p.floor() + 0.5, drawn.depth[at]);
    assert!((seen - center).length() < 0.9, "{seen} is not the newcomer");
    let still = motion_at(eye, (p.floor() + 0.5, drawn.depth[at]), STILL);
    let got = drawn.motion[at];
    assert!((DVec2::new(got[0] as f64, got[1] as f64) - still).length() < 0.05);
    let from_stale = motion_at(eye, (p.floor() + 0.5, drawn.depth[at]), &stale);
    assert!(
        (from_stale - still).length() > 5.0,
        "the cases differ: {from_stale}"
    );

    // A frame without edits after them: the moved instance and the newcomer stand
    // still (the copy of the records is taken only when they change, so this fails if
    // the previous records were left from before the moves).
    let after = frames.draw(&view, 0.65);
    let counts = matches(&after, &[STILL, &rigid(spun_at(0.6), spun_at(0.65))]);
    assert!(counts[0] > 200 && counts[1] > 100, "{counts:?}");
}

/// glTF node animation posed on the GPU: each posed instance moves from its pose at the
/// previous time to its pose now.
#[test]
fn gpu_posed_nodes_move_from_their_previous_pose() {
    let file = support::gltf_sample("BoxAnimated", "glb");
    let scene = scene_spec::load(file.to_str().unwrap()).unwrap();
    let view = rig([0.0, 1.0, 5.0], 0.0, -8.0);
    let options = RendererOptions {
        posing: PosingMode::Gpu,
        ..options()
    };
    let mut frames = Frames::new(&scene, &view, options);
    let (before, now) = (1.0, 1.15);
    frames.draw(&view, before);
    let drawn = frames.draw(&view, now);
    let pose = |t| {
        let mut s = scene.clone();
        s.pose(t);
        s
    };
    let (a, b) = (pose(before), pose(now));
    let twins: Vec<_> = (a.instances.iter().zip(&b.instances))
        .filter(|(i, j)| i.world_from_local != j.world_from_local)
        .map(|(i, j)| rigid(i.world_from_local, j.world_from_local))
        .collect();
    assert!(
        !twins.is_empty(),
        "the clip moves something between the times"
    );
    let mut candidates: Vec<Previously> = vec![STILL];
    candidates.extend(twins.iter().map(|t| t as Previously));
    let counts = matches(&drawn, &candidates);
    assert!(counts[1..].iter().any(|&c| c > 50), "{counts:?}");
}

/// A skinned figure whose every joint turns by one rigid motion: its vertices (skinned
/// on the GPU each frame) move by it, which only the previous frame's vertices carry.
#[test]
fn a_skinned_figure_moves_with_its_joints() {
    let scene = scene_spec::load("crowd:1:3").unwrap();
    let skin = scene.skins.skins[0].clone();
    let worlds = scene.posing.node_worlds(0.4);
    let joints: Vec<Affine3A> = skin.joints.iter().map(|&j| worlds[j as usize]).collect();
    let mut live = LiveScene::new(scene.clone());
    let handle = live.handles()[skin.instance as usize];
    let figure = scene.instances[skin.instance as usize].world_from_local;
    let center = Vec3::from(figure.translation) + Vec3::Y;
    let view = rig([center.x, center.y + 0.2, center.z + 2.2], 0.0, -5.0);
    let mut frames = Frames::new(live.scene(), &view, options());
    live.set_joints(handle, &joints).unwrap();
    frames.sync(&mut live);
    frames.draw(&view, 0.4);
    let turn = Affine3A::from_translation(center)
        * Affine3A::from_rotation_y(0.3)
        * Affine3A::from_translation(-center);
    let turned: Vec<Affine3A> = joints.iter().map(|j| turn * *j).collect();
    live.set_joints(handle, &turned).unwrap();
    frames.sync(&mut live);
    let drawn = frames.draw(&view, 0.4);
    let counts = matches(&drawn, &[STILL, &rigid(Affine3A::IDENTITY, turn)]);
    assert!(counts[1] > 200, "{counts:?}");
}

/// Frame N warped by frame N+1's motion (each pixel of N+1 fetched from N where its
/// vector says it was) comes close to frame N+1: under a third of the error of no warp
/// (lavapipe: 12.8 against 69.1 levels a pixel, 0.19; what remains is nearest
/// sampling, disocclusions and the shading's change with the eye).
#[test]
fn warping_by_the_vectors_approaches_the_next_frame() {
    let scene = scene_spec::load("procedural:400:6:7").unwrap();
    let now = rig([0.0, 1.6, 2.0], 0.0, 0.0);
    let mut frames = Frames::new(&scene, &now, options());
    let before = frames.draw(&rig([0.04, 1.6, 2.02], 3.0, -1.5), 1.0);
    let after = frames.draw(&now, 1.05);
    let (mut warped, mut unwarped, mut n) = (0.0, 0.0, 0u32);
    let width = 2 * SIZE;
    let level = |im: &image::RgbaImage, x: u32, y: u32| {
        let p = im.get_pixel(x, y).0;
        [p[0], p[1], p[2]].map(f64::from)
    };
    let error = |a: [f64; 3], b: [f64; 3]| (0..3).map(|c| (a[c] - b[c]).abs()).sum::<f64>();
    for (i, &[mx, my]) in after.motion.iter().enumerate() {
        let (x, y) = (i as u32 % width, i as u32 / width);
        let from = DVec2::new(x as f64 + 0.5 - mx as f64, y as f64 + 0.5 - my as f64);
        let half = (x / SIZE) * SIZE;
        let inside = from.x >= half as f64 && from.x < (half + SIZE) as f64;
        if after.depth[i] >= 1.0 || !inside || from.y < 0.0 || from.y >= SIZE as f64 {
            continue;
        }
        let now = level(&after.color, x, y);
        warped += error(now, level(&before.color, from.x as u32, from.y as u32));
        unwarped += error(now, level(&before.color, x, y));
        n += 1;
    }
    let (warped, unwarped) = (warped / n as f64, unwarped / n as f64);
    eprintln!("mean error per pixel: warped {warped:.2}, unwarped {unwarped:.2} levels");
    assert!(
        warped < unwarped / 3.0,
        "warped {warped}, unwarped {unwarped}"
    );
}

/// The modes and layers the vectors are not written by refuse them by name, and a
/// frame's targets must have the attachment.
#[test]
fn what_cannot_write_motion_says_so() {
    let gpu = support::gpu();
    let scene = cubes();
    let hmd = rig([0.0, 1.6, 2.0], 0.0, 0.0);
    let refused = |rig: &Rig, options: RendererOptions, says: &str| {
        let message = match Renderer::new(&gpu.device, &scene, rig, options) {
            Err(e @ (Error::Unsupported(_) | Error::Rig { .. })) => e.to_string(),
            Err(e) => panic!("{says}: {e}"),
            Ok(_) => panic!("{says}: made"),
        };
        assert!(message.contains(says), "{message}");
    };
    let with = |mode, far_layer| RendererOptions {
        mode,
        far_layer,
        cull: support::cull_for(mode),
        ..options()
    };
    refused(&hmd, with(StereoMode::Multiview, false), "multiview");
    refused(&hmd, with(StereoMode::MultiPass, false), "classic modes");
    refused(&hmd, with(StereoMode::Instanced, true), "far layer");
    let foveated = support::sized("hmd-foveated", SIZE, SIZE);
    refused(&foveated, options(), "foveated");

    let mut renderer = Renderer::new(&gpu.device, &scene, &hmd, options()).unwrap();
    let plain = Renderer::new(&gpu.device, &scene, &hmd, Default::default()).unwrap();
    let targets = plain.create_targets(&gpu.device);
    let result = renderer.submit_frame(&gpu.device, &gpu.queue, &hmd, 0.0, &targets);
    assert!(
        matches!(&result, Err(Error::Unsupported(m)) if m.contains("motion attachment")),
        "{:?}",
        result.err()
    );
}
