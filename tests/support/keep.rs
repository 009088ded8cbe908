//! A renderer drawing a live scene frame after frame into the same targets, as keeping
//! unchanged pixels needs (`tests/keep.rs`, `tests/keep_posed.rs`).

use image::RgbaImage;
use stereocull::device::Gpu;
use stereocull::live::LiveScene;
use stereocull::readback::read_rgba8;
use stereocull::renderer::{DisplayTarget, FrameStats, PosingMode, Renderer, RendererOptions};
use stereocull::rig::Rig;
use stereocull::scene::Scene;

/// A renderer, its targets and its live scene.
pub struct Run {
    pub renderer: Renderer,
    pub targets: Vec<DisplayTarget>,
    pub live: LiveScene,
}

impl Run {
    pub fn new(gpu: &Gpu, scene: &Scene, rig: &Rig, options: RendererOptions) -> Run {
        let renderer = Renderer::new(&gpu.device, scene, rig, options).unwrap();
        let targets = renderer.create_targets(&gpu.device);
        Run {
            renderer,
            targets,
            live: LiveScene::new(scene.clone()),
        }
    }

    /// Poses the live scene at `time` (where the renderer does not pose on the GPU),
    /// syncs its edits and draws the frame; its stats and images.
    pub fn frame(&mut self, gpu: &Gpu, rig: &Rig, time: f32) -> (FrameStats, Vec<RgbaImage>) {
        if self.renderer.options().posing == PosingMode::Cpu {
            self.live.pose(time).unwrap();
        }
        (self.renderer)
            .sync(&gpu.device, &gpu.queue, &mut self.live)
            .unwrap();
        let stats = (self.renderer)
            .submit_frame(&gpu.device, &gpu.queue, rig, time, &self.targets)
            .unwrap();
        let images = (self.targets.iter())
            .map(|t| read_rgba8(&gpu.device, &gpu.queue, &t.color).unwrap())
            .collect();
        (stats, images)
    }
}
