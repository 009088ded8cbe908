//! The lens's hidden area (`rig::VisibilityMask`): written to depth before the scene,
//! it keeps its pixels the clear color and leaves every other pixel as drawn without
//! it, exactly, side by side and in multiview; its CPU twin counts the pixels it hides.
//! The display's cull drops what it hides in both eyes (`cull::hidden`): only that
//! (every point of a dropped sphere is hidden or outside each eye's window), GPU and
//! CPU alike, and the image outside the mask stays what it is without the mask.

mod support;

use glam::{DVec4, Vec3, Vec4};
use image::RgbaImage;
use rand::{Rng, SeedableRng};
use stereocull::cull::HiddenArea;
use stereocull::device::Gpu;
use stereocull::frustum::View;
use stereocull::renderer::{CullMode, Renderer, RendererOptions, StereoMode};
use stereocull::rig::{Rig, VisibilityMask};
use stereocull::scene::Scene;

/// Whether the center of pixel `(x, y)` of a `size` view lies within `margin` pixels of
/// an edge of one of `view`'s triangles (where rasterization's tie rules decide).
fn near_edge(
    mask: &VisibilityMask,
    view: usize,
    (x, y): (u32, u32),
    size: (u32, u32),
    margin: f32,
) -> bool {
    let to_px = |[u, v]: [f32; 2]| {
        (
            (u + 1.0) / 2.0 * size.0 as f32,
            (1.0 - v) / 2.0 * size.1 as f32,
        )
    };
    let p = (x as f32 + 0.5, y as f32 + 0.5);
    mask.views[view].iter().any(|t| {
        (0..3).any(|i| {
            let (a, b) = (to_px(t[i]), to_px(t[(i + 1) % 3]));
            let (dx, dy) = (b.0 - a.0, b.1 - a.1);
            let len2 = dx * dx + dy * dy;
            let s = (((p.0 - a.0) * dx + (p.1 - a.1) * dy) / len2).clamp(0.0, 1.0);
            let (cx, cy) = (a.0 + s * dx - p.0, a.1 + s * dy - p.1);
            (cx * cx + cy * cy).sqrt() < margin
        })
    })
}

fn render(rig: &Rig, mode: StereoMode, mask: bool) -> (RgbaImage, u64) {
    let scene = stereocull::scene_spec::load("default").unwrap();
    let gpu = support::gpu();
    let (image, renderer) = render_scene(&gpu, &scene, rig, (mode, CullMode::Gpu), mask);
    (image, renderer.masked_pixels())
}

/// One frame of `scene` (display 0's image, and the renderer for its culls).
fn render_scene(
    gpu: &Gpu,
    scene: &Scene,
    rig: &Rig,
    (mode, cull): (StereoMode, CullMode),
    mask: bool,
) -> (RgbaImage, Renderer) {
    let options = RendererOptions {
        mode,
        cull,
        sample_count: 1,
        visibility_mask: mask,
        ..support::frustum_only()
    };
    let mut renderer = Renderer::new(&gpu.device, scene, rig, options).unwrap();
    let targets = renderer.create_targets(&gpu.device);
    renderer
        .submit_frame(&gpu.device, &gpu.queue, rig, 0.0, &targets)
        .unwrap();
    let image =
        stereocull::readback::read_rgba8(&gpu.device, &gpu.queue, &targets[0].color).unwrap();
    (image, renderer)
}

/// The point `distance` meters from `eye` along its ray through `ndc`.
fn along(eye: &View, ndc: (f64, f64), distance: f64) -> Vec3 {
    let p = eye.world_from_clip().as_dmat4() * DVec4::new(ndc.0, ndc.1, 0.5, 1.0);
    let apex = eye.world_from_view.translation;
    (apex + (p.truncate() / p.w - apex).normalize() * distance).as_vec3()
}

/// Where `eye` sees `p` in normalized coordinates; `None` behind its near plane.
fn project(eye: &View, p: Vec3) -> Option<(f32, f32)> {
    let clip = eye.clip_from_world().as_dmat4() * p.as_dvec3().extend(1.0);
    (clip.w > eye.near as f64).then(|| ((clip.x / clip.w) as f32, (clip.y / clip.w) as f32))
}

/// Whether eye `e` (of `eyes`, masked by `mask`) may see `p`: in front, within its
/// window, outside its hidden triangles.
fn seen(eyes: &[View], mask: &VisibilityMask, e: usize, p: Vec3) -> bool {
    project(&eyes[e], p)
        .is_some_and(|(x, y)| x.abs() <= 1.0 && y.abs() <= 1.0 && !mask.hides(e, (x, y)))
}

