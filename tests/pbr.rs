//! The built-in shading, glTF's metallic-roughness model, held to its CPU twin
//! (`stereocull::pbr`): a normal-mapped plane whose quadrants tilt its normal, read its
//! roughness, metalness and occlusion from a texture and emit, lit from a known
//! direction, matches the CPU's BRDF at sampled pixels of both eyes; and the highlight
//! falls as roughness rises and stands out more as metalness rises.

use glam::{Vec2, Vec3, Vec4};
use image::{Rgba, RgbaImage};
use stereocull::exposure::{self, Exposure, Tonemap};
use stereocull::keep::KeepUnchanged;
use stereocull::pbr::{self, Pbr};
use stereocull::records::pack_unorm4x8;
use stereocull::renderer::{Renderer, RendererOptions};
use stereocull::rig::Rig;
use stereocull::scene::{Animation, Encoding, Instance, Material, Scene, Texture, Vertex};
use stereocull::shadow::Light;

mod support;

const EYE_W: u32 = 160;
const EYE_H: u32 = 128;

/// Towards the light: high, to the right and in front of the plane.
const LIGHT: Vec3 = Vec3::new(0.3, 0.45, 0.84);

/// Per quadrant of the plane (u and v below or above one half, in that order): the
/// normal map's tangent-space normal, and (occlusion, roughness, metalness) of the
/// metallic-roughness texture.
const QUADRANTS: [([f32; 3], [f32; 3]); 4] = [
    ([0.35, 0.2, 0.91], [1.0, 0.5, 0.0]),
    ([-0.4, 0.1, 0.91], [0.6, 0.8, 0.0]),
    ([0.1, -0.45, 0.89], [1.0, 0.35, 1.0]),
    ([0.0, 0.0, 1.0], [0.3, 0.65, 0.5]),
];

/// A 2 m square in the plane z = 0 facing +z, u along +x and v down the square (as
/// glTF's images run), its tangents generated from those coordinates.
fn plane(scene: &mut Scene) -> u32 {
    let corner = |x: f32, y: f32| Vertex {
        uv: [(x + 1.0) / 2.0, (1.0 - y) / 2.0],
        ..Vertex::new(Vec3::new(x, y, 0.0), Vec3::Z)
    };
    let mut vertices = [
        corner(-1.0, -1.0),
        corner(1.0, -1.0),
        corner(1.0, 1.0),
        corner(-1.0, 1.0),
    ];
    let indices = [0, 1, 2, 0, 2, 3];
    pbr::generate_tangents(&mut vertices, &indices);
    scene.add_mesh("plane", &vertices, &indices)
}

/// A 64 x 64 texture, each quadrant one color.
fn quadrants(
    name: &str,
    color: impl Fn([f32; 3]) -> [u8; 3],
    of: fn(usize) -> [f32; 3],
) -> Texture {
    let image = RgbaImage::from_fn(64, 64, |x, y| {
        let q = usize::from(x >= 32) + 2 * usize::from(y >= 32);
        let [r, g, b] = color(of(q));
        Rgba([r, g, b, 255])
    });
    Texture {
        name: name.into(),
        image,
        encoding: Encoding::Linear,
        basis: None,
    }
}

fn byte(x: f32) -> u8 {
    (x.clamp(0.0, 1.0) * 255.0).round() as u8
}

/// The plane with its one material: the two quadrant textures, a base color of the
/// instance's, an emission.
fn mapped_plane() -> Scene {
    let mut scene = Scene::default();
    let mesh = plane(&mut scene);
    let encode = |n: [f32; 3]| {
        let n = Vec3::from(n).normalize();
        [
            byte(n.x * 0.5 + 0.5),
            byte(n.y * 0.5 + 0.5),
            byte(n.z * 0.5 + 0.5),
        ]
    };
    scene.textures = vec![
        quadrants("normals", encode, |q| QUADRANTS[q].0),
        quadrants("orm", |c| c.map(byte), |q| QUADRANTS[q].1),
    ];
    scene.materials = vec![Material {
        name: "mapped".into(),
        normal_texture: Some(0),
        normal_scale: 0.9,
        metallic_roughness_texture: Some(1),
        occlusion_texture: Some(1),
        occlusion_strength: 0.8,
        metallic: 1.0,
        roughness: 1.0,
        emissive: Vec3::new(0.02, 0.01, 0.0),
        emissive_strength: 2.0,
        ..Default::default()
    }];
    scene.instances.push(Instance {
        world_from_local: glam::Affine3A::IDENTITY,
        mesh,
        color: Vec4::new(200.0, 120.0, 70.0, 255.0) / 255.0,
        material: None,
        animation: Animation::NONE,
    });
    scene
}

