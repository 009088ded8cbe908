//! A kept frame's changed tiles ([`crate::keep`]) built on the GPU
//! (`wgsl/keep_mark.wgsl`), so that what only the GPU moves (posing on the GPU) keeps
//! pixels too, and the CPU only lists slots. The frame's listed slots mark, in each
//! display's tiles in the occlusion buffer (where the display's cull reads them), the
//! tiles their world sphere may cover: once before the frame's scatter and pose (the
//! sphere as last drawn) and once after (the sphere now). [`crate::cull::tiles::TileMask`] is
//! the CPU twin: marking the same spheres gives the same words.

use encase::ShaderType;
use glam::Vec4;

use crate::buffers::{Upload, init_buffer, storage_buffer};
use crate::cull::gpu_buffers::CullScene;
use crate::cull::rig::RigOcclusion;
use crate::records::storage_bytes;
pub use crate::shaders::{MARK_AFTER, MARK_BEFORE, MARK_GROUP, MARK_SLOT};
use crate::shaders::{
    MARK_TILES_BINDINGS, Windows, bind_group, bind_group_layout, compute_pipeline, dispatch_size,
    keep_mark_source, pipeline_layout,
};

/// One display as the marking pass sees it (`TileDisplay` in `wgsl/keep_mark.wgsl`).
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub struct TileDisplay {
    /// Its eyes, as the cull's tile test reads them.
    pub eyes: RigOcclusion,
    /// Its frustum: a sphere outside marks nothing.
    pub planes: [Vec4; 6],
    /// Its tiles' first word in the occlusion buffer.
    pub base: u32,
}

/// The marking pass over one culler's scene buffers.
pub struct TileMarks {
    pipeline: wgpu::ComputePipeline,
    /// Bound with the before phase's flag, then the after phase's.
    bind_groups: [wgpu::BindGroup; 2],
    marks: wgpu::Buffer,
    displays: wgpu::Buffer,
    /// The displays as last written.
    written: Option<Vec<TileDisplay>>,
    occlusion: wgpu::Buffer,
    /// Where the tiles start in `occlusion` and the words from one display slot's to
    /// the next's, and the display slots.
    tiles: (u32, u32, u32),
    max_groups: u32,
    /// This frame's listed slots and displays; `None`: the frame is not kept.
    armed: Option<(u32, u32)>,
}

impl TileMarks {
    /// The pass over `scene`'s spheres and tiles, for up to `slots` listed slots and
    /// `displays` display slots.
    pub fn new(
        device: &wgpu::Device,
        scene: &CullScene,
        (slots, displays): (u32, u32),
        windows: Windows,
    ) -> TileMarks {
        let label = "stereocull.keep_mark";
        let layout = bind_group_layout(device, label, &MARK_TILES_BINDINGS, &windows);
        let pipeline_layout = pipeline_layout(device, label, &layout);
        let source = keep_mark_source(&windows);
        let pipeline = compute_pipeline(device, label, &pipeline_layout, source, "mark");
        let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
        let marks = storage_buffer(device, label, 4 * (1 + u64::from(slots)), usage);
        let display_bytes = TileDisplay::min_size().get() * u64::from(displays.max(1));
        let display_buffer = storage_buffer(device, label, display_bytes, usage);
        let phase = |flag: u32| {
            let mut bytes = [0u32; 4];
            bytes[0] = flag;
            let usage = wgpu::BufferUsages::UNIFORM;
            init_buffer(device, label, bytemuck::bytes_of(&bytes), usage)
        };
        let phases = [phase(MARK_BEFORE), phase(MARK_AFTER)];
        let [spheres, positions, _, _, occlusion] = scene.scatter_targets();
        let bind_groups = phases.each_ref().map(|phase| {
            bind_group(
                device,
                label,
                &layout,
                &MARK_TILES_BINDINGS,
                &windows,
                [
                    &marks,
                    phase,
                    &display_buffer,
                    positions,
                    occlusion,
                    spheres,
                ],
            )
        });
        let (offset, stride) = scene.tile_layout();
        TileMarks {
            pipeline,
            bind_groups,
            marks,
            displays: display_buffer,
            written: None,
            occlusion: occlusion.clone(),
            tiles: (offset, stride, displays),
            max_groups: device.limits().max_compute_workgroups_per_dimension,
            armed: None,
        }
    }

    /// Arms this frame's marking: `entries` (each a slot with [`MARK_BEFORE`] and
    /// [`MARK_AFTER`] as they apply, each slot at most once) over `displays`. Returns
    /// the bytes written.
    pub fn write(&mut self, queue: &impl Upload, entries: &[u32], displays: &[TileDisplay]) -> u64 {
        let count = entries.len() as u32;
        let mut list = Vec::with_capacity(entries.len() + 1);
        list.push(count);
        list.extend_from_slice(entries);
        let list: &[u8] = bytemuck::cast_slice(&list);
        queue.write_buffer(&self.marks, 0, list);
        self.armed = Some((count, displays.len() as u32));
        // The displays change with the pose alone: kept frames share it.
        if self.written.as_deref() == Some(displays) {
            return list.len() as u64;
        }
        let displays_bytes = storage_bytes(displays);
        queue.write_buffer(&self.displays, 0, &displays_bytes);
        self.written = Some(displays.to_vec());
        (list.len() + displays_bytes.len()) as u64
    }

    /// Records the before phase: every display's tiles cleared, then the listed slots'
    /// spheres as last drawn marked. Returns the dispatches (0 when the frame is not
    /// kept).
    pub fn encode_before(&self, encoder: &mut wgpu::CommandEncoder) -> u32 {
        if self.armed.is_none() {
            return 0;
        }
        let (offset, stride, slots) = self.tiles;
        let size = 4 * u64::from(stride * slots);
        encoder.clear_buffer(&self.occlusion, 4 * u64::from(offset), Some(size));
        self.dispatch(encoder, 0)
    }

    /// Records the after phase (after the frame's scatter and pose): the listed slots'
    /// spheres now marked. Disarms. Returns the dispatches.
    pub fn encode_after(&mut self, encoder: &mut wgpu::CommandEncoder) -> u32 {
        let dispatches = self.dispatch(encoder, 1);
        self.armed = None;
        dispatches
    }

    fn dispatch(&self, encoder: &mut wgpu::CommandEncoder, phase: usize) -> u32 {
        let Some((count, displays)) = self.armed.filter(|(c, d)| *c > 0 && *d > 0) else {
            return 0;
        };
        let label = ["stereocull.keep_mark.before", "stereocull.keep_mark.after"][phase];
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(label),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind_groups[phase], &[]);
        let (x, y) = dispatch_size(count.div_ceil(MARK_GROUP), self.max_groups);
        pass.dispatch_workgroups(x, y, displays);
        1
    }

    /// Display slot `slot`'s first word of tiles in the occlusion buffer
    /// ([`TileDisplay::base`]).
    pub fn base(&self, slot: u32) -> u32 {
        self.tiles.0 + slot * self.tiles.1
    }

    /// Display slot `slot`'s `words` words of tiles: the occlusion buffer and where
    /// they lie in it, in bytes.
    pub fn words_of(&self, slot: u32, words: u32) -> (&wgpu::Buffer, u64, u64) {
        (
            &self.occlusion,
            4 * u64::from(self.base(slot)),
            4 * u64::from(words),
        )
    }
}
