//! A kept frame's changed tiles cleared ([`crate::keep`], `wgsl/keep_tiles.wgsl`): at
//! the start of a display's draw pass, which loads last frame's color and depth, each
//! changed tile becomes the clear color at the far plane, as a cleared pass would
//! leave it, before the scene redraws it. The tiles' bits come from the CPU (culling on
//! the CPU) or from the GPU's marking pass, copied here from the culler's occlusion
//! buffer ([`crate::keep::marks`]). A dispatch lists the changed tiles
//! (`wgsl/keep_list.wgsl`) and one indirect draw per display clears them: an instance
//! of two triangles per changed tile, none for the rest.

use crate::buffers::storage_buffer;
use crate::cull::tiles::{self, TileMask};
use crate::draw::TargetFormat;
use crate::shaders::{
    Bound, KEEP_LIST_BINDINGS, KEEP_TILES_BINDINGS, LIST_GROUP, ScreenTargets, Windows, bind_group,
    bind_group_layout, compute_pipeline, depth_write, keep_list_source, keep_tiles_source,
    pipeline_layout, screen_pipeline,
};
use glam::UVec2;

/// A display's grid of tiles (`TileWords` in `wgsl/shared/tile_words.wgsl`), before its
/// bits.
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

impl TileGrid {
    /// The target's pixels in the tiles `words` marks (tiles at the right and bottom
    /// edges clipped to the target).
    pub fn pixels(&self, words: &[u32]) -> u64 {
        let rows = self.height.div_ceil(tiles::TILE);
        let tiles =
            (0..self.cols * rows).filter(|&t| (words[(t / 32) as usize] >> (t % 32)) & 1 != 0);
        tiles
            .map(|t| {
                let (x, y) = ((t % self.cols) * tiles::TILE, (t / self.cols) * tiles::TILE);
                let w = tiles::TILE.min(self.width - x);
                let h = tiles::TILE.min(self.height - y);
                u64::from(w * h)
            })
            .sum()
    }
}

const GRID_BYTES: u64 = size_of::<TileGrid>() as u64;

/// The tile pass's pipelines for targets of one format (the listing and the clear),
/// and each display's tiles.
pub struct KeepTiles {
    list: wgpu::ComputePipeline,
    clear: wgpu::RenderPipeline,
    displays: Vec<DisplayTiles>,
}

/// One display's grid (as last written) and bits, its changed tiles' list and draw,
/// bound, and its words when this frame keeps (0: it does not).
struct DisplayTiles {
    grid: Option<TileGrid>,
    words: wgpu::Buffer,
    draw: wgpu::Buffer,
    list_group: wgpu::BindGroup,
    clear_group: wgpu::BindGroup,
    word_count: u32,
}

impl KeepTiles {
    /// The pass for targets of `format` (without a motion target: kept pixels would
    /// keep last frame's motion, so motion vectors never keep), with room for
    /// `tiles[i]` tiles on display `i`.
    pub fn new(device: &wgpu::Device, format: TargetFormat, tiles: &[u32]) -> KeepTiles {
        let label = "stereocull.keep_tiles";
        let list_layout = bind_group_layout(device, label, &KEEP_LIST_BINDINGS, &Windows::WHOLE);
        let clear_layout = bind_group_layout(device, label, &KEEP_TILES_BINDINGS, &Windows::WHOLE);
        let list = compute_pipeline(
            device,
            "stereocull.keep_list",
            &pipeline_layout(device, label, &list_layout),
            keep_list_source(),
            "list_tiles",
        );
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
        let clear = screen_pipeline(
            device,
            label,
            (
                keep_tiles_source(format.color, crate::draw::CLEAR_COLOR),
                &clear_layout,
            ),
            targets,
        );
        let layouts = (&list_layout, &clear_layout);
        let displays = (tiles.iter())
            .map(|&n| DisplayTiles::new(device, layouts, n))
            .collect();
        KeepTiles {
            list,
            clear,
            displays,
        }
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
        display.word_count = tiles::tile_words(grid);
        let mut written = 0;
        // The grid changes with the target alone: kept frames share it.
        if display.grid != Some(header) {
            queue.write_buffer(&display.words, 0, bytemuck::bytes_of(&header));
            display.grid = Some(header);
            written += GRID_BYTES;
        }
        let words: &[u8] = mask.map_or(&[], |m| bytemuck::cast_slice(&m.words));
        if !words.is_empty() {
            queue.write_buffer(&display.words, GRID_BYTES, words);
        }
        written + words.len() as u64
    }

