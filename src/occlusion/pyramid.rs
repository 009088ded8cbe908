//! The depth pyramids of a set of displays on the GPU (`wgsl/occlusion_pyramid.wgsl`):
//! one dispatch from the displays' depth targets into each eye's levels 0 to 5, then
//! one per six levels, each eye of each display in its own z slice so that no
//! reduction crosses a seam or a display's edge. Up to [`crate::shaders::PYRAMID_SET_DEPTHS`] displays
//! a set. The CPU twin is [`crate::occlusion::reduce`].

use encase::ShaderType;
use glam::UVec2;

use super::PyramidShape;
use crate::buffers::init_buffer;
use crate::records::uniform_bytes;
use crate::shaders::{
    PYRAMID_LEVELS_PER_DISPATCH, PYRAMID_SET_SLICES, PYRAMID_SIDE, Windows, compute_pipeline,
    pyramid_bindings, pyramid_source,
};

/// One eye of a display in a pyramid set (`PyramidSlice` in
/// `wgsl/occlusion_pyramid.wgsl`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ShaderType)]
pub struct PyramidSlice {
    /// Where its view starts in its display's depth target, in pixels (side by side;
    /// zero for a layer).
    pub origin: UVec2,
    /// Its view's pixels.
    pub size: UVec2,
    /// Where its display's pyramids start in the pyramids' buffer, in words.
    pub base: u32,
    /// Which eye it is: its pyramid's place among its display's, and its layer in
    /// multiview.
    pub eye: u32,
    /// Which of the set's depth targets it reads.
    pub depth: u32,
}

/// One set's eyes (`PyramidSet` in `wgsl/occlusion_pyramid.wgsl`): the first `count`
/// of `slices`.
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub struct PyramidSet {
    /// The set's eyes, then unused slices.
    pub slices: [PyramidSlice; PYRAMID_SET_SLICES],
    /// How many of `slices` are the set's.
    pub count: u32,
}

impl PyramidSet {
    /// `slices` (at most [`PYRAMID_SET_SLICES`]; the rest are dropped) as one set.
    pub fn new(slices: &[PyramidSlice]) -> PyramidSet {
        let count = slices.len().min(PYRAMID_SET_SLICES);
        let mut all = [PyramidSlice::default(); PYRAMID_SET_SLICES];
        all[..count].copy_from_slice(&slices[..count]);
        PyramidSet {
            slices: all,
            count: count as u32,
        }
    }
}

/// The pyramid passes for a set of depth targets of one sample count and layering.
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
    /// The passes over `depths` depth targets (1 to [`crate::shaders::PYRAMID_SET_DEPTHS`]) of
    /// `samples` samples per pixel, `layered` (a layer per eye: multiview) or not.
    pub fn new(device: &wgpu::Device, samples: u32, layered: bool, depths: usize) -> PyramidPass {
        let list = pyramid_bindings(samples, layered, depths);
        let label = "stereocull.occlusion_pyramid";
        let layout = crate::shaders::bind_group_layout(device, label, &list, &Windows::WHOLE);
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
                pyramid_source(samples, layered, depths),
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

    /// The uniform of a set of `slices`, written once: a set's displays keep their
    /// shapes, viewports and regions.
    pub fn set_buffer(device: &wgpu::Device, slices: &[PyramidSlice]) -> wgpu::Buffer {
        let bytes = uniform_bytes(&PyramidSet::new(slices));
        init_buffer(
            device,
            "stereocull.pyramid_set",
            &bytes,
            wgpu::BufferUsages::UNIFORM,
        )
    }

    /// The bindings of one set: its slices (`set`, [`PyramidPass::set_buffer`]), the
    /// buffer every display's pyramids are in (whole: the slices say where), and its
    /// displays' depth targets in slice order, as many as the pass was made for.
    pub fn bind_group(
        &self,
        device: &wgpu::Device,
        (set, pyramids): (&wgpu::Buffer, &wgpu::Buffer),
        depths: &[&wgpu::TextureView],
    ) -> wgpu::BindGroup {
        let level = wgpu::BufferBinding {
            buffer: &self.levels,
            offset: 0,
            size: std::num::NonZeroU64::new(4),
        };
        let fixed = [
            set.as_entire_binding(),
            wgpu::BindingResource::Buffer(level),
            pyramids.as_entire_binding(),
        ];
        let textures = depths
            .iter()
            .map(|view| wgpu::BindingResource::TextureView(view));
        let entries: Vec<_> = (fixed.into_iter().chain(textures).enumerate())
            .map(|(binding, resource)| wgpu::BindGroupEntry {
                binding: binding as u32,
                resource,
            })
            .collect();
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("stereocull.occlusion_pyramid"),
            layout: &self.layout,
            entries: &entries,
        })
    }

    /// Records a set's pyramids with `group`: its `dispatches`
    /// ([`PyramidPass::dispatches`]); returns how many.
    pub fn encode(
        &self,
        pass: &mut wgpu::ComputePass,
        group: &wgpu::BindGroup,
        dispatches: &[PyramidDispatch],
    ) -> u32 {
        for d in dispatches {
            pass.set_pipeline(match d.first {
                0 => &self.reduce_depth,
                _ => &self.reduce_level,
            });
            pass.set_bind_group(0, group, &[d.first * self.stride]);
            let [x, y, z] = d.workgroups;
            pass.dispatch_workgroups(x, y, z);
        }
        dispatches.len() as u32
    }

    /// The dispatches of a set of `slices`, six levels each: each as wide as the set's
    /// largest eye at its first level (a set's slices are fixed, so once per set).
    pub fn dispatches(slices: &[PyramidSlice]) -> Vec<PyramidDispatch> {
        let shapes: Vec<PyramidShape> = (slices.iter())
            .map(|s| PyramidShape {
                eye: s.size,
                eyes: 1,
            })
            .collect();
        let levels = shapes.iter().map(PyramidShape::levels).max().unwrap_or(0);
        (0..levels.min(MAX_LEVELS))
            .step_by(PYRAMID_LEVELS_PER_DISPATCH as usize)
            .map(|first| {
                let size = (shapes.iter())
                    .filter(|s| s.levels() > first)
                    .map(|s| s.level_size(first))
                    .fold(UVec2::ZERO, UVec2::max);
                let (x, y) = (size.x.div_ceil(TILE), size.y.div_ceil(TILE));
                PyramidDispatch {
                    first,
                    workgroups: [x, y, slices.len() as u32],
                }
            })
            .collect()
    }
}

/// One dispatch of a set's pyramids: the first level it writes and its workgroups.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PyramidDispatch {
    /// The first level it writes (a multiple of six; 0 reads the depth targets).
    pub first: u32,
    /// Its workgroups: x and y over the set's largest eye, z a slice each.
    pub workgroups: [u32; 3],
}