/// The hmd at EYE_W x EYE_H per eye, `distance` in front of the plane's center.
fn facing_the_plane(distance: f32) -> Rig {
    let mut rig = support::sized("hmd", EYE_W, EYE_H);
    rig.viewer.position = [0.0, 0.0, distance];
    rig
}

/// Towards the light for the sweeps: nearly behind the eyes, so that the light's
/// mirror point lies on the plane, in view.
const BEHIND: Vec3 = Vec3::new(0.12, 0.16, 0.98);

fn options(light: Vec3) -> RendererOptions {
    RendererOptions {
        light: Light {
            direction: light,
            ..Light::default()
        },
        ..support::frustum_only()
    }
}

fn on_plane(rig: &Rig, e: usize, pixel: (u32, u32)) -> (Vec3, Vec3) {
    support::on_plane(rig, e, pixel, (EYE_W, EYE_H))
}

/// The CPU twin's color at world point `p` (on the plane, seen from `eye`), with the
/// normal map applied or not.
fn expected(scene: &Scene, p: Vec3, eye: Vec3, mapped: bool) -> Vec3 {
    let uv = Vec2::new((p.x + 1.0) / 2.0, (1.0 - p.y) / 2.0);
    let texel = |t: usize| {
        let image = &scene.textures[t].image;
        let px = image.get_pixel((uv.x * 64.0) as u32, (uv.y * 64.0) as u32);
        Vec3::new(px[0] as f32, px[1] as f32, px[2] as f32) / 255.0
    };
    let m = &scene.materials[0];
    let vertex = scene.vertices[0];
    let n = Vec3::from(vertex.normal);
    let normal = match mapped {
        true => pbr::perturbed_normal(n, vertex.tangent(), texel(0), m.normal_scale),
        false => n,
    };
    let orm = texel(1);
    let color = glam::Vec4::from(
        image::Rgba(pack_unorm4x8(scene.instances[0].color).to_le_bytes())
            .0
            .map(|c| c as f32 / 255.0),
    );
    let inputs = Pbr {
        base: color,
        metallic: (m.metallic * orm.z).clamp(0.0, 1.0),
        roughness: (m.roughness * orm.y).clamp(pbr::MIN_ROUGHNESS, 1.0),
        normal,
        occlusion: 1.0 + m.occlusion_strength * (orm.x - 1.0),
        emissive: m.emissive * m.emissive_strength,
    };
    pbr::shade(&inputs, eye - p, LIGHT.normalize(), 1.0)
}

/// Sampled pixels, away from the quadrants' borders (the textures' filtering blends
/// a texel across them) and the plane's edges, in both eyes: each within 2 levels of
/// the CPU's BRDF. The two differ in the order a few transcendental functions round
/// (llvmpipe's sqrt and normalize against Rust's), in the world position the GPU
/// rebuilds from a 32-bit depth (a tenth of a millimeter at 2 m) and in the
/// hardware's sRGB rounding: each well under a level. Without the normal map the CPU
/// would miss most samples by more than 10 levels: the test sees the tilt.
#[test]
fn a_normal_mapped_plane_matches_the_cpu_brdf() {
    let tilted = matches_the_cpu(options(LIGHT), |c| c);
    assert!(tilted, "the normal map changes most samples");
}

