//! Edited instances reach the GPU sparsely, in one compute pass per frame with edits
//! (`wgsl/scatter_*.wgsl`), three dispatches in this order: places filled or vacated in
//! the cull order (place and slot: 8 bytes each, from
//! [`crate::live::LiveScene::insert`] and `remove`), moves (slot, new transform rows,
//! new world sphere's radius: 56 bytes each, made by
//! [`crate::live::LiveScene::set_transform`] and inserts) written into the instance
//! records and, under GPU culling, the spheres in cull order, and whole records (slot
//! and the 80-byte record: recolors, inserts). A frame without edits uploads and
//! dispatches nothing.
//!
//! The radius is computed on the CPU ([`crate::scene::Scene::world_sphere`]): WGSL's
//! `sqrt` need not be correctly rounded, so a GPU-computed radius could differ from the
//! CPU culler's in the last bit and flip a decision at a tangent. The center is one
//! affine transform of the mesh's local center, in the same products and left-to-right
//! sums on both sides (no fma, as the plane tests themselves assume), so the scatter
//! pass computes it and the edit saves 12 bytes.

use std::time::{Duration, Instant};

use wgpu::util::StagingBelt;

use bytemuck::Pod;

use crate::buffers::storage_buffer;
use crate::live::LiveScene;
use crate::places::Places;
use crate::records::{EditHeader, MoveEdit, PlaceEdit, RecordEdit};
use crate::shaders::{
    EditKind, SCATTER_BINDINGS, Windows, bind_group, bind_group_layout, compute_pipeline,
    dispatch_size, pipeline_layout, scatter_source,
};

const HEADER_BYTES: u64 = size_of::<EditHeader>() as u64;
const GROUP: u32 = 64;
/// The staging belt's chunk: a frame's edits of up to about 18,000 moves fit one; more
/// get a chunk of their own size, which the belt keeps for the next frames.
const BELT_CHUNK: u64 = 1 << 20;

/// An edit record of the edits buffer: each edit's key is its place or slot, at most one
/// edit per key.
pub trait Edit: Pod {
    const KIND: EditKind;
    fn key(&self) -> u32;
}

impl Edit for PlaceEdit {
    const KIND: EditKind = EditKind::Places;
    fn key(&self) -> u32 {
        self.place
    }
}

impl Edit for MoveEdit {
    const KIND: EditKind = EditKind::Moves;
    fn key(&self) -> u32 {
        self.slot
    }
}

impl Edit for RecordEdit {
    const KIND: EditKind = EditKind::Records;
    fn key(&self) -> u32 {
        self.slot
    }
}

/// A frame's three scatters, dispatched in this order: places (an inserted instance's
/// place first), moves, then whole records (an inserted instance has both a move and a
/// record, and its record must win).
///
/// A sync keeps the frame's edits on the CPU (taking the live scene's lists, no copy);
/// the frame's encode copies them once into a staging belt, whose chunks are made once
/// and reused frame after frame, and records the copies before the dispatches in the
/// caller's encoder. `queue.write_buffer` made a staging buffer per call, two per
/// scatter and sync (header and edits); the belt takes about 15 % less CPU per moved
/// instance (3.96 against 4.63 ns at 10 % moving, 1M `hmd`, three alternating runs).
pub struct Scatters {
    pub places: Scatter<PlaceEdit>,
    pub moves: Scatter<MoveEdit>,
    pub records: Scatter<RecordEdit>,
    belt: StagingBelt,
}

impl Scatters {
    pub fn new(device: &wgpu::Device, windows: Windows) -> Scatters {
        Scatters {
            places: Scatter::new(device, windows),
            moves: Scatter::new(device, windows),
            records: Scatter::new(device, windows),
            belt: StagingBelt::new(device.clone(), BELT_CHUNK),
        }
    }

    /// The scatters of a submission's second frame: its moves grow each sphere to hold
    /// both frames' poses ([`EditHeader::grow`]).
    pub fn second_frame(device: &wgpu::Device, windows: Windows) -> Scatters {
        let mut scatters = Scatters::new(device, windows);
        scatters.moves.grow = EditHeader::GROWN_GIVEN;
        scatters
    }

