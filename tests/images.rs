//! Image tests of the double-wide stereo target. Each failure writes `-actual.png` and
//! `-difference.png` (and the reference) under `target/test-images/`.

mod support;

use glam::Vec3;
use image::RgbaImage;
use stereocull::device::Gpu;
use stereocull::frustum::Fov;
use stereocull::renderer::{CullMode, RendererOptions, StereoMode};
use stereocull::rig::{Mount, Rig};
use stereocull::scene::{Animation, Scene};
use stereocull::scene_spec;
use support::{Tolerance, assert_images_match, gpu_with};

/// Per-eye test resolution: small enough for lavapipe, large enough for real edges.
const W: u32 = 240;
const H: u32 = 200;

fn render(gpu: &Gpu, scene: &Scene, rig: &Rig, cull: CullMode) -> Vec<RgbaImage> {
    support::render(gpu, scene, rig, options(cull, StereoMode::Instanced, 1)).unwrap()
}

fn options(cull: CullMode, mode: StereoMode, sample_count: u32) -> RendererOptions {
    RendererOptions {
        cull,
        mode,
        sample_count,
        ..Default::default()
    }
}

fn sized(preset: &str) -> Rig {
    support::sized(preset, W, H)
}

/// Display `d`'s eye `e` as a mono display of its own: the plain projection of that eye.
fn single_eye(rig: &Rig, d: usize, e: usize) -> Rig {
    let mut mono = rig.clone();
    let eye = rig.resolve().unwrap().displays[d].eyes[e];
    mono.viewer.position = eye.position().into();
    let mut display = rig.displays[d].clone();
    display.stereo = false;
    if let Mount::Head(h) = &mut display.mount {
        h.fov = eye.fov;
    }
    mono.displays = vec![display];
    mono
}

fn half(image: &RgbaImage, eye: u32) -> RgbaImage {
    image::imageops::crop_imm(image, eye * W, 0, W, H).to_image()
}

/// The remap `x' = x/2 -+ w/2` is exact in real numbers; in floats a vertex can round a
/// hair differently, which moves an edge pixel's coverage or shading by a level or two.
/// Tolerance: channels within 2 levels, and at most 0.05 % of pixels beyond that.
/// Measured on lavapipe: 1 pixel (of 48,000) off by at most 2 levels; none beyond.
const EDGES: Tolerance = Tolerance {
    levels: 2,
    share: 0.0005,
};
/// See [`every_stereo_mode_agrees_with_instanced`]. Lavapipe's multiview (Mesa 22.3)
/// clips some triangles that cross the near plane into the wrong view: a one-pixel line
/// of the table across the left eye's floor. Measured: 155 pixels of 96,000 (0.16 %) at
/// 1x, up to 246 (0.26 %) at 4x; everything else agrees.
const MULTIVIEW: Tolerance = Tolerance {
    levels: 2,
    share: 0.003,
};

/// How far `mode`'s image may be from `instanced`'s.
fn tolerance(mode: StereoMode) -> Tolerance {
    match mode {
        StereoMode::Multiview => MULTIVIEW,
        _ => EDGES,
    }
}

#[test]
fn each_half_equals_that_eye_rendered_alone() {
    assert_halves_are_single_eyes(&["hmd", "cave", "hmd-peripheral"], 1);
}

/// MSAA keeps the seam exact: no sample of one eye lands in the other half, so each
/// half still equals that eye rendered alone (at the same sample count).
#[test]
fn each_half_equals_that_eye_rendered_alone_under_msaa() {
    assert_halves_are_single_eyes(&["hmd", "cave"], 4);
}

