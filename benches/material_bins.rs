//! Issue 21's ratio: the CPU cost of a frame (prepare, encode, submit; each frame waited
//! for untimed) of 100k instances of 64 meshes over 16 materials, each shaded by its own
//! hook (16 bins: 16 draw calls per display), against the same scene over one material,
//! `hmd`, GPU cull, LOD on, occlusion off.
//!
//! Timed in alternating rounds (`support/alternate.rs`).
//!
//! `cargo bench --bench material_bins`; under `cargo test` one short round.

#[path = "support/alternate.rs"]
mod alternate;

use stereocull::device::Gpu;
use stereocull::procedural;
use stereocull::renderer::{OcclusionMode, Renderer, RendererOptions};
use stereocull::rig::Rig;
use stereocull::scene::{Material, Scene, Shading};

fn main() {
    let benching = std::env::args().any(|a| a == "--bench");
    let shape = if benching { (7, 50) } else { (1, 3) };
    let gpu = Gpu::headless().expect("no adapter: install mesa-vulkan-drivers (lavapipe)");
    println!("adapter: {}", gpu.adapter_line());
    let mut rig = Rig::preset("hmd").expect("preset");
    rig.displays[0].resolution = [64, 64];
    let mut configs = [1u32, 16].map(|bins| {
        let (scene, options) = binned(bins);
        let renderer = Renderer::new(&gpu.device, &scene, &rig, options).expect("renderer");
        alternate::Config {
            name: format!("{bins} bins"),
            targets: renderer.create_targets(&gpu.device),
            renderer,
        }
    });
    alternate::compare(&gpu, &rig, &mut configs, shape);
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
