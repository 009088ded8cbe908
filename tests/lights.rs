//! Punctual lights through clustered forward shading: each display's clusters, built on
//! the GPU once per frame for both eyes, equal the CPU twin's byte for byte on random
//! light sets and every preset; a point light's falloff and a spot's cone, looked up
//! through the clusters, match the CPU twin of the shading at sampled pixels of both
//! eyes; a moved light moves its light; past the budget is an error naming it.

use glam::Vec3;
use rand::{Rng, SeedableRng};
use stereocull::lights::{DISPLAY_WORDS, Light, LightKind, MAX_LIGHTS, cluster_bits};
use stereocull::pbr::{self, Pbr};
use stereocull::renderer::{Renderer, RendererOptions};
use stereocull::scene::Scene;

mod support;

const EYE_W: u32 = 160;
const EYE_H: u32 = 128;

/// `n` lights of every kind scattered around the origin (seeded).
fn random_lights(n: usize, seed: u64) -> Vec<Light> {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    (0..n)
        .map(|i| {
            let position = Vec3::new(
                rng.random_range(-30.0..30.0),
                rng.random_range(-2.0..6.0),
                rng.random_range(-40.0..20.0),
            );
            let color = Vec3::new(rng.random(), rng.random(), rng.random());
            let intensity = rng.random_range(0.5..40.0);
            let range = (i % 3 != 0).then(|| rng.random_range(0.5..12.0));
            let kind = match i % 7 {
                0 => LightKind::Spot {
                    inner: 0.2,
                    outer: 0.6,
                },
                6 => LightKind::Directional,
                _ => LightKind::Point,
            };
            let direction = Vec3::new(
                rng.random_range(-1.0..1.0),
                -1.0,
                rng.random_range(-1.0..1.0),
            )
            .normalize();
            Light {
                kind,
                direction,
                ..Light::point(position, color, intensity, range)
            }
        })
        .collect()
}

/// A scene of a few cubes around the viewer, with `lights`.
fn lit_cubes(lights: Vec<Light>) -> Scene {
    let instances = [
        (Vec3::new(0.0, 0.0, -4.0), 0),
        (Vec3::new(2.0, 0.5, -6.0), 1),
    ];
    let mut scene = support::cubes(&instances, 2);
    scene.lights = lights;
    scene
}

/// Every preset, with random light sets of 1 to the budget: the GPU's clusters (each
/// light testing the clusters of its slices) equal the CPU twin's (every cluster
/// against every light) for every display, summaries and bits.
/// The sets are dense enough that many clusters hold several lights and some none.
#[test]
fn gpu_clusters_equal_the_cpu_twins_on_every_preset() {
    let gpu = support::gpu();
    for (k, preset) in ["hmd", "cave", "hmd-peripheral", "hmd-foveated"]
        .iter()
        .enumerate()
    {
        for (j, count) in [1usize, 37, MAX_LIGHTS].into_iter().enumerate() {
            let lights = random_lights(count, (10 * k + j) as u64);
            let scene = lit_cubes(lights.clone());
            let rig = support::sized(preset, 48, 40);
            let mut renderer =
                Renderer::new(&gpu.device, &scene, &rig, RendererOptions::default()).unwrap();
            let targets = renderer.create_targets(&gpu.device);
            renderer
                .submit_frame(&gpu.device, &gpu.queue, &rig, 0.0, &targets)
                .unwrap();
            let names: Vec<&str> = renderer.passes().iter().map(|p| p.name).collect();
            assert_eq!(
                names.iter().filter(|n| **n == "light_clusters").count(),
                1,
                "{names:?}"
            );
            let words = renderer
                .diagnostics(&gpu.device, &gpu.queue)
                .light_clusters()
                .unwrap();
            let records: Vec<_> = lights.iter().map(Light::record).collect();
            let plan = renderer.plan(&rig, 0.0).unwrap();
            let mut set = 0usize;
            for (d, context) in plan.displays.iter().map(|d| &d.context).enumerate() {
                let want =
                    cluster_bits(&records, &context.view_from_world, &context.clip_from_view);
                let at = (d as u32 * DISPLAY_WORDS) as usize;
                let got = &words[at..at + DISPLAY_WORDS as usize];
                if let Some(c) = (0..want.len()).find(|&i| got[i] != want[i]) {
                    panic!(
                        "{preset}, {count} lights, display {d}: word {c}: GPU {:#x}, CPU {:#x}",
                        got[c], want[c]
                    );
                }
                set += want.iter().filter(|w| **w != 0).count();
            }
            assert!(set > 0, "{preset}: some cluster holds a light");
        }
    }
}

