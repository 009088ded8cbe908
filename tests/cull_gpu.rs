//! GPU culling against the CPU reference, byte for byte: random scenes (fixed seeds) on
//! every preset, up to 200k instances and 300 meshes, the edge cases, and the prefix
//! sums' edges up to 2^20 + 3 instances.

mod support;

use glam::Vec3;
use stereocull::cull::cpu;
use stereocull::device::Gpu;
use stereocull::keep::KeepUnchanged;
use stereocull::procedural;
use stereocull::records::CullLayout;
use stereocull::renderer::{CullMode, OcclusionMode, Renderer, RendererOptions, frame_lod};
use stereocull::rig::Rig;
use stereocull::scene::MAX_LODS;
use stereocull::scene::Scene;
use stereocull::shaders::{CullTests, SPAN, WORKGROUP_SIZE, subgroup_tier};
use support::{cubes, frustum_only, gpu, reference_culls};

/// Runs one GPU-culled frame and compares every display's buffers with the CPU's.
fn compare(gpu: &Gpu, scene: &Scene, rig: &Rig, what: &str) -> Vec<usize> {
    let renderer = support::one_frame(gpu, scene, rig, frustum_only());
    reference_culls(scene, rig)
        .into_iter()
        .enumerate()
        .map(|(d, want)| {
            let got = renderer
                .diagnostics(&gpu.device, &gpu.queue)
                .cull(d)
                .unwrap();
            support::assert_same_cull(&format!("{what} display {d}"), &got, &want);
            want.visible.len()
        })
        .collect()
}

/// Reduced display resolution: these tests are about buffers, not pixels.
fn small(preset: &str) -> Rig {
    support::sized(preset, 64, 64)
}

#[test]
fn gpu_matches_cpu_on_random_scenes_and_every_preset() {
    let gpu = gpu();
    let cases = [
        (1, 1, 1),
        (255, 3, 2),
        (257, 7, 3),
        (65_537, 64, 4),
        (200_000, 300, 5),
    ];
    for (k, (n, meshes, seed)) in cases.into_iter().enumerate() {
        let scene = procedural::scene(n, meshes, seed);
        // Odd cases spread their meshes over every material bin.
        let scene = match k % 2 {
            0 => scene,
            _ => support::with_random_bins(scene, seed),
        };
        for preset in ["hmd", "cave", "hmd-peripheral"] {
            let counts = compare(
                &gpu,
                &scene,
                &small(preset),
                &format!("n={n} meshes={meshes} {preset}"),
            );
            eprintln!("n={n} meshes={meshes} {preset}: visible {counts:?}");
        }
    }
}

#[test]
fn gpu_matches_cpu_on_edge_cases() {
    let gpu = gpu();
    let rig = small("hmd");
    // Nothing visible: everything behind the viewer at (0, 1.6, 2).
    let behind: Vec<_> = (0..1000)
        .map(|i| (Vec3::new(i as f32 * 0.01, 1.6, 8.0), i % 5))
        .collect();
    assert_eq!(
        compare(&gpu, &cubes(&behind, 5), &rig, "nothing visible"),
        [0]
    );
    // Everything visible: a tight cluster straight ahead.
    let ahead: Vec<_> = (0..1000)
        .map(|i| (Vec3::new(0.0, 1.6, -3.0 - i as f32 * 0.01), i % 5))
        .collect();
    assert_eq!(
        compare(&gpu, &cubes(&ahead, 5), &rig, "everything visible"),
        [1000]
    );
    // One mesh holding every instance, the others empty.
    let one: Vec<_> = (0..3000)
        .map(|i| (Vec3::new((i % 60) as f32 - 30.0, 1.6, -5.0), 3))
        .collect();
    compare(&gpu, &cubes(&one, 8), &rig, "one mesh holds all");
    // Spheres straddling the display frustum's planes, at distances from inside to out.
    let planes = rig.cull_jobs().unwrap()[0].planes;
    let mut straddling = Vec::new();
    for (k, p) in planes.iter().take(4).enumerate() {
        let n = p.truncate();
        let on_plane = Vec3::new(0.0, 1.6, -4.0) - n * (n.dot(Vec3::new(0.0, 1.6, -4.0)) + p.w);
        for j in 0..200 {
            let t = (j as f32 - 100.0) / 50.0; // -2 .. 2 radii
            straddling.push((on_plane - n * t, (k + j) as u32 % 4));
        }
    }
    compare(&gpu, &cubes(&straddling, 4), &rig, "straddling planes");
}