/// Renders the mapped plane under `options` and holds sampled pixels to the CPU twin's
/// color passed through `camera` (2 levels: see the test above). Returns whether the
/// normal map changed most samples by more than 10 levels.
fn matches_the_cpu(options: RendererOptions, camera: impl Fn(Vec3) -> Vec3) -> bool {
    let gpu = support::gpu();
    let scene = mapped_plane();
    let rig = facing_the_plane(2.2);
    let image = support::render(&gpu, &scene, &rig, options)
        .unwrap()
        .remove(0);
    let (mut checked, mut tilted, mut worst) = (0, 0, 0.0f32);
    for e in 0..2 {
        for y in (4..EYE_H).step_by(5) {
            for x in (4..EYE_W).step_by(5) {
                let (p, eye) = on_plane(&rig, e, (x, y));
                let inside = |c: f32| c.abs() < 0.9 && c.abs() > 0.1;
                if !(inside(p.x) && inside(p.y)) {
                    continue;
                }
                let got = image.get_pixel(x + e as u32 * EYE_W, y);
                let want = camera(expected(&scene, p, eye, true))
                    .to_array()
                    .map(support::srgb);
                let flat = camera(expected(&scene, p, eye, false))
                    .to_array()
                    .map(support::srgb);
                for c in 0..3 {
                    let d = (got[c] as f32 - want[c]).abs();
                    worst = worst.max(d);
                    assert!(
                        d <= 2.0,
                        "eye {e} pixel ({x}, {y}) at {p}: channel {c} is {} on the GPU, {:.2} on the CPU",
                        got[c],
                        want[c]
                    );
                }
                checked += 1;
                tilted += usize::from((0..3).any(|c| (flat[c] - want[c]).abs() > 10.0));
            }
        }
    }
    eprintln!(
        "{checked} pixels checked, worst {worst:.2} levels; {tilted} lit differently without the map"
    );
    assert!(checked > 150, "{checked} pixels checked");
    tilted * 2 > checked
}

/// The exposure scales the shaded light by `1 / (1.2 * 2^EV100)`: the plane at three
/// EVs a stop apart (tone mapping off) matches the CPU twin scaled by each, so a
/// surface's value before tone mapping halves per EV (the scale itself halves exactly:
/// `stereocull::exposure`'s unit test).
#[test]
fn the_exposure_scales_the_light_by_two_to_the_minus_ev() {
    for ev100 in [-1.5, -0.5, 0.5] {
        let exposed = RendererOptions {
            exposure: Exposure::Ev100(ev100),
            tonemap: Tonemap::None,
            ..options(LIGHT)
        };
        let scale = exposure::scale_of_ev100(ev100);
        matches_the_cpu(exposed, |c| c * scale);
    }
}

/// Each tone mapper on the GPU follows its CPU twin (whose values the published curves
/// give: `stereocull::exposure`'s unit tests), with the plane exposed a stop and a
/// half over unit, so that its brightest texels reach the curves' shoulders.
#[test]
fn each_tone_mapper_follows_its_curve() {
    let ev100 = -1.8;
    for curve in [Tonemap::Neutral, Tonemap::Aces] {
        let mapped = RendererOptions {
            exposure: Exposure::Ev100(ev100),
            tonemap: curve,
            ..options(LIGHT)
        };
        let scale = exposure::scale_of_ev100(ev100);
        matches_the_cpu(mapped, |c| exposure::tone_map(c * scale, curve));
    }
}