/// The 2 m plane z = 0 facing +z, white and untextured, and `lights`.
fn lit_plane(lights: Vec<Light>) -> Scene {
    let mut scene = support::plane(1.0);
    scene.lights = lights;
    scene
}

/// A point light in front of the plane's left half and a spot aimed at its right half,
/// its cone's edge across the plane.
fn point_and_spot() -> Vec<Light> {
    let point = Light::point(
        Vec3::new(-0.5, 0.2, 0.6),
        Vec3::new(1.0, 0.8, 0.6),
        0.3,
        Some(0.8),
    );
    let spot = Light {
        kind: LightKind::Spot {
            inner: 0.25,
            outer: 0.45,
        },
        direction: Vec3::new(0.0, 0.0, -1.0),
        ..Light::point(
            Vec3::new(0.5, -0.1, 1.2),
            Vec3::new(0.5, 0.7, 1.0),
            1.2,
            None,
        )
    };
    vec![point, spot]
}

/// What the lights alone bring, as a material hook: the built-in inputs shaded by
/// `lights_shading`, which looks the fragment's cluster up.
const LIGHTS_ONLY: &str = "
fn material(s: Surface) -> vec4<f32> {
    let v = normalize(display.eye[s.eye].position - s.world_position);
    return vec4(lights_shading(s, pbr_inputs(s), v), 1.0);
}";

/// Sampled pixels of both eyes within 2 levels of the CPU twin, which sums every light
/// (one outside a point's cluster gives it exactly nothing: its window is zero past its
/// range). They differ, as the frame light's test says, in rounding well under a level.
/// The spot's cone edge and the point light's window both cross the plane; both eyes
/// see the same clusters, from one grid.
#[test]
fn point_falloff_and_spot_cone_match_the_cpu_twin_in_both_eyes() {
    let gpu = support::gpu();
    let lights = point_and_spot();
    let scene = lit_plane(lights.clone());
    let mut rig = support::sized("hmd", EYE_W, EYE_H);
    rig.viewer.position = [0.0, 0.0, 2.2];
    let options = RendererOptions {
        material: Some(LIGHTS_ONLY.into()),
        ..support::frustum_only()
    };
    let image = support::render(&gpu, &scene, &rig, options)
        .unwrap()
        .remove(0);
    let records: Vec<_> = lights.iter().map(Light::record).collect();
    let inputs = Pbr {
        base: glam::Vec4::ONE,
        metallic: 0.0,
        roughness: 0.5,
        normal: Vec3::Z,
        occlusion: 1.0,
        emissive: Vec3::ZERO,
    };
    let (mut checked, mut lit, mut dark) = (0, 0, 0);
    for e in 0..2 {
        for y in (3..EYE_H).step_by(4) {
            for x in (3..EYE_W).step_by(4) {
                let (p, eye) = support::on_plane(&rig, e, (x, y), (EYE_W, EYE_H));
                if p.x.abs() > 0.95 || p.y.abs() > 0.95 {
                    continue;
                }
                let want = pbr::shade_lights(&inputs, eye - p, &records, p)
                    .to_array()
                    .map(support::srgb);
                let got = image.get_pixel(x + e as u32 * EYE_W, y);
                for c in 0..3 {
                    let d = (got[c] as f32 - want[c]).abs();
                    assert!(
                        d <= 2.0,
                        "eye {e} pixel ({x}, {y}) at {p}: channel {c} is {} on the GPU, {:.2} on the CPU",
                        got[c],
                        want[c]
                    );
                }
                checked += 1;
                lit += usize::from(want[2] > 40.0);
                dark += usize::from(want[2] < 1.0);
            }
        }
    }
    eprintln!("{checked} pixels checked: {lit} lit, {dark} dark");
    assert!(
        checked > 300 && lit > 50 && dark > 20,
        "{checked} {lit} {dark}"
    );
}

