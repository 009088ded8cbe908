//! Foveated stereo: four views per display (outer pair, inset pair) in one target and
//! one indirect pass, insets following a gaze, runtime-style posed quad views, and the
//! composite of each eye's inset over its outer view.

mod support;

use glam::DQuat;
use image::{RgbaImage, imageops};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use stereocull::foveated_composite::{CompositeParams, FoveatedComposite, composite_cpu};
use stereocull::frustum::{Fov, sphere_in_planes};
use stereocull::readback::read_rgba8;
use stereocull::renderer::{CullMode, RendererOptions, StereoMode};
use stereocull::rig::{Foveation, Gaze, Mount, Rig};
use stereocull::scene_spec;
use support::{Tolerance, assert_images_match, gpu, sized};

/// The outer views are drawn by other placement constants than a stereo target's (a
/// quarter of a four-view target instead of half of a double-wide one) and clipped by
/// four planes instead of one: the same triangles, but a clip position's last bit can
/// differ, flipping the coverage of a pixel that an edge passes within a rounding step
/// of its center (and its neighbour's depth test with it). Colors are computed from the
/// same pixel and depth, so only edge pixels differ: at most 0.3 % of them, any amount.
/// Measured on this host (AMD EPYC / Intel Xeon, llvmpipe): see the eprintln counts.
const PLACED: Tolerance = Tolerance {
    levels: 0,
    share: 0.003,
};

fn options(cull: CullMode) -> RendererOptions {
    RendererOptions {
        cull,
        mode: StereoMode::Instanced,
        ..Default::default()
    }
}

fn foveated(width: u32, height: u32) -> Rig {
    sized("hmd-foveated", width, height)
}

fn crop(image: &RgbaImage, [x, y, w, h]: [u32; 4]) -> RgbaImage {
    imageops::crop_imm(image, x, y, w, h).to_image()
}

fn drawn_pixels(image: &RgbaImage) -> usize {
    image.pixels().filter(|p| **p != image[(0, 0)]).count()
}

/// The outer pair of a foveated display, against the same rig without foveation at the
/// outer views' resolution.
#[test]
fn the_outer_views_draw_what_stereo_draws_at_the_outer_resolution() {
    let gpu = gpu();
    let scene = scene_spec::load("procedural:3000:8").unwrap();
    let rig = foveated(192, 160);
    let layout = rig.displays[0].layout();
    let [_, _, w, h] = layout.viewports[0];
    let mut stereo = rig.clone();
    stereo.displays[0].foveation = None;
    stereo.displays[0].resolution = [w, h];
    for cull in [CullMode::Gpu, CullMode::Cpu] {
        let four = support::render(&gpu, &scene, &rig, options(cull)).unwrap();
        let two = support::render(&gpu, &scene, &stereo, options(cull)).unwrap();
        let outer = crop(&four[0], [0, 0, 2 * w, h]);
        assert!(drawn_pixels(&outer) > (2 * w * h / 4) as usize);
        assert_images_match(&format!("foveated-outer-{cull:?}"), &outer, &two[0], PLACED);
    }
}

/// The insets, against a stereo rig whose eyes look through the inset windows at the
/// insets' resolution; with a gaze that moves them off the eyes' axes.
#[test]
fn the_insets_draw_what_stereo_draws_through_the_inset_windows() {
    let gpu = gpu();
    let scene = scene_spec::load("procedural:3000:8").unwrap();
    for gaze in [None, Some(Gaze::both(8.0, -5.0))] {
        let mut rig = foveated(192, 160);
        rig.displays[0].foveation.as_mut().unwrap().gaze = gaze;
        let resolved = rig.resolve().unwrap();
        let insets = &resolved.displays[0].eyes[2..];
        let layout = rig.displays[0].layout();
        let [x, _, w, h] = layout.viewports[2];
        let mut stereo = rig.clone();
        stereo.displays[0].foveation = None;
        stereo.displays[0].resolution = [w, h];
        let Mount::Head(panel) = &mut stereo.displays[0].mount else {
            panic!("hmd is head-fixed");
        };
        panel.fov = insets[0].fov;
        panel.fov_right = Some(insets[1].fov);
        let four = support::render(&gpu, &scene, &rig, options(CullMode::Gpu)).unwrap();
        let two = support::render(&gpu, &scene, &stereo, options(CullMode::Gpu)).unwrap();
        let inner = crop(&four[0], [x, 0, 2 * w, h]);
        assert!(drawn_pixels(&inner) > (2 * w * h / 4) as usize);
        let name = format!("foveated-insets-{}", gaze.is_some());
        assert_images_match(&name, &inner, &two[0], PLACED);
    }
}