    /// Stages place edits. They change only the GPU culler's cull order: without its
    /// buffers (`targets.spheres` is `None`: the CPU culler took the edits into its
    /// layout) nothing is staged. Returns the bytes and a cleared list, as
    /// [`Scatter::stage`].
    pub fn stage_places(
        &mut self,
        device: &wgpu::Device,
        mut placed: Vec<PlaceEdit>,
        targets: ScatterTargets,
    ) -> (u64, Vec<PlaceEdit>) {
        if targets.spheres.is_none() {
            placed.clear();
            return (0, placed);
        }
        self.places.stage(device, placed, targets)
    }

    /// Records the copies of what is staged and its dispatches, in one compute pass
    /// (dispatches in a pass are ordered); returns the dispatches (0 to 3) and the CPU
    /// time of copying the edits into staging memory. The belt's chunks come back for
    /// reuse once `encoder`'s commands are submitted and done.
    pub fn encode(&mut self, encoder: &mut wgpu::CommandEncoder) -> (u32, Duration) {
        let pending = self.places.pending() + self.moves.pending() + self.records.pending();
        if pending == 0 {
            return (0, Duration::ZERO);
        }
        let start = Instant::now();
        self.places.upload(&mut self.belt, encoder);
        self.moves.upload(&mut self.belt, encoder);
        self.records.upload(&mut self.belt, encoder);
        let staging = start.elapsed();
        let dispatches = {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("stereocull.scatter"),
                timestamp_writes: None,
            });
            self.places.encode(&mut pass)
                + self.moves.encode(&mut pass)
                + self.records.encode(&mut pass)
        };
        self.belt.finish_and_recall_on_submit(encoder);
        (dispatches, staging)
    }

    /// Drops what is staged: the scene was uploaded whole again.
    pub fn reset(&mut self) {
        self.places.reset();
        self.moves.reset();
        self.records.reset();
    }
}

/// A scatter pipeline, its edits buffer (of `E` records) and the edits staged for it.
pub struct Scatter<E: Edit> {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    windows: Windows,
    edits: wgpu::Buffer,
    bind_group: Option<wgpu::BindGroup>,
    /// The edits for the next dispatch, in buffer order, and per key 1 + its edit's
    /// index (0: none): a key edited in two syncs before a dispatch keeps one edit. The
    /// index is built only when a second sync comes (`indexed`): one sync per frame
    /// pays no random writes for it.
    staged: Vec<E>,
    index: Vec<u32>,
    indexed: bool,
    spheres_too: bool,
    /// How moved spheres are written ([`EditHeader::grow`]).
    grow: u32,
    visibility: (u32, u32),
    max_groups: u32,
}

/// Where the edits go: the instance records, and the spheres in cull order with each
/// slot's cull position, each place's slot and each mesh's local bounds (the GPU
/// culler's, or `None` when culling on the CPU).
#[derive(Clone, Copy)]
pub struct ScatterTargets<'a> {
    pub instances: &'a wgpu::Buffer,
    /// The spheres, positions, order, mesh bounds and occlusion words.
    pub spheres: Option<[&'a wgpu::Buffer; 5]>,
    /// With occlusion: the visibility words per display slot and the slots.
    pub visibility: (u32, u32),
}

impl<E: Edit> Scatter<E> {
    const EDIT_BYTES: u64 = size_of::<E>() as u64;

    /// The scatter pass of `E`'s kind for instance records and spheres bound in
    /// `windows`.
    pub fn new(device: &wgpu::Device, windows: Windows) -> Scatter<E> {
        let layout = bind_group_layout(device, "stereocull.scatter", &SCATTER_BINDINGS, &windows);
        let pipeline_layout = pipeline_layout(device, "stereocull.scatter", &layout);
        let source = scatter_source(&windows, E::KIND);
        let label = "stereocull.scatter";
        let pipeline = compute_pipeline(device, label, &pipeline_layout, source, "scatter");
        Scatter {
            pipeline,
            layout,
            windows,
            edits: edits_buffer(device, 0),
            bind_group: None,
            staged: Vec::new(),
            index: Vec::new(),
            indexed: false,
            spheres_too: false,
            grow: EditHeader::EXACT,
            visibility: (0, 0),
            max_groups: device.limits().max_compute_workgroups_per_dimension,
        }
    }

    /// Edits staged, not yet dispatched.
    pub fn pending(&self) -> usize {
        self.staged.len()
    }

