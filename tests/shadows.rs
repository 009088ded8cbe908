//! The frame's shadow map: boxes above a floor darken the floor where their shadows
//! fall and not beside, in both eyes of every display of the CAVE that sees the floor;
//! the shadow pass is recorded once per frame whatever the rig and mode; GPU- and
//! CPU-culled shadows draw the same image; and the map agrees with rays to the light.

mod support;

use glam::{Affine3A, DVec3, Vec3, Vec4};
use image::RgbaImage;
use stereocull::renderer::{CullMode, Level, Renderer, RendererOptions, StereoMode};
use stereocull::rig::Rig;
use stereocull::scene::{Animation, Instance, Scene};
use stereocull::shadow::Light;
use stereocull::shapes;
use support::{Tolerance, assert_images_match};

const FLOOR_Y: f32 = -1.0;
const HALF: f32 = 0.25;

/// Light from the upper right: shadows fall towards -x. Shadows reach 12 m, where the
/// farthest box stands, so that a texel is about 2 cm.
fn light() -> Light {
    Light {
        direction: Vec3::new(1.0, 1.0, 0.0),
        shadow_map_size: 2048,
        shadow_distance: 12.0,
    }
}

/// Boxes seen through the CAVE's front, left and right walls and (below its floor
/// screen) through the floor, over one wide floor under the screens.
const BOXES: [[f32; 3]; 4] = [
    [0.0, 0.5, -4.0],
    [-4.0, 0.5, 0.0],
    [5.0, 0.5, 0.0],
    [0.6, -0.35, -0.6],
];

fn scene() -> Scene {
    let mut s = Scene::default();
    let floor = shapes::cuboid(Vec3::new(20.0, 0.05, 20.0));
    s.add_mesh("floor", &floor.vertices, &floor.indices);
    let cube = shapes::cuboid(Vec3::splat(HALF));
    s.add_mesh("box", &cube.vertices, &cube.indices);
    let instance = |mesh: u32, at: Vec3, color: Vec4| Instance {
        world_from_local: Affine3A::from_translation(at),
        mesh,
        color,
        material: None,
        animation: Animation::NONE,
    };
    s.instances.push(instance(
        0,
        Vec3::new(0.0, FLOOR_Y - 0.05, 0.0),
        Vec4::new(0.7, 0.7, 0.7, 1.0),
    ));
    for b in BOXES {
        s.instances
            .push(instance(1, Vec3::from(b), Vec4::new(0.2, 0.4, 0.9, 1.0)));
    }
    s
}

/// Per box, a floor point in the middle of its shadow and one 0.75 m beside it (along
/// z, away from the shadow and from the box).
fn probes() -> Vec<(Vec3, Vec3)> {
    let l = light().direction.normalize();
    BOXES
        .iter()
        .map(|&b| {
            let b = Vec3::from(b);
            let drop = (b.y - FLOOR_Y) / l.y;
            let shadow = Vec3::new(b.x - l.x * drop, FLOOR_Y, b.z);
            (shadow, shadow + Vec3::new(0.0, 0.0, HALF + 0.75))
        })
        .collect()
}

/// The pixel of eye `e` of display `d` where `p` shows, if it is well inside the view.
fn pixel(rig: &Rig, (d, e): (usize, usize), p: Vec3, size: (u32, u32)) -> Option<(u32, u32)> {
    let eye = rig.resolve().unwrap().displays[d].eyes[e];
    let clip = eye.clip_from_world().as_dmat4() * p.as_dvec3().extend(1.0);
    let ndc = DVec3::new(clip.x, clip.y, clip.z) / clip.w;
    if clip.w <= 0.0 || ndc.x.abs() > 0.9 || ndc.y.abs() > 0.9 {
        return None;
    }
    let x = (ndc.x * 0.5 + 0.5) * size.0 as f64;
    let y = (0.5 - ndc.y * 0.5) * size.1 as f64;
    Some((x as u32 + e as u32 * size.0, y as u32))
}

fn brightness(image: &RgbaImage, (x, y): (u32, u32)) -> u32 {
    image.get_pixel(x, y).0[..3].iter().map(|&c| c as u32).sum()
}

fn render(rig: &Rig, shadows: bool) -> Vec<RgbaImage> {
    let options = RendererOptions {
        shadows,
        light: light(),
        ..RendererOptions::default()
    };
    support::render(&support::gpu(), &scene(), rig, options).unwrap()
}

