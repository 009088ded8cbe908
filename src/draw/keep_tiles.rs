//! A kept frame's changed tiles cleared ([`crate::keep`], `wgsl/keep_tiles.wgsl`): at
//! the start of a display's draw pass, which loads last frame's color and depth, each
//! changed tile becomes the clear color at the far plane, as a cleared pass would
//! leave it, before the scene redraws it. One draw per display, its tiles' triangles
//! placed on the CPU.

use super::TargetFormat;
use crate::buffers::storage_buffer;
use crate::cull::tiles::TileMask;
use crate::shaders::{
    Bound, KEEP_TILES_BINDINGS, ScreenTargets, Windows, bind_group, bind_group_layout, depth_write,
    keep_tiles_source, screen_pipeline,
};

/// The tile pass's pipeline for targets of one format, and each display's corners.
pub struct KeepTiles {
    pipeline: wgpu::RenderPipeline,
    displays: Vec<TileCorners>,
}

/// One display's changed tiles' corners, bound, and how many this frame draws.
struct TileCorners {
    corners: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    vertices: u32,
}

impl KeepTiles {
    /// The pass for targets of `format` (without a motion target: kept pixels would
    /// keep last frame's motion, so motion vectors never keep), with room for
    /// `tiles[i]` tiles on display `i`.
    pub fn new(device: &wgpu::Device, format: TargetFormat, tiles: &[u32]) -> KeepTiles {
        let label = "stereocull.keep_tiles";
        let layout = bind_group_layout(device, label, &KEEP_TILES_BINDINGS, &Windows::WHOLE);
        let targets = ScreenTargets {
            color: vec![wgpu::ColorTargetState {
                format: format.color,
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            }],
            depth: Some(depth_write(format.depth)),
            samples: format.samples,
            multiview_mask: None,
        };
        let pipeline = screen_pipeline(
            device,
            label,
            (keep_tiles_source(format.color, super::CLEAR_COLOR), &layout),
            targets,
        );
        let displays = (tiles.iter())
            .map(|&n| {
                // Six corners of two floats per tile.
                let size = 6 * 8 * u64::from(n);
                let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
                let corners = storage_buffer(device, label, size, usage);
                let bind_group = bind_group(
                    device,
                    label,
                    &layout,
                    &KEEP_TILES_BINDINGS,
                    &Windows::WHOLE,
                    [corners.bound()],
                );
                TileCorners {
                    corners,
                    bind_group,
                    vertices: 0,
                }
            })
            .collect();
        KeepTiles { pipeline, displays }
    }

    /// Writes display `index`'s changed tiles for this frame; returns the bytes written.
    pub fn write(&mut self, queue: &wgpu::Queue, index: usize, mask: &TileMask) -> u64 {
        let corners = mask.quads();
        let display = &mut self.displays[index];
        display.vertices = corners.len() as u32;
        let bytes: &[u8] = bytemuck::cast_slice(&corners);
        if !bytes.is_empty() {
            queue.write_buffer(&display.corners, 0, bytes);
        }
        bytes.len() as u64
    }

    /// Clears display `index`'s changed tiles in `pass`, which must have just opened,
    /// loading the last frame; returns the draw calls (0 or 1).
    pub fn draw(&self, pass: &mut wgpu::RenderPass, index: usize) -> u32 {
        let display = &self.displays[index];
        if display.vertices == 0 {
            return 0;
        }
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &display.bind_group, &[]);
        pass.draw(0..display.vertices, 0..1);
        1
    }
}
