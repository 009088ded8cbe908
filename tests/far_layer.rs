//! The far layer: near and far culls are the GPU's and the CPU's byte for byte and split
//! the display cull exactly; far objects land within the threshold of where the full
//! per-eye render puts them; depth between the far layer and near geometry is right
//! both ways; with nothing far, no pixel changes.

mod support;

use std::collections::BTreeSet;

use glam::{Affine3A, DVec3, Vec3, Vec4};
use image::RgbaImage;
use stereocull::Error;
use stereocull::cull::CullOutput;
use stereocull::far_layer::FarPlan;
use stereocull::renderer::{CullMode, Renderer, RendererOptions, StereoMode};
use stereocull::rig::Rig;
use stereocull::scene::{Animation, Instance, Scene};
use stereocull::{scene_spec, shapes};
use support::{Tolerance, assert_images_match, frustum_only};

/// Unlit: each object one flat color, so that it can be found in the image.
const FLAT: &str = "fn material(s: Surface) -> vec4<f32> { return vec4(s.color.rgb, 1.0); }";

/// Each display's cull and far cull after one frame.
fn culls(
    scene: &Scene,
    rig: &Rig,
    cull: CullMode,
    far_layer: bool,
) -> Vec<(CullOutput, Option<CullOutput>)> {
    let gpu = support::gpu();
    let options = RendererOptions {
        cull,
        far_layer,
        ..frustum_only()
    };
    let renderer = support::one_frame(&gpu, scene, rig, options);
    let far = |d| {
        renderer
            .diagnostics(&gpu.device, &gpu.queue)
            .far_cull(d)
            .unwrap()
    };
    let near = support::read_culls(&gpu, &renderer, rig);
    near.into_iter()
        .enumerate()
        .map(|(d, n)| (n, far(d)))
        .collect()
}

fn ids(out: &CullOutput) -> BTreeSet<u32> {
    out.visible.iter().copied().collect()
}

/// On every preset and random rigs, over objects from 10 cm to 2,000 km away: the near
/// and far culls are byte-identical on GPU and CPU, disjoint, and together exactly the
/// display cull without a far layer.
#[test]
fn near_and_far_culls_split_the_display_cull_identically_on_gpu_and_cpu() {
    let rigs = support::presets_and_random_rigs(3);
    let (mut far_seen, mut near_seen) = (0, 0);
    for (i, rig) in rigs.iter().enumerate() {
        let scene = support::extreme_scene(rig, 3000, 7, 40 + i as u64);
        let whole = culls(&scene, rig, CullMode::Gpu, false);
        let split = culls(&scene, rig, CullMode::Gpu, true);
        assert_eq!(
            split,
            culls(&scene, rig, CullMode::Cpu, true),
            "rig {i}: GPU == CPU"
        );
        for (d, (display, (near, far))) in rig.displays.iter().zip(split).enumerate() {
            let (all, near) = (ids(&whole[d].0), ids(&near));
            let far = far.as_ref().map(ids).unwrap_or_default();
            if !display.stereo {
                assert!(far.is_empty(), "rig {i} display {d}: mono has no far layer");
                assert_eq!(near, all);
                continue;
            }
            assert!(near.is_disjoint(&far), "rig {i} display {d}");
            let union: BTreeSet<u32> = near.union(&far).copied().collect();
            assert_eq!(union, all, "rig {i} display {d}");
            far_seen += far.len();
            near_seen += near.len();
        }
    }
    assert!(
        far_seen > 100 && near_seen > 100,
        "far {far_seen}, near {near_seen}"
    );
}

fn flat_box(at: Vec3, half: Vec3, color: Vec4, mesh: u32) -> Instance {
    turned_box(at, half, color, (mesh, glam::Quat::IDENTITY))
}

fn turned_box(at: Vec3, half: Vec3, color: Vec4, (mesh, turn): (u32, glam::Quat)) -> Instance {
    Instance {
        world_from_local: Affine3A::from_scale_rotation_translation(half * 2.0, turn, at),
        mesh,
        color,
        material: None,
        animation: Animation::NONE,
    }
}