/// Colors each fragment by its view: what lands in a viewport must be that view's.
const BY_VIEW: &str = "
fn material(s: Surface) -> vec4<f32> {
    return vec4(f32(s.eye) / 3.0, 1.0 - f32(s.eye) / 3.0, 0.25, 1.0);
}
";

#[test]
fn every_view_stays_in_its_viewport() {
    let with = wgpu::Features::all();
    views_stay_in_their_viewports(&support::gpu_with(with));
    // Without clip distances a fragment outside its view's viewport is discarded.
    views_stay_in_their_viewports(&support::gpu_with(with - wgpu::Features::CLIP_DISTANCES));
}

fn views_stay_in_their_viewports(gpu: &stereocull::device::Gpu) {
    let scene = scene_spec::load("procedural:4000:8").unwrap();
    let rig = foveated(160, 120);
    let layout = rig.displays[0].layout();
    let options = RendererOptions {
        material: Some(BY_VIEW.into()),
        ..options(CullMode::Gpu)
    };
    let image = &support::render(gpu, &scene, &rig, options).unwrap()[0];
    assert_eq!(image.dimensions(), layout.size);
    let clear = image[(layout.size.0 - 1, layout.size.1 - 1)];
    let mut colors = Vec::new();
    for (view, viewport) in layout.viewports().iter().enumerate() {
        let pixels = crop(image, *viewport);
        let mut seen: Vec<_> = pixels.pixels().filter(|p| **p != clear).collect();
        seen.sort_by_key(|p| p.0);
        seen.dedup();
        assert_eq!(
            seen.len(),
            1,
            "view {view} holds one view's color: {seen:?}"
        );
        colors.push(*seen[0]);
    }
    colors.dedup();
    assert_eq!(colors.len(), 4, "four views, four colors: {colors:?}");
    // Below the shorter insets the target stays clear.
    let [x, _, w, h] = layout.viewports[2];
    let below = crop(image, [x, h, 2 * w, layout.size.1 - h]);
    assert!(
        below.pixels().all(|p| *p == clear),
        "an inset leaked below itself"
    );
}

/// Four views: every visible object four times in the draws, GPU as CPU to the byte.
#[test]
fn four_views_cull_gpu_as_cpu() {
    let gpu = gpu();
    let scene = scene_spec::load("procedural:5000:8").unwrap();
    let rig = foveated(64, 64);
    let renderer = support::one_frame(&gpu, &scene, &rig, options(CullMode::Gpu));
    let culls = support::read_culls(&gpu, &renderer, &rig);
    let reference = support::reference_culls(&scene, &rig);
    assert_eq!(culls, reference);
    let cull = &culls[0];
    assert!(cull.visible.len() > 100);
    let drawn = &cull.draws[..cull.draw_count as usize];
    assert!(
        drawn
            .iter()
            .all(|d| d.instance_count % 4 == 0 && d.first_instance % 4 == 0)
    );
    let instances: u32 = drawn.iter().map(|d| d.instance_count).sum();
    assert_eq!(instances as usize, 4 * cull.visible.len());
}

/// One indirect pass per display, one multi-draw: the frame's draw calls.
#[test]
fn a_foveated_display_is_one_draw_call() {
    let gpu = gpu();
    let scene = scene_spec::load("procedural:2000:8").unwrap();
    let rig = foveated(64, 64);
    let mut renderer =
        stereocull::Renderer::new(&gpu.device, &scene, &rig, options(CullMode::Gpu)).unwrap();
    let targets = renderer.create_targets(&gpu.device);
    let stats = renderer
        .submit_frame(&gpu.device, &gpu.queue, &rig, 0.0, &targets)
        .unwrap();
    assert_eq!(stats.draw_calls, 1);
}