/// Points of sphere `s`: its center and 26 on its surface.
fn sphere_points(s: Vec4) -> Vec<Vec3> {
    let c = s.truncate();
    let mut points = vec![c];
    for x in -1..=1 {
        for y in -1..=1 {
            for z in -1..=1 {
                let d = Vec3::new(x as f32, y as f32, z as f32);
                if d != Vec3::ZERO {
                    points.push(c + d.normalize() * s.w);
                }
            }
        }
    }
    points
}

/// The hmd's eyes, mask and hidden area at `size` pixels per eye.
fn hmd_area(size: (u32, u32)) -> (Rig, Vec<View>, VisibilityMask, HiddenArea) {
    let rig = support::sized("hmd", size.0, size.1);
    let eyes = rig.resolve().unwrap().displays[0].eyes.clone();
    let mask = rig.displays[0].visibility_mask.clone().unwrap();
    let area = HiddenArea::new(&eyes, &mask.views, size).unwrap();
    (rig, eyes, mask, area)
}

/// `area` with view `v` alone.
fn one_view(area: &HiddenArea, v: usize) -> HiddenArea {
    HiddenArea {
        views: [area.views[v]; stereocull::cull::hidden::MAX_HIDDEN_VIEWS],
        count: 1,
    }
}

/// Spheres through every part of the windows and past them, near and far: a sphere the
/// hidden area drops shows no point to either eye, and the area drops a good share of
/// those in the mask's corners, while keeping those hidden in one eye only.
#[test]
fn the_hidden_area_drops_only_what_both_eyes_cannot_see() {
    let (_, eyes, mask, area) = hmd_area((1440, 1600));
    let mut rng = rand_pcg::Pcg64::seed_from_u64(42);
    let (mut dropped, mut one_eye) = (0, 0);
    let (mut masked_only, mut masked_dropped) = (0, 0);
    for _ in 0..20_000 {
        let eye = &eyes[rng.random_range(0..2)];
        let ndc = (rng.random_range(-1.15..1.15), rng.random_range(-1.15..1.15));
        let distance = 10f64.powf(rng.random_range(-0.7..2.0));
        let radius = (distance * 10f64.powf(rng.random_range(-3.5..-1.0))) as f32;
        let s = along(eye, ndc, distance).extend(radius);
        let hidden_in = [0, 1].map(|v| one_view(&area, v).hides(s));
        assert_eq!(area.hides(s), hidden_in[0] && hidden_in[1]);
        for (v, &hidden) in hidden_in.iter().enumerate() {
            if let Some(p) = sphere_points(s)
                .into_iter()
                .find(|&p| seen(&eyes, &mask, v, p))
            {
                assert!(!hidden, "{s}: view {v} sees {p}, yet hides it");
            }
        }
        dropped += usize::from(area.hides(s));
        one_eye += usize::from(hidden_in[0] != hidden_in[1]);
        // Outside each eye's window or within its mask by a margin, and within a
        // mask somewhere: what the mask makes invisible.
        let points = sphere_points(s);
        let eyes = &eyes;
        let at = |v: usize| points.iter().map(move |&p| project(&eyes[v], p));
        let unseen = |v: usize| {
            at(v).all(|q| {
                q.is_none_or(|(x, y)| {
                    let out = x.abs().max(y.abs());
                    out > 1.02 || (out < 0.98 && mask.hides(v, (x, y)))
                })
            })
        };
        let masked = |v: usize| at(v).flatten().any(|(x, y)| x.abs().max(y.abs()) < 1.0);
        if unseen(0) && unseen(1) && (masked(0) || masked(1)) {
            masked_only += 1;
            masked_dropped += usize::from(area.hides(s));
        }
    }
    assert!(
        dropped > 1_000 && one_eye > 200,
        "dropped {dropped}, hidden in one eye {one_eye}"
    );
    // Of the spheres that only the mask makes invisible, the area drops most (it keeps
    // those within a pixel of the mask's edge).
    assert!(
        masked_only > 100 && masked_dropped * 10 > masked_only * 7,
        "{masked_dropped} of {masked_only} hidden by the mask dropped"
    );
    eprintln!(
        "dropped {dropped}, one eye {one_eye}, by the mask {masked_dropped} of {masked_only}"
    );
}

