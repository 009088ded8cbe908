//! Issue 40's light figures: `rooms:20000` on `hmd` at 1440 x 1600 per eye, its lamps
//! replaced by one light, by 256 scattered point lights, and kept with 256 more (1,097
//! lights): each frame waited for (prepare, encode, submit, wait) and its CPU part
//! (prepare, encode, submit), in alternating rounds; and the cluster pass alone
//! (`Diagnostics::light_clusters_wall_ms`). Memory of the clusters per display, against
//! a grid per eye.
//!
//! `cargo bench --bench lights`; under `cargo test` one small round.

use std::time::Instant;

use stereocull::device::Gpu;
use stereocull::lights::DISPLAY_WORDS;
use stereocull::renderer::{Renderer, RendererOptions};
use stereocull::rig::Rig;
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
        ("256 lights", scattered),
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
    let per_display = DISPLAY_WORDS as f64 * 4.0 / 1e6;
    println!(
        "clusters: {per_display:.2} MB per display (both eyes); a grid per eye: {:.2} MB and each light tested twice",
        2.0 * per_display
    );
}
