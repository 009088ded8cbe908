//! What a compositor's depth layer takes (`stereocull::compositor`): each view's depth
//! read back, against the depth the CPU computes for the surface each pixel sees, with
//! and without MSAA (resolved to the nearest sample), side by side and in multiview.

mod support;

use stereocull::compositor::{MAX_DEPTH, MIN_DEPTH, read_layer};
use stereocull::renderer::{Renderer, RendererOptions, StereoMode};
use stereocull::rig::Rig;
use stereocull::scene::Scene;

/// The plane z = 0, 40 m a side: every pixel of the rig below sees it.
fn ground() -> Scene {
    support::plane(20.0)
}

/// The hmd 0.6 m before the plane, turned so that it sees the plane at a slant: depth
/// changes across every pixel.
fn slanted(width: u32, height: u32) -> Rig {
    let mut rig = support::sized("hmd", width, height);
    rig.viewer.position = [0.2, -0.1, 0.6];
    rig.viewer.yaw_deg = 10.0;
    rig.viewer.pitch_deg = 12.0;
    rig
}

/// The depth the CPU computes where eye `e`'s screen point `at` sees the plane.
fn cpu_depth(rig: &Rig, e: usize, at: (f64, f64), size: (u32, u32)) -> f64 {
    let (p, _) = support::on_plane_at(rig, e, at, size);
    let view = rig.resolve().unwrap().displays[0].eyes[e];
    let clip = view.clip_from_world().as_dmat4() * p.extend(1.0);
    clip.z / clip.w
}

fn layered_mode(mode: StereoMode) -> bool {
    mode == StereoMode::Multiview
}

/// Each view's depth, read back, is the depth of the plane point its pixel sees: at the
/// pixel's center without MSAA (within 4e-6: f32 depth near 1 against an f64
/// intersection); with 4x MSAA resolved to the nearest sample, between the pixel's
/// nearest corner and its center, and nearer than the center where the plane slants
/// (an average of the samples would sit at the center). Multiview puts each view in its
/// layer.
#[test]
fn each_views_depth_is_the_depth_of_what_it_sees() {
    let gpu = support::gpu();
    let (w, h) = (40, 32);
    let rig = slanted(w, h);
    let scene = ground();
    for (mode, samples) in [
        (StereoMode::Instanced, 1),
        (StereoMode::Instanced, 4),
        (StereoMode::Multiview, 1),
        (StereoMode::Multiview, 4),
    ] {
        let options = RendererOptions {
            mode,
            sample_count: samples,
            ..support::frustum_only()
        };
        let what = format!("{mode:?} x{samples}");
        let mut renderer = Renderer::new(&gpu.device, &scene, &rig, options).unwrap();
        let targets = renderer.create_targets(&gpu.device);
        renderer
            .submit_frame(&gpu.device, &gpu.queue, &rig, 0.0, &targets)
            .unwrap();
        let (width, values) = read_layer(&gpu.device, &gpu.queue, &targets[0].depth).unwrap();
        let layer = renderer.depth_layer(&rig, 0).unwrap();
        assert_eq!(
            (layer.min_depth, layer.max_depth, layer.reversed_z),
            (MIN_DEPTH, MAX_DEPTH, false)
        );
        assert_eq!(layer.views.len(), 2, "{what}");
        let mut below = 0;
        // lavapipe (Mesa 22.3) keeps a multiview pass's depth in layer 0 only, the last
        // view's (its colors are right): there the layers' values are not checked.
        let lavapipe = gpu.adapter_line().contains("llvmpipe");
        for (e, view) in layer.views.iter().enumerate() {
            let layered = layered_mode(mode);
            assert_eq!(view.layer, if layered { e as u32 } else { 0 }, "{what}");
            let [x0, y0, vw, vh] = view.rect;
            assert_eq!((vw, vh), (w, h), "{what}");
            // Read back, multiview's layers lie side by side as the halves do.
            let x0 = if layered { e as u32 * w } else { x0 };
            for y in (0..h).step_by(3) {
                for x in (0..w).step_by(3) {
                    let gpu_depth = values[((y0 + y) * width + x0 + x) as usize] as f64;
                    let center = cpu_depth(&rig, e, (x as f64 + 0.5, y as f64 + 0.5), (w, h));
                    let eps = 4e-6;
                    if layered && lavapipe {
                        continue;
                    }
                    if samples == 1 {
                        assert!(
                            (gpu_depth - center).abs() < eps,
                            "{what} eye {e} ({x}, {y}): {gpu_depth} against {center}"
                        );
                        continue;
                    }
                    // The nearest of samples inside the pixel: no nearer than its
                    // nearest corner, no farther than its center (the depth of a plane
                    // is linear across the screen, so some sample is nearer).
                    let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
                        .map(|(dx, dy)| cpu_depth(&rig, e, (x as f64 + dx, y as f64 + dy), (w, h)));
                    let nearest = corners.iter().copied().fold(f64::INFINITY, f64::min);
                    assert!(
                        gpu_depth > nearest - eps && gpu_depth < center + eps,
                        "{what} eye {e} ({x}, {y}): {gpu_depth} outside [{nearest}, {center}]"
                    );
                    below += usize::from(gpu_depth < center - 1e-6);
                }
            }
        }
        if samples > 1 && !(layered_mode(mode) && lavapipe) {
            assert!(
                below > 200,
                "{what}: only {below} pixels resolved nearer than their centers"
            );
        }
    }
}
