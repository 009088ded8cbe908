//! Issue 40's light figures: `rooms:20000` on `hmd` at 1440 x 1600 per eye, its lamps
//! replaced by one light, by 256 scattered point lights, and kept with 256 more (1,097
//! lights): each frame waited for (prepare, encode, submit, wait) and its CPU part
//! (prepare, encode, submit), in alternating rounds; and the cluster pass alone
//! (`Diagnostics::light_clusters_wall_ms`). Then the clusters built once per display
//! against once per eye (the same eyes as two mono displays, a grid each): the pass's
//! time and the clusters' memory, in the same run.
//!
//! `cargo bench --bench lights`; under `cargo test` one small round.

use std::time::Instant;

use stereocull::device::Gpu;
use stereocull::lights::DISPLAY_WORDS;
use stereocull::renderer::{Renderer, RendererOptions};
use stereocull::rig::{Display, Mount, Rig};
use stereocull::scene::Scene;

fn main() {
    let benching = std::env::args().any(|a| a == "--bench");
    let (size, rounds, frames) = if benching {
        ([1440, 1600], 5, 3)
    } else {
        ([64, 64], 1, 1)
    };
    let gpu = Gpu::headless().expect("no adapter: install mesa-vulkan-drivers (lavapipe)");
    println!("adapter: {}", gpu.adapter_line());
    let mut rig = Rig::preset("hmd").expect("preset");
    rig.displays[0].resolution = size;
    let rooms = stereocull::scene_spec::load("rooms:20000").expect("rooms");
    let one = {
        let mut s = rooms.clone();
        let middle = s.lights[s.lights.len() / 2];
        s.lights = vec![middle];
        s
    };
    let scattered = {
        let mut s = rooms.clone();
        s.lights.clear();
        stereocull::procedural::scatter_lights(&mut s, 256, 1);
        s
    };
    let mut all = rooms.clone();
    stereocull::procedural::scatter_lights(&mut all, 256, 1);
    let mut configs: Vec<(String, Renderer, Vec<_>)> = [
        ("1 light", one),
        ("256 lights", scattered.clone()),
        ("1097 lights", all),
    ]
    .into_iter()
    .map(|(name, scene): (&str, Scene)| {
        let renderer =
            Renderer::new(&gpu.device, &scene, &rig, RendererOptions::default()).expect("renderer");
        let targets = renderer.create_targets(&gpu.device);
        (name.to_string(), renderer, targets)
    })
    .collect();
    let mut waited = vec![Vec::new(); configs.len()];
    let mut cpu = vec![Vec::new(); configs.len()];
    for round in 0..=rounds {
        for (k, (_, renderer, targets)) in configs.iter_mut().enumerate() {
            for _ in 0..frames {
                let start = Instant::now();
                renderer.prepare(&gpu.queue, &rig, 0.0).expect("prepare");
                let mut encoder = gpu.device.create_command_encoder(&Default::default());
                let views: Vec<_> = targets.iter().map(|t| t.views()).collect();
                renderer.encode(&mut encoder, &views, None).expect("encode");
                gpu.queue.submit([encoder.finish()]);
                let recorded = start.elapsed().as_secs_f64() * 1e3;
                stereocull::readback::wait_idle(&gpu.device).expect("wait");
                if round > 0 {
                    cpu[k].push(recorded);
                    waited[k].push(start.elapsed().as_secs_f64() * 1e3);
                }
            }
        }
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let base = (median(&mut waited[0].clone()), median(&mut cpu[0].clone()));
    for (k, (name, renderer, _)) in configs.iter().enumerate() {
        let (w, c) = (median(&mut waited[k]), median(&mut cpu[k]));
        let clusters = renderer
            .diagnostics(&gpu.device, &gpu.queue)
            .light_clusters_wall_ms(5)
            .expect("cluster pass");
        println!(
            "{name:12} frame {w:8.2} ms ({:.3} of 1 light), CPU {c:.3} ms ({:.3}), cluster pass alone {clusters:.2} ms",
            w / base.0,
            c / base.1
        );
    }
    per_eye_grids(&gpu, &rig, &configs[1].1, scattered);
}

/// The clusters built once per display (both eyes, `renderer`'s rig) against once per
/// eye: the same eyes as two mono displays, each with its own grid, on the same lights.
fn per_eye_grids(gpu: &Gpu, rig: &Rig, renderer: &Renderer, scene: Scene) {
    let mut apart = rig.as_posed().expect("the hmd poses");
    let display = apart.displays.remove(0);
    let Mount::Views(views) = &display.mount else {
        unreachable!("as_posed mounts every display on its views")
    };
    for (eye, view) in ["left", "right"].into_iter().zip(views) {
        apart.displays.push(Display {
            name: eye.into(),
            stereo: false,
            mount: Mount::Views(vec![*view]),
            ..display.clone()
        });
    }
    let mut per_eye =
        Renderer::new(&gpu.device, &scene, &apart, RendererOptions::default()).expect("renderer");
    let targets = per_eye.create_targets(&gpu.device);
    per_eye.prepare(&gpu.queue, &apart, 0.0).expect("prepare");
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    let views: Vec<_> = targets.iter().map(|t| t.views()).collect();
    per_eye.encode(&mut encoder, &views, None).expect("encode");
    gpu.queue.submit([encoder.finish()]);
    let time = |r: &Renderer| {
        (r.diagnostics(&gpu.device, &gpu.queue))
            .light_clusters_wall_ms(5)
            .expect("cluster pass")
    };
    let (once, twice) = (time(renderer), time(&per_eye));
    let mb = DISPLAY_WORDS as f64 * 4.0 / 1e6;
    println!(
        "256 lights, clusters once per display: {once:.2} ms, {mb:.2} MB; once per eye: {twice:.2} ms ({:.2}), {:.2} MB",
        twice / once,
        2.0 * mb
    );
}