#[test]
fn boxes_shade_the_floor_below_them_in_both_eyes_of_every_display_that_sees_it() {
    let size = (96, 96);
    let rig = support::sized("cave", size.0, size.1);
    let (lit, shaded) = (render(&rig, false), render(&rig, true));
    let mut checked = Vec::new();
    for (d, display) in rig.displays.iter().enumerate() {
        for (shadow, beside) in probes() {
            let seen = |e| pixel(&rig, (d, e), shadow, size).zip(pixel(&rig, (d, e), beside, size));
            let (Some(left), Some(right)) = (seen(0), seen(1)) else {
                continue;
            };
            for (e, (at, next)) in [left, right].into_iter().enumerate() {
                let case = format!(
                    "{} eye {e}: shadow at {shadow}, beside at {beside}",
                    display.name
                );
                let (under, aside) = (brightness(&shaded[d], at), brightness(&shaded[d], next));
                let (under_lit, aside_lit) = (brightness(&lit[d], at), brightness(&lit[d], next));
                assert!(
                    (under_lit as f64) > 0.85 * aside_lit as f64,
                    "{case}: without shadows the two differ ({under_lit} vs {aside_lit})"
                );
                // sRGB bytes: 0.75 is about half the linear light.
                assert!(
                    (under as f64) < 0.75 * aside as f64,
                    "{case}: not darker under the box ({under} vs {aside})"
                );
                assert!(
                    aside as f64 > 0.9 * aside_lit as f64,
                    "{case}: shaded beside"
                );
            }
            checked.push(display.name.clone());
        }
    }
    checked.dedup();
    // The ceiling looks up and sees no floor.
    assert_eq!(checked, ["front", "left", "right", "floor"]);
}

/// Frames on every preset, indirect (GPU and CPU culls) and per-eye modes: the shadow
/// pass is recorded once per frame, at the frame level, before any display's pass.
#[test]
fn the_shadow_pass_runs_once_per_frame() {
    let gpu = support::gpu();
    let scene = scene();
    for preset in support::PRESETS {
        let rig = support::sized(preset, 32, 32);
        for (mode, cull) in [
            (StereoMode::Instanced, CullMode::Gpu),
            (StereoMode::Instanced, CullMode::Cpu),
            (StereoMode::MultiPass, CullMode::Cpu),
        ] {
            for shadows in [true, false] {
                let options = RendererOptions {
                    mode,
                    cull,
                    shadows,
                    light: light(),
                    ..RendererOptions::default()
                };
                let mut renderer = Renderer::new(&gpu.device, &scene, &rig, options).unwrap();
                let targets = renderer.create_targets(&gpu.device);
                for _ in 0..2 {
                    renderer
                        .submit_frame(&gpu.device, &gpu.queue, &rig, 0.0, &targets)
                        .unwrap();
                    let passes = renderer.passes();
                    let named = |n: &str| passes.iter().filter(|p| p.name == n).count();
                    let case = format!("{preset} {mode:?} {cull:?} shadows {shadows}");
                    assert_eq!(named("shadow"), usize::from(shadows), "{case}: {passes:?}");
                    let first_display = passes.iter().position(|p| p.level != Level::Frame);
                    let shadow = passes.iter().position(|p| p.name == "shadow");
                    assert!(shadow <= first_display, "{case}: {passes:?}");
                    let draws = named("draw");
                    let per_eye = mode == StereoMode::MultiPass;
                    let views: usize = rig.displays.iter().map(|d| d.views() as usize).sum();
                    let want = if per_eye { views } else { rig.displays.len() };
                    assert_eq!(draws, want, "{case}: {passes:?}");
                }
            }
        }
    }
}

#[test]
fn gpu_and_cpu_culled_shadows_draw_the_same_image() {
    let gpu = support::gpu();
    let scene = stereocull::scene_spec::load("procedural:2000:6").unwrap();
    let rig = support::sized("hmd-peripheral", 64, 64);
    let images = [CullMode::Gpu, CullMode::Cpu].map(|cull| {
        let options = RendererOptions {
            cull,
            shadows: true,
            ..RendererOptions::default()
        };
        support::render(&gpu, &scene, &rig, options).unwrap()
    });
    // Exact on any CPU: the light's and the displays' culls are byte-identical, so the
    // same pipelines draw the same shadow map and the same images.
    for (d, (a, b)) in images[0].iter().zip(&images[1]).enumerate() {
        assert_images_match(&format!("shadow-cull-{d}"), a, b, Tolerance::EXACT);
    }
}

