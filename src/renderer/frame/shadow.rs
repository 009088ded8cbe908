//! The frame's shadow pass in either path: the light's cull (the frame's culler, never
//! over the coarse cull's blocks) and one depth-only pass with one multi-draw-indirect
//! call into the shadow map, once per frame, before any display.

use crate::contexts::DisplayContext;
use crate::draw::{BinPipelines, Drawing, cleared_depth};
use crate::renderer::culler::Culler;
use crate::renderer::plan::CullView;
use crate::renderer::recorder::{PassRecord, Recorder};
use crate::renderer::view::ViewPass;
use crate::shadow::LightView;

/// The light as one more view.
pub(in crate::renderer) struct ShadowPass {
    view: ViewPass,
}

impl ShadowPass {
    pub(in crate::renderer) fn new(
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
    pub(in crate::renderer) fn prepare(
        &self,
        queue: &wgpu::Queue,
        view: &LightView,
        size: u32,
        culler: &Culler,
    ) -> u64 {
        let context = DisplayContext::light(view, size);
        self.view.prepare(queue, &context, culler)
    }

    /// Records the light's cull (on the GPU) and the shadow pass, timed as
    /// `shadow_cull` and `shadow` inside a `shadow` scope, logged at the frame level.
    /// Returns (dispatches, draw calls).
    pub(in crate::renderer) fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        drawing: Drawing,
        culler: &Culler,
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
                depth_stencil_attachment: Some(cleared_depth(&drawing.scene.shadow_map.view)),
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
