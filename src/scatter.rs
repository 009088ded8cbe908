//! Edited instances reach the GPU sparsely: per frame, one buffer of moves (slot, new
//! transform rows, new world sphere: 68 bytes each, made by
//! [`crate::live::LiveScene::set_transform`]) and one compute dispatch
//! (`wgsl/scatter.wgsl`) that writes them into the instance records and, under GPU
//! culling, the spheres in cull order; then one buffer of whole records (slot and the
//! 64-byte record: recolors, respawns) and one dispatch that writes them. A frame
//! without edits uploads and dispatches nothing.
//!
//! The spheres are computed on the CPU ([`crate::scene::Scene::world_sphere`]), not in
//! the scatter pass: WGSL's `sqrt` need not be correctly rounded and drivers may fuse
//! multiply-adds, so a GPU-computed sphere could differ from the CPU culler's in the last
//! bit and flip a decision at a tangent; 16 bytes more per edit keep GPU and CPU culls
//! byte-identical.

use crate::buffers::storage_buffer;
use crate::live::{Edit, make_edit};
use crate::records::instance_record;
use crate::scene::Scene;
use crate::shaders::{
    SCATTER_BINDINGS, Windows, bind_group, bind_group_layout, compute_pipeline, dispatch_size,
    pipeline_layout, scatter_source,
};

const HEADER_BYTES: u64 = 16;
const EDIT_BYTES: u64 = size_of::<Edit>() as u64;
const GROUP: u32 = 64;

/// What a scatter's 17-word edits carry.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EditKind {
    /// Slot, transform rows, world sphere ([`make_edit`]).
    Moves,
    /// Slot and the whole record ([`record_edit`]).
    Records,
}

impl EditKind {
    fn entry_point(self) -> &'static str {
        match self {
            EditKind::Moves => "scatter",
            EditKind::Records => "scatter_records",
        }
    }

    fn make(self, scene: &Scene, slot: u32) -> Edit {
        match self {
            EditKind::Moves => make_edit(scene, slot),
            EditKind::Records => record_edit(scene, slot),
        }
    }
}

/// A frame's two scatters, dispatched in this order: moves, then whole records (a
/// respawned instance has both, and its record must win).
pub struct Scatters {
    pub moves: Scatter,
    pub records: Scatter,
}

impl Scatters {
    pub fn new(device: &wgpu::Device, windows: Windows) -> Scatters {
        Scatters {
            moves: Scatter::new(device, windows, EditKind::Moves),
            records: Scatter::new(device, windows, EditKind::Records),
        }
    }

    /// Records the dispatches of what is staged; returns them (0 to 2).
    /// Records the dispatches of what is staged, in one compute pass (dispatches in a
    /// pass are ordered); returns them (0 to 2).
    pub fn encode(&mut self, encoder: &mut wgpu::CommandEncoder) -> u32 {
        if self.moves.pending() + self.records.pending() == 0 {
            return 0;
        }
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("stereocull.scatter"),
            timestamp_writes: None,
        });
        self.moves.encode(&mut pass) + self.records.encode(&mut pass)
    }

    /// Drops what is staged: the scene was uploaded whole again.
    pub fn reset(&mut self) {
        self.moves.reset();
        self.records.reset();
    }
}

/// A scatter pipeline, its edits buffer and which slots it holds edits for.
pub struct Scatter {
    kind: EditKind,
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    windows: Windows,
    edits: wgpu::Buffer,
    bind_group: Option<wgpu::BindGroup>,
    /// Slots with an edit in the buffer, in buffer order, and per slot 1 + its edit's
    /// index (0: none): a slot moved in two syncs before a dispatch keeps one edit. The
    /// index is built only when a second sync comes (`indexed`): one sync per frame
    /// pays no random writes for it.
    slots: Vec<u32>,
    index: Vec<u32>,
    indexed: bool,
    spheres_too: bool,
    max_groups: u32,
}

/// Where the edits go: the instance records, and the spheres in cull order with each
/// slot's cull position (the GPU culler's, or `None` when culling on the CPU).
pub struct ScatterTargets<'a> {
    pub instances: &'a wgpu::Buffer,
    pub spheres: Option<[&'a wgpu::Buffer; 2]>,
}

impl Scatter {
    /// The scatter pass of `kind` for instance records and spheres bound in `windows`.
    pub fn new(device: &wgpu::Device, windows: Windows, kind: EditKind) -> Scatter {
        let layout = bind_group_layout(device, "stereocull.scatter", &SCATTER_BINDINGS, &windows);
        let pipeline_layout = pipeline_layout(device, "stereocull.scatter", &layout);
        let entry = (scatter_source(&windows), kind.entry_point());
        let pipeline = compute_pipeline(device, "stereocull.scatter", &pipeline_layout, entry);
        Scatter {
            kind,
            pipeline,
            layout,
            windows,
            edits: edits_buffer(device, 0),
            bind_group: None,
            slots: Vec::new(),
            index: Vec::new(),
            indexed: false,
            spheres_too: false,
            max_groups: device.limits().max_compute_workgroups_per_dimension,
        }
    }

    /// Edits in the buffer, not yet dispatched.
    pub fn pending(&self) -> usize {
        self.slots.len()
    }

