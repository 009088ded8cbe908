//! Drawing into the caller's own passes: the frame's culls (and frame-level passes)
//! into its encoder, then each display's draws inside a render pass it began, with the
//! built-in pipelines or one of its own.

use super::frame_stats::FrameStats;
use super::recorder::Recorder;
use super::{Display, Renderer};
use crate::cull::targets::CullTargets;
use crate::draw::OwnPipeline;
use crate::error::{Error, Result};
use crate::profiling::GpuTimer;

impl Renderer {
    /// For drawing into the caller's own render passes: records this frame's culls
    /// (GPU culling: each display's dispatches, timed as `cull` inside a scope per
    /// display; CPU culling: nothing, `prepare` uploaded them). Then, in passes the
    /// caller begins, [`Renderer::draw_display`] for each display. Occlusion's two
    /// phases need the renderer's own passes (a draw, the depth's pyramids, another
    /// draw): here each display is culled by its frustum alone. Culling on the CPU with
    /// occlusion, `prepare` uploaded the early phases, so that is
    /// [`Error::Unsupported`].
    pub fn encode_culls(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        timer: Option<&mut GpuTimer>,
    ) -> Result<FrameStats> {
        if self.reads_back() {
            return Err(Error::Unsupported(
                "occlusion with CPU culling draws in the renderer's own passes (encode_early, encode_late): make the renderer with occlusion off to draw in passes of your own".into(),
            ));
        }
        let mut rec = Recorder::new(timer, Vec::new());
        let mut stats = self.encode_frame(encoder, &mut rec);
        stats.dispatch_levels.frame = stats.dispatches;
        for display in &self.displays {
            stats = stats + display.encode_cull(encoder, &self.shared, &mut rec);
        }
        self.passes = rec.finish(encoder, true);
        Ok(stats)
    }

    /// Draws display `index` into a render pass the caller began, after
    /// [`Renderer::encode_culls`] was recorded for this frame. The pass must render into
    /// that display's target shape ([`super::TargetViews`]) with the formats and sample count of
    /// [`super::RendererOptions`], and with `multiview_mask` `0b11` for a stereo display in
    /// multiview. Its load and store operations, and whatever the caller draws before and
    /// after (sky, UI, transparent geometry), are the caller's. Returns the draw calls.
    pub fn draw_display(&self, pass: &mut wgpu::RenderPass, index: usize) -> Result<u32> {
        self.display(index)?.draw(pass, &self.shared)
    }

    /// Display `index`, or [`Error::NoSuchDisplay`].
    pub(super) fn display(&self, index: usize) -> Result<&Display> {
        let displays = self.displays.len();
        self.displays
            .get(index)
            .ok_or(Error::NoSuchDisplay { index, displays })
    }

    /// Sets display `index`'s pipeline of the caller's own for the material bins of
    /// [`crate::scene::Shading::Own`]`(shading)` (the GPU-driven modes): from now on
    /// every draw of the display, in the renderer's passes and in
    /// [`Renderer::draw_display`], issues those bins' multi-draw with it. One pipeline
    /// may serve several displays of one target shape. A frame whose display draws an
    /// own bin without its pipeline is [`Error::MissingOwnPipeline`].
    pub fn set_own_pipeline(&mut self, index: usize, shading: u32, own: OwnPipeline) -> Result<()> {
        if self.options.mode.per_instance() {
            return Err(self.per_instance());
        }
        self.display(index)?;
        if let Some(d) = self.displays[index].indirect_mut() {
            d.set_own_pipeline(shading, own);
        }
        Ok(())
    }

    /// What the classic modes answer a call for the indirect modes' own pipelines.
    fn per_instance(&self) -> Error {
        Error::Unsupported(format!(
            "{} draws per instance; pipelines of the caller's own draw the indirect modes",
            self.options.mode.name()
        ))
    }

    /// For an engine's own draw pipeline (the indirect modes): group 0's layout, to
    /// build its pipeline layout on (its own bind groups from group 1), with
    /// [`Renderer::decode_source`] as the shader's start. `None` in the classic modes.
    pub fn bind_group_layout(&self) -> Option<&wgpu::BindGroupLayout> {
        (!self.options.mode.per_instance()).then(|| self.shared.drawer.layout())
    }

    /// Display `index`'s cull outputs on the GPU (the indirect modes): the visible list,
    /// the draws and the counts, per the README's cull contract.
    pub fn cull_buffers(&self, index: usize) -> Option<&CullTargets> {
        Some(self.displays.get(index)?.indirect()?.cull_targets())
    }

    /// Display `index`'s one multi-draw-indirect call, in a pass the caller began with a
    /// pipeline of its own already set (layout from [`Renderer::bind_group_layout`]):
    /// binds group 0, the vertex and index buffers, and draws. The indirect modes only.
    pub fn draw_display_with_own_pipeline(
        &self,
        pass: &mut wgpu::RenderPass,
        index: usize,
    ) -> Result<()> {
        if self.options.mode.per_instance() {
            return Err(self.per_instance());
        }
        if self.options.far_layer {
            return Err(Error::Unsupported(
                "with the far layer the renderer composites before its draws; draw_display draws both".into(),
            ));
        }
        if let Some(d) = self.display(index)?.indirect() {
            d.draw_with_own_pipeline(pass, &self.shared);
        }
        Ok(())
    }

    /// The stereo decode for an engine's own pipeline on this renderer's group 0
    /// ([`crate::shaders::decode_source_with`] with this renderer's binding windows):
    /// `None` in the classic modes.
    pub fn decode_source(&self, views: u32) -> Option<String> {
        (!self.options.mode.per_instance())
            .then(|| crate::shaders::decode_source_with(views, &self.shared.drawer.windows))
    }
}