    /// Stages `edits` (each key once) after or over the ones a sync earlier this frame
    /// staged; returns the bytes this adds to the frame's upload, and a cleared list for
    /// the caller to fill next (`edits` itself, kept without a copy, when nothing was
    /// staged: the common case of one sync per frame).
    pub fn stage(
        &mut self,
        device: &wgpu::Device,
        mut edits: Vec<E>,
        targets: ScatterTargets,
    ) -> (u64, Vec<E>) {
        self.spheres_too = targets.spheres.is_some();
        self.visibility = targets.visibility;
        let before = self.staged.len();
        if before == 0 {
            std::mem::swap(&mut self.staged, &mut edits);
        } else {
            self.merge(&edits);
        }
        edits.clear();
        self.grow(device, self.staged.len());
        if self.bind_group.is_none() {
            self.bind_group = Some(self.bind(device, &targets));
        }
        let header = if before == 0 { HEADER_BYTES } else { 0 };
        let added = (self.staged.len() - before) as u64;
        (header + Self::EDIT_BYTES * added, edits)
    }

    fn build_index(&mut self) {
        if self.indexed {
            return;
        }
        let most = self
            .staged
            .iter()
            .map(|e| e.key() as usize + 1)
            .max()
            .unwrap_or(0);
        self.index.resize(self.index.len().max(most), 0);
        for (k, edit) in self.staged.iter().enumerate() {
            self.index[edit.key() as usize] = k as u32 + 1;
        }
        self.indexed = true;
    }

    /// A second sync before the dispatch: keys already staged are overwritten in place,
    /// new ones appended.
    fn merge(&mut self, edits: &[E]) {
        self.build_index();
        let most = edits
            .iter()
            .map(|e| e.key() as usize + 1)
            .max()
            .unwrap_or(0);
        self.index.resize(self.index.len().max(most), 0);
        for edit in edits {
            let key = edit.key() as usize;
            match self.index[key] {
                0 => {
                    self.staged.push(*edit);
                    self.index[key] = self.staged.len() as u32;
                }
                at => self.staged[at as usize - 1] = *edit,
            }
        }
    }

    /// Makes room for `count` edits (the buffer is written whole at each upload).
    fn grow(&mut self, device: &wgpu::Device, count: usize) {
        let needed = HEADER_BYTES + Self::EDIT_BYTES * count as u64;
        if needed > self.edits.size() {
            self.edits = edits_buffer(device, needed + needed / 2);
            self.bind_group = None;
        }
    }

    /// Records the copy of the header and the staged edits into the edits buffer.
    fn upload(&self, belt: &mut StagingBelt, encoder: &mut wgpu::CommandEncoder) {
        let size = HEADER_BYTES + Self::EDIT_BYTES * self.staged.len() as u64;
        let Some(size) = wgpu::BufferSize::new(size).filter(|_| !self.staged.is_empty()) else {
            return;
        };
        let mut view = belt.write_buffer(encoder, &self.edits, 0, size);
        let header = HEADER_BYTES as usize;
        view.slice(..header)
            .copy_from_slice(bytemuck::bytes_of(&self.header()));
        view.slice(header..)
            .copy_from_slice(bytemuck::cast_slice(&self.staged));
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
            // Void edits' keys index nothing.
            for edit in &self.staged {
                if let Some(at) = self.index.get_mut(edit.key() as usize) {
                    *at = 0;
                }
            }
            self.indexed = false;
        }
        self.staged.clear();
    }

    fn groups(&self) -> (u32, u32) {
        dispatch_size((self.pending() as u32).div_ceil(GROUP), self.max_groups)
    }

    fn header(&self) -> EditHeader {
        EditHeader {
            count: self.pending() as u32,
            spheres_too: u32::from(self.spheres_too),
            groups_x: self.groups().0,
            visibility_words: self.visibility.0,
            visibility_slots: self.visibility.1,
            grow: self.grow,
            unused: [0; 2],
        }
    }

    fn bind(&self, device: &wgpu::Device, targets: &ScatterTargets) -> wgpu::BindGroup {
        let (layout, windows) = (&self.layout, &self.windows);
        bind_edits(device, (layout, windows), &self.edits, targets)
    }
}

