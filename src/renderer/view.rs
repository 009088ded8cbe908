//! One more view than the displays (the frame's light, a display's far layer): its own
//! context, culled by the frame's culler like a display into its own cull outputs, and
//! drawn with one multi-draw-indirect call.

use super::culler::{CullPass, Culler};
use super::plan::CullView;
use super::recorder::{PassRecord, Recorder};
use crate::bins::BinRange;
use crate::buffers::Upload;
use crate::buffers::write;
use crate::contexts::DisplayContext;
use crate::contexts::context_buffer;
use crate::cull::targets::CullTargets;
use crate::draw::{BinPipelines, Drawer, Drawing};
use crate::occlusion::Phase;
use crate::records::uniform_bytes;
use crate::renderer::uploads::Writes;

/// The view's context, its cull and bindings.
pub struct ViewPass {
    context: wgpu::Buffer,
    /// A context of its own for the cull, where the cull tests against another view's
    /// pyramids (a far layer's, [`Phase::Tested`]); else the cull reads `context`.
    cull_context: Option<wgpu::Buffer>,
    cull: CullPass,
    draw_bind_group: wgpu::BindGroup,
    /// The material bins' ranges of the draws.
    bins: Vec<BinRange>,
}

impl ViewPass {
    /// `view`, culled by `culler` and drawn with `drawing` (both bound to `frame`, the
    /// frame context).
    pub fn new(
        device: &wgpu::Device,
        drawing: Drawing,
        frame: &wgpu::Buffer,
        culler: &Culler,
        view: CullView,
    ) -> ViewPass {
        let context = context_buffer(device);
        ViewPass::phased(
            device,
            drawing,
            frame,
            culler,
            view,
            Phase::Frustum,
            context,
        )
    }

    /// `view` in occlusion `phase`, with `context` for its context buffer (the late
    /// phase shares its display's).
    pub fn phased(
        device: &wgpu::Device,
        drawing: Drawing,
        frame: &wgpu::Buffer,
        culler: &Culler,
        view: CullView,
        phase: Phase,
        context: wgpu::Buffer,
    ) -> ViewPass {
        let cull = culler.view(device, view, phase, [frame, &context]);
        ViewPass::bound(device, drawing, frame, culler, context, None, cull)
    }

    /// `view` culled in [`Phase::Tested`]: against its display's pyramids, with a cull
    /// context of its own ([`crate::far_layer::FarPlan::tested_context`]) beside the
    /// context it is drawn with.
    pub fn tested(
        device: &wgpu::Device,
        drawing: Drawing,
        frame: &wgpu::Buffer,
        culler: &Culler,
        view: CullView,
    ) -> ViewPass {
        let cull_context = context_buffer(device);
        let cull = culler.view(device, view, Phase::Tested, [frame, &cull_context]);
        let context = context_buffer(device);
        ViewPass::bound(
            device,
            drawing,
            frame,
            culler,
            context,
            Some(cull_context),
            cull,
        )
    }

    fn bound(
        device: &wgpu::Device,
        drawing: Drawing,
        frame: &wgpu::Buffer,
        culler: &Culler,
        context: wgpu::Buffer,
        cull_context: Option<wgpu::Buffer>,
        cull: CullPass,
    ) -> ViewPass {
        ViewPass {
            draw_bind_group: drawing.drawer.bind_group(
                device,
                [frame, &context],
                drawing.scene,
                cull.targets.visible_binding(),
            ),
            context,
            cull_context,
            cull,
            bins: culler.bins().to_vec(),
        }
    }

    /// The view's context buffer (what a composite reads of it).
    pub fn context(&self) -> &wgpu::Buffer {
        &self.context
    }

    /// The view's cull, as the culler keeps it.
    pub fn cull_pass(&self) -> &CullPass {
        &self.cull
    }

    /// The view's cull outputs, per the cull contract.
    pub fn cull(&self) -> &CullTargets {
        &self.cull.targets
    }

    /// Writes this frame's `context` and the culler's result for the view (nothing on
    /// the GPU); returns the bytes written.
    pub fn prepare(&self, to: Writes, context: &DisplayContext, culler: &Culler) -> u64 {
        let member = culler.write_member(to.pose, &self.cull, context);
        to.pose.write_uniform(&self.context, 0, context)
            + culler.upload(to.queue, &self.cull)
            + member
    }

    /// Writes this frame's cull context, for a view that has one of its own
    /// ([`ViewPass::tested`]); returns the bytes written.
    pub fn prepare_cull_context(&self, queue: &impl Upload, context: &DisplayContext) -> u64 {
        match &self.cull_context {
            Some(buffer) => write(queue, buffer, &uniform_bytes(context)),
            None => 0,
        }
    }

    /// Records the view's cull (on the GPU) in its phase, timed and logged as `what`.
    /// Returns the dispatches.
    pub fn encode_cull(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        culler: &Culler,
        rec: &mut Recorder,
        what: PassRecord,
    ) -> u32 {
        self.encode_cull_in(encoder, culler, self.cull.phase(), rec, what)
    }

    /// [`ViewPass::encode_cull`] in `phase` (a tested view culled by its frustum alone
    /// where its display draws in one pass).
    pub fn encode_cull_in(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        culler: &Culler,
        phase: Phase,
        rec: &mut Recorder,
        what: PassRecord,
    ) -> u32 {
        culler.encode(encoder, &self.cull, phase, rec, what)
    }

    /// The view's draws into `pass`: per material bin, its pipeline of `with` and one
    /// multi-draw. Returns the draw calls.
    pub fn draw(
        &self,
        pass: &mut wgpu::RenderPass,
        Drawing { drawer, scene }: Drawing,
        with: BinPipelines,
    ) -> u32 {
        match with {
            BinPipelines::Draw(..) => Drawer::bind(pass, scene, &self.draw_bind_group),
            BinPipelines::Shadow => {
                // The cutout pipeline reads the materials.
                Drawer::bind_resources(pass, scene, &self.draw_bind_group);
                pass.set_bind_group(1, &scene.materials.bind_group, &[]);
            }
            BinPipelines::Own => Drawer::bind_resources(pass, scene, &self.draw_bind_group),
        }
        drawer.draw_bins(pass, (&self.bins, scene), with, &self.cull.targets)
    }
}
