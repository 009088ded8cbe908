//! The lens's hidden area (`rig::VisibilityMask`): written to depth before the scene,
//! it keeps its pixels the clear color and leaves every other pixel as drawn without
//! it, exactly, side by side and in multiview; its CPU twin counts the pixels it hides.

mod support;

use image::RgbaImage;
use stereocull::renderer::{Renderer, RendererOptions, StereoMode};
use stereocull::rig::{Rig, VisibilityMask};

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
    let gpu = support::gpu();
    let scene = stereocull::scene_spec::load("default").unwrap();
    let options = RendererOptions {
        mode,
        sample_count: 1,
        visibility_mask: mask,
        ..RendererOptions::default()
    };
    let mut renderer = Renderer::new(&gpu.device, &scene, rig, options).unwrap();
    let targets = renderer.create_targets(&gpu.device);
    renderer
        .submit_frame(&gpu.device, &gpu.queue, rig, 0.0, &targets)
        .unwrap();
    let image =
        stereocull::readback::read_rgba8(&gpu.device, &gpu.queue, &targets[0].color).unwrap();
    (image, renderer.masked_pixels())
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