fn assert_halves_are_single_eyes(presets: &[&str], samples: u32) {
    let gpu = gpu_with(wgpu::Features::all());
    let scene = scene_spec::load("default").unwrap();
    let draw = |rig: &Rig| {
        let options = options(CullMode::Gpu, StereoMode::Instanced, samples);
        support::render(&gpu, &scene, rig, options.clone()).unwrap()
    };
    for preset in presets {
        let rig = sized(preset);
        let stereo = draw(&rig);
        for (d, display) in rig.displays.iter().enumerate().filter(|(_, d)| d.stereo) {
            for e in 0..2 {
                let alone = draw(&single_eye(&rig, d, e)).remove(0);
                let actual = half(&stereo[d], e as u32);
                let name = format!("half-{preset}-{}-eye{e}-msaa{samples}", display.name);
                assert_images_match(&name, &actual, &alone, EDGES);
            }
        }
    }
}

/// A left eye looking at a floor that runs far past its right edge, and a right eye
/// whose window looks above the horizon where there is nothing: any non-clear pixel in
/// the right half leaked across the seam.
fn leak_rig() -> (Scene, Rig) {
    let mut scene = scene_spec::load("procedural:1:1").unwrap();
    scene.instances[0].world_from_local = glam::Affine3A::from_scale_rotation_translation(
        Vec3::new(400.0, 0.5, 400.0),
        glam::Quat::IDENTITY,
        Vec3::ZERO,
    );
    let mut rig = sized("hmd");
    let Mount::Head(head) = &mut rig.displays[0].mount else {
        panic!("hmd is head-fixed")
    };
    head.fov_right = Some(Fov {
        left: 1.0,
        right: 1.0,
        up: 1.0,
        down: -0.5,
    });
    (scene, rig)
}

fn assert_no_leak(gpu: &Gpu, label: &str) {
    for samples in [1, 4] {
        assert_no_leak_at(gpu, &format!("{label}-msaa{samples}"), samples);
    }
}

fn assert_no_leak_at(gpu: &Gpu, label: &str, samples: u32) {
    let (scene, rig) = leak_rig();
    let options = options(CullMode::Gpu, StereoMode::Instanced, samples);
    let image = support::render(gpu, &scene, &rig, options.clone())
        .unwrap()
        .remove(0);
    let clear = *image.get_pixel(2 * W - 1, 0);
    let left_drawn = half(&image, 0).pixels().filter(|p| **p != clear).count();
    assert!(
        left_drawn as u32 > W * H / 4,
        "{label}: the left eye should see the floor ({left_drawn} px)"
    );
    let blank = RgbaImage::from_pixel(W, H, clear);
    // Exact on any CPU: pixel centers lie half a pixel from the seam, farther than any
    // rounding of the clip distance (or the discard) can move it.
    assert_images_match(
        &format!("leak-{label}"),
        &half(&image, 1),
        &blank,
        Tolerance::EXACT,
    );
}

#[test]
fn nothing_of_one_eye_leaks_into_the_other_half_with_clip_distances() {
    let gpu = gpu_with(wgpu::Features::all());
    assert!(
        gpu.device
            .features()
            .contains(wgpu::Features::CLIP_DISTANCES),
        "lavapipe has clip distances"
    );
    assert_no_leak(&gpu, "clip-distances");
}

#[test]
fn nothing_of_one_eye_leaks_into_the_other_half_with_the_discard_fallback() {
    let gpu = gpu_with(wgpu::Features::all() - wgpu::Features::CLIP_DISTANCES);
    assert_no_leak(&gpu, "discard");
}

#[test]
fn gpu_and_cpu_culling_give_identical_images() {
    let gpu = gpu_with(wgpu::Features::all());
    let scene = scene_spec::load("procedural:3000:12").unwrap();
    for preset in ["hmd", "cave"] {
        let rig = sized(preset);
        let on_gpu = render(&gpu, &scene, &rig, CullMode::Gpu);
        let on_cpu = render(&gpu, &scene, &rig, CullMode::Cpu);
        // Exact on any CPU: the culls are byte-identical, so the same pipeline draws the
        // same draws.
        for (d, (a, b)) in on_gpu.iter().zip(&on_cpu).enumerate() {
            assert_images_match(&format!("cull-{preset}-{d}"), a, b, Tolerance::EXACT);
        }
    }
}

