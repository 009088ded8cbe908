//! Drawing into the engine's own render pass with its own material: the culls go into
//! the engine's encoder, then the engine begins its pass (here clearing to its sky),
//! stereocull draws each display into it with a material hook of the engine's WGSL, and
//! the engine could go on drawing in the same pass (UI, transparent geometry).
//!
//! `cargo run --example engine_pass -- [FRAMES]`

use std::sync::Arc;

use stereocull::device::Gpu;
use stereocull::renderer::{Renderer, RendererOptions};
use stereocull::rig::Rig;
use stereocull::{Result, scene_spec};

/// The engine's shading: the surface's color, lit from above, tinted per eye so each
/// half of the double-wide image shows which eye drew it.
const MATERIAL: &str = "
fn material(s: Surface) -> vec4<f32> {
    let up = 0.5 + 0.5 * normalize(s.normal).y;
    let tint = select(vec3(1.0, 0.85, 0.85), vec3(0.85, 0.85, 1.0), s.eye == 1u);
    return vec4(s.color.rgb * up * tint, 1.0);
}";

/// The engine's sky, what its pass clears to.
pub const SKY: wgpu::Color = wgpu::Color {
    r: 0.2,
    g: 0.4,
    b: 0.8,
    a: 1.0,
};

/// `frames` frames of the built-in room on `hmd`, drawn into the engine's pass; returns
/// the last frame's image.
pub fn run(frames: u32) -> Result<image::RgbaImage> {
    let gpu = Gpu::headless()?;
    let scene = scene_spec::load("default")?;
    let mut rig = Rig::preset("hmd")?;
    for display in &mut rig.displays {
        display.resolution = [160, 120];
    }
    let options = RendererOptions {
        material: Some(Arc::from(MATERIAL)),
        ..RendererOptions::default()
    };
    let mut renderer = Renderer::new(&gpu.device, &scene, &rig, options)?;
    let targets = renderer.create_targets(&gpu.device);
    for frame in 0..frames {
        renderer.prepare(&gpu.queue, &rig, frame as f32 / 90.0)?;
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        renderer.encode_culls(&mut encoder, None)?;
        let views = targets[0].views();
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("engine opaque"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: views.color,
                depth_slice: None,
                resolve_target: views.resolve,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(SKY),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: views.depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        let draw_calls = renderer.draw_display(&mut pass, 0)?;
        // ... the engine's own draws in the same pass ...
        drop(pass);
        gpu.queue.submit([encoder.finish()]);
        println!("frame {frame}: {draw_calls} draw call(s) in the engine's pass");
    }
    stereocull::readback::read_rgba8(&gpu.device, &gpu.queue, &targets[0].color)
}

fn main() -> std::process::ExitCode {
    let frames = std::env::args()
        .nth(1)
        .and_then(|f| f.parse().ok())
        .unwrap_or(3);
    match run(frames) {
        Ok(_) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("engine_pass: {}", e.one_line());
            std::process::ExitCode::FAILURE
        }
    }
}
