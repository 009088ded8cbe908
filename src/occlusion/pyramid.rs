//! The depth pyramids of a display on the GPU (`wgsl/occlusion_pyramid.wgsl`): one
//! dispatch from the display's depth target into each eye's levels 0 to 5, then one
//! per six levels, each eye in its own z slice so that no reduction crosses the seam. The CPU
//! twin is [`crate::occlusion::reduce`].

use super::PyramidShape;
use crate::buffers::init_buffer;
use crate::shaders::{
    PYRAMID_LEVELS_PER_DISPATCH, PYRAMID_SIDE, Windows, compute_pipeline, pyramid_bindings,
    pyramid_source,
};

/// The pyramid passes for depth targets of one sample count and layering (cloned
/// handles share them).
#[derive(Clone)]
pub struct PyramidPass {
    layout: wgpu::BindGroupLayout,
    reduce_depth: wgpu::ComputePipeline,
    reduce_level: wgpu::ComputePipeline,
    /// Each level's index, one per dynamic offset of `stride` bytes.
    levels: wgpu::Buffer,
    stride: u32,
}

/// Levels the uniform holds: eyes up to 2^MAX_LEVELS pixels wide.
const MAX_LEVELS: u32 = 24;
/// Texels of its first level a workgroup covers per side (each invocation a 2 x 2 block).
const TILE: u32 = 2 * PYRAMID_SIDE;

impl PyramidPass {
    /// The passes over a depth target of `samples` samples per pixel, `layered` (a
    /// layer per eye: multiview) or not.
    pub fn new(device: &wgpu::Device, samples: u32, layered: bool) -> PyramidPass {
        let layout = bind_group_layout(device, samples, layered);
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("stereocull.occlusion_pyramid"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = |entry: &str| {
            let label = format!("stereocull.occlusion_pyramid.{entry}");
            compute_pipeline(
                device,
                &label,
                &pipeline_layout,
                pyramid_source(samples, layered),
                entry,
            )
        };
        let stride = device.limits().min_uniform_buffer_offset_alignment;
        let mut bytes = vec![0u8; (stride * MAX_LEVELS) as usize];
        for l in 0..MAX_LEVELS {
            let at = (l * stride) as usize;
            bytes[at..at + 4].copy_from_slice(&l.to_le_bytes());
        }
        let levels = init_buffer(
            device,
            "stereocull.pyramid_levels",
            &bytes,
            wgpu::BufferUsages::UNIFORM,
        );
        PyramidPass {
            reduce_depth: pipeline("reduce_depth"),
            reduce_level: pipeline("reduce_level"),
            layout,
            levels,
            stride,
        }
    }

    /// The bindings of one display: its context (resolution and viewports), where its
    /// pyramids go and its depth target.
    pub fn bind_group(
        &self,
        device: &wgpu::Device,
        context: &wgpu::Buffer,
        pyramid: wgpu::BufferBinding,
        depth: &wgpu::TextureView,
    ) -> wgpu::BindGroup {
        let level = wgpu::BufferBinding {
            buffer: &self.levels,
            offset: 0,
            size: std::num::NonZeroU64::new(4),
        };
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("stereocull.occlusion_pyramid"),
            layout: &self.layout,
            entries: &[
                entry(0, context.as_entire_binding()),
                entry(1, wgpu::BindingResource::Buffer(level)),
                entry(2, wgpu::BindingResource::Buffer(pyramid)),
                entry(3, wgpu::BindingResource::TextureView(depth)),
            ],
        })
    }

    /// Records the pyramids of `shape` with `group`, six levels per dispatch; returns
    /// the dispatches.
    pub fn encode(
        &self,
        pass: &mut wgpu::ComputePass,
        group: &wgpu::BindGroup,
        shape: PyramidShape,
    ) -> u32 {
        let levels = shape.levels().min(MAX_LEVELS);
        for l in (0..levels).step_by(PYRAMID_LEVELS_PER_DISPATCH as usize) {
            let size = shape.level_size(l);
            pass.set_pipeline(match l {
                0 => &self.reduce_depth,
                _ => &self.reduce_level,
            });
            pass.set_bind_group(0, group, &[l * self.stride]);
            pass.dispatch_workgroups(size.x.div_ceil(TILE), size.y.div_ceil(TILE), shape.eyes);
        }
        levels.div_ceil(PYRAMID_LEVELS_PER_DISPATCH)
    }
}

fn entry(binding: u32, resource: wgpu::BindingResource<'_>) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry { binding, resource }
}

fn bind_group_layout(device: &wgpu::Device, samples: u32, layered: bool) -> wgpu::BindGroupLayout {
    let list = pyramid_bindings(samples, layered);
    let label = "stereocull.occlusion_pyramid";
    crate::shaders::bind_group_layout(device, label, &list, &Windows::WHOLE)
}