/// A cube far out in the top left corner, hidden by both eyes' masks, is dropped by
/// the cull on the GPU and the CPU, side by side and in multiview; one near the left
/// eye's top right corner, which the right eye sees through its lens, is kept; the
/// image outside the mask is the unmasked image's.
#[test]
fn the_cull_drops_what_both_masks_hide_and_keeps_what_one_eye_sees() {
    let size = (144, 160);
    let (rig, eyes, mask, area) = hmd_area(size);
    // Picked with room: the scene's bounding spheres may round larger.
    let hidden = (2..40)
        .map(|d| along(&eyes[0], (-0.96, 0.96), d as f64).extend(0.02 * d as f32))
        .find(|&s| area.hides(s * Vec4::new(1.0, 1.0, 1.0, 1.1)))
        .expect("a sphere both masks hide");
    let one_eye = (3..40)
        .map(|k| {
            let d = k as f64 * 0.05;
            along(&eyes[0], (0.97, 0.85), d).extend(0.004 * d as f32)
        })
        .find(|&s| one_view(&area, 0).hides(s) && seen(&eyes, &mask, 1, s.truncate()))
        .expect("a sphere the left mask hides and the right eye sees");
    assert!(!area.hides(one_eye));
    // Cubes of half-size 0.5 (bounding radius sqrt(3) / 2), scaled to those spheres.
    let mut scene = support::cubes(&[(Vec3::ZERO, 0), (Vec3::ZERO, 0)], 1);
    for (instance, s) in scene.instances.iter_mut().zip([hidden, one_eye]) {
        instance.world_from_local = glam::Affine3A::from_scale_rotation_translation(
            Vec3::splat(s.w / 0.75f32.sqrt()),
            glam::Quat::IDENTITY,
            s.truncate(),
        );
    }
    let (hidden_id, one_eye_id) = (0, 1);
    let gpu = support::gpu();
    let ways = [
        (StereoMode::Instanced, CullMode::Gpu),
        (StereoMode::Instanced, CullMode::Cpu),
        (StereoMode::Multiview, CullMode::Gpu),
    ];
    let mut culls = Vec::new();
    for way in ways {
        let (masked, renderer) = render_scene(&gpu, &scene, &rig, way, true);
        let (plain, unmasked) = render_scene(&gpu, &scene, &rig, way, false);
        let cull = support::read_culls(&gpu, &renderer, &rig).remove(0);
        let all = support::read_culls(&gpu, &unmasked, &rig).remove(0);
        assert!(all.visible.contains(&hidden_id) && all.visible.contains(&one_eye_id));
        assert!(
            !cull.visible.contains(&hidden_id),
            "{way:?}: hidden, yet kept"
        );
        assert!(
            cull.visible.contains(&one_eye_id),
            "{way:?}: seen, yet dropped"
        );
        culls.push(cull);
        let (w, h) = size;
        for (x, y, p) in masked.enumerate_pixels() {
            let (view, vx) = ((x / w) as usize, x % w);
            if way.0 == StereoMode::Multiview && view > 0 {
                continue;
            }
            let ndc = (
                (vx as f32 + 0.5) / w as f32 * 2.0 - 1.0,
                1.0 - (y as f32 + 0.5) / h as f32 * 2.0,
            );
            if !mask.hides(view, ndc) && !near_edge(&mask, view, (vx, y), size, 0.05) {
                // Exact on any CPU: the same pipelines draw the same draws, but for a
                // cube none of whose pixels lies outside the mask.
                assert_eq!(p, plain.get_pixel(x, y), "{way:?} ({x}, {y})");
            }
        }
    }
    assert_eq!(culls[0], culls[1], "GPU and CPU culls");
}

