//! The lens's hidden area ([`VisibilityMask`]) written to depth at the start of a
//! display's draw pass (`wgsl/visibility_mask.wgsl`): at depth 0, the near plane, so
//! that every fragment the scene would put there fails the depth test (`Less`) and is
//! never shaded, and its pixels keep the clear color. One draw per display: side by
//! side one instance per view, its triangles placed into the view's viewport on the CPU;
//! in multiview the view index picks them.

use glam::Vec4;

use super::TargetFormat;
use crate::rig::{MAX_MASK_TRIANGLES, ViewLayout, VisibilityMask};
use crate::shaders::MAX_HIDDEN_VIEWS;
use crate::shaders::{
    ScreenTargets, VISIBILITY_MASK_BINDINGS, Windows, depth_write, screen_pipeline,
};

/// Vertices per view in the mask buffer.
const PER_VIEW: usize = 3 * MAX_MASK_TRIANGLES;

/// The mask pipeline of one target shape (format, samples, multiview or not).
pub struct MaskPipeline {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
}

/// One display's mask: its placed triangles, bound.
pub struct DisplayMask {
    bind_group: wgpu::BindGroup,
    /// Instances per draw: the views side by side, or 1 in multiview.
    instances: u32,
    /// Pixels whose centers it covers ([`VisibilityMask::hidden_pixels`], its views
    /// together): what it keeps from being shaded at one sample per pixel.
    pub pixels: u64,
}

impl MaskPipeline {
    /// Its pipeline for targets of `format`; `multiview_mask` for a layered target.
    pub fn new(
        device: &wgpu::Device,
        format: TargetFormat,
        multiview_mask: Option<std::num::NonZeroU32>,
    ) -> MaskPipeline {
        let label = "stereocull.visibility_mask";
        let layout = crate::shaders::bind_group_layout(
            device,
            label,
            &VISIBILITY_MASK_BINDINGS,
            &Windows::WHOLE,
        );
        let source = crate::shaders::visibility_mask_source(multiview_mask.is_some());
        // Every target of the pass, none written: the hidden area keeps the clear color
        // and zero motion.
        let untouched = |format| wgpu::ColorTargetState {
            format,
            blend: None,
            write_mask: wgpu::ColorWrites::empty(),
        };
        let motion = format.motion.then_some(crate::motion::MOTION_FORMAT);
        let targets = ScreenTargets {
            color: [Some(format.color), motion]
                .into_iter()
                .flatten()
                .map(untouched)
                .collect(),
            depth: Some(depth_write(format.depth)),
            samples: format.samples,
            multiview_mask,
        };
        let pipeline = screen_pipeline(device, label, (source, &layout), targets);
        MaskPipeline { pipeline, layout }
    }

    /// A display's mask, its views placed by `layout` (one layer each when `layered`).
    pub fn display(
        &self,
        device: &wgpu::Device,
        mask: &VisibilityMask,
        layout: &ViewLayout,
        layered: bool,
    ) -> DisplayMask {
        use wgpu::util::DeviceExt;
        let vertices = placed_vertices(mask, layout, layered);
        let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("stereocull.visibility_mask"),
            contents: bytemuck::cast_slice(&vertices),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("stereocull.visibility_mask"),
            layout: &self.layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: buffer.as_entire_binding(),
            }],
        });
        let views = mask
            .views
            .len()
            .min(layout.views as usize)
            .min(MAX_HIDDEN_VIEWS);
        let size = |v: usize| (layout.viewports[v][2], layout.viewports[v][3]);
        DisplayMask {
            bind_group,
            instances: if layered { 1 } else { views as u32 },
            pixels: (0..views).map(|v| mask.hidden_pixels(v, size(v))).sum(),
        }
    }

    /// Draws `mask` into `pass`, which must have just opened on a cleared depth.
    pub fn draw(&self, pass: &mut wgpu::RenderPass, mask: &DisplayMask) {
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &mask.bind_group, &[]);
        pass.draw(0..PER_VIEW as u32, 0..mask.instances);
    }
}

/// A display's mask pass for `mask` over its views' `layout` (one layer each or not),
/// drawn into targets of `format`.
pub fn display_mask(
    device: &wgpu::Device,
    mask: &VisibilityMask,
    (layout, layered): (&ViewLayout, bool),
    format: TargetFormat,
) -> (MaskPipeline, DisplayMask) {
    // In multiview the pass renders every layer (`DrawKey::multiview_mask`).
    let layers = layered.then(|| std::num::NonZeroU32::new((1 << layout.views) - 1));
    let pipeline = MaskPipeline::new(device, format, layers.flatten());
    let display = pipeline.display(device, mask, layout, layered);
    (pipeline, display)
}

/// The mask buffer: per masked view ([`MAX_HIDDEN_VIEWS`] slots: a foveated display's
/// outer pair, or two frames' eyes), its triangles' corners as clip
/// coordinates placed into the view's viewport (side by side) or as they are (each
/// view its layer), `w` = 1; unused corners `w` = 0, outside every clip volume.
pub fn placed_vertices(mask: &VisibilityMask, layout: &ViewLayout, layered: bool) -> Vec<Vec4> {
    let mut vertices = vec![Vec4::ZERO; MAX_HIDDEN_VIEWS * PER_VIEW];
    let masked = (layout.views as usize).min(MAX_HIDDEN_VIEWS);
    for (v, triangles) in mask.views.iter().take(masked).enumerate() {
        let p = match layered {
            true => Vec4::new(1.0, 0.0, 1.0, 0.0),
            false => crate::contexts::placement(layout.viewports[v], layout.size),
        };
        let corners = triangles.iter().flatten();
        for (slot, [x, y]) in vertices[v * PER_VIEW..].iter_mut().zip(corners) {
            *slot = Vec4::new(x * p.x + p.y, y * p.z + p.w, 0.0, 1.0);
        }
    }
    vertices
}