#[test]
fn the_inset_follows_the_gaze_and_stays_inside() {
    let mut rng = Pcg64Mcg::seed_from_u64(23);
    let window = Fov {
        left: 1.19,
        right: 0.84,
        up: 1.11,
        down: 1.19,
    };
    for _ in 0..500 {
        let gaze = Gaze {
            left: [rng.random_range(-60.0..60.0), rng.random_range(-60.0..60.0)],
            right: [rng.random_range(-60.0..60.0), rng.random_range(-60.0..60.0)],
        };
        let f = Foveation {
            gaze: Some(gaze),
            ..Default::default()
        };
        for eye in 0..2 {
            let (inset, clamped) = f.inset(window, eye);
            let tangents = |f: Fov| [f.left, f.right, f.up, f.down];
            let [l, r, u, d] = tangents(inset);
            assert!(
                -l >= -window.left - 1e-6 && r <= window.right + 1e-6,
                "{inset:?}"
            );
            assert!(
                -d >= -window.down - 1e-6 && u <= window.up + 1e-6,
                "{inset:?}"
            );
            // The inset's share of the window, wherever it is.
            let width = (l + r) / (window.left + window.right);
            let height = (u + d) / (window.up + window.down);
            assert!((width - 0.35).abs() < 1e-5 && (height - 0.35).abs() < 1e-5);
            // Unclamped, its center is where the gaze meets the image plane.
            let [yaw, pitch] = if eye == 0 { gaze.left } else { gaze.right };
            let q = DQuat::from_euler(
                glam::EulerRot::YXZ,
                (yaw as f64).to_radians(),
                (pitch as f64).to_radians(),
                0.0,
            );
            let dir = q * glam::DVec3::NEG_Z;
            let (cx, cy) = (dir.x / -dir.z, dir.y / -dir.z);
            let center = (0.5 * (r - l) as f64, 0.5 * (u - d) as f64);
            let at_gaze = (center.0 - cx).abs() < 1e-5 && (center.1 - cy).abs() < 1e-5;
            assert_eq!(at_gaze, !clamped, "{gaze:?} eye {eye}: {inset:?}");
        }
    }
    // Fixed foveation: centered on the eye's axis, larger.
    let (inset, clamped) = Foveation::default().inset(window, 0);
    assert!(!clamped);
    assert!((inset.left - inset.right).abs() < 1e-6 && (inset.up - inset.down).abs() < 1e-6);
    assert!(((inset.left + inset.right) / (window.left + window.right) - 0.5).abs() < 1e-6);
}

#[test]
fn the_gaze_moves_the_insets_of_a_frame() {
    let mut rig = foveated(64, 64);
    rig.set_gaze(Gaze::both(0.0, 0.0)).unwrap();
    let ahead = rig.resolve().unwrap();
    rig.set_gaze(Gaze::both(15.0, 10.0)).unwrap();
    let turned = rig.resolve().unwrap();
    let (a, b) = (&ahead.displays[0], &turned.displays[0]);
    assert_eq!(
        a.eyes[..2],
        b.eyes[..2],
        "the outer views do not follow the gaze"
    );
    for e in 2..4 {
        // Left and up: the window's left edge grows, its right edge shrinks.
        assert!(b.eyes[e].fov.left > a.eyes[e].fov.left);
        assert!(b.eyes[e].fov.up > a.eyes[e].fov.up);
    }
    assert!(!b.gaze_clamped);
    rig.set_gaze(Gaze::both(70.0, 0.0)).unwrap();
    assert!(rig.resolve().unwrap().displays[0].gaze_clamped);
    let mut plain = sized("hmd", 64, 64);
    let err = plain.set_gaze(Gaze::both(1.0, 1.0)).unwrap_err();
    assert!(err.contains("no foveated display"), "{err}");
}

