//! GPU culling against the CPU reference, byte for byte: random scenes (fixed seeds) on
//! every preset, up to 200k instances and 300 meshes, and the edge cases.

use glam::{Affine3A, Vec3, Vec4};
use stereocull::contexts::DisplayContext;
use stereocull::cull::cpu;
use stereocull::device::Gpu;
use stereocull::records::CullLayout;
use stereocull::renderer::{Renderer, RendererOptions};
use stereocull::rig::Rig;
use stereocull::scene::{Instance, Scene};

fn gpu() -> Gpu {
    let gpu = Gpu::headless().expect("no adapter: install mesa-vulkan-drivers (lavapipe)");
    eprintln!("adapter: {}", gpu.adapter_line());
    gpu
}

/// Runs one GPU-culled frame and compares every display's buffers with the CPU's.
fn compare(gpu: &Gpu, scene: &Scene, rig: &Rig, what: &str) -> Vec<usize> {
    let mut renderer = Renderer::new(&gpu.device, scene, rig, RendererOptions::default()).unwrap();
    let targets = renderer.create_targets(&gpu.device);
    renderer
        .submit_frame(&gpu.device, &gpu.queue, rig, &targets)
        .unwrap();
    let layout = CullLayout::new(scene);
    (0..rig.displays.len())
        .map(|d| {
            let ctx = DisplayContext::new(rig, d).unwrap();
            let want = cpu::cull(&layout, &ctx.planes, ctx.views);
            let got = renderer.read_cull(&gpu.device, &gpu.queue, d).unwrap();
            assert_eq!(
                got.draw_count, want.draw_count,
                "{what} display {d}: draw_count"
            );
            assert_eq!(got.draws, want.draws, "{what} display {d}: draws");
            assert!(
                got.visible == want.visible,
                "{what} display {d}: visible lists differ"
            );
            want.visible.len()
        })
        .collect()
}

/// Reduced display resolution: these tests are about buffers, not pixels.
fn small(preset: &str) -> Rig {
    let mut rig = Rig::preset(preset).unwrap();
    for d in &mut rig.displays {
        d.resolution = [64, 64];
    }
    rig
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
    for (n, meshes, seed) in cases {
        let scene = Scene::procedural(n, meshes, seed);
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

fn cubes(positions: &[(Vec3, u32)], meshes: u32) -> Scene {
    let mut s = Scene::procedural(0, meshes, 1);
    s.instances = positions
        .iter()
        .map(|&(p, mesh)| Instance {
            world_from_local: Affine3A::from_translation(p),
            mesh,
            color: Vec4::ONE,
        })
        .collect();
    s
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
    let planes = DisplayContext::new(&rig, 0).unwrap().planes;
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
