//! Moved instances reach the GPU sparsely: per frame, one buffer of edits (slot, new
//! transform rows, new world sphere: 68 bytes each) and one compute dispatch
//! (`wgsl/scatter.wgsl`) that writes them into the instance records and, under GPU
//! culling, the spheres in cull order. A frame without moves uploads and dispatches
//! nothing.
//!
//! The spheres are computed on the CPU ([`crate::scene::Scene::world_sphere`]), not in
//! the scatter pass: WGSL's `sqrt` need not be correctly rounded and drivers may fuse
//! multiply-adds, so a GPU-computed sphere could differ from the CPU culler's in the last
//! bit and flip a decision at a tangent; 16 bytes more per edit keep GPU and CPU culls
//! byte-identical.

use std::collections::HashMap;

use glam::Vec4;

use crate::buffers::storage_buffer;
use crate::records::instance_record;
use crate::scene::Scene;
use crate::shaders::{SCATTER_BINDINGS, bind_group, bind_group_layout, scatter_source};

const HEADER_WORDS: usize = 4;
/// Slot, 12 transform words, 4 sphere words.
pub const WORDS_PER_EDIT: usize = 17;
const GROUP: u32 = 64;

/// The scatter pipeline, its edits buffer and the edits staged for the next frame.
pub struct Scatter {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    edits: wgpu::Buffer,
    bind_group: Option<wgpu::BindGroup>,
    /// Staged edits (17 words each) and each staged slot's index: a slot moved twice
    /// before a dispatch keeps one edit, the last.
    staged: Vec<u32>,
    index: HashMap<u32, usize>,
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
    pub fn new(device: &wgpu::Device) -> Scatter {
        let layout = bind_group_layout(device, "stereocull.scatter", &SCATTER_BINDINGS);
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("stereocull.scatter"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("stereocull.scatter"),
            source: wgpu::ShaderSource::Wgsl(scatter_source().into()),
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("stereocull.scatter"),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some("scatter"),
            compilation_options: Default::default(),
            cache: None,
        });
        Scatter {
            pipeline,
            layout,
            edits: edits_buffer(device, 0),
            bind_group: None,
            staged: Vec::new(),
            index: HashMap::new(),
            spheres_too: false,
            max_groups: device.limits().max_compute_workgroups_per_dimension,
        }
    }

    /// Staged edits not yet dispatched.
    pub fn pending(&self) -> usize {
        self.staged.len() / WORDS_PER_EDIT
    }

    /// Stages the moved `slots` of `scene` and uploads every staged edit; returns the
    /// new spheres (in `slots` order, for a CPU culler's layout) and the bytes written.
    pub fn stage(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        (scene, slots): (&Scene, &[u32]),
        targets: ScatterTargets,
    ) -> (Vec<Vec4>, u64) {
        let spheres: Vec<Vec4> = slots
            .iter()
            .map(|&slot| {
                let instance = &scene.instances[slot as usize];
                let sphere = scene.world_sphere(instance);
                let at = *self.index.entry(slot).or_insert_with(|| {
                    self.staged.resize(self.staged.len() + WORDS_PER_EDIT, 0);
                    self.staged.len() - WORDS_PER_EDIT
                });
                let edit = &mut self.staged[at..at + WORDS_PER_EDIT];
                edit[0] = slot;
                let rows = instance_record(instance).world_from_local;
                edit[1..13].copy_from_slice(bytemuck::cast_slice(&rows));
                edit[13..].copy_from_slice(bytemuck::cast_slice(&sphere.to_array()));
                sphere
            })
            .collect();
        self.spheres_too = targets.spheres.is_some();
        let needed = self.bytes();
        if needed > self.edits.size() {
            self.edits = edits_buffer(device, needed + needed / 2);
            self.bind_group = None;
        }
        if self.bind_group.is_none() {
            self.bind_group = Some(self.bind(device, &targets));
        }
        let header = self.header();
        queue.write_buffer(&self.edits, 0, bytemuck::cast_slice(&header));
        let body = 4 * HEADER_WORDS as u64;
        queue.write_buffer(&self.edits, body, bytemuck::cast_slice(&self.staged));
        (spheres, needed)
    }

    /// Drops the staged edits and the bind group: the scene was uploaded whole again
    /// (its buffers may be new, and its cull positions are).
    pub fn reset(&mut self) {
        self.staged.clear();
        self.index.clear();
        self.bind_group = None;
    }

    /// Records the scatter dispatch if edits are staged; returns the dispatches (0 or 1).
    pub fn encode(&mut self, encoder: &mut wgpu::CommandEncoder) -> u32 {
        let (Some(bind_group), count) = (&self.bind_group, self.pending()) else {
            return 0;
        };
        if count == 0 {
            return 0;
        }
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("stereocull.scatter"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, bind_group, &[]);
        let (x, y) = self.groups();
        pass.dispatch_workgroups(x, y, 1);
        self.staged.clear();
        self.index.clear();
        1
    }

    fn bytes(&self) -> u64 {
        4 * (HEADER_WORDS + self.staged.len()) as u64
    }

    fn groups(&self) -> (u32, u32) {
        let groups = (self.pending() as u32).div_ceil(GROUP);
        let x = groups.clamp(1, self.max_groups);
        (x, groups.div_ceil(x).max(1))
    }

    fn header(&self) -> [u32; HEADER_WORDS] {
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
        let buffers = [&self.edits, targets.instances, s, p];
        bind_group(device, "stereocull.scatter", &self.layout, buffers)
    }
}

fn edits_buffer(device: &wgpu::Device, size: u64) -> wgpu::Buffer {
    let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
    storage_buffer(device, "stereocull.edits", size, usage)
}
