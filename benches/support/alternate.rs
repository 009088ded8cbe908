//! Two renderers timed in alternating rounds of frames (prepare, encode, finish, submit; each
//! frame waited for untimed), each round giving the ratio of the two medians. A small
//! VM's speed drifts over the seconds one configuration takes by more than the effects
//! these benches measure, and two blocks of samples (criterion's way, one configuration
//! after the other) fold that drift into the ratio; alternating rounds do not.
//!
//! Then the same rounds recorded only (prepare, encode, finish; the command buffer
//! dropped): the CPU cost of recording without the GPU's work between frames, which on
//! lavapipe runs on the same cores and leaves each frame's recording with cold caches.
//! Its rounds agree within about 5 % where the waited view's spread by 10 to 30 %.

use std::time::Instant;

use stereocull::device::Gpu;
use stereocull::profiling::percentile;
use stereocull::renderer::{DisplayTarget, Renderer};
use stereocull::rig::Rig;

/// Frames recorded only per frame waited, a round (see `compare`).
const RECORDED_PER_WAITED: u32 = 5;

/// Microseconds of a frame's prepare, encode, finish (wgpu records a pass's commands
/// into the device's when the encoder finishes) and submit.
type Phases = [f64; 4];

/// One configuration: its name, renderer and targets.
pub struct Config {
    pub name: String,
    pub renderer: Renderer,
    pub targets: Vec<DisplayTarget>,
}

/// Times `configs` (two: the second over the first) on `rig` in `rounds` alternating
/// rounds of `frames` frames after a warm-up round; prints each round's ratio, each
/// configuration's median phases, and the median ratio, which it returns. Then the
/// same recorded only.
pub fn compare(gpu: &Gpu, rig: &Rig, configs: &mut [Config; 2], shape: (u32, u32)) -> f64 {
    let waited = |c: &mut Config| frame(gpu, &mut c.renderer, &c.targets, rig);
    let total = |p: &Phases| p.iter().sum();
    let (all, ratios) = alternate(configs, shape, waited, total, || ());
    for (round, r) in ratios.iter().enumerate() {
        println!("round {}: CPU per frame {r:.3}", round + 1);
    }
    for (c, timed) in configs.iter().zip(&all) {
        let phase = |i: usize| percentile(&timed.iter().map(|p| p[i]).collect::<Vec<_>>(), 0.5);
        println!(
            "{}: median prepare {:.1} us, encode {:.1} us, finish {:.1} us, submit {:.1} us",
            c.name,
            phase(0),
            phase(1),
            phase(2),
            phase(3)
        );
    }
    let ratio = percentile(&ratios, 0.5);
    println!(
        "{} / {}, median of the rounds: {ratio:.3}",
        configs[1].name, configs[0].name
    );
    let record_only = |c: &mut Config| recorded(gpu, &mut c.renderer, &c.targets, rig);
    // The buffer writes of the frames' prepares, which no frame submitted.
    let flush = || {
        gpu.queue.submit([]);
        gpu.device
            .poll(wgpu::PollType::wait_indefinitely())
            .expect("poll");
    };
    // A recorded frame costs a few hundred microseconds at most: more of them a round.
    // Not too many between flushes: at 25 per waited frame `cave`'s rounds split
    // between 1.55 and 2.60; at 5 they agree within 5 %.
    let many = (shape.0, shape.1 * RECORDED_PER_WAITED);
    let (all, ratios) = alternate(configs, many, record_only, |t| *t, flush);
    let rounds: Vec<_> = ratios.iter().map(|r| format!("{r:.3}")).collect();
    println!("rounds recorded only: {}", rounds.join(", "));
    for (c, timed) in configs.iter().zip(&all) {
        println!(
            "{} recorded only: median {:.1} us",
            c.name,
            percentile(timed, 0.5)
        );
    }
    println!(
        "{} / {} recorded only, median of the rounds: {:.3}",
        configs[1].name,
        configs[0].name,
        percentile(&ratios, 0.5)
    );
    ratio
}

/// `rounds` alternating rounds of `frames` frames of each configuration after a warm-up
/// round (the first frames compile llvmpipe's shader variants), `after` each block:
/// each configuration's frames and each round's ratio of the medians of `total`.
fn alternate<T>(
    configs: &mut [Config; 2],
    (rounds, frames): (u32, u32),
    mut run: impl FnMut(&mut Config) -> T,
    total: impl Fn(&T) -> f64,
    mut after: impl FnMut(),
) -> ([Vec<T>; 2], Vec<f64>) {
    let mut all = [Vec::new(), Vec::new()];
    let mut ratios = Vec::new();
    for round in 0..=rounds {
        let mut medians = [0.0; 2];
        for (k, c) in configs.iter_mut().enumerate() {
            let timed: Vec<T> = (0..frames).map(|_| run(c)).collect();
            let totals: Vec<f64> = timed.iter().map(&total).collect();
            medians[k] = percentile(&totals, 0.5);
            after();
            if round > 0 {
                all[k].extend(timed);
            }
        }
        if round > 0 {
            ratios.push(medians[1] / medians[0]);
        }
    }
    (all, ratios)
}

/// Microseconds to prepare, encode and finish one frame, which is then dropped.
fn recorded(gpu: &Gpu, renderer: &mut Renderer, targets: &[DisplayTarget], rig: &Rig) -> f64 {
    let start = Instant::now();
    renderer.prepare(&gpu.queue, rig, 0.0).expect("prepare");
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    let views: Vec<_> = targets.iter().map(DisplayTarget::views).collect();
    renderer.encode(&mut encoder, &views, None).expect("encode");
    drop(encoder.finish());
    start.elapsed().as_secs_f64() * 1e6
}

/// One frame's CPU phases, the frame then waited for.
fn frame(gpu: &Gpu, renderer: &mut Renderer, targets: &[DisplayTarget], rig: &Rig) -> Phases {
    let start = Instant::now();
    renderer.prepare(&gpu.queue, rig, 0.0).expect("prepare");
    let prepared = Instant::now();
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    let views: Vec<_> = targets.iter().map(DisplayTarget::views).collect();
    renderer.encode(&mut encoder, &views, None).expect("encode");
    let recorded = Instant::now();
    let commands = encoder.finish();
    let encoded = Instant::now();
    gpu.queue.submit([commands]);
    let submitted = Instant::now();
    gpu.device
        .poll(wgpu::PollType::wait_indefinitely())
        .expect("poll");
    let us = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e6;
    [
        us(start, prepared),
        us(prepared, recorded),
        us(recorded, encoded),
        us(encoded, submitted),
    ]
}