#[test]
fn posed_quad_views_draw_what_the_head_fixed_foveated_rig_draws() {
    let head = foveated(128, 96);
    let posed = head.as_posed().unwrap();
    posed.validate("posed").unwrap();
    let (a, b) = (posed.resolve().unwrap(), head.resolve().unwrap());
    for (x, y) in a.displays[0].eyes.iter().zip(&b.displays[0].eyes) {
        let (x, y) = (x.clip_from_world(), y.clip_from_world());
        assert!(x.abs_diff_eq(y, 1e-5), "{x} against {y}");
    }
    let gpu = gpu();
    let scene = scene_spec::load("procedural:2000:8").unwrap();
    let one = support::render(&gpu, &scene, &posed, options(CullMode::Gpu)).unwrap();
    let two = support::render(&gpu, &scene, &head, options(CullMode::Gpu)).unwrap();
    assert!(drawn_pixels(&one[0]) > one[0].len() / 40);
    // The windows come back from atan and tan a bit off (no tangents are chosen to
    // round-trip here): the same pipeline, projections a rounding step apart.
    assert_images_match("posed-quad-views", &one[0], &two[0], PLACED);
}

#[test]
fn bad_foveated_views_are_clear_errors() {
    let check = |rig: &Rig, want: &str| {
        let err = rig.validate("test").unwrap_err().to_string();
        assert!(err.contains(want), "{err} lacks {want:?}");
        assert!(err.contains("hmd"), "{err} names the display");
    };
    let mut outside = foveated(64, 64).as_posed().unwrap();
    if let Mount::Views(v) = &mut outside.displays[0].mount {
        v[2].fov.angle_left = -1.4;
    }
    check(
        &outside,
        "views[2]: the inset is not inside its eye's outer view",
    );
    let mut three = foveated(64, 64).as_posed().unwrap();
    if let Mount::Views(v) = &mut three.displays[0].mount {
        v.pop();
    }
    check(&three, "views: 3 given, the display has 4");
    let mut mono = foveated(64, 64);
    mono.displays[0].stereo = false;
    check(&mono, "foveation needs a stereo display");
    let mut gaze = foveated(64, 64);
    gaze.set_gaze(Gaze::both(f32::NAN, 0.0)).unwrap();
    check(&gaze, "foveation.gaze");
    gaze.set_gaze(Gaze::both(0.0, 89.5)).unwrap();
    check(&gaze, "under 89 degrees");
    let mut density = foveated(64, 64);
    density.displays[0]
        .foveation
        .as_mut()
        .unwrap()
        .peripheral_density = 0.0;
    check(&density, "densities must be in (0, 4]");
    let mut share = foveated(64, 64);
    share.displays[0].foveation.as_mut().unwrap().inset_fixed = [0.5, 1.5];
    check(&share, "foveation.inset_fixed");
}

/// The classic modes draw the four views too, each view's draws in its own viewport
/// (the pass's), and give the instanced image: the same shading from a pipeline
/// compiled apart (one view per context, no placement): `PLACED`.
#[test]
fn every_mode_draws_the_foveated_image() {
    let gpu = gpu();
    let scene = scene_spec::load("procedural:2000:8").unwrap();
    let mut rig = foveated(128, 96);
    rig.set_gaze(Gaze::both(-6.0, 3.0)).unwrap();
    let reference = &support::render(&gpu, &scene, &rig, options(CullMode::Gpu)).unwrap()[0];
    assert!(drawn_pixels(reference) > reference.len() / 40);
    for mode in [
        StereoMode::MultiCamera,
        StereoMode::MultiPass,
        StereoMode::SinglePass,
    ] {
        let options = RendererOptions {
            mode,
            cull: CullMode::Cpu,
            ..Default::default()
        };
        let image = &support::render(&gpu, &scene, &rig, options).unwrap()[0];
        assert_images_match(
            &format!("foveated-{}", mode.name()),
            image,
            reference,
            PLACED,
        );
    }
}

/// Multiview needs as many views as the display has; a device with fewer says so.
#[test]
fn multiview_names_the_view_limit_it_lacks() {
    let rig = foveated(64, 64);
    let options = RendererOptions {
        mode: StereoMode::Multiview,
        ..Default::default()
    };
    let err = stereocull::renderer::check_rig(&rig, &options, 2)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("max_multiview_view_count >= 4") && err.contains("hmd"),
        "{err}"
    );
    stereocull::renderer::check_rig(&rig, &options, 4).unwrap();
    let instanced = RendererOptions::default();
    stereocull::renderer::check_rig(&rig, &instanced, 2).unwrap();
}

