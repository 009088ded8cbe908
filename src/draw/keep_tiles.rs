//! A kept frame's changed tiles cleared ([`crate::keep`], `wgsl/keep_tiles.wgsl`): at
//! the start of a display's draw pass, which loads last frame's color and depth, each
//! changed tile becomes the clear color at the far plane, as a cleared pass would
//! leave it, before the scene redraws it. One draw per display: an instance of two
//! triangles per tile, placed from the tile's bit, which the CPU writes (culling on
//! the CPU) or the GPU's marking pass leaves in the culler's occlusion buffer
//! ([`crate::cull::tile_marks`]), copied here.

use super::TargetFormat;
use crate::buffers::storage_buffer;
use crate::cull::tiles::{self, TileMask};
use crate::shaders::{
    Bound, KEEP_TILES_BINDINGS, ScreenTargets, Windows, bind_group, bind_group_layout, depth_write,
    keep_tiles_source, screen_pipeline,
};
use glam::UVec2;

/// A display's grid of tiles (`TileWords` in `wgsl/keep_tiles.wgsl`), before its bits.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct TileGrid {
    /// Tiles per row.
    pub cols: u32,
    /// The target's width, in pixels.
    pub width: u32,
    /// The target's height, in pixels.
    pub height: u32,
}

const GRID_BYTES: u64 = size_of::<TileGrid>() as u64;

/// The tile pass's pipeline for targets of one format, and each display's tiles.
pub struct KeepTiles {
    pipeline: wgpu::RenderPipeline,
    displays: Vec<DisplayTiles>,
}

/// One display's grid and bits, bound, and its tiles when this frame keeps.
struct DisplayTiles {
    words: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    tiles: u32,
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
                let size = GRID_BYTES + 4 * u64::from(n.div_ceil(32));
                // Read back by the diagnostics.
                let usage = wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_DST
                    | wgpu::BufferUsages::COPY_SRC;
                let words = storage_buffer(device, label, size, usage);
                let bind_group = bind_group(
                    device,
                    label,
                    &layout,
                    &KEEP_TILES_BINDINGS,
                    &Windows::WHOLE,
                    [words.bound()],
                );
                DisplayTiles {
                    words,
                    bind_group,
                    tiles: 0,
                }
            })
            .collect();
        KeepTiles { pipeline, displays }
    }

    /// Writes display `index`'s grid for this frame, over `views` views of `size`
    /// pixels side by side, and its bits where the CPU marked them (`None`: the GPU
    /// marks them, [`KeepTiles::copy`]). Returns the bytes written.
    pub fn write(
        &mut self,
        queue: &wgpu::Queue,
        index: usize,
        (size, views): (UVec2, u32),
        mask: Option<&TileMask>,
    ) -> u64 {
        let grid = tiles::grid(size, views);
        let header = TileGrid {
            cols: grid.x,
            width: size.x * views,
            height: size.y,
        };
        let display = &mut self.displays[index];
        display.tiles = grid.x * grid.y;
        queue.write_buffer(&display.words, 0, bytemuck::bytes_of(&header));
        let words: &[u8] = mask.map_or(&[], |m| bytemuck::cast_slice(&m.words));
        if !words.is_empty() {
            queue.write_buffer(&display.words, GRID_BYTES, words);
        }
        GRID_BYTES + words.len() as u64
    }

    /// Records the copy of display `index`'s bits from where the GPU marked them: a
    /// buffer, the offset and the bytes.
    pub fn copy(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        index: usize,
        (from, at, bytes): (&wgpu::Buffer, u64, u64),
    ) {
        let display = &self.displays[index];
        if display.tiles > 0 {
            encoder.copy_buffer_to_buffer(from, at, &display.words, GRID_BYTES, bytes);
        }
    }

    /// Display `index`'s bits buffer and where its bits start (diagnostics).
    pub fn words(&self, index: usize) -> (&wgpu::Buffer, u64) {
        (&self.displays[index].words, GRID_BYTES)
    }

    /// Clears display `index`'s changed tiles in `pass`, which must have just opened,
    /// loading the last frame; returns the draw calls (0 or 1).
    pub fn draw(&self, pass: &mut wgpu::RenderPass, index: usize) -> u32 {
        let display = &self.displays[index];
        if display.tiles == 0 {
            return 0;
        }
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &display.bind_group, &[]);
        pass.draw(0..6, 0..display.tiles);
        1
    }
}
