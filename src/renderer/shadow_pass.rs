//! The frame's shadow pass in either path: the light's cull (the GPU culler's display
//! passes over every instance, or the CPU culler and an upload) and one depth-only pass
//! with one multi-draw-indirect call into the shadow map, once per frame, before any
//! display.

use super::passes::{PassRecord, close, compute_pass, open_display, open_pass};
use super::write;
use crate::contexts::DisplayContext;
use crate::cull::cpu::{self, FrameLod};
use crate::cull::gpu::{CullScene, CullTargets, GpuCuller};
use crate::draw::{DrawScene, Drawer, cleared_depth};
use crate::profiling::GpuTimer;
use crate::records::{CullLayout, uniform_bytes};
use crate::shadow::LightView;

/// Where the light's cull comes from: the GPU culler (its passes and scene data), or
/// the CPU culler's layout.
pub(super) enum LightCull<'a> {
    Gpu(&'a GpuCuller, &'a CullScene),
    Cpu(&'a CullLayout),
}

/// The light's context, cull outputs and bindings.
pub(super) struct ShadowPass {
    context: wgpu::Buffer,
    cull: CullTargets,
    /// GPU culling only.
    cull_bind_group: Option<wgpu::BindGroup>,
    draw_bind_group: wgpu::BindGroup,
    /// Draw entries: meshes times levels of detail.
    max_draws: u32,
}

impl ShadowPass {
    pub(super) fn new(
        device: &wgpu::Device,
        (drawer, draw_scene): (&Drawer, &DrawScene),
        frame: &wgpu::Buffer,
        culler: Option<(&GpuCuller, &CullScene)>,
        (slots, max_draws): (u32, u32),
    ) -> ShadowPass {
        let context = super::context_buffer(device);
        let cull = CullTargets::new(device, slots, max_draws);
        ShadowPass {
            cull_bind_group: culler
                .map(|(c, scene)| c.bind_group(device, scene, [frame, &context], &cull)),
            draw_bind_group: drawer.bind_group(
                device,
                [frame, &context],
                draw_scene,
                &cull.visible,
            ),
            context,
            cull,
            max_draws,
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
        let mut bytes = write(
            queue,
            &self.context,
            &uniform_bytes(&DisplayContext::light(view, size)),
        );
        if let LightCull::Cpu(layout) = cull {
            let out = cpu::cull_many_lod(layout, &[view.cull_job()], lod).remove(0);
            bytes += self.cull.upload(queue, &out);
        }
        bytes
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
        let mut dispatches = 0;
        if let (LightCull::Gpu(culler, scene), Some(group)) = (cull, &self.cull_bind_group) {
            let what = (&mut *log, PassRecord::frame("shadow_cull"));
            compute_pass(encoder, (timer, &frame), what, |pass| {
                culler.encode(pass, scene, group, false);
            });
            dispatches = GpuCuller::DISPATCHES_PER_DISPLAY;
        }
        let scope = open_pass(timer, "shadow", &frame, encoder);
        let writes = scope
            .as_ref()
            .and_then(|q| q.render_pass_timestamp_writes());
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("stereocull.shadow"),
            color_attachments: &[],
            depth_stencil_attachment: Some(cleared_depth(&draw_scene.shadow_map.view)),
            timestamp_writes: writes,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        let statistics = timer
            .as_deref_mut()
            .and_then(|t| t.begin_statistics(&mut pass));
        pass.set_pipeline(&shadow.pipeline);
        Drawer::bind_resources(&mut pass, draw_scene, &self.draw_bind_group);
        drawer.draw_indirect(&mut pass, self.max_draws, &self.cull);
        GpuTimer::end_statistics(&mut pass, statistics.is_some());
        drop(pass);
        close(timer, encoder, scope);
        close(timer, encoder, frame);
        log.push(PassRecord {
            statistics,
            ..PassRecord::frame("shadow")
        });
        (dispatches, 1)
    }
}
