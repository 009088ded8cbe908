//! A live scene moved every frame: the engine owns the instances in a [`LiveScene`],
//! moves some each frame, and [`Renderer::sync`] uploads only what changed (a 56-byte
//! edit per moved instance, scattered on the GPU) before the frame is drawn.
//!
//! `cargo run --example live_scene -- [FRAMES]`

use glam::{Affine3A, Quat, Vec3};
use stereocull::device::Gpu;
use stereocull::live::LiveScene;
use stereocull::renderer::{Renderer, RendererOptions, SyncStats};
use stereocull::rig::Rig;
use stereocull::{Result, scene_spec};

/// `frames` frames of 2,000 procedural instances on `hmd`, every tenth one circling its
/// start; returns each frame's sync.
pub fn run(frames: u32) -> Result<Vec<SyncStats>> {
    let gpu = Gpu::headless()?;
    let mut live = LiveScene::new(scene_spec::load("procedural:2000")?);
    let mut rig = Rig::preset("hmd")?;
    for display in &mut rig.displays {
        display.resolution = [128, 128];
    }
    let mut renderer = Renderer::new(&gpu.device, live.scene(), &rig, RendererOptions::default())?;
    let targets = renderer.create_targets(&gpu.device);
    let moving: Vec<_> = live.handles().into_iter().step_by(10).collect();
    let starts: Vec<Vec3> = moving
        .iter()
        .map(|&h| live.get(h).map(|i| i.world_from_local.translation.into()))
        .collect::<Result<_>>()?;
    let mut syncs = Vec::new();
    for frame in 0..frames {
        let angle = 0.1 * frame as f32;
        for (&handle, start) in moving.iter().zip(&starts) {
            let at = *start + 0.5 * Vec3::new(angle.cos(), 0.0, angle.sin());
            live.set_transform(
                handle,
                Affine3A::from_rotation_translation(Quat::IDENTITY, at),
            )?;
        }
        let synced = renderer.sync(&gpu.device, &gpu.queue, &mut live)?;
        let time = frame as f32 / 90.0;
        renderer.submit_frame(&gpu.device, &gpu.queue, &rig, time, &targets)?;
        gpu.wait()?;
        println!(
            "frame {frame}: {} moved, {} bytes up",
            synced.moved, synced.bytes_uploaded
        );
        syncs.push(synced);
    }
    Ok(syncs)
}

fn main() -> std::process::ExitCode {
    let frames = std::env::args()
        .nth(1)
        .and_then(|f| f.parse().ok())
        .unwrap_or(3);
    match run(frames) {
        Ok(_) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("live_scene: {}", e.one_line());
            std::process::ExitCode::FAILURE
        }
    }
}
