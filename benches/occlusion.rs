//! Issue 20's CPU ratio: a frame of `rooms:20000` (rooms with doorways: occluders) on
//! `hmd` at 1440 x 1600 and on `cave`, GPU cull, with occlusion on against off: what the pyramids,
//! the late cull and the late draw cost the CPU to record and submit. Timed in
//! alternating rounds (`support/alternate.rs`).
//!
//! `cargo bench --bench occlusion`; under `cargo test` one short round at 64 x 64.

#[path = "support/alternate.rs"]
mod alternate;

use stereocull::device::Gpu;
use stereocull::procedural;
use stereocull::renderer::{OcclusionMode, Renderer, RendererOptions};
use stereocull::rig::Rig;

fn main() {
    let benching = std::env::args().any(|a| a == "--bench");
    let gpu = Gpu::headless().expect("no adapter: install mesa-vulkan-drivers (lavapipe)");
    println!("adapter: {}", gpu.adapter_line());
    let scene = procedural::rooms(20_000, 1);
    // `hmd` at 1440 x 1600 (one display, two pyramids) and `cave` at 1024 x 1024 (five
    // displays, ten pyramids).
    for (preset, full) in [("hmd", [1440, 1600]), ("cave", [1024, 1024])] {
        let (shape, size) = match benching {
            true => ((5, 12), full),
            false => ((1, 3), [64, 64]),
        };
        let mut rig = Rig::preset(preset).expect("preset");
        for d in &mut rig.displays {
            d.resolution = size;
        }
        println!("{preset} at {} x {}:", size[0], size[1]);
        let mut configs = [OcclusionMode::Off, OcclusionMode::On].map(|occlusion| {
            let options = RendererOptions {
                occlusion,
                ..Default::default()
            };
            let renderer = Renderer::new(&gpu.device, &scene, &rig, options).expect("renderer");
            alternate::Config {
                name: format!("occlusion {occlusion:?}").to_lowercase(),
                targets: renderer.create_targets(&gpu.device),
                renderer,
            }
        });
        alternate::compare(&gpu, &rig, &mut configs, shape);
    }
}