/// A white-grey plane under a 2,000 lux sun from straight behind the viewer, lit in
/// physical units as a file's `KHR_lights_punctual` are. At `auto` exposure no lit
/// pixel saturates. At EV100 10 without tone mapping, each sampled pixel is the glTF
/// BRDF worked by hand at a rough surface (roughness 1: GGX's D is 1/pi, the
/// visibility term 0.5 / (n.v + n.l)) lit at normal incidence: E / (1.2 * 2^10) *
/// ((1 - F) * base / pi + F * V / pi), F Schlick's from v.h. Within a level: the
/// built-in light and ambient add under 0.0003 at this exposure (a third of a level
/// here), and the sRGB rounding the rest.
#[test]
fn a_sun_in_lux_is_metered_and_matches_the_brdf_worked_by_hand() {
    let gpu = support::gpu();
    let base = 0.5;
    let lux = 2000.0;
    let mut scene = support::plane(1.0);
    scene.instances[0].color = Vec4::new(base, base, base, 1.0);
    scene.materials = vec![material(1.0, 0.0)];
    scene.lights = vec![stereocull::lights::Light {
        kind: stereocull::lights::LightKind::Directional,
        color: Vec3::ONE,
        intensity: lux,
        range: None,
        position: Vec3::ZERO,
        direction: Vec3::NEG_Z,
    }];
    scene.physical_lights = true;
    let rig = facing_the_plane(2.2);
    let render = |o| support::render(&gpu, &scene, &rig, o).unwrap().remove(0);

    let metered = render(support::frustum_only());
    let brightest = metered.pixels().map(|p| p[0].max(p[1]).max(p[2])).max();
    assert!(brightest.is_some_and(|b| b < 255), "{brightest:?}");
    assert!(
        brightest.is_some_and(|b| b > 100),
        "not black: {brightest:?}"
    );

    let ev100 = 10.0;
    let fixed = RendererOptions {
        exposure: Exposure::Ev100(ev100),
        tonemap: Tonemap::None,
        ..support::frustum_only()
    };
    let image = render(fixed);
    let k = 1.0 / (1.2 * 1024.0);
    let pi = std::f32::consts::PI;
    let mut checked = 0;
    for e in 0..2 {
        for (x, y) in [(70, 56), (80, 64), (92, 70)] {
            let (p, eye) = on_plane(&rig, e, (x, y));
            assert!(
                p.x.abs() < 0.9 && p.y.abs() < 0.9,
                "({x}, {y}) sees {p}, off the plane"
            );
            let v = (eye - p).normalize();
            let (n_dot_v, h) = (v.z, (v + Vec3::Z).normalize());
            let f = 0.04 + 0.96 * (1.0 - v.dot(h)).powi(5);
            let visibility = 0.5 / (n_dot_v + 1.0);
            let want = lux * k * ((1.0 - f) * base / pi + f * visibility / pi);
            let got = image.get_pixel(x + e as u32 * EYE_W, y)[1] as f32;
            let want = support::srgb(want);
            assert!(
                (got - want).abs() <= 1.0,
                "eye {e} ({x}, {y}): {got} against {want:.2}"
            );
            checked += 1;
        }
    }
    assert_eq!(checked, 6);
}

/// An engine sets its camera's exposure per frame (`Renderer::set_exposure`): the
/// next frame equals a renderer made with those settings, byte for byte (the same
/// pipelines read the same frame context), though the frames keep unchanged pixels:
/// a new exposure moves every pixel, so that frame redraws whole.
#[test]
fn an_exposure_set_per_frame_draws_as_one_made_with_it() {
    let gpu = support::gpu();
    let scene = mapped_plane();
    let rig = facing_the_plane(2.2);
    let kept = RendererOptions {
        keep_unchanged: KeepUnchanged::On,
        ..options(LIGHT)
    };
    let (exposure, tonemap) = (Exposure::Ev100(-1.0), Tonemap::Aces);
    let with = RendererOptions {
        exposure,
        tonemap,
        ..kept.clone()
    };
    let made = support::render(&gpu, &scene, &rig, with).unwrap().remove(0);
    let mut renderer = Renderer::new(&gpu.device, &scene, &rig, kept).unwrap();
    let targets = renderer.create_targets(&gpu.device);
    let frame = |renderer: &mut Renderer| support::next_frame(&gpu, renderer, &rig, &targets);
    let before = frame(&mut renderer);
    renderer.set_exposure(exposure, tonemap);
    assert_eq!(renderer.exposure(), (Some(-1.0), Tonemap::Aces));
    let after = frame(&mut renderer);
    assert!(after != before, "the exposure changes the kept frame");
    assert!(
        after == made,
        "the frame differs from one made with the exposure"
    );
}