/// The prefix sums' edges (issue 24): nothing, one instance, a span (16 positions, one
/// invocation's walk) and one past it, a workgroup of positions and one past it, a
/// group of spans (the cull pass's workgroup, 4,096 positions: the draws pass's unit)
/// and one past it, and 2^20 + 3, with LOD off and on (where the entries' per-level
/// fields carry the prefixes: at least two levels must be drawn). Both tiers of the
/// cull pass's workgroup scan (subgroup operations where the adapter has one subgroup
/// size, as lavapipe does, and workgroup memory) write the CPU's buffers.
#[test]
fn gpu_matches_cpu_at_the_scans_edges() {
    let tiers = [
        support::gpu(),
        support::gpu_with(wgpu::Features::all() - wgpu::Features::SUBGROUP),
    ];
    assert!(!subgroup_tier(&tiers[1].device), "the fallback tier");
    if !subgroup_tier(&tiers[0].device) {
        eprintln!("this adapter has no subgroup tier: the fallback twice");
    }
    for gpu in &tiers {
        scans_edges(gpu);
    }
}

fn scans_edges(gpu: &Gpu) {
    let rig = support::sized("hmd", 256, 256);
    let jobs = rig.cull_jobs().unwrap();
    let lod = frame_lod(&rig, &rig.resolve().unwrap(), MAX_LODS as u32);
    let group = SPAN * WORKGROUP_SIZE;
    let span = SPAN;
    for n in [
        0,
        1,
        span,
        span + 1,
        256,
        257,
        group,
        group + 1,
        (1 << 20) + 3,
    ] {
        // The one instance straight ahead, so that it is drawn.
        let scene = match n {
            1 => cubes(&[(Vec3::new(0.0, 1.6, -3.0), 0)], 1),
            _ => procedural::scene(n, 6, n as u64 + 7),
        };
        let layout = CullLayout::new(&scene);
        for on in [false, true] {
            let options = RendererOptions {
                lod: on,
                ..frustum_only()
            };
            let renderer = support::one_frame(gpu, &scene, &rig, options);
            let got = support::read_culls(gpu, &renderer, &rig);
            let want = match on {
                true => cpu::cull_many_lod(&layout, &jobs, &lod),
                false => cpu::cull_many(&layout, &jobs),
            };
            let what = format!("n={n} lod={on}");
            assert_eq!(got, want, "{what}");
            // Some mesh drawn at two levels: more draws than meshes drawn.
            let mut meshes = want[0].draw_meshes(2, |id| scene.instances[id as usize].mesh);
            let draws = meshes.len();
            meshes.sort();
            meshes.dedup();
            if on && n >= 256 {
                assert!(draws > meshes.len(), "{what}: one level only");
            }
            assert_eq!(want[0].visible.is_empty(), n == 0, "{what}");
            eprintln!("{what}: visible {}", want[0].visible.len());
        }
    }
}

/// A renderer's cull holds the optional tests its frames can use and no other: a frame
/// without the lens mask, kept pixels, occlusion or the far layer runs a cull compiled
/// without them (the GPU == CPU tests above and the mask's, keep's, occlusion's and far
/// layer's own hold the images and buffers of each variant).
#[test]
fn the_cull_holds_only_the_tests_its_frames_can_use() {
    let gpu = gpu();
    let scene = procedural::scene(500, 4, 7);
    let rig = small("hmd");
    let tests = |options: RendererOptions| {
        let renderer = Renderer::new(&gpu.device, &scene, &rig, options).unwrap();
        renderer.diagnostics(&gpu.device, &gpu.queue).cull_tests()
    };
    assert_eq!(tests(frustum_only()), Some(CullTests::NONE));
    // Each option, and the one test it adds: (hidden, tiles, early, split).
    let cases: [(RendererOptions, [bool; 4]); 4] = [
        (
            RendererOptions {
                visibility_mask: true,
                ..frustum_only()
            },
            [true, false, false, false],
        ),
        (
            RendererOptions {
                keep_unchanged: KeepUnchanged::On,
                ..frustum_only()
            },
            [false, true, false, false],
        ),
        (
            RendererOptions {
                occlusion: OcclusionMode::On,
                ..Default::default()
            },
            [false, false, true, false],
        ),
        (
            RendererOptions {
                far_layer: true,
                ..frustum_only()
            },
            [false, false, false, true],
        ),
    ];
    for (options, [hidden, tiles, early, split]) in cases {
        let want = CullTests {
            hidden,
            tiles,
            early,
            split,
        };
        assert_eq!(tests(options), Some(want), "{want:?}");
    }
    let cpu = RendererOptions {
        cull: CullMode::Cpu,
        ..frustum_only()
    };
    assert_eq!(tests(cpu), None);
}