/// Center of the pixels `is_color` picks, in half `eye`.
fn centroid(
    image: &RgbaImage,
    eye: u32,
    is_color: impl Fn(&image::Rgba<u8>) -> bool,
) -> Option<f32> {
    let h = half(image, eye);
    let xs: Vec<f32> = h
        .enumerate_pixels()
        .filter(|(_, _, p)| is_color(p))
        .map(|(x, _, _)| x as f32)
        .collect();
    (!xs.is_empty()).then(|| xs.iter().sum::<f32>() / xs.len() as f32)
}

#[test]
fn a_near_object_sits_further_right_in_the_left_eye() {
    let gpu = gpu_with(wgpu::Features::all());
    // The room's yellow torus floats 0.8 m in front of the hmd viewer.
    let image = render(
        &gpu,
        &scene_spec::load("default").unwrap(),
        &sized("hmd"),
        CullMode::Gpu,
    )
    .remove(0);
    // Yellow by hue, whatever the shading's brightness: red and green well above blue.
    let yellow = |p: &image::Rgba<u8>| {
        let [r, g, b] = [p[0], p[1], p[2]].map(f32::from);
        r > 100.0 && g > 90.0 && b < 0.45 * g
    };
    let (left, right) = (centroid(&image, 0, yellow), centroid(&image, 1, yellow));
    let (left, right) = (
        left.expect("torus in the left half"),
        right.expect("torus in the right half"),
    );
    eprintln!("torus center: left eye x = {left:.1}, right eye x = {right:.1}");
    assert!(
        left > right + 5.0,
        "disparity has the wrong sign: {left} vs {right}"
    );
}

/// Every stereo mode draws the same images as `instanced`. Multi-camera culls per eye
/// and the others per display, which changes nothing visible (culling is conservative).
/// The classic modes' per-eye viewports round like the single-eye renders above
/// (measured: 0 pixels differ). Multiview gets 0.15 %: lavapipe's multiview path clips
/// triangles that cross the near plane (the room's long side walls) a pixel differently
/// along one edge (measured: 58 and 77 pixels of 96,000, on hmd and on hmd-peripheral).
/// Renders `rig` in `mode` on `gpu` (CPU-culled where the mode draws per instance) and
/// checks every display against `reference` within `tolerance`. `label` names the case
/// in the log and the failure images.
fn assert_mode_matches(
    gpu: &Gpu,
    (scene, rig): (&Scene, &Rig),
    (mode, samples): (StereoMode, u32),
    reference: &[RgbaImage],
    tolerance: Tolerance,
    label: &str,
) {
    let cull = support::cull_for(mode);
    let images = support::render(gpu, scene, rig, options(cull, mode, samples)).unwrap();
    for (d, (actual, want)) in images.iter().zip(reference).enumerate() {
        let name = format!("{label}-{d}-{}", mode.name());
        assert_images_match(&name, actual, want, tolerance);
    }
}

#[test]
fn every_stereo_mode_agrees_with_instanced() {
    let gpu = gpu_with(wgpu::Features::all());
    let scene = scene_spec::load("default").unwrap();
    for preset in ["hmd", "hmd-peripheral"] {
        let rig = sized(preset);
        let reference = render(&gpu, &scene, &rig, CullMode::Gpu);
        for mode in StereoMode::ALL {
            let label = format!("mode-{preset}");
            let case = (&scene, &rig);
            assert_mode_matches(&gpu, case, (mode, 1), &reference, tolerance(mode), &label);
        }
    }
}