/// Random colors in a foveated target's layout, composited on the GPU and by the CPU
/// twin: the same f32 arithmetic on linear values, read with textureLoad. The two may
/// round a channel one level apart: llvmpipe encodes sRGB with its own approximation
/// (within half a level of the exact curve the twin uses), and LLVM may contract the
/// mixes into FMAs.
#[test]
fn the_composite_matches_its_cpu_twin() {
    let gpu = gpu();
    let mut rng = Pcg64Mcg::seed_from_u64(5);
    for round in 0..3 {
        let mut rig = foveated(96, 80);
        let gaze = [rng.random_range(-30.0..30.0), rng.random_range(-30.0..30.0)];
        rig.set_gaze(Gaze::both(gaze[0], gaze[1])).unwrap();
        let layout = rig.displays[0].layout();
        let params = CompositeParams::of_display(&rig, 0, &layout)
            .unwrap()
            .unwrap();
        let source = RgbaImage::from_fn(layout.size.0, layout.size.1, |_, _| {
            image::Rgba([rng.random(), rng.random(), rng.random(), 255])
        });
        let format = wgpu::TextureFormat::Rgba8UnormSrgb;
        let texture = upload(&gpu, &source, format);
        let output = FoveatedComposite::create_output(&gpu.device, &params, format);
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        FoveatedComposite::new(&gpu.device, format).encode(
            &gpu.device,
            &mut encoder,
            &texture.create_view(&Default::default()),
            &params,
            &output.create_view(&Default::default()),
        );
        gpu.queue.submit([encoder.finish()]);
        let actual = read_rgba8(&gpu.device, &gpu.queue, &output).unwrap();
        let expected = composite_cpu(&source, &params);
        assert_eq!(actual.dimensions(), (192, 80));
        let one_level = Tolerance {
            levels: 1,
            share: 0.0,
        };
        assert_images_match(&format!("composite-{round}"), &actual, &expected, one_level);
    }
}

/// The composite puts each inset where its window lies in its eye's image: composited
/// from a target whose insets are white and outer views black, the white part is the
/// inset's window, faded at its border.
#[test]
fn the_composite_places_the_inset_over_its_window() {
    let mut rig = foveated(200, 160);
    rig.set_gaze(Gaze::both(10.0, 5.0)).unwrap();
    let layout = rig.displays[0].layout();
    let params = CompositeParams::of_display(&rig, 0, &layout)
        .unwrap()
        .unwrap();
    let inset_x = layout.viewports[2][0];
    let source = RgbaImage::from_fn(layout.size.0, layout.size.1, |x, _| {
        let v = if x >= inset_x { 255 } else { 0 };
        image::Rgba([v, v, v, 255])
    });
    let out = composite_cpu(&source, &params);
    let resolved = rig.resolve().unwrap();
    for eye in 0..2 {
        let (outer, inset) = (
            resolved.displays[0].eyes[eye].fov,
            resolved.displays[0].eyes[eye + 2].fov,
        );
        // The inset window's center and a point outside it, in the eye's pixels.
        let to_pixel = |tx: f32, ty: f32| {
            let u = (tx + outer.left) / (outer.left + outer.right);
            let v = (outer.up - ty) / (outer.up + outer.down);
            (eye as u32 * 200 + (u * 200.0) as u32, (v * 160.0) as u32)
        };
        let center = to_pixel(
            0.5 * (inset.right - inset.left),
            0.5 * (inset.up - inset.down),
        );
        assert_eq!(
            out[center][0], 255,
            "eye {eye}: the inset's center is the inset"
        );
        let beside = to_pixel(-inset.left - 0.05, 0.5 * (inset.up - inset.down));
        assert_eq!(
            out[beside][0], 0,
            "eye {eye}: left of the inset is the outer view"
        );
    }
}