/// A light moved with `set_lights` moves its light from the next frame; the clusters
/// follow it.
#[test]
fn a_moved_light_moves_its_light() {
    let gpu = support::gpu();
    let mut lights = point_and_spot();
    let scene = lit_plane(lights.clone());
    let mut rig = support::sized("hmd", EYE_W, EYE_H);
    rig.viewer.position = [0.0, 0.0, 2.2];
    let options = RendererOptions {
        material: Some(LIGHTS_ONLY.into()),
        ..support::frustum_only()
    };
    let mut renderer = Renderer::new(&gpu.device, &scene, &rig, options).unwrap();
    let targets = renderer.create_targets(&gpu.device);
    let frame = |renderer: &mut Renderer| support::next_frame(&gpu, renderer, &rig, &targets);
    let before = frame(&mut renderer);
    lights[0].position = Vec3::new(0.5, 0.5, 0.6);
    renderer.set_lights(&lights).unwrap();
    let after = frame(&mut renderer);
    // The left half darkens where the point light was; its new place brightens. The
    // pixel of eye 0 that sees plane point (wx, wy):
    let at = |img: &image::RgbaImage, wx: f32, wy: f32| {
        let pixels = (0..EYE_H).flat_map(|y| (0..EYE_W).map(move |x| (x, y)));
        let nearest = pixels
            .min_by(|&a, &b| {
                let d = |px| {
                    let (p, _) = support::on_plane(&rig, 0, px, (EYE_W, EYE_H));
                    (p.x - wx).hypot(p.y - wy)
                };
                d(a).total_cmp(&d(b))
            })
            .unwrap();
        img.get_pixel(nearest.0, nearest.1)[0]
    };
    assert!(at(&before, -0.3, 0.1) > at(&after, -0.3, 0.1) + 20);
    assert!(at(&after, 0.35, 0.35) > at(&before, 0.35, 0.35) + 20);
}

/// One light past the budget is an error naming it; a light that is not valid too.
#[test]
fn lights_past_the_budget_are_an_error_naming_it() {
    let gpu = support::gpu();
    let rig = support::sized("hmd", 32, 32);
    let scene = lit_cubes(random_lights(MAX_LIGHTS + 1, 7));
    let e = Renderer::new(&gpu.device, &scene, &rig, RendererOptions::default())
        .err()
        .unwrap()
        .to_string();
    let over = format!("{} lights", MAX_LIGHTS + 1);
    let budget = format!("budget of {MAX_LIGHTS}");
    assert!(e.contains(&over) && e.contains(&budget), "{e}");
    let mut bad = random_lights(2, 8);
    bad[1].range = Some(-1.0);
    let e = Renderer::new(
        &gpu.device,
        &lit_cubes(bad),
        &rig,
        RendererOptions::default(),
    )
    .err()
    .unwrap()
    .to_string();
    assert!(e.contains("light 1") && e.contains("range"), "{e}");
}

