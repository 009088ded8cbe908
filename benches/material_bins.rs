//! Issue 21's ratio: the CPU cost of a frame (prepare, encode, submit; each frame waited
//! for untimed) of 100k instances of 64 meshes over 16 materials, each shaded by its own
//! hook (16 bins: 16 draw calls per display), against the same scene over one material,
//! `hmd`, GPU cull, LOD on, occlusion off.
//!
//! The two renderers run in alternating rounds of frames, and each round gives a ratio
//! of the two medians: a small VM's speed drifts by more than the 15 % measured here
//! over the seconds one configuration takes, which two blocks of samples (criterion's
//! way, one configuration after the other) fold into the ratio.
//!
//! `cargo bench --bench material_bins`; under `cargo test` one short round.

use std::time::Instant;

use stereocull::device::Gpu;
use stereocull::procedural;
use stereocull::profiling::percentile;
use stereocull::renderer::{DisplayTarget, OcclusionMode, Renderer, RendererOptions};
use stereocull::rig::Rig;
use stereocull::scene::{Material, Scene, Shading};

/// Microseconds of a frame's prepare, encode (and finish) and submit.
type Phases = [f64; 3];

fn main() {
    let benching = std::env::args().any(|a| a == "--bench");
    let (rounds, frames) = if benching { (7, 50) } else { (1, 3) };
    let gpu = Gpu::headless().expect("no adapter: install mesa-vulkan-drivers (lavapipe)");
    println!("adapter: {}", gpu.adapter_line());
    let mut rig = Rig::preset("hmd").expect("preset");
    rig.displays[0].resolution = [64, 64];
    let mut made: Vec<(u32, Renderer, Vec<DisplayTarget>)> = [1u32, 16]
        .into_iter()
        .map(|bins| {
            let (scene, options) = binned(bins);
            let renderer = Renderer::new(&gpu.device, &scene, &rig, options).expect("renderer");
            let targets = renderer.create_targets(&gpu.device);
            (bins, renderer, targets)
        })
        .collect();
    let mut all: Vec<Vec<Phases>> = vec![Vec::new(); made.len()];
    let mut ratios = Vec::new();
    for round in 0..=rounds {
        let mut medians = Vec::new();
        for (k, (_, renderer, targets)) in made.iter_mut().enumerate() {
            let timed: Vec<Phases> = (0..frames)
                .map(|_| frame(&gpu, renderer, targets, &rig))
                .collect();
            let totals: Vec<f64> = timed.iter().map(|p| p.iter().sum()).collect();
            medians.push(percentile(&totals, 0.5));
            // Round 0 warms up: the first frames compile llvmpipe's shader variants.
            if round > 0 {
                all[k].extend(timed);
            }
        }
        if round > 0 {
            ratios.push(medians[1] / medians[0]);
            println!(
                "round {round}: 16 bins / 1 bin CPU per frame {:.3}",
                ratios[ratios.len() - 1]
            );
        }
    }
    for ((bins, _, _), timed) in made.iter().zip(&all) {
        let phase = |i: usize| percentile(&timed.iter().map(|p| p[i]).collect::<Vec<_>>(), 0.5);
        println!(
            "{bins} bins: median prepare {:.1} us, encode {:.1} us, submit {:.1} us",
            phase(0),
            phase(1),
            phase(2)
        );
    }
    println!(
        "16 bins / 1 bin, median of the rounds: {:.3}",
        percentile(&ratios, 0.5)
    );
}

/// The scene and options of `bins` materials: mesh m draws with material m % bins,
/// material k with hook k.
fn binned(bins: u32) -> (Scene, RendererOptions) {
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
    // Occlusion off: its late pass would double the draw calls of both. LOD on: lavapipe
    // then draws each untimed frame in a fraction of the time.
    let options = RendererOptions {
        hooks,
        occlusion: OcclusionMode::Off,
        lod: true,
        ..Default::default()
    };
    (scene, options)
}

/// One frame's CPU phases, the frame then waited for.
fn frame(gpu: &Gpu, renderer: &mut Renderer, targets: &[DisplayTarget], rig: &Rig) -> Phases {
    let start = Instant::now();
    renderer.prepare(&gpu.queue, rig, 0.0).expect("prepare");
    let prepared = Instant::now();
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    let views: Vec<_> = targets.iter().map(DisplayTarget::views).collect();
    let stats = renderer.encode(&mut encoder, &views, None).expect("encode");
    let commands = encoder.finish();
    let encoded = Instant::now();
    gpu.queue.submit([commands]);
    let submitted = Instant::now();
    gpu.device
        .poll(wgpu::PollType::wait_indefinitely())
        .expect("poll");
    assert!(stats.draw_calls == 1 || stats.draw_calls == 16);
    let us = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e6;
    [
        us(start, prepared),
        us(prepared, encoded),
        us(encoded, submitted),
    ]
}
