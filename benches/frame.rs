//! CPU cost of one frame (prepare + encode + submit) per stereo mode at 10k and 100k
//! instances on `hmd`. Only the CPU side is timed: each frame is waited for untimed.
//! (Material bins: `benches/material_bins.rs`.)

use std::time::{Duration, Instant};

use criterion::{Criterion, criterion_group, criterion_main};
use stereocull::device::Gpu;
use stereocull::procedural;
use stereocull::renderer::{CullMode, DisplayTarget, Renderer, RendererOptions, StereoMode};
use stereocull::rig::Rig;

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

criterion_group!(benches, frame);
criterion_main!(benches);