/// With the frame's shadow map on, every mode samples the same map: the images agree
/// as without it (and shadows show: the image differs from the unshadowed one).
#[test]
fn every_stereo_mode_agrees_with_instanced_with_shadows() {
    let gpu = gpu_with(wgpu::Features::all());
    let scene = scene_spec::load("default").unwrap();
    let rig = sized("hmd");
    let with_shadows = |mode| RendererOptions {
        shadows: true,
        ..options(support::cull_for(mode), mode, 1)
    };
    let render = |mode| support::render(&gpu, &scene, &rig, with_shadows(mode)).unwrap();
    let reference = render(StereoMode::Instanced);
    let plain = support::render(
        &gpu,
        &scene,
        &rig,
        options(CullMode::Gpu, StereoMode::Instanced, 1),
    );
    let darker = reference[0]
        .pixels()
        .zip(plain.unwrap()[0].pixels())
        .filter(|(s, p)| {
            let sum = |c: &[u8]| c.iter().map(|&v| v as u32).sum::<u32>();
            sum(&s.0[..3]) + 30 < sum(&p.0[..3])
        })
        .count();
    assert!(darker > 100, "{darker} pixels in shadow");
    for mode in StereoMode::ALL {
        for (d, (actual, want)) in render(mode).iter().zip(&reference).enumerate() {
            let name = format!("shadows-hmd-{d}-{}", mode.name());
            assert_images_match(&name, actual, want, tolerance(mode));
        }
    }
}

/// wgpu's GL backend over Mesa's llvmpipe (needs `libegl1` and `libgl1-mesa-dri`, which
/// `.ci/run` installs): no indirect count and no multiview there, so this also runs the
/// fixed-count fallback on a second API. Every mode it has draws the Vulkan image
/// (measured: 0 pixels differ).
#[cfg(feature = "gl")]
#[test]
fn the_gl_backend_draws_the_vulkan_image() {
    let gl = support::gpu_on(Some(wgpu::Backends::GL), wgpu::Features::all());
    assert!(
        !gl.device
            .features()
            .contains(wgpu::Features::MULTI_DRAW_INDIRECT_COUNT),
        "GL has no indirect count, so the fixed-count fallback runs here"
    );
    let vulkan = gpu_with(wgpu::Features::all());
    let scene = scene_spec::load("default").unwrap();
    for preset in ["hmd", "cave"] {
        let rig = sized(preset);
        let reference = render(&vulkan, &scene, &rig, CullMode::Gpu);
        let modes = StereoMode::ALL
            .into_iter()
            .filter(|m| *m != StereoMode::Multiview);
        for mode in modes {
            let label = format!("gl-{preset}");
            assert_mode_matches(&gl, (&scene, &rig), (mode, 1), &reference, EDGES, &label);
        }
    }
}

/// An instance animated on the GPU (spin and bob from the frame context's time) draws
/// where a still instance posed on the CPU at that time draws: same pixels within the
/// edge tolerance (sin and cos are the GPU's there, glam's here). At time 0 the pose
/// differs, so the comparison sees the motion.
#[test]
fn an_animated_instance_draws_where_its_pose_at_that_time_does() {
    let gpu = gpu_with(wgpu::Features::all());
    let rig = sized("hmd");
    let mut animated = scene_spec::load("procedural:1:8:3").unwrap();
    let motion = Animation {
        spin: 1.3,
        bob: 0.4,
    };
    {
        let inst = &mut animated.instances[0];
        inst.mesh = 4; // a box with three different sides: no spin symmetry
        inst.world_from_local = glam::Affine3A::from_scale_rotation_translation(
            Vec3::splat(0.8),
            glam::Quat::from_rotation_x(0.4),
            Vec3::new(0.2, 1.3, -1.0),
        );
        inst.animation = motion;
    }
    let t = 0.7;
    let mut posed = animated.clone();
    let inst = &mut posed.instances[0];
    let lift =
        glam::Affine3A::from_translation(Vec3::Y * motion.bob * (std::f32::consts::PI * t).sin());
    let spin = glam::Affine3A::from_rotation_y(motion.spin * t);
    inst.world_from_local = lift * inst.world_from_local * spin;
    inst.animation = Animation::NONE;
    let options = RendererOptions::default();
    let moving = support::render_at(&gpu, &animated, &rig, options.clone(), t).unwrap();
    let still = support::render_at(&gpu, &posed, &rig, options.clone(), t).unwrap();
    assert_images_match("animated-at-t", &moving[0], &still[0], EDGES);
    let at_zero = support::render_at(&gpu, &animated, &rig, options.clone(), 0.0).unwrap();
    let moved = at_zero[0]
        .pixels()
        .zip(still[0].pixels())
        .filter(|(a, b)| a != b)
        .count();
    assert!(
        moved > 200,
        "the pose at t = {t} should differ from t = 0: {moved} px"
    );
}

