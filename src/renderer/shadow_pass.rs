//! The frame's shadow pass in either path: the light's cull (the GPU culler's display
//! passes over every instance, or the CPU culler and an upload) and one depth-only pass
//! with one multi-draw-indirect call into the shadow map, once per frame, before any
//! display.

use super::passes::{PassRecord, close, open_display, opener, render_pass};
use super::view_pass::ViewPass;
use crate::contexts::DisplayContext;
use crate::cull::cpu::{self, FrameLod};
use crate::cull::gpu::{CullScene, GpuCuller};
use crate::draw::{DrawScene, Drawer, cleared_depth};
use crate::profiling::GpuTimer;
use crate::records::CullLayout;
use crate::shadow::LightView;

/// Where the light's cull comes from: the GPU culler (its passes and scene data), or
/// the CPU culler's layout.
pub(super) enum LightCull<'a> {
    Gpu(&'a GpuCuller, &'a CullScene),
    Cpu(&'a CullLayout),
}

/// The light as one more view.
pub(super) struct ShadowPass {
    view: ViewPass,
}

impl ShadowPass {
    pub(super) fn new(
        device: &wgpu::Device,
        drawing: (&Drawer, &DrawScene),
        frame: &wgpu::Buffer,
        culler: Option<(&GpuCuller, &CullScene)>,
        sizes: (u32, u32),
    ) -> ShadowPass {
        ShadowPass {
            view: ViewPass::new(device, drawing, frame, culler, sizes),
        }
    }

    /// Writes the light's context for `view` and, culling on the CPU, its cull with the
    /// frame's levels of detail. Returns the bytes written.
    pub(super) fn prepare(
        &self,
        queue: &wgpu::Queue,
        (view, size): (&LightView, u32),
        cull: &LightCull,
        lod: &FrameLod,
    ) -> u64 {
        let cpu = match cull {
            LightCull::Cpu(layout) => {
                Some(cpu::cull_many_lod(layout, &[view.cull_job()], lod).remove(0))
            }
            LightCull::Gpu(..) => None,
        };
        let context = DisplayContext::light(view, size);
        self.view.prepare(queue, &context, cpu.as_ref())
    }

    /// Records the light's cull (on the GPU) and the shadow pass, timed as
    /// `shadow_cull` and `shadow` inside a `shadow` scope, logged at the frame level.
    /// Returns (dispatches, draw calls).
    pub(super) fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        (drawer, draw_scene): (&Drawer, &DrawScene),
        cull: &LightCull,
        (timer, log): (&mut Option<&mut GpuTimer>, &mut Vec<PassRecord>),
    ) -> (u32, u32) {
        let Some(shadow) = &drawer.shadow else {
            return (0, 0);
        };
        let frame = open_display(timer, "shadow", encoder);
        let gpu = match cull {
            LightCull::Gpu(culler, scene) => Some((*culler, *scene, None)),
            LightCull::Cpu(_) => None,
        };
        let what = (&mut *log, PassRecord::frame("shadow_cull"));
        let dispatches = self.view.encode_cull(encoder, gpu, (timer, &frame), what);
        let begin = opener(|encoder, writes| {
            encoder
                .begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("stereocull.shadow"),
                    color_attachments: &[],
                    depth_stencil_attachment: Some(cleared_depth(&draw_scene.shadow_map.view)),
                    timestamp_writes: writes,
                    occlusion_query_set: None,
                    multiview_mask: None,
                })
                .forget_lifetime()
        });
        let logged = (log, PassRecord::frame("shadow"));
        let draw_calls = render_pass(encoder, begin, ((timer, &frame), logged), |pass| {
            pass.set_pipeline(&shadow.pipeline);
            self.view.draw(pass, (drawer, draw_scene), None)
        });
        close(timer, encoder, frame);
        (dispatches, draw_calls)
    }
}