#[test]
fn masked_pixels_keep_the_clear_color_and_the_rest_is_drawn_as_without() {
    let (w, h) = (72, 80);
    let rig = support::sized("hmd", w, h);
    let mask = rig.displays[0]
        .visibility_mask
        .clone()
        .expect("the hmd preset has a mask");
    let clear = stereocull::draw::CLEAR_COLOR;
    let byte = |l: f64| support::srgb(l as f32).round() as u8;
    let clear = [byte(clear.r), byte(clear.g), byte(clear.b), 255];
    for mode in [StereoMode::Instanced, StereoMode::Multiview] {
        let (masked, pixels) = render(&rig, mode, true);
        let (plain, none) = render(&rig, mode, false);
        let expected: u64 = (0..2).map(|v| mask.hidden_pixels(v, (w, h))).sum();
        assert_eq!((pixels, none), (expected, 0), "{mode:?}");
        let (mut hidden, mut kept) = (0, 0);
        for (x, y, p) in masked.enumerate_pixels() {
            let (view, vx) = ((x / w) as usize, x % w);
            if near_edge(&mask, view, (vx, y), (w, h), 0.05) {
                continue;
            }
            let ndc = (
                (vx as f32 + 0.5) / w as f32 * 2.0 - 1.0,
                1.0 - (y as f32 + 0.5) / h as f32 * 2.0,
            );
            if mask.hides(view, ndc) {
                assert_eq!(p.0, clear, "{mode:?} ({x}, {y}): hidden, yet drawn");
                hidden += 1;
            } else {
                // Exact on any CPU: the same pipelines draw the same draws; the mask's
                // draw writes no color and no depth outside its triangles.
                assert_eq!(
                    p,
                    plain.get_pixel(x, y),
                    "{mode:?} ({x}, {y}): outside the mask, yet changed"
                );
                kept += 1;
            }
        }
        assert!(
            hidden > 500 && kept > 8000,
            "{mode:?}: {hidden} hidden, {kept} kept"
        );
        // The control: without the mask the scene reaches some of those pixels.
        let reached = (plain.enumerate_pixels())
            .filter(|&(x, y, p)| {
                let (view, vx) = ((x / w) as usize, x % w);
                let ndc = (
                    (vx as f32 + 0.5) / w as f32 * 2.0 - 1.0,
                    1.0 - (y as f32 + 0.5) / h as f32 * 2.0,
                );
                mask.hides(view, ndc) && p.0 != clear
            })
            .count();
        assert!(
            reached > 100,
            "{mode:?}: the scene reaches only {reached} masked pixels unmasked"
        );
    }
}

/// The `hmd` preset's mask hides a share of each eye in the range the runtimes' do (5
/// to 20 %), more below the nose, and mirrors between the eyes.
#[test]
fn the_headset_mask_hides_a_headsets_share() {
    let mask = VisibilityMask::headset();
    let size = (200, 200);
    let [left, right] = [0, 1].map(|v| mask.hidden_pixels(v, size));
    assert_eq!(left, right);
    let share = left as f64 / 40_000.0;
    assert!((0.05..0.20).contains(&share), "{share}");
    // Below the nose (the left eye's lower right) more than below the temple.
    let corner = |x0: f32| {
        (0..100)
            .flat_map(|i| (0..100).map(move |j| (i, j)))
            .filter(|&(i, j)| {
                mask.hides(
                    0,
                    (x0 + i as f32 * 0.01 * x0.signum(), -1.0 + j as f32 * 0.01),
                )
            })
            .count()
    };
    assert!(
        corner(0.01) > corner(-0.01),
        "nose {} temple {}",
        corner(0.01),
        corner(-0.01)
    );
}

#[test]
fn a_mask_is_checked_with_its_rig() {
    let mut rig = Rig::preset("hmd").unwrap();
    let text = serde_json::to_string(&rig).unwrap();
    assert_eq!(
        Rig::parse(&text, Some("json")).unwrap(),
        rig,
        "a rig file keeps its mask"
    );
    let mask = rig.displays[0].visibility_mask.as_mut().unwrap();
    mask.views[0][0][1] = [1.5, 0.0];
    let error = rig.validate("test").unwrap_err().to_string();
    assert!(error.contains("within -1 to 1"), "{error}");
    let mut few = Rig::preset("hmd").unwrap();
    few.displays[0]
        .visibility_mask
        .as_mut()
        .unwrap()
        .views
        .pop();
    let error = few.validate("test").unwrap_err().to_string();
    assert!(
        error.contains("1 views given, the display has 2"),
        "{error}"
    );
    let mut many = Rig::preset("hmd").unwrap();
    let t = many.displays[0].visibility_mask.as_ref().unwrap().views[0][0];
    many.displays[0].visibility_mask.as_mut().unwrap().views[0] = vec![t; 17];
    let error = many.validate("test").unwrap_err().to_string();
    assert!(error.contains("at most 16"), "{error}");
}

