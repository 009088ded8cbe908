//! One more view than the displays (the frame's light, a display's far layer): its own
//! context, culled by the same cull passes as a display (or uploaded from the CPU
//! culler) into its own cull outputs, and drawn with one multi-draw-indirect call.

use super::passes::{Logged, Timing, compute_pass};
use super::{context_buffer, write};
use crate::contexts::DisplayContext;
use crate::cull::CullOutput;
use crate::cull::gpu::{CullScene, CullTargets, GpuCuller};
use crate::draw::{DrawScene, Drawer};
use crate::records::uniform_bytes;
use crate::shaders::DrawKey;

/// The view's context, cull outputs and bindings.
pub(super) struct ViewPass {
    context: wgpu::Buffer,
    cull: CullTargets,
    /// GPU culling only.
    cull_bind_group: Option<wgpu::BindGroup>,
    draw_bind_group: wgpu::BindGroup,
    /// Draw entries: meshes times levels of detail.
    max_draws: u32,
}

impl ViewPass {
    pub(super) fn new(
        device: &wgpu::Device,
        (drawer, draw_scene): (&Drawer, &DrawScene),
        frame: &wgpu::Buffer,
        culler: Option<(&GpuCuller, &CullScene)>,
        (slots, max_draws): (u32, u32),
    ) -> ViewPass {
        let context = context_buffer(device);
        let cull = CullTargets::new(device, slots, max_draws);
        ViewPass {
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

    /// The view's context buffer (what a composite reads of it).
    pub(super) fn context(&self) -> &wgpu::Buffer {
        &self.context
    }

    /// The view's cull outputs, per the cull contract.
    pub(super) fn cull(&self) -> &CullTargets {
        &self.cull
    }

    /// Writes this frame's `context` and, culled on the CPU, the view's cull; returns
    /// the bytes written.
    pub(super) fn prepare(
        &self,
        queue: &wgpu::Queue,
        context: &DisplayContext,
        cpu: Option<&CullOutput>,
    ) -> u64 {
        let bytes = write(queue, &self.context, &uniform_bytes(context));
        bytes + cpu.map_or(0, |out| self.cull.upload(queue, out))
    }

    /// Records the view's cull on the GPU (`gpu`: the culler, its scene, and the coarse
    /// cull's slot whose block list it runs over, if any), timed and logged as `what`; nothing when
    /// culling on the CPU. Returns the dispatches.
    pub(super) fn encode_cull(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        gpu: Option<(&GpuCuller, &CullScene, Option<u32>)>,
        timing: Timing,
        logged: Logged,
    ) -> u32 {
        let (Some((culler, scene, slot)), Some(group)) = (gpu, &self.cull_bind_group) else {
            return 0;
        };
        compute_pass(encoder, timing, logged, |pass| {
            culler.encode(pass, scene, group, slot);
        });
        GpuCuller::DISPATCHES_PER_DISPLAY
    }

    /// The view's one multi-draw into `pass`: with `drawer`'s pipeline for `key`, or
    /// (`None`) with the pipeline `pass` already has. Returns the draw calls.
    pub(super) fn draw(
        &self,
        pass: &mut wgpu::RenderPass,
        (drawer, draw_scene): (&Drawer, &DrawScene),
        key: Option<DrawKey>,
    ) -> u32 {
        match key {
            Some(key) => drawer.bind(pass, key, draw_scene, &self.draw_bind_group),
            None => Drawer::bind_resources(pass, draw_scene, &self.draw_bind_group),
        }
        drawer.draw_indirect(pass, self.max_draws, &self.cull);
        1
    }
}