fn upload(
    gpu: &stereocull::device::Gpu,
    image: &RgbaImage,
    format: wgpu::TextureFormat,
) -> wgpu::Texture {
    use wgpu::util::DeviceExt;
    gpu.device.create_texture_with_data(
        &gpu.queue,
        &wgpu::TextureDescriptor {
            label: Some("test.source"),
            size: wgpu::Extent3d {
                width: image.width(),
                height: image.height(),
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        image.as_raw(),
    )
}

fn inset_culled(cull: CullMode) -> RendererOptions {
    RendererOptions {
        inset_cull: true,
        ..options(cull)
    }
}

/// With the inset cull the insets draw from their own cull (a second multi-draw in the
/// same pass), and the image is the one-draw image. Not to the byte: the inset pair is
/// drawn by a pipeline compiled apart (two views per object, not four), and in another
/// order, so a clip position's last bit or an exact depth tie can differ on an edge
/// pixel (`PLACED`).
#[test]
fn the_inset_cull_draws_what_four_views_draw() {
    let gpu = gpu();
    let scene = scene_spec::load("procedural:4000:8").unwrap();
    for gaze in [None, Some(Gaze::both(-12.0, 6.0))] {
        let mut rig = foveated(192, 160);
        rig.displays[0].foveation.as_mut().unwrap().gaze = gaze;
        for cull in [CullMode::Gpu, CullMode::Cpu] {
            let one = support::render(&gpu, &scene, &rig, options(cull)).unwrap();
            let two = support::render(&gpu, &scene, &rig, inset_culled(cull)).unwrap();
            assert!(drawn_pixels(&one[0]) > one[0].len() / 40);
            let name = format!("inset-cull-{cull:?}-{}", gaze.is_some());
            assert_images_match(&name, &two[0], &one[0], PLACED);
        }
    }
}

/// The inset cull keeps what meets the insets' frustum, no more: GPU as CPU to the
/// byte, a subset of the display's, two instances per object, and fewer objects than the
/// display frustum keeps (the insets see less); the display's own cull then draws the
/// outer pair only (two per object).
#[test]
fn the_inset_cull_is_exact_and_smaller() {
    let gpu = gpu();
    let scene = scene_spec::load("procedural:20000:8").unwrap();
    let mut rig = foveated(64, 64);
    rig.set_gaze(Gaze::both(5.0, 0.0)).unwrap();
    let renderer = support::one_frame(&gpu, &scene, &rig, inset_culled(CullMode::Gpu));
    let diagnostics = renderer.diagnostics(&gpu.device, &gpu.queue);
    let (display, inset) = (
        diagnostics.cull(0).unwrap(),
        diagnostics.inset_cull(0).unwrap().unwrap(),
    );
    let plan = renderer.plan(&rig, 0.0).unwrap();
    let layout = stereocull::records::CullLayout::new(&scene);
    let jobs: Vec<_> = plan.inset_culls().iter().map(|c| c.job.clone()).collect();
    let reference = stereocull::cull::cpu::cull_many(&layout, &jobs);
    assert_eq!(inset, reference[0], "GPU inset cull == CPU");
    assert!(inset.visible.iter().all(|id| display.visible.contains(id)));
    assert!(
        inset.visible.len() * 2 < display.visible.len(),
        "{} of {}",
        inset.visible.len(),
        display.visible.len()
    );
    for cull in [&display, &inset] {
        let drawn = &cull.draws[..cull.draw_count as usize];
        let instances: u32 = drawn.iter().map(|d| d.instance_count).sum();
        assert_eq!(instances as usize, 2 * cull.visible.len());
    }
    // Every object whose sphere meets either inset's own frustum is kept.
    let resolved = rig.resolve().unwrap();
    for (id, instance) in scene.instances.iter().enumerate() {
        let sphere = scene.world_sphere(instance);
        let planes = |e: &stereocull::frustum::View| e.frustum().planes;
        let eyes = &resolved.displays[0].eyes[2..];
        let seen = eyes.iter().any(|e| sphere_in_planes(&planes(e), sphere));
        if seen {
            assert!(
                inset.visible.contains(&(id as u32)),
                "instance {id} in an inset, not kept"
            );
        }
    }
}

/// One pass, two multi-draws (the outer pair's, the insets'), two culls: with the rig
/// cull, two members of its one set of dispatches; without, a cull pass each.
#[test]
fn the_inset_cull_adds_one_cull_and_one_draw() {
    let gpu = gpu();
    let scene = scene_spec::load("procedural:2000:8").unwrap();
    let rig = foveated(64, 64);
    let mut renderer =
        stereocull::Renderer::new(&gpu.device, &scene, &rig, inset_culled(CullMode::Gpu)).unwrap();
    let targets = renderer.create_targets(&gpu.device);
    let stats = renderer
        .submit_frame(&gpu.device, &gpu.queue, &rig, 0.0, &targets)
        .unwrap();
    assert_eq!(stats.draw_calls, 2);
    let names: Vec<_> = renderer.passes().iter().map(|p| p.name).collect();
    assert_eq!(names, ["rig_cull", "draw"]);
    assert_eq!(stats.dispatches, 3, "the rig cull's three for both culls");
    let apart = RendererOptions {
        rig_cull: false,
        ..inset_culled(CullMode::Gpu)
    };
    let mut renderer = stereocull::Renderer::new(&gpu.device, &scene, &rig, apart).unwrap();
    let stats = renderer
        .submit_frame(&gpu.device, &gpu.queue, &rig, 0.0, &targets)
        .unwrap();
    assert_eq!(stats.draw_calls, 2);
    let names: Vec<_> = renderer.passes().iter().map(|p| p.name).collect();
    assert_eq!(names, ["cull", "inset_cull", "draw"]);
    assert_eq!(stats.dispatches, 6);
}

/// Lavapipe's multiview (Mesa 22.3) clips some triangles crossing the near plane a pixel
/// differently, and draws back faces (face culling is off in multiview, see
/// `DrawKey::face_culling`): as `tests/images.rs`'s MULTIVIEW, edge pixels up to 0.3 %.
/// Measured here: 4, 9 and 3 pixels of 7,680 and 15,360 (at most 0.12 %).
const MULTIVIEW: Tolerance = Tolerance {
    levels: 2,
    share: 0.003,
};

/// Multiview draws the four views as four layers of one size (the largest view's): the
/// outer layers are the instanced outer views (the same size), the inset layers a
/// stereo render through the inset windows at the layer size.
#[test]
fn multiview_draws_four_layers() {
    let gpu = gpu();
    let max_views = gpu.device.limits().max_multiview_view_count;
    assert!(max_views >= 4, "lavapipe has {max_views} multiview views");
    let scene = scene_spec::load("procedural:3000:8").unwrap();
    let rig = foveated(192, 160);
    let multiview = RendererOptions {
        mode: StereoMode::Multiview,
        ..options(CullMode::Gpu)
    };
    let layers = &support::render(&gpu, &scene, &rig, multiview).unwrap()[0];
    let layered = rig.displays[0].layout_in(true);
    let [_, _, w, h] = layered.viewports[0];
    assert_eq!(
        layers.dimensions(),
        (4 * w, h),
        "four layers, read back side by side"
    );
    let instanced = &support::render(&gpu, &scene, &rig, options(CullMode::Gpu)).unwrap()[0];
    let packed = rig.displays[0].layout();
    for view in 0..2 {
        let a = crop(layers, layered.viewports[view]);
        let b = crop(instanced, packed.viewports[view]);
        assert_images_match(&format!("multiview-outer-{view}"), &a, &b, MULTIVIEW);
    }
    let resolved = rig.resolve().unwrap();
    let mut stereo = rig.clone();
    stereo.displays[0].foveation = None;
    stereo.displays[0].resolution = [w, h];
    let Mount::Head(panel) = &mut stereo.displays[0].mount else {
        panic!("hmd is head-fixed");
    };
    panel.fov = resolved.displays[0].eyes[2].fov;
    panel.fov_right = Some(resolved.displays[0].eyes[3].fov);
    let insets = &support::render(&gpu, &scene, &stereo, options(CullMode::Gpu)).unwrap()[0];
    let a = crop(layers, [2 * w, 0, 2 * w, h]);
    assert!(drawn_pixels(&a) > (2 * w * h / 4) as usize);
    assert_images_match("multiview-insets", &a, insets, MULTIVIEW);
}
