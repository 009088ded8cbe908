//! Embedding stereocull in an engine that owns its wgpu instance, device, textures and
//! encoder: the renderer takes them, records the frame into the engine's encoder, and
//! keeps no window and no global state.
//!
//! `cargo run --example own_device -- [FRAMES]`

use stereocull::renderer::{Renderer, RendererOptions, TargetViews};
use stereocull::rig::Rig;
use stereocull::{Error, Result, scene_spec};

/// The engine's own GPU, opened the way it would open it anyway; the one thing it adds
/// for stereocull is to ask for the optional features the adapter has.
async fn engine_device() -> Result<(wgpu::Device, wgpu::Queue)> {
    let instance =
        wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let adapter = instance
        .request_adapter(&wgpu::RequestAdapterOptions::default())
        .await
        .map_err(|e| Error::Unsupported(format!("no adapter: {e}")))?;
    let features = stereocull::device::features_for(adapter.features());
    Ok(adapter
        .request_device(&wgpu::DeviceDescriptor {
            label: Some("engine"),
            required_features: features,
            required_limits: adapter.limits(),
            ..Default::default()
        })
        .await?)
}

/// One texture of the engine's, `width` x `height`.
fn engine_texture(
    device: &wgpu::Device,
    (width, height): (u32, u32),
    format: wgpu::TextureFormat,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some("engine target"),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    })
}

/// `frames` frames of the built-in room on `hmd` with the viewer turning, into the
/// engine's own double-wide color and depth textures; returns the last frame's image.
pub fn run(frames: u32) -> Result<image::RgbaImage> {
    let (device, queue) = pollster::block_on(engine_device())?;
    let scene = scene_spec::load("default")?;
    let mut rig = Rig::preset("hmd")?;
    for display in &mut rig.displays {
        display.resolution = [160, 120];
    }
    let options = RendererOptions::default();
    let mut renderer = Renderer::new(&device, &scene, &rig, options.clone())?;
    // Both eyes side by side: twice the width of one eye.
    let size = (2 * 160, 120);
    let color = engine_texture(&device, size, options.color_format);
    let depth = engine_texture(&device, size, options.depth_format);
    let (color_view, depth_view) = (
        color.create_view(&Default::default()),
        depth.create_view(&Default::default()),
    );
    for frame in 0..frames {
        rig.viewer.yaw_deg = 2.0 * frame as f32;
        renderer.prepare(&queue, &rig, frame as f32 / 90.0)?;
        let mut encoder = device.create_command_encoder(&Default::default());
        let views = TargetViews {
            color: &color_view,
            depth: &depth_view,
            resolve: None,
            motion: None,
        };
        let stats = renderer.encode(&mut encoder, &[views], None)?;
        queue.submit([encoder.finish()]);
        println!(
            "frame {frame}: {} draw calls, {} dispatches",
            stats.draw_calls, stats.dispatches
        );
    }
    stereocull::readback::read_rgba8(&device, &queue, &color)
}

fn main() -> std::process::ExitCode {
    let frames = std::env::args()
        .nth(1)
        .and_then(|f| f.parse().ok())
        .unwrap_or(3);
    match run(frames) {
        Ok(image) => {
            println!("{} x {} image, both eyes", image.width(), image.height());
            std::process::ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("own_device: {}", e.one_line());
            std::process::ExitCode::FAILURE
        }
    }
}
