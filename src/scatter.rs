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

use glam::Vec4;

use crate::buffers::storage_buffer;
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
    /// Staged edits (17 words each) and, per slot, 1 + its edit's index (0: none): a
    /// slot moved twice before a dispatch keeps one edit, the last.
    staged: Vec<u32>,
    index: Vec<u32>,
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
            index: Vec::new(),
            spheres_too: false,
            max_groups: device.limits().max_compute_workgroups_per_dimension,
        }
    }

    /// Staged edits not yet dispatched.
    pub fn pending(&self) -> usize {
        self.staged.len() / WORDS_PER_EDIT
    }

    /// Stages the moved `slots` of `scene` (each listed once) and uploads every staged
    /// edit; returns the bytes written.
    pub fn stage(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        (scene, slots): (&Scene, &[u32]),
        targets: ScatterTargets,
    ) -> u64 {
        self.index
            .resize(self.index.len().max(scene.instances.len()), 0);
        // Slots not staged yet get new edits at the end; those staged by an earlier sync
        // of this frame are overwritten in place.
        let split;
        let (fresh, again): (&[u32], &[u32]) = match self.staged.is_empty() {
            true => (slots, &[]),
            false => {
                split = slots
                    .iter()
                    .partition::<Vec<u32>, _>(|&&s| self.index[s as usize] == 0);
                (&split.0, &split.1)
            }
        };
        let first = self.staged.len();
        // Into the staged vector's kept capacity, on every core: no allocation, no page
        // faults in the steady state.
        self.staged.reserve(fresh.len() * WORDS_PER_EDIT);
        for &slot in fresh {
            self.staged.extend_from_slice(&make_edit(scene, slot));
        }
        for (k, &slot) in fresh.iter().enumerate() {
            self.index[slot as usize] = (first / WORDS_PER_EDIT + k + 1) as u32;
        }
        for &slot in again {
            let at = (self.index[slot as usize] as usize - 1) * WORDS_PER_EDIT;
            self.staged[at..at + WORDS_PER_EDIT].copy_from_slice(&make_edit(scene, slot));
        }
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
        needed
    }

    /// The staged world sphere of `slot` (which must be staged).
    pub fn staged_sphere(&self, slot: u32) -> Vec4 {
        let at = (self.index[slot as usize] as usize - 1) * WORDS_PER_EDIT;
        let words: [u32; 4] = std::array::from_fn(|k| self.staged[at + 13 + k]);
        Vec4::from_array(words.map(f32::from_bits))
    }

    /// Drops the staged edits and the bind group: the scene was uploaded whole again
    /// (its buffers may be new, and its cull positions are).
    pub fn reset(&mut self) {
        self.clear();
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
        self.clear();
        1
    }

    fn clear(&mut self) {
        for edit in self.staged.chunks_exact(WORDS_PER_EDIT) {
            self.index[edit[0] as usize] = 0;
        }
        self.staged.clear();
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

/// One edit: the slot, its transform's rows, its world sphere.
fn make_edit(scene: &Scene, slot: u32) -> [u32; WORDS_PER_EDIT] {
    let instance = &scene.instances[slot as usize];
    let m = instance.world_from_local;
    let (x, y, z, t) = (
        m.matrix3.x_axis,
        m.matrix3.y_axis,
        m.matrix3.z_axis,
        m.translation,
    );
    let sphere = scene.world_sphere(instance);
    let floats = [
        x.x, y.x, z.x, t.x, x.y, y.y, z.y, t.y, x.z, y.z, z.z, t.z, sphere.x, sphere.y, sphere.z,
        sphere.w,
    ];
    let mut edit = [slot; WORDS_PER_EDIT];
    edit[1..].copy_from_slice(&floats.map(f32::to_bits));
    edit
}

fn edits_buffer(device: &wgpu::Device, size: u64) -> wgpu::Buffer {
    let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
    storage_buffer(device, "stereocull.edits", size, usage)
}
