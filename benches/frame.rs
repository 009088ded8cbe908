//! CPU cost of one frame (prepare + encode + submit) per stereo mode at 10k and 100k
//! instances on `hmd`, and at 100k over 1 and 16 material bins (issue 21's ratio). Only
//! the CPU side is timed: each frame is waited for untimed.

use std::time::{Duration, Instant};

use criterion::{Criterion, criterion_group, criterion_main};
use stereocull::device::Gpu;
use stereocull::procedural;
use stereocull::renderer::{
    CullMode, DisplayTarget, OcclusionMode, Renderer, RendererOptions, StereoMode,
};
use stereocull::rig::Rig;
use stereocull::scene::{Material, Shading};

fn frame(c: &mut Criterion) {
    let gpu = Gpu::headless().expect("no adapter: install mesa-vulkan-drivers (lavapipe)");
    eprintln!("adapter: {}", gpu.adapter_line());
    let mut rig = Rig::preset("hmd").expect("preset");
    rig.displays[0].resolution = [64, 64];
    let mut group = c.benchmark_group("frame_cpu");
    group.sample_size(10);
    for n in [10_000u32, 100_000] {
        let scene = procedural::scene(n, 8, 1);
        for mode in StereoMode::ALL {
            for cull in [CullMode::Gpu, CullMode::Cpu] {
                if mode.per_instance() && cull == CullMode::Gpu {
                    continue;
                }
                let options = RendererOptions {
                    cull,
                    mode,
                    ..Default::default()
                };
                let Ok(mut renderer) = Renderer::new(&gpu.device, &scene, &rig, options) else {
                    eprintln!("{} unavailable on this adapter", mode.name());
                    continue;
                };
                let targets = renderer.create_targets(&gpu.device);
                let name = format!("{n}/{}/{cull:?}", mode.name()).to_lowercase();
                group.bench_function(name, |b| {
                    b.iter_custom(|iters| cpu_time(&gpu, (&mut renderer, &targets), &rig, iters))
                });
            }
        }
    }
    group.finish();
}

/// The CPU time of `iters` frames, each waited for untimed.
fn cpu_time(
    gpu: &Gpu,
    (renderer, targets): (&mut Renderer, &[DisplayTarget]),
    rig: &Rig,
    iters: u64,
) -> Duration {
    let mut cpu = Duration::ZERO;
    for _ in 0..iters {
        let start = Instant::now();
        renderer
            .submit_frame(&gpu.device, &gpu.queue, rig, 0.0, targets)
            .expect("frame");
        cpu += start.elapsed();
        gpu.device
            .poll(wgpu::PollType::wait_indefinitely())
            .expect("poll");
    }
    cpu
}

/// 100k instances of 64 meshes over 16 materials, each shaded by its own hook (16
/// bins: 16 draw calls per display), against the same scene with one material (one
/// bin), `hmd`, GPU cull, LOD on, occlusion off.
fn materials(c: &mut Criterion) {
    let gpu = Gpu::headless().expect("no adapter: install mesa-vulkan-drivers (lavapipe)");
    let mut rig = Rig::preset("hmd").expect("preset");
    rig.displays[0].resolution = [64, 64];
    let mut group = c.benchmark_group("materials_cpu");
    group.sample_size(10);
    for bins in [1u32, 16] {
        let mut scene = procedural::scene(100_000, 64, 1);
        scene.materials = (0..bins)
            .map(|k| Material {
                name: format!("tint {k}"),
                shading: Shading::Hook(k),
                ..Default::default()
            })
            .collect();
        let starts: Vec<usize> = scene
            .meshes
            .iter()
            .map(|m| m.base_vertex as usize)
            .collect();
        for (m, &start) in starts.iter().enumerate() {
            let end = starts.get(m + 1).copied().unwrap_or(scene.vertices.len());
            for v in &mut scene.vertices[start..end] {
                v.material = m as u32 % bins;
            }
        }
        let hooks = (0..bins)
            .map(|k| {
                let tint = 0.5 + 0.5 * k as f32 / bins as f32;
                format!("fn material(s: Surface) -> vec4<f32> {{ return vec4(base_color(s).rgb * {tint:?}, 1.0); }}\n").into()
            })
            .collect();
        // Occlusion off: its late pass would double the draw calls of both. LOD on:
        // lavapipe then draws each untimed frame in a fraction of the time.
        let options = RendererOptions {
            hooks,
            occlusion: OcclusionMode::Off,
            lod: true,
            ..Default::default()
        };
        let mut renderer = Renderer::new(&gpu.device, &scene, &rig, options).expect("renderer");
        let targets = renderer.create_targets(&gpu.device);
        let stats =
            (renderer.submit_frame(&gpu.device, &gpu.queue, &rig, 0.0, &targets)).expect("frame");
        eprintln!("{bins} bins: {} draw calls per frame", stats.draw_calls);
        group.bench_function(format!("100000/{bins}_bins"), |b| {
            b.iter_custom(|iters| cpu_time(&gpu, (&mut renderer, &targets), &rig, iters))
        });
    }
    group.finish();
}

criterion_group!(benches, frame, materials);
criterion_main!(benches);
