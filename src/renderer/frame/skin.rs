//! The frame's skinning pass on the GPU ([`crate::skin`], `wgsl/skin.wgsl`): one
//! dispatch per frame over every skinned vertex, before the shadow pass and every
//! display, writing into the vertex buffer they all draw from.

use crate::buffers::init_buffer;
use crate::renderer::recorder::Recorder;
use crate::shaders::{
    SKIN_BINDINGS, Windows, bind_group_layout, compute_pipeline, dispatch_size, skin_source,
};
use std::ops::Range;

use crate::skin::{JointMatrix, Skins};

/// What the pass reads and writes, and its pipeline.
pub struct SkinPass {
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    rest: wgpu::Buffer,
    joints: wgpu::Buffer,
    /// A two-frame submission's second frame's joint matrices where its own sync
    /// wrote them ([`SkinPass::upload_next`]): copied over `joints` between the frames
    /// (a queue write would land before the first frame's dispatch).
    next: wgpu::Buffer,
    next_ranges: Vec<Range<u32>>,
    vertices: u32,
    dispatch: (u32, u32),
}

const WORKGROUP: u32 = 64;

impl SkinPass {
    /// The pass for `skins` writing into `vertex_buffer` (`None` without skins).
    pub fn new(
        device: &wgpu::Device,
        skins: &Skins,
        vertex_buffer: &wgpu::Buffer,
    ) -> Option<SkinPass> {
        if skins.is_empty() {
            return None;
        }
        let storage = wgpu::BufferUsages::STORAGE;
        let rest = init_buffer(
            device,
            "stereocull.skin_vertices",
            bytemuck::cast_slice(&skins.vertices),
            storage,
        );
        let joints = init_buffer(
            device,
            "stereocull.joint_matrices",
            bytemuck::cast_slice(&skins.joint_matrices),
            // COPY_SRC: read back by diagnostics (`joint_matrices`).
            storage | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
        );
        let next = crate::buffers::storage_buffer(
            device,
            "stereocull.next_joint_matrices",
            joints.size(),
            storage | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
        );
        let vertices = skins.vertices.len() as u32;
        let dispatch = dispatch_size(
            vertices.div_ceil(WORKGROUP),
            device.limits().max_compute_workgroups_per_dimension,
        );
        let params = init_buffer(
            device,
            "stereocull.skin_params",
            bytemuck::cast_slice(&[vertices, dispatch.0 * WORKGROUP]),
            wgpu::BufferUsages::UNIFORM,
        );
        let whole = &Windows::WHOLE;
        let layout = bind_group_layout(device, "stereocull.skin", &SKIN_BINDINGS, whole);
        let entries = [&rest, &joints, vertex_buffer, &params]
            .iter()
            .enumerate()
            .map(|(i, b)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource: b.as_entire_binding(),
            })
            .collect::<Vec<_>>();
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("stereocull.skin"),
            layout: &layout,
            entries: &entries,
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("stereocull.skin"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = compute_pipeline(
            device,
            "stereocull.skin",
            &pipeline_layout,
            skin_source(),
            "skin",
        );
        Some(SkinPass {
            pipeline,
            bind_group,
            rest,
            joints,
            next,
            next_ranges: Vec::new(),
            vertices,
            dispatch,
        })
    }

    /// Writes `skins`' current joint matrices in `range`; returns the bytes.
    pub fn upload(&self, queue: &wgpu::Queue, skins: &Skins, range: Range<u32>) -> u64 {
        write_matrices(queue, &self.joints, skins, range)
    }

    /// [`SkinPass::upload`] for a two-frame submission's second frame: its matrices
    /// in `range` replace the first frame's before its dispatch
    /// ([`SkinPass::encode_next`]).
    pub fn upload_next(&mut self, queue: &wgpu::Queue, skins: &Skins, range: Range<u32>) -> u64 {
        self.next_ranges.push(range.clone());
        write_matrices(queue, &self.next, skins, range)
    }

    /// A two-frame submission's second skinning: the second frame's matrices copied
    /// into place, then the dispatch.
    pub fn encode_next(&mut self, encoder: &mut wgpu::CommandEncoder, rec: &mut Recorder) -> u32 {
        let size = size_of::<JointMatrix>() as u64;
        for range in self.next_ranges.drain(..) {
            let (at, bytes) = (range.start as u64 * size, range.len() as u64 * size);
            encoder.copy_buffer_to_buffer(&self.next, at, &self.joints, at, bytes);
        }
        self.encode(encoder, rec)
    }

    /// Records the frame's one skinning dispatch, logged as the frame pass `skin`.
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder, rec: &mut Recorder) -> u32 {
        let (pipeline, group) = (&self.pipeline, &self.bind_group);
        super::one_dispatch(encoder, rec, "skin", pipeline, group, self.dispatch)
    }

    /// The rest vertices the pass moves (the morph pass writes a morphed skin's).
    pub fn rest(&self) -> &wgpu::Buffer {
        &self.rest
    }

    /// The joint matrices the pass applies (the pose pass writes them on the GPU).
    pub fn joint_matrices(&self) -> &wgpu::Buffer {
        &self.joints
    }

    /// Skinned vertices per frame.
    pub fn vertices(&self) -> u32 {
        self.vertices
    }
}

/// Writes `skins`' joint matrices in `range` into `buffer` at their place; returns the
/// bytes.
fn write_matrices(
    queue: &wgpu::Queue,
    buffer: &wgpu::Buffer,
    skins: &Skins,
    range: Range<u32>,
) -> u64 {
    let matrices = &skins.joint_matrices[range.start as usize..range.end as usize];
    let bytes: &[u8] = bytemuck::cast_slice(matrices);
    let offset = range.start as u64 * size_of::<JointMatrix>() as u64;
    queue.write_buffer(buffer, offset, bytes);
    bytes.len() as u64
}