    /// Writes `edits` (each slot once) into the edits buffer, after or over the ones a
    /// sync earlier this frame wrote; returns the bytes written. `scene` is read only in
    /// the rare case of a second sync outgrowing the buffer.
    pub fn stage(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        (scene, edits): (&Scene, &[Edit]),
        targets: ScatterTargets,
    ) -> u64 {
        self.spheres_too = targets.spheres.is_some();
        let mut bytes = 0;
        if self.slots.is_empty() {
            // The common case, one sync per frame: the edits go up as they are.
            self.grow(device, edits.len());
            self.slots.extend(edits.iter().map(|e| e[0]));
            queue.write_buffer(&self.edits, HEADER_BYTES, bytemuck::cast_slice(edits));
            bytes += EDIT_BYTES * edits.len() as u64;
        } else {
            bytes += self.merge(device, queue, (scene, edits));
        }
        if self.bind_group.is_none() {
            self.bind_group = Some(self.bind(device, &targets));
        }
        queue.write_buffer(&self.edits, 0, bytemuck::cast_slice(&self.header()));
        bytes + HEADER_BYTES
    }

    /// A second sync before the dispatch: slots already staged are overwritten in place,
    /// new ones appended; a buffer too small is replaced and refilled from `scene`.
    fn merge(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        (scene, edits): (&Scene, &[Edit]),
    ) -> u64 {
        if !self.indexed {
            self.index
                .resize(self.index.len().max(scene.instances.len()), 0);
            for (k, &slot) in self.slots.iter().enumerate() {
                self.index[slot as usize] = k as u32 + 1;
            }
            self.indexed = true;
        }
        let fresh = edits
            .iter()
            .filter(|e| self.index[e[0] as usize] == 0)
            .count();
        if self.grow(device, self.slots.len() + fresh) {
            let all: Vec<Edit> = self
                .slots
                .iter()
                .map(|&s| self.kind.make(scene, s))
                .collect();
            queue.write_buffer(&self.edits, HEADER_BYTES, bytemuck::cast_slice(&all));
        }
        for edit in edits {
            let slot = edit[0] as usize;
            if self.index[slot] == 0 {
                self.slots.push(edit[0]);
                self.index[slot] = self.slots.len() as u32;
            }
            let at = HEADER_BYTES + EDIT_BYTES * (self.index[slot] as u64 - 1);
            queue.write_buffer(&self.edits, at, bytemuck::bytes_of(edit));
        }
        EDIT_BYTES * edits.len() as u64
    }

    /// Makes room for `count` edits; returns whether the buffer is new (and empty).
    fn grow(&mut self, device: &wgpu::Device, count: usize) -> bool {
        let needed = HEADER_BYTES + EDIT_BYTES * count as u64;
        if needed <= self.edits.size() {
            return false;
        }
        self.edits = edits_buffer(device, needed + needed / 2);
        self.bind_group = None;
        true
    }

    /// Drops the staged edits and the bind group: the scene was uploaded whole again
    /// (its buffers may be new, and its cull positions are).
    pub fn reset(&mut self) {
        self.clear();
        self.bind_group = None;
    }

    /// Records the scatter dispatch into `pass` if edits are staged; returns the
    /// dispatches (0 or 1).
    pub fn encode(&mut self, pass: &mut wgpu::ComputePass) -> u32 {
        let (Some(bind_group), count) = (&self.bind_group, self.pending()) else {
            return 0;
        };
        if count == 0 {
            return 0;
        }
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, bind_group, &[]);
        let (x, y) = self.groups();
        pass.dispatch_workgroups(x, y, 1);
        self.clear();
        1
    }

    fn clear(&mut self) {
        if self.indexed {
            for &slot in &self.slots {
                self.index[slot as usize] = 0;
            }
            self.indexed = false;
        }
        self.slots.clear();
    }

    fn groups(&self) -> (u32, u32) {
        dispatch_size((self.pending() as u32).div_ceil(GROUP), self.max_groups)
    }

    /// Edit count, spheres too (GPU culling), workgroups along x.
    fn header(&self) -> [u32; 4] {
        let count = self.pending() as u32;
        [count, u32::from(self.spheres_too), self.groups().0, 0]
    }

    fn bind(&self, device: &wgpu::Device, targets: &ScatterTargets) -> wgpu::BindGroup {
        // Under CPU culling the shader skips the spheres; these stand in for the binding.
        let stand_in = || {
            let usage = wgpu::BufferUsages::STORAGE;
            storage_buffer(device, "stereocull.scatter_stand_in", 0, usage)
        };
        let (spheres, positions);
        let [s, p] = match targets.spheres {
            Some(pair) => pair,
            None => {
                (spheres, positions) = (stand_in(), stand_in());
                [&spheres, &positions]
            }
        };
        // In SCATTER_BINDINGS order.
        let buffers = [&self.edits, p, targets.instances, s];
        let list = (&SCATTER_BINDINGS[..], &self.windows);
        bind_group(device, ("stereocull.scatter", &self.layout), list, buffers)
    }
}

fn edits_buffer(device: &wgpu::Device, size: u64) -> wgpu::Buffer {
    let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
    storage_buffer(device, "stereocull.edits", size, usage)
}

/// The record edit of `slot`: the slot, then its whole 64-byte instance record, as the
/// records scatter reads them.
pub fn record_edit(scene: &Scene, slot: u32) -> Edit {
    let record = instance_record(&scene.instances[slot as usize]);
    let words: [u32; 16] = bytemuck::cast(record);
    let mut edit = [slot; 17];
    edit[1..].copy_from_slice(&words);
    edit
}
