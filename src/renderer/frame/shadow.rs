//! The frame's shadow pass in either path: the light's cull (the frame's culler, never
//! over the coarse cull's blocks) and one depth-only pass with one multi-draw-indirect
//! call into the shadow map, once per frame, before any display.

use crate::contexts::DisplayContext;
use crate::draw::{BinPipelines, Drawing, cleared_depth};
use crate::renderer::culler::Culler;
use crate::renderer::plan::CullView;
use crate::renderer::recorder::{PassRecord, Recorder};
use crate::renderer::uploads::Writes;
use crate::renderer::view::ViewPass;
use crate::shaders::{SHADOW_MAP_BINDINGS, Windows, bind_group_layout};
use crate::shadow::{LightView, SHADOW_FORMAT};

/// The light as one more view.
pub struct ShadowPass {
    view: ViewPass,
}

impl ShadowPass {
    pub fn new(
        device: &wgpu::Device,
        drawing: Drawing,
        frame: &wgpu::Buffer,
        culler: &Culler,
    ) -> ShadowPass {
        ShadowPass {
            view: ViewPass::new(device, drawing, frame, culler, CullView::Light),
        }
    }

    /// Writes the light's context for `view` and the culler's result for it. Returns the
    /// bytes written.
    pub fn prepare(&self, to: Writes, view: &LightView, size: u32, culler: &Culler) -> u64 {
        let context = DisplayContext::light(view, size);
        self.view.prepare(to, &context, culler)
    }

    /// Records the light's cull (on the GPU) and the shadow pass, timed as
    /// `shadow_cull` and `shadow` inside a `shadow` scope, logged at the frame level.
    /// Returns (dispatches, draw calls).
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        drawing: Drawing,
        culler: &Culler,
        map: &ShadowMap,
        rec: &mut Recorder,
    ) -> (u32, u32) {
        if drawing.drawer.shadow.is_none() {
            return (0, 0);
        }
        rec.enter(encoder, "shadow");
        let cull = PassRecord::frame("shadow_cull");
        let dispatches = self.view.encode_cull(encoder, culler, rec, cull);
        let mut open = rec.open(encoder, PassRecord::frame("shadow"));
        let mut pass = encoder
            .begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("stereocull.shadow"),
                color_attachments: &[],
                depth_stencil_attachment: Some(cleared_depth(&map.view)),
                timestamp_writes: open.render_writes(),
                occlusion_query_set: None,
                multiview_mask: None,
            })
            .forget_lifetime();
        rec.count(&mut pass, &mut open);
        let draw_calls = self.view.draw(&mut pass, drawing, BinPipelines::Shadow);
        rec.close_render(encoder, pass, open);
        rec.leave(encoder);
        (dispatches, draw_calls)
    }
}

/// The frame's shadow map on the GPU (1 x 1 and never drawn with shadows off, so that
/// the draw pipelines bind the same groups either way).
pub struct ShadowMap {
    /// The depth texture's view.
    view: wgpu::TextureView,
    /// Group 2 of the draw pipelines ([`SHADOW_MAP_BINDINGS`]): the map and its
    /// comparison sampler.
    pub bind_group: wgpu::BindGroup,
    /// Texels a side.
    pub size: u32,
}

impl ShadowMap {
    /// A `size` x `size` shadow map, bound with the punctual lights and their
    /// clusters (the rest of group 2).
    pub fn new(
        device: &wgpu::Device,
        size: u32,
        lights: &wgpu::Buffer,
        views: &wgpu::Buffer,
        clusters: &wgpu::Buffer,
    ) -> ShadowMap {
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("stereocull.shadow_map"),
            size: wgpu::Extent3d {
                width: size,
                height: size,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: SHADOW_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let view = texture.create_view(&Default::default());
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("stereocull.shadow_sampler"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            compare: Some(wgpu::CompareFunction::LessEqual),
            ..Default::default()
        });
        let list = &SHADOW_MAP_BINDINGS;
        let layout = &bind_group_layout(device, "stereocull.shadow_map", list, &Windows::WHOLE);
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("stereocull.shadow_map"),
            layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&view),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::Sampler(&sampler),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: lights.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: views.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: clusters.as_entire_binding(),
                },
            ],
        });
        ShadowMap {
            view,
            bind_group,
            size,
        }
    }
}