/// `KHR_lights_punctual` as exporters write it (required): a point, a spot and a
/// directional light on nodes, one of them under an animated node: read in glTF's
/// units at their nodes' places, the spot and the sun shining down their nodes' -z, and
/// the animated one moving with its node when the scene is posed.
#[test]
fn gltf_lights_are_read_on_their_nodes_and_move_with_them() {
    let mut scene = gltf_lights();
    assert_eq!(scene.lights.len(), 3);
    // Depth first: node 0, node 1's child 3, node 2.
    let [point, spot, sun] = [scene.lights[0], scene.lights[1], scene.lights[2]];
    assert_eq!(point.kind, LightKind::Point);
    assert_eq!(
        (point.position, point.intensity, point.range),
        (Vec3::new(1.0, 2.0, 3.0), 20.0, Some(6.0))
    );
    assert_eq!(point.color, Vec3::new(1.0, 0.5, 0.25));
    assert_eq!(sun.kind, LightKind::Directional);
    assert!(
        sun.direction.distance(Vec3::NEG_Y) < 1e-6,
        "{}",
        sun.direction
    );
    assert_eq!(
        spot.kind,
        LightKind::Spot {
            inner: 0.2,
            outer: 0.5
        }
    );
    assert!(spot.direction.distance(Vec3::NEG_Y) < 1e-6);
    assert_eq!(
        scene.posing.lights.len(),
        1,
        "the spot hangs under the animated node"
    );
    scene.pose(1.0);
    assert!(
        scene.lights[1].position.distance(Vec3::new(2.0, 3.0, 0.0)) < 1e-5,
        "{}",
        scene.lights[1].position
    );
    assert_eq!(
        scene.lights[0].position,
        Vec3::new(1.0, 2.0, 3.0),
        "a still node's light stays"
    );
}

/// A glTF file of three lights (point, spot, directional) on nodes, the spot under a
/// node that moves 4 m along x over 2 s, as exporters write it (the extension
/// required), imported.
fn gltf_lights() -> Scene {
    use serde_json::json;
    let times = [0.0f32, 2.0];
    let moves = [[0.0f32, 0.0, 0.0], [4.0, 0.0, 0.0]];
    let mut bin: Vec<u8> = bytemuck::cast_slice(&times).to_vec();
    bin.extend_from_slice(bytemuck::cast_slice(&moves));
    let down = [
        -std::f32::consts::FRAC_1_SQRT_2,
        0.0,
        0.0,
        std::f32::consts::FRAC_1_SQRT_2,
    ];
    let file = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_lights_punctual"], "extensionsRequired": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "point", "color": [1.0, 0.5, 0.25], "intensity": 20.0, "range": 6.0},
            {"type": "spot", "intensity": 50.0, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.5}},
            {"type": "directional", "intensity": 3.0}
        ]}},
        "scene": 0, "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [
            {"translation": [1.0, 2.0, 3.0], "extensions": {"KHR_lights_punctual": {"light": 0}}},
            {"children": [3]},
            {"rotation": down, "extensions": {"KHR_lights_punctual": {"light": 2}}},
            {"translation": [0.0, 3.0, 0.0], "rotation": down, "extensions": {"KHR_lights_punctual": {"light": 1}}}
        ],
        "animations": [{"channels": [{"sampler": 0, "target": {"node": 1, "path": "translation"}}],
            "samplers": [{"input": 0, "output": 1}]}],
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": [{"buffer": 0, "byteLength": 8}, {"buffer": 0, "byteOffset": 8, "byteLength": 24}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 2, "type": "SCALAR", "min": [0], "max": [2]},
            {"bufferView": 1, "componentType": 5126, "count": 2, "type": "VEC3"}
        ]
    });
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("lights.glb");
    std::fs::write(&path, support::glb::write_glb(&file, &bin)).unwrap();
    stereocull::gltf_import::import(&path).unwrap()
}

/// Posing on the GPU (nothing on the CPU poses the scene), the renderer poses the lights
/// on animated nodes at each frame's time: the clusters are the CPU twin's of the scene
/// posed at that time, and they change as the spot moves.
#[test]
fn posing_on_the_gpu_moves_lights_on_animated_nodes() {
    let gpu = support::gpu();
    let lights = gltf_lights();
    let mut scene = lit_plane(lights.lights.clone());
    scene.posing = lights.posing.clone();
    let rig = support::sized("hmd", 48, 40);
    let options = RendererOptions {
        posing: stereocull::renderer::PosingMode::Gpu,
        ..RendererOptions::default()
    };
    let mut renderer = Renderer::new(&gpu.device, &scene, &rig, options).unwrap();
    let targets = renderer.create_targets(&gpu.device);
    let mut seen = Vec::new();
    for time in [0.0, 1.0] {
        renderer
            .submit_frame(&gpu.device, &gpu.queue, &rig, time, &targets)
            .unwrap();
        let got = renderer
            .diagnostics(&gpu.device, &gpu.queue)
            .light_clusters()
            .unwrap();
        let mut posed = scene.clone();
        posed.pose(time);
        let records: Vec<_> = posed.lights.iter().map(Light::record).collect();
        let context = &renderer.plan(&rig, time).unwrap().displays[0].context;
        let want = cluster_bits(&records, &context.view_from_world, &context.clip_from_view);
        assert!(
            got[..want.len()] == want[..],
            "t {time}: the clusters of the lights posed then"
        );
        seen.push(want);
    }
    assert_ne!(seen[0], seen[1], "the spot moved");
}