/// Under 4x MSAA every stereo mode still draws the `instanced` image on stereo and mono
/// displays (multiview on multisampled two-layer targets, multi-pass resolving after
/// each eye's pass), and the image is antialiased: it differs from the 1x image only
/// along edges.
#[test]
fn every_stereo_mode_agrees_with_instanced_under_msaa() {
    let gpu = gpu_with(wgpu::Features::all());
    let scene = scene_spec::load("default").unwrap();
    for preset in ["hmd", "hmd-peripheral"] {
        assert_modes_agree_under_msaa(&gpu, &scene, &sized(preset), preset);
    }
}

/// Every mode against `instanced` at 4x on `rig`, and 4x against 1x on display 0.
fn assert_modes_agree_under_msaa(gpu: &Gpu, scene: &Scene, rig: &Rig, label: &str) {
    let draw = |mode, samples| {
        let cull = if mode == StereoMode::Instanced {
            CullMode::Gpu
        } else {
            CullMode::Cpu
        };
        support::render(gpu, scene, rig, options(cull, mode, samples)).unwrap()
    };
    let reference = draw(StereoMode::Instanced, 4);
    for mode in StereoMode::ALL {
        let name = format!("msaa-{label}");
        let case = (scene, rig);
        assert_mode_matches(gpu, case, (mode, 4), &reference, tolerance(mode), &name);
    }
    let aliased = draw(StereoMode::Instanced, 1).remove(0);
    let edges = reference[0]
        .pixels()
        .zip(aliased.pixels())
        .filter(|(a, b)| a != b)
        .count();
    let share = edges as f64 / (aliased.width() * aliased.height()) as f64;
    eprintln!(
        "4x MSAA changes {edges} pixels ({:.2} %) of the 1x image",
        100.0 * share
    );
    assert!(
        edges > 500 && share < 0.15,
        "{edges} pixels changed by MSAA"
    );
}

/// A process drawing a subset of a rig's displays (`Rig::subset`, one process per CAVE
/// wall) draws each of them as the full rig does: the shadow map is fitted to the whole
/// rig and the levels of detail chosen for it.
#[test]
fn a_subset_of_displays_draws_as_the_full_rig() {
    let gpu = gpu_with(wgpu::Features::all());
    let scene = scene_spec::load("procedural:3000:8:5").unwrap();
    for (preset, names) in [
        ("cave", ["left", "floor"]),
        ("hmd-peripheral", ["peripheral-right", "center"]),
    ] {
        let rig = support::sized(preset, 64, 64);
        let names = names.map(String::from);
        let subset = rig.subset(&names, preset).unwrap();
        let options = RendererOptions {
            shadows: true,
            lod: true,
            ..options(CullMode::Gpu, StereoMode::Instanced, 1)
        };
        let full = support::render(&gpu, &scene, &rig, options.clone()).unwrap();
        let part = support::render(&gpu, &scene, &subset, options).unwrap();
        for (k, d) in subset.displays.iter().enumerate() {
            let i = rig.displays.iter().position(|x| x.name == d.name).unwrap();
            // Exact on any CPU: the same plan for this display (tests/frame_plan.rs), so
            // the same pipelines draw the same draws from the same contexts and shadow map.
            let name = format!("subset-{preset}-{}", d.name);
            assert_images_match(&name, &part[k], &full[i], Tolerance::EXACT);
        }
    }
}