fn unit_box_scene(instances: Vec<Instance>) -> Scene {
    let mut s = Scene::default();
    let cube = shapes::cuboid(Vec3::splat(0.5));
    s.add_mesh("box", &cube.vertices, &cube.indices);
    s.instances = instances;
    s
}

fn render(scene: &Scene, rig: &Rig, far_layer: bool, threshold: f32) -> Vec<RgbaImage> {
    let options = RendererOptions {
        far_layer,
        far_threshold_px: threshold,
        material: Some(FLAT.into()),
        ..frustum_only()
    };
    support::render(&support::gpu(), scene, rig, options).unwrap()
}

/// The hmd's far distance at `size` pixels per eye and the default threshold.
fn far_distance(rig: &Rig) -> f32 {
    let resolved = rig.resolve().unwrap();
    let d = &rig.displays[0];
    FarPlan::new(&resolved.displays[0], d.resolution, 0.5).distance
}

/// Coverage-weighted centroid of `color` in eye `eye`'s half: each pixel weighs by how
/// far it is, in linear light, from the clear color towards `color` (edges blended by
/// the far layer's filtering count in part, as coverage), pixels of other hues not at
/// all. Returns the centroid and the summed weight.
fn centroid(image: &RgbaImage, eye: u32, color: [f64; 3]) -> Option<(f64, f64, f64)> {
    const BACKGROUND: [f64; 3] = [0.02, 0.02, 0.03];
    let linear = |v: u8| {
        let c = v as f64 / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    let towards: Vec<f64> = (0..3).map(|c| color[c] - BACKGROUND[c]).collect();
    let length2: f64 = towards.iter().map(|t| t * t).sum();
    let half = image.width() / 2;
    let (mut sx, mut sy, mut total) = (0.0, 0.0, 0.0);
    for y in 0..image.height() {
        for x in eye * half..(eye + 1) * half {
            let p = image.get_pixel(x, y).0;
            let off: Vec<f64> = (0..3).map(|c| linear(p[c]) - BACKGROUND[c]).collect();
            let along = off.iter().zip(&towards).map(|(o, t)| o * t).sum::<f64>() / length2;
            let across: f64 = (0..3).map(|c| (off[c] - along * towards[c]).powi(2)).sum();
            if along > 0.02 && across.sqrt() < 0.1 {
                let w = along.min(1.0);
                (sx, sy, total) = (sx + w * x as f64, sy + w * y as f64, total + w);
            }
        }
    }
    (total > 0.0).then(|| (sx / total, sy / total, total))
}

/// Boxes of distinct colors from 1.2 to 3 far distances away: in each eye, each box's
/// centroid with the far layer lies within the threshold (half a pixel) of its centroid
/// in the full per-eye render, and the images agree but for edge pixels.
#[test]
fn far_objects_land_within_the_threshold_of_the_full_render() {
    let rig = support::sized("hmd", 320, 320);
    let far = far_distance(&rig);
    let colors = [
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 1.0],
        [1.0, 0.0, 1.0],
    ];
    let eye = Vec3::from(rig.viewer.position);
    let boxes: Vec<Instance> = colors
        .iter()
        .enumerate()
        .map(|(k, &c)| {
            let distance = far * (1.2 + 0.35 * k as f32);
            let angle = -0.6 + 0.24 * k as f32;
            let up = 0.15 * ((k % 3) as f32 - 1.0);
            let at = eye + Vec3::new(angle.sin(), up, -angle.cos()) * distance;
            let half = Vec3::splat(0.05 * distance);
            // Turned, so that no edge runs along the pixel grid: the centroid then
            // measures where the box is, not how its edges fell on pixel centers.
            let turn = glam::Quat::from_euler(glam::EulerRot::ZYX, 0.5 + 0.1 * k as f32, 0.4, 0.3);
            turned_box(at, half, Vec3::from(c).extend(1.0), (0, turn))
        })
        .collect();
    let scene = unit_box_scene(boxes);
    let (with, without) = (
        render(&scene, &rig, true, 0.5),
        render(&scene, &rig, false, 0.5),
    );
    let mut largest: f64 = 0.0;
    for c in colors {
        for e in 0..2 {
            let a = centroid(&with[0], e, c.map(f64::from))
                .expect("the far box shows with the far layer");
            let b = centroid(&without[0], e, c.map(f64::from)).expect("the far box shows without");
            assert!(a.2 > 20.0, "{c:?}: {} pixels", a.2);
            let shift = ((a.0 - b.0).powi(2) + (a.1 - b.1).powi(2)).sqrt();
            eprintln!("{c:?} eye {e}: moved {shift:.3} px");
            largest = largest.max(shift);
        }
    }
    eprintln!("largest shift of a far box: {largest:.3} px (threshold 0.5)");
    assert!(largest < 0.5, "a far box moved {largest} px");
    let edges = Tolerance {
        levels: 2,
        share: 0.01,
    };
    assert_images_match("far-layer-shift", &with[0], &without[0], edges);
}