/// The headset's corners are fans that meet at the window's corners: its mask cuts the
/// window along the lens edges (three per corner), one region each beside the window's
/// six; a mask that is not the outside of a convex window, or whose triangles overlap,
/// is taken triangle by triangle.
#[test]
fn a_mask_that_cuts_a_convex_window_is_taken_by_its_cuts() {
    let (_, eyes, mask, area) = hmd_area((1440, 1600));
    assert_eq!(mask.views[0].len(), 12);
    assert_eq!([area.views[0].count, area.views[1].count], [6 + 12, 6 + 12]);
    let area_of =
        |views: Vec<Vec<[[f32; 2]; 3]>>| HiddenArea::new(&eyes[..1], &views, (1440, 1600)).unwrap();
    let regions = |views| area_of(views).views[0].count;
    let corner = [[-1.0, 1.0], [-1.0, 0.5], [-0.5, 1.0]];
    let middle = [[-0.1, -0.1], [0.1, -0.1], [0.0, 0.1]];
    // Two edges inside the window, over the corner's.
    let over = [[-1.0, 1.0], [-1.0, 0.4], [-0.7, 0.7]];
    assert_eq!(regions(vec![vec![corner]]), 6 + 1);
    assert_eq!(regions(vec![vec![middle]]), 6 + 1);
    assert_eq!(regions(vec![vec![corner, middle]]), 6 + 2);
    assert_eq!(regions(vec![vec![corner, over]]), 6 + 2);
    // A fan of two triangles in a corner: one cut each, none along their shared edge,
    // so that a sphere across that edge is hidden, as it is not by either triangle.
    let fan = vec![
        [[-1.0, 1.0], [-1.0, 0.5], [-0.8, 0.8]],
        [[-1.0, 1.0], [-0.8, 0.8], [-0.5, 1.0]],
    ];
    let across = along(&eyes[0], (-0.95, 0.95), 10.0).extend(0.05);
    assert!(area_of(vec![fan.clone()]).hides(across));
    let mixed = [fan.clone(), vec![middle]].concat();
    assert!(!area_of(vec![mixed]).hides(across));
}

/// A sync that outgrows the buffers builds every display again, whole: its lens mask
/// comes back with it, and still keeps the pixels it hides at the clear color.
#[test]
fn a_sync_that_reallocates_keeps_the_lens_mask() {
    let (w, h) = (72, 80);
    let rig = support::sized("hmd", w, h);
    let mask = rig.displays[0].visibility_mask.clone().unwrap();
    let gpu = support::gpu();
    let scene = stereocull::scene_spec::load("default").unwrap();
    let options = RendererOptions {
        sample_count: 1,
        visibility_mask: true,
        ..support::frustum_only()
    };
    let mut renderer = Renderer::new(&gpu.device, &scene, &rig, options).unwrap();
    let masked = renderer.masked_pixels();
    assert!(masked > 0);
    let mut live = stereocull::live::LiveScene::new(scene.clone());
    // One instance more than the buffers hold: everything goes up again.
    live.insert(scene.instances[0]).unwrap();
    let synced = renderer.sync(&gpu.device, &gpu.queue, &mut live).unwrap();
    assert!(synced.reallocated);
    assert_eq!(renderer.masked_pixels(), masked);
    let targets = renderer.create_targets(&gpu.device);
    (renderer.submit_frame(&gpu.device, &gpu.queue, &rig, 0.0, &targets)).unwrap();
    let image =
        stereocull::readback::read_rgba8(&gpu.device, &gpu.queue, &targets[0].color).unwrap();
    let clear = stereocull::draw::CLEAR_COLOR;
    let byte = |l: f64| support::srgb(l as f32).round() as u8;
    let clear = [byte(clear.r), byte(clear.g), byte(clear.b), 255];
    let (plain, _) = render_scene(
        &gpu,
        live.scene(),
        &rig,
        (StereoMode::Instanced, CullMode::Gpu),
        false,
    );
    let (mut hidden, mut reached) = (0, 0);
    for (x, y, p) in image.enumerate_pixels() {
        let (view, vx) = ((x / w) as usize, x % w);
        let ndc = (
            (vx as f32 + 0.5) / w as f32 * 2.0 - 1.0,
            1.0 - (y as f32 + 0.5) / h as f32 * 2.0,
        );
        if !mask.hides(view, ndc) || near_edge(&mask, view, (vx, y), (w, h), 0.05) {
            continue;
        }
        assert_eq!(p.0, clear, "({x}, {y}): hidden, yet drawn after the sync");
        hidden += 1;
        reached += usize::from(plain.get_pixel(x, y).0 != clear);
    }
    // The control: unmasked, the scene reaches some of those pixels.
    assert!(
        hidden > 500 && reached > 100,
        "{hidden} hidden, {reached} reached"
    );
}