/// A live scene's lights by handle: inserted, moved and removed lights reach the
/// renderer at the next sync, and a removed handle is an error.
#[test]
fn live_lights_are_added_moved_and_removed_by_handle() {
    use stereocull::live::LiveScene;
    let gpu = support::gpu();
    let scene = lit_plane(Vec::new());
    let mut rig = support::sized("hmd", EYE_W, EYE_H);
    rig.viewer.position = [0.0, 0.0, 2.2];
    let options = RendererOptions {
        material: Some(LIGHTS_ONLY.into()),
        ..support::frustum_only()
    };
    let mut renderer = Renderer::new(&gpu.device, &scene, &rig, options).unwrap();
    let mut live = LiveScene::new(scene);
    let targets = renderer.create_targets(&gpu.device);
    let frame = |renderer: &mut Renderer, live: &mut LiveScene| {
        renderer.sync(&gpu.device, &gpu.queue, live).unwrap();
        renderer
            .submit_frame(&gpu.device, &gpu.queue, &rig, 0.0, &targets)
            .unwrap();
        let image =
            stereocull::readback::read_rgba8(&gpu.device, &gpu.queue, &targets[0].color).unwrap();
        image.pixels().map(|p| p[0] as u64).sum::<u64>()
    };
    let dark = frame(&mut renderer, &mut live);
    let lamp = Light::point(Vec3::new(0.0, 0.0, 0.5), Vec3::ONE, 0.5, Some(2.0));
    let handle = live.insert_light(lamp).unwrap();
    let lit = frame(&mut renderer, &mut live);
    live.set_light(
        handle,
        Light {
            position: Vec3::new(0.0, 0.0, 1.5),
            ..lamp
        },
    )
    .unwrap();
    let farther = frame(&mut renderer, &mut live);
    live.remove_light(handle).unwrap();
    let off = frame(&mut renderer, &mut live);
    assert!(lit > farther && farther > dark, "{dark} {lit} {farther}");
    assert_eq!(off, dark, "removed: as before any light");
    assert!(live.set_light(handle, lamp).is_err());
}

/// `rooms:` hangs a lamp in every room; `--lights N[:SEED]` adds N more, the same for
/// the same seed and elsewhere for another; `info --scene` counts them.
#[test]
fn rooms_have_lamps_and_the_cli_adds_seeded_lights() {
    let scene = stereocull::scene_spec::load("rooms:200").unwrap();
    assert_eq!(scene.lights.len(), 9, "a 3 x 3 grid of rooms");
    let lights = |seed: u64| {
        let mut s = stereocull::scene_spec::load("procedural:100").unwrap();
        stereocull::procedural::scatter_lights(&mut s, 16, seed);
        s.lights
    };
    assert_eq!(lights(3), lights(3));
    assert_ne!(lights(3), lights(4));
    assert!(lights(3).iter().all(|l| l.check().is_ok()));
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_stereocull"))
        .args(["info", "--scene", "rooms:200"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains(", 9 lights"), "{text}");
    let dir = tempfile::tempdir().unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_stereocull"))
        .args([
            "render",
            "--scene",
            "rooms:200",
            "--lights",
            "40:2",
            "--width",
            "32",
            "--height",
            "32",
        ])
        .arg("--out")
        .arg(dir.path())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}