/// A long near wall to the right, reaching past the far distance: a far box in front of
/// its far part hides it there, and a far box behind it is hidden by it, with and
/// without the far layer.
#[test]
fn far_objects_hide_and_are_hidden_by_the_far_ends_of_near_ones() {
    let rig = support::sized("hmd", 320, 320);
    let far = far_distance(&rig);
    let eye = Vec3::from(rig.viewer.position);
    let wall_color = Vec4::new(0.0, 1.0, 0.0, 1.0);
    let (front, behind) = (Vec4::new(1.0, 0.0, 0.0, 1.0), Vec4::new(0.0, 0.0, 1.0, 1.0));
    let depth = |k: f32| eye.z - k * far;
    let wall_x = eye.x + 0.25 * far;
    let wall = flat_box(
        Vec3::new(wall_x, eye.y, depth(1.75)),
        Vec3::new(0.5, 0.4 * far, 1.25 * far),
        wall_color,
        0,
    );
    let front_at = Vec3::new(eye.x + 0.15 * far, eye.y, depth(2.0));
    let behind_at = Vec3::new(eye.x + 0.5 * far, eye.y, depth(2.5));
    let scene = unit_box_scene(vec![
        wall,
        flat_box(front_at, Vec3::splat(0.05 * far), front, 0),
        flat_box(behind_at, Vec3::splat(0.05 * far), behind, 0),
    ]);
    for far_layer in [true, false] {
        let images = render(&scene, &rig, far_layer, 0.5);
        for e in 0..2 {
            let at = |p: Vec3| pixel(&rig, e, p);
            let shade = |p: Vec3| images[0].get_pixel(at(p).0, at(p).1).0;
            let srgb = |c: Vec4| c.truncate().to_array().map(|v| (v * 255.0) as u8);
            let case = format!("far layer {far_layer}, eye {e}");
            assert_eq!(
                shade(front_at)[..3],
                srgb(front),
                "{case}: the far box in front"
            );
            assert_eq!(
                shade(behind_at)[..3],
                srgb(wall_color),
                "{case}: the far box behind"
            );
        }
    }
}

/// Where eye `e` of the hmd sees `p`, in the double-wide image.
fn pixel(rig: &Rig, e: u32, p: Vec3) -> (u32, u32) {
    let view = rig.resolve().unwrap().displays[0].eyes[e as usize];
    let clip = view.clip_from_world().as_dmat4() * p.as_dvec3().extend(1.0);
    let ndc = DVec3::new(clip.x, clip.y, clip.z) / clip.w;
    let (w, h) = (rig.displays[0].resolution[0], rig.displays[0].resolution[1]);
    let x = (ndc.x * 0.5 + 0.5) * w as f64;
    let y = (0.5 - ndc.y * 0.5) * h as f64;
    (x as u32 + e * w, y as u32)
}