/// The bind group of a scatter over `edits` into `targets`.
fn bind_edits(
    device: &wgpu::Device,
    (layout, windows): (&wgpu::BindGroupLayout, &Windows),
    edits: &wgpu::Buffer,
    targets: &ScatterTargets,
) -> wgpu::BindGroup {
    // Under CPU culling the shader skips the spheres; these stand in for the binding.
    let stand_in = || {
        let usage = wgpu::BufferUsages::STORAGE;
        storage_buffer(device, "stereocull.scatter_stand_in", 0, usage)
    };
    let stand_ins: [wgpu::Buffer; 5];
    let [s, p, o, b, v] = match targets.spheres {
        Some(four) => four,
        None => {
            stand_ins = std::array::from_fn(|_| stand_in());
            stand_ins.each_ref()
        }
    };
    // In SCATTER_BINDINGS order.
    let buffers = [edits, p, o, v, b, targets.instances, s];
    let label = "stereocull.scatter";
    bind_group(device, label, layout, &SCATTER_BINDINGS, windows, buffers)
}

/// The moves scatter over edits the GPU writes (the pose pass's, [`crate::pose_tables`]):
/// a fixed count of edits, one per posed target, rewritten on the GPU every frame, so
/// that nothing of a pose crosses the bus.
pub struct GpuMoves {
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    edits: wgpu::Buffer,
    groups: (u32, u32),
}

impl GpuMoves {
    /// The scatter of `count` GPU-written moves into `targets`, bound in `windows`,
    /// their spheres written as `grow` says ([`EditHeader::grow`]).
    pub fn new(
        device: &wgpu::Device,
        (windows, grow): (Windows, u32),
        count: u32,
        targets: ScatterTargets,
    ) -> GpuMoves {
        let layout = bind_group_layout(device, "stereocull.scatter", &SCATTER_BINDINGS, &windows);
        let pipeline_layout = pipeline_layout(device, "stereocull.scatter", &layout);
        let source = scatter_source(&windows, EditKind::Moves);
        let label = "stereocull.scatter";
        let pipeline = compute_pipeline(device, label, &pipeline_layout, source, "scatter");
        let max = device.limits().max_compute_workgroups_per_dimension;
        let groups = dispatch_size(count.div_ceil(GROUP), max);
        let header = EditHeader {
            count,
            spheres_too: u32::from(targets.spheres.is_some()),
            groups_x: groups.0,
            visibility_words: targets.visibility.0,
            visibility_slots: targets.visibility.1,
            grow,
            unused: [0; 2],
        };
        let mut contents = bytemuck::bytes_of(&header).to_vec();
        contents.resize(contents.len() + count as usize * size_of::<MoveEdit>(), 0);
        let usage = wgpu::BufferUsages::STORAGE;
        let edits = crate::buffers::init_buffer(device, "stereocull.posed_moves", &contents, usage);
        let bind_group = bind_edits(device, (&layout, &windows), &edits, &targets);
        GpuMoves {
            pipeline,
            bind_group,
            edits,
            groups,
        }
    }

    /// The edits buffer the GPU writes: the header, then one move per target.
    pub fn edits(&self) -> &wgpu::Buffer {
        &self.edits
    }

    /// Records the scatter of the moves the pose pass wrote, after it in `pass`.
    pub fn encode(&self, pass: &mut wgpu::ComputePass) {
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.dispatch_workgroups(self.groups.0, self.groups.1, 1);
    }
}

impl Scatter<MoveEdit> {
    /// Voids the staged edit of `key`, if any (its instance was removed after an
    /// earlier sync this frame staged its move): the shader skips void keys.
    pub fn void(&mut self, key: u32) {
        if self.staged.is_empty() {
            return;
        }
        self.build_index();
        if let Some(at) = self.index.get_mut(key as usize)
            && *at != 0
        {
            self.staged[*at as usize - 1].slot = Places::VACANT;
            *at = 0;
        }
    }
}

fn edits_buffer(device: &wgpu::Device, size: u64) -> wgpu::Buffer {
    let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
    storage_buffer(device, "stereocull.edits", size, usage)
}

/// The record edit of `slot`: the slot, then its whole instance record, as the
/// records scatter reads them.
pub fn record_edit(live: &LiveScene, slot: u32) -> RecordEdit {
    RecordEdit::new(slot, live.instance_record(slot))
}