/// Where the ray from `origin` along `direction` first enters the box `(center, half)`,
/// as a distance along it (slab test); `None` when it misses.
fn ray_box(origin: Vec3, direction: Vec3, (center, half): (Vec3, Vec3)) -> Option<f32> {
    let inverse = direction.recip();
    let a = (center - half - origin) * inverse;
    let b = (center + half - origin) * inverse;
    let (near, far) = (a.min(b).max_element(), a.max(b).min_element());
    (near <= far && far > 0.0).then_some(near.max(0.0))
}

/// The CPU reference of the shadow map: a floor point is in shadow when the ray from it
/// towards the light meets a box. Random boxes over a floor, seen from the hmd looking
/// down: at random floor points the eye sees, well away from any shadow's edge (every
/// point within 15 cm agrees), a material showing only `light_reaching` reads dark
/// exactly where the ray says shadow, in at least 99 % of them, both kinds plentiful.
#[test]
fn the_shadow_map_agrees_with_rays_to_the_light() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_pcg::Pcg64::seed_from_u64(21);
    let boxes: Vec<(Vec3, Vec3)> = (0..14)
        .map(|_| {
            let at = Vec3::new(
                rng.random_range(-2.5..2.5),
                rng.random_range(0.4..1.4),
                rng.random_range(-4.5..-0.5),
            );
            (at, Vec3::splat(rng.random_range(0.12..0.35)))
        })
        .collect();
    let mut s = Scene::default();
    let floor = shapes::cuboid(Vec3::new(20.0, 0.05, 20.0));
    s.add_mesh("floor", &floor.vertices, &floor.indices);
    let cube = shapes::cuboid(Vec3::splat(1.0));
    s.add_mesh("box", &cube.vertices, &cube.indices);
    let place = |mesh, at, scale: Vec3| Instance {
        world_from_local: Affine3A::from_scale_rotation_translation(
            scale,
            glam::Quat::IDENTITY,
            at,
        ),
        mesh,
        color: Vec4::ONE,
        material: None,
        animation: Animation::NONE,
    };
    s.instances
        .push(place(0, Vec3::new(0.0, -0.05, 0.0), Vec3::ONE));
    s.instances
        .extend(boxes.iter().map(|&(at, half)| place(1, at, half)));
    let size = (256, 256);
    let mut rig = support::sized("hmd", size.0, size.1);
    rig.viewer.pitch_deg = -35.0;
    let light = Light {
        direction: Vec3::new(0.4, 1.0, 0.25),
        shadow_map_size: 2048,
        shadow_distance: 12.0,
    };
    let options = RendererOptions {
        shadows: true,
        light,
        material: Some(
            "fn material(s: Surface) -> vec4<f32> { \
             return vec4(vec3(light_reaching(s.world_position, normalize(s.normal))), 1.0); }"
                .into(),
        ),
        ..RendererOptions::default()
    };
    let image = &support::render(&support::gpu(), &s, &rig, options).unwrap()[0];
    let eye = Vec3::from(rig.viewer.position);
    let towards_light = light.direction.normalize();
    let shaded = |p: Vec3| {
        boxes
            .iter()
            .any(|&b| ray_box(p, towards_light, b).is_some())
    };
    let (mut agree, mut checked, mut dark) = (0, 0, 0);
    for _ in 0..3000 {
        let p = Vec3::new(
            rng.random_range(-3.0..3.0),
            0.0,
            rng.random_range(-5.0..0.0),
        );
        let to = p - eye;
        let hidden = boxes
            .iter()
            .any(|&b| ray_box(eye, to, b).is_some_and(|t| t < 1.0));
        let around = [-0.15, 0.0, 0.15]
            .iter()
            .flat_map(|&dx| [-0.15, 0.0, 0.15].map(|dz| shaded(p + Vec3::new(dx, 0.0, dz))));
        let truth = shaded(p);
        let Some(at) = pixel(&rig, (0, 0), p, size) else {
            continue;
        };
        if hidden || around.clone().any(|s| s != truth) {
            continue;
        }
        let seen_dark = image.get_pixel(at.0, at.1).0[0] < 128;
        checked += 1;
        dark += usize::from(truth);
        agree += usize::from(seen_dark == truth);
    }
    eprintln!("{agree} of {checked} floor points agree with the rays ({dark} in shadow)");
    assert!(
        dark > 50 && checked - dark > 50,
        "{dark} shadowed of {checked}"
    );
    assert!(agree * 100 >= checked * 99, "{agree} of {checked} agree");
}