/// The plane (no textures) with material `m` and a dark base color, and where eye 0
/// sees the mirror point of the light (its highlight's peak) and a point well off it.
fn highlight(m: Material, base: Vec4) -> (u8, u8) {
    let gpu = support::gpu();
    let mut scene = Scene::default();
    let mesh = plane(&mut scene);
    scene.materials = vec![m];
    scene.instances.push(Instance {
        world_from_local: glam::Affine3A::IDENTITY,
        mesh,
        color: base,
        material: None,
        animation: Animation::NONE,
    });
    let rig = facing_the_plane(2.2);
    let image = support::render(&gpu, &scene, &rig, options(BEHIND))
        .unwrap()
        .remove(0);
    let eye = rig.resolve().unwrap().displays[0].eyes[0].position();
    let l = BEHIND.normalize();
    // The eye sees the light mirrored where the direction to the eye is L mirrored.
    let to_eye = Vec3::new(-l.x, -l.y, l.z);
    let peak = eye - to_eye * (eye.z / to_eye.z);
    let pixel = |p: Vec3| {
        let view = rig.resolve().unwrap().displays[0].eyes[0];
        let clip = view.clip_from_world() * p.extend(1.0);
        let x = (clip.x / clip.w * 0.5 + 0.5) * EYE_W as f32;
        let y = (0.5 - clip.y / clip.w * 0.5) * EYE_H as f32;
        let px = image.get_pixel(x as u32, y as u32);
        px[0]
    };
    (pixel(peak), pixel(Vec3::new(-0.8, -0.8, 0.0)))
}

fn material(roughness: f32, metallic: f32) -> Material {
    Material {
        roughness,
        metallic,
        ..Default::default()
    }
}

/// Rougher is dimmer at the highlight's peak (GGX spreads the same light wider); more
/// metal makes the highlight stand out more (its reflectance rises to the base color's
/// while the diffuse that lifts the rest falls). Strictly, by a level or more a step,
/// and unsaturated, so the sweep is measured, not clipped.
#[test]
fn the_highlight_falls_with_roughness_and_rises_with_metalness() {
    let dark = Vec4::new(0.2, 0.1, 0.05, 1.0);
    let peaks: Vec<u8> = [0.4, 0.55, 0.7, 0.85, 1.0]
        .map(|r| highlight(material(r, 0.0), dark).0)
        .to_vec();
    eprintln!("peaks by roughness: {peaks:?}");
    assert!(
        peaks[0] < 250,
        "the sharpest highlight is not clipped: {peaks:?}"
    );
    assert!(peaks.windows(2).all(|w| w[0] > w[1]), "{peaks:?}");
    let red = Vec4::new(0.6, 0.2, 0.1, 1.0);
    let contrast: Vec<i32> = [0.0, 0.25, 0.5, 0.75, 1.0]
        .map(|m| {
            let (peak, off) = highlight(material(0.7, m), red);
            assert!(peak < 250, "metalness {m}: the peak {peak} is not clipped");
            peak as i32 - off as i32
        })
        .to_vec();
    eprintln!("peak over off-peak by metalness: {contrast:?}");
    assert!(contrast.windows(2).all(|w| w[0] < w[1]), "{contrast:?}");
}

/// A hook sees what the built-in shading uses: `pbr_inputs` and `pbr_shade` restated
/// as a material function draw what the built-in shading draws (the RECOMPILED
/// tolerance: the same operations compiled in another expression tree), and a hook
/// that changes an input between the two (every surface a mirror-smooth metal) draws
/// something else.
#[test]
fn hooks_shade_with_the_built_in_inputs() {
    let gpu = support::gpu();
    let scene = mapped_plane();
    let rig = facing_the_plane(2.2);
    let with = |hook: Option<&str>| RendererOptions {
        material: hook.map(Into::into),
        ..options(LIGHT)
    };
    let render = |o| support::render(&gpu, &scene, &rig, o).unwrap().remove(0);
    let built_in = render(with(None));
    let restated = "fn material(s: Surface) -> vec4<f32> { return pbr_shade(s, pbr_inputs(s)); }";
    let same = render(with(Some(restated)));
    support::assert_images_match("restated", &same, &built_in, support::Tolerance::RECOMPILED);
    let metal = "fn material(s: Surface) -> vec4<f32> {\n    var p = pbr_inputs(s);\n    p.metallic = 1.0;\n    p.roughness = 0.2;\n    return pbr_shade(s, p);\n}";
    assert_ne!(
        render(with(Some(metal))),
        built_in,
        "the hook's inputs are used"
    );
}
