//! The frame's morph pass on the GPU ([`crate::morph`], `wgsl/morph.wgsl`): one
//! dispatch per frame over every morphed vertex, before the skinning pass (which moves
//! what it writes into a skin's rest), the shadow pass and every display.

use crate::buffers::init_buffer;
use crate::morph::Morphs;
use crate::renderer::recorder::Recorder;
use crate::shaders::{
    MORPH_BINDINGS, Windows, bind_group, bind_group_layout, compute_pipeline, dispatch_size,
    morph_source,
};

/// What the pass reads and writes, its pipeline, and the weights' animations.
pub struct MorphPass {
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    /// The weights (their defaults and channels; no vertices), sampled each frame.
    morphs: Morphs,
    weights: wgpu::Buffer,
    /// A two-frame submission's second frame's weights, copied over `weights` between
    /// the frames (a queue write would land before the first frame's dispatch).
    next_weights: wgpu::Buffer,
    vertices: u32,
    dispatch: (u32, u32),
}

const WORKGROUP: u32 = 64;

impl MorphPass {
    /// The pass for `morphs` writing into `vertex_buffer` and, for skinned meshes, the
    /// skins' `skin_rest` (`None` without morphs).
    pub fn new(
        device: &wgpu::Device,
        morphs: &Morphs,
        vertex_buffer: &wgpu::Buffer,
        skin_rest: Option<&wgpu::Buffer>,
    ) -> Option<MorphPass> {
        if morphs.is_empty() {
            return None;
        }
        let storage = wgpu::BufferUsages::STORAGE;
        let buffer = |label, bytes: &[u8], usage| init_buffer(device, label, bytes, usage);
        let rest = buffer(
            "stereocull.morph_vertices",
            bytemuck::cast_slice(&morphs.vertices),
            storage,
        );
        let deltas = buffer(
            "stereocull.morph_deltas",
            bytemuck::cast_slice(&morphs.deltas),
            storage,
        );
        let weights = buffer(
            "stereocull.morph_weights",
            bytemuck::cast_slice(&morphs.weights),
            storage | wgpu::BufferUsages::COPY_DST,
        );
        let next_weights = crate::buffers::storage_buffer(
            device,
            "stereocull.next_morph_weights",
            weights.size(),
            wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        );
        // No skin: a word stands in for the skins' rest, which nothing then writes.
        let stand_in = buffer("stereocull.morph_no_skin", &[0; 4], storage);
        let vertices = morphs.vertices.len() as u32;
        let dispatch = dispatch_size(
            vertices.div_ceil(WORKGROUP),
            device.limits().max_compute_workgroups_per_dimension,
        );
        let params = buffer(
            "stereocull.morph_params",
            bytemuck::cast_slice(&[vertices, dispatch.0 * WORKGROUP]),
            wgpu::BufferUsages::UNIFORM,
        );
        let whole = &Windows::WHOLE;
        let layout = bind_group_layout(device, "stereocull.morph", &MORPH_BINDINGS, whole);
        let buffers = [
            &rest,
            &deltas,
            &weights,
            vertex_buffer,
            skin_rest.unwrap_or(&stand_in),
            &params,
        ];
        let bind_group = bind_group(
            device,
            "stereocull.morph",
            &layout,
            &MORPH_BINDINGS,
            whole,
            buffers,
        );
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("stereocull.morph"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = compute_pipeline(
            device,
            "stereocull.morph",
            &pipeline_layout,
            morph_source(),
            "morph",
        );
        let weights_only = Morphs {
            morphs: morphs.morphs.clone(),
            weights: morphs.weights.clone(),
            ..Morphs::default()
        };
        Some(MorphPass {
            pipeline,
            bind_group,
            morphs: weights_only,
            weights,
            next_weights,
            vertices,
            dispatch,
        })
    }

    /// See [`crate::renderer::Renderer::set_morph_weights`].
    pub fn set_weights(&mut self, m: usize, weights: &[f32]) -> Result<(), String> {
        self.morphs.set_weights(m, weights)
    }

    /// Samples every morph's weights at `time` and writes them; returns the bytes.
    pub fn prepare(&mut self, queue: &wgpu::Queue, time: f32) -> u64 {
        self.morphs.set_time(time);
        let bytes: &[u8] = bytemuck::cast_slice(&self.morphs.weights);
        queue.write_buffer(&self.weights, 0, bytes);
        bytes.len() as u64
    }

    /// [`MorphPass::prepare`] for a two-frame submission's second frame, at its
    /// `time`: the weights go to [`MorphPass::encode_next`]'s copy.
    pub fn prepare_next(&mut self, queue: &wgpu::Queue, time: f32) -> u64 {
        self.morphs.set_time(time);
        let bytes: &[u8] = bytemuck::cast_slice(&self.morphs.weights);
        queue.write_buffer(&self.next_weights, 0, bytes);
        bytes.len() as u64
    }

    /// A two-frame submission's second morph dispatch, after its weights' copy.
    pub fn encode_next(&self, encoder: &mut wgpu::CommandEncoder, rec: &mut Recorder) -> u32 {
        let size = self.weights.size();
        encoder.copy_buffer_to_buffer(&self.next_weights, 0, &self.weights, 0, size);
        self.encode(encoder, rec)
    }

    /// Records the frame's one morph dispatch, logged as the frame pass `morph`.
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder, rec: &mut Recorder) -> u32 {
        let (pipeline, group) = (&self.pipeline, &self.bind_group);
        super::one_dispatch(encoder, rec, "morph", pipeline, group, self.dispatch)
    }

    /// Morphed vertices per frame.
    pub fn vertices(&self) -> u32 {
        self.vertices
    }
}