    /// Records, for display `index` where this frame keeps, the copy of its bits from
    /// where the GPU marked them (`marked`: a buffer, the offset and the bytes), then
    /// the listing of its changed tiles. Returns the dispatches.
    pub fn encode_list(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        index: usize,
        marked: Option<(&wgpu::Buffer, u64, u64)>,
    ) -> u32 {
        let display = &self.displays[index];
        if display.word_count == 0 {
            return 0;
        }
        if let Some((from, at, bytes)) = marked {
            encoder.copy_buffer_to_buffer(from, at, &display.words, GRID_BYTES, bytes);
        }
        // The listing counts from no instances (and sets the six corners).
        encoder.clear_buffer(&display.draw, 0, None);
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("stereocull.keep_list"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.list);
        pass.set_bind_group(0, &display.list_group, &[]);
        pass.dispatch_workgroups(display.word_count.div_ceil(LIST_GROUP), 1, 1);
        1
    }

    /// Display `index`'s bits buffer and where its bits start, and its grid as last
    /// written (diagnostics).
    pub fn words(&self, index: usize) -> ((&wgpu::Buffer, u64), Option<TileGrid>) {
        let display = &self.displays[index];
        ((&display.words, GRID_BYTES), display.grid)
    }

    /// Clears display `index`'s changed tiles in `pass`, which must have just opened,
    /// loading the last frame; returns the draw calls (0 or 1).
    pub fn draw(&self, pass: &mut wgpu::RenderPass, index: usize) -> u32 {
        let display = &self.displays[index];
        if display.word_count == 0 {
            return 0;
        }
        pass.set_pipeline(&self.clear);
        pass.set_bind_group(0, &display.clear_group, &[]);
        pass.draw_indirect(&display.draw, 0);
        1
    }
}

impl DisplayTiles {
    /// Room for `tiles` tiles, bound for the listing and the clear.
    fn new(
        device: &wgpu::Device,
        (list_layout, clear_layout): (&wgpu::BindGroupLayout, &wgpu::BindGroupLayout),
        tiles: u32,
    ) -> DisplayTiles {
        let label = "stereocull.keep_tiles";
        use wgpu::BufferUsages as U;
        let size = GRID_BYTES + 4 * u64::from(tiles.div_ceil(32));
        // Read back by the diagnostics.
        let words = storage_buffer(device, label, size, U::STORAGE | U::COPY_DST | U::COPY_SRC);
        let list = storage_buffer(device, label, 4 * u64::from(tiles), U::STORAGE);
        let draw_bytes = size_of::<wgpu::util::DrawIndirectArgs>() as u64;
        let draw = storage_buffer(
            device,
            label,
            draw_bytes,
            U::STORAGE | U::INDIRECT | U::COPY_DST,
        );
        let whole = &Windows::WHOLE;
        let list_group = bind_group(
            device,
            label,
            list_layout,
            &KEEP_LIST_BINDINGS,
            whole,
            [words.bound(), list.bound(), draw.bound()],
        );
        let clear_group = bind_group(
            device,
            label,
            clear_layout,
            &KEEP_TILES_BINDINGS,
            whole,
            [words.bound(), list.bound()],
        );
        DisplayTiles {
            grid: None,
            words,
            draw,
            list_group,
            clear_group,
            word_count: 0,
        }
    }
}