/// A threshold so fine that nothing is far: the far layer is empty and changes no
/// pixel of the default scene, on the GPU and CPU paths.
#[test]
fn with_nothing_far_the_far_layer_changes_no_pixel() {
    let scene = scene_spec::load("default").unwrap();
    let rig = support::sized("hmd", 96, 96);
    for cull in [CullMode::Gpu, CullMode::Cpu] {
        let options = |far_layer| RendererOptions {
            cull,
            far_layer,
            far_threshold_px: 1e-4,
            ..frustum_only()
        };
        let gpu = support::gpu();
        let with = support::render(&gpu, &scene, &rig, options(true)).unwrap();
        let without = support::render(&gpu, &scene, &rig, options(false)).unwrap();
        // Exact on any CPU: the far layer holds only its clear color, which the composite
        // samples from uniform texels unchanged, at the clear depth; then the same
        // pipeline draws the same near draws.
        assert_images_match(
            &format!("far-none-{cull:?}"),
            &with[0],
            &without[0],
            Tolerance::EXACT,
        );
    }
}

#[test]
fn the_far_layer_is_an_error_outside_instanced() {
    let gpu = support::gpu();
    let scene = scene_spec::load("default").unwrap();
    let rig = support::sized("hmd", 32, 32);
    for mode in [StereoMode::Multiview, StereoMode::MultiPass] {
        let options = RendererOptions {
            mode,
            cull: support::cull_for(mode),
            far_layer: true,
            ..frustum_only()
        };
        let result = Renderer::new(&gpu.device, &scene, &rig, options);
        assert!(matches!(result, Err(Error::Unsupported(_))), "{mode:?}");
    }
}

/// The composite's mapping (FarPlan::far_uv, `far_uv` in `wgsl/far_composite.wgsl`): an
/// eye pixel takes the far layer where the far view projects a point 100 km along that
/// pixel's ray, on the hmd (parallel eyes) and every CAVE wall (off-axis windows).
#[test]
fn an_eye_pixel_takes_the_far_layer_where_its_ray_ends() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_pcg::Pcg64::seed_from_u64(11);
    let mut checked = 0;
    for preset in ["hmd", "cave"] {
        let rig = support::sized(preset, 200, 160);
        let resolved = rig.resolve().unwrap();
        for (d, display) in resolved.displays.iter().enumerate() {
            let plan = FarPlan::new(display, rig.displays[d].resolution, 0.5);
            for eye in &display.eyes {
                for _ in 0..50 {
                    let pixel = (rng.random_range(0.0..200.0), rng.random_range(0.0..160.0));
                    let Some(uv) = plan.far_uv(eye, pixel, (200, 160)) else {
                        continue;
                    };
                    let [l, r, u, dn] = eye.fov.tangents();
                    let t = (
                        -l + (l + r) * pixel.0 / 200.0,
                        u - (u + dn) * pixel.1 / 160.0,
                    );
                    let ray = eye.world_from_view.matrix3 * DVec3::new(t.0, t.1, -1.0);
                    let end = eye.world_from_view.translation + ray.normalize() * 1e5;
                    let clip = glam::DMat4::from(plan.view.world_from_view.inverse());
                    let local = clip.transform_point3(end);
                    let [fl, fr, fu, fd] = plan.view.fov.tangents();
                    let want = (
                        (local.x / -local.z + fl) / (fl + fr),
                        (fu - local.y / -local.z) / (fu + fd),
                    );
                    let texel = |v: f64, n: u32| v * n as f64;
                    let (w, h) = plan.size;
                    let off = (texel(uv.0 - want.0, w).abs(), texel(uv.1 - want.1, h).abs());
                    // 100 km is not infinity: the eye's offset from the apex still shows.
                    assert!(
                        off.0 < 0.01 && off.1 < 0.01,
                        "{preset} display {d}: {off:?} texels"
                    );
                    checked += 1;
                }
            }
        }
    }
    assert!(checked > 500, "{checked} pixels checked");
}
