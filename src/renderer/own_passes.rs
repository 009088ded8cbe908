//! Drawing into the caller's own passes: the frame's culls (and frame-level passes)
//! into its encoder, then each display's draws inside a render pass it began, with the
//! built-in pipelines or one of its own.

use super::frame_stats::FrameStats;
use super::recorder::Recorder;
use super::{Path, Renderer};
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
        if let Some(p) = self.path.indirect() {
            for i in 0..self.shapes.len() {
                rec.enter(encoder, &self.names[i]);
                let culled = p.encode_cull(encoder, (i, true), &mut rec);
                stats.dispatches += culled.dispatches;
                stats.draw_calls += culled.draw_calls;
            }
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
        if index >= self.shapes.len() {
            return Err(Error::NoSuchDisplay {
                index,
                displays: self.shapes.len(),
            });
        }
        Ok(match &self.path {
            Path::Indirect(p) => {
                p.check_own_pipelines(index)?;
                p.draw(pass, index)
            }
            Path::Classic(p) => p.draw(pass, index),
        })
    }

    /// Sets display `index`'s pipeline of the caller's own for the material bins of
    /// [`crate::scene::Shading::Own`]`(shading)` (the GPU-driven modes): from now on
    /// every draw of the display, in the renderer's passes and in
    /// [`Renderer::draw_display`], issues those bins' multi-draw with it. One pipeline
    /// may serve several displays of one target shape. A frame whose display draws an
    /// own bin without its pipeline is [`Error::MissingOwnPipeline`].
    pub fn set_own_pipeline(&mut self, index: usize, shading: u32, own: OwnPipeline) -> Result<()> {
        let displays = self.shapes.len();
        match &mut self.path {
            Path::Indirect(_) if index >= displays => Err(Error::NoSuchDisplay { index, displays }),
            Path::Indirect(p) => {
                p.set_own_pipeline(index, shading, own);
                Ok(())
            }
            Path::Classic(_) => Err(Error::Unsupported(format!(
                "{} draws per instance; pipelines of the caller's own draw the indirect modes",
                self.options.mode.name()
            ))),
        }
    }

    /// For an engine's own draw pipeline (the indirect modes): group 0's layout, to
    /// build its pipeline layout on (its own bind groups from group 1), with
    /// [`Renderer::decode_source`] as the shader's start. `None` in the classic modes.
    pub fn bind_group_layout(&self) -> Option<&wgpu::BindGroupLayout> {
        self.path.indirect().map(|p| p.bind_group_layout())
    }

    /// Display `index`'s cull outputs on the GPU (the indirect modes): the visible list,
    /// the draws and the counts, per the README's cull contract.
    pub fn cull_buffers(&self, index: usize) -> Option<&CullTargets> {
        let p = self.path.indirect().filter(|_| index < self.shapes.len())?;
        Some(p.cull_targets(index))
    }

    /// Display `index`'s one multi-draw-indirect call, in a pass the caller began with a
    /// pipeline of its own already set (layout from [`Renderer::bind_group_layout`]):
    /// binds group 0, the vertex and index buffers, and draws. The indirect modes only.
    pub fn draw_display_with_own_pipeline(
        &self,
        pass: &mut wgpu::RenderPass,
        index: usize,
    ) -> Result<()> {
        match &self.path {
            Path::Indirect(_) if self.options.far_layer => Err(Error::Unsupported(
                "with the far layer the renderer composites before its draws; draw_display draws both".into(),
            )),
            Path::Indirect(p) if index < self.shapes.len() => {
                p.draw_with_own_pipeline(pass, index);
                Ok(())
            }
            Path::Indirect(_) => Err(Error::NoSuchDisplay {
                index,
                displays: self.shapes.len(),
            }),
            Path::Classic(_) => Err(Error::Unsupported(format!(
                "{} draws per instance; pipelines of the caller's own draw the indirect modes",
                self.options.mode.name()
            ))),
        }
    }

    /// The stereo decode for an engine's own pipeline on this renderer's group 0
    /// ([`crate::shaders::decode_source_with`] with this renderer's binding windows):
    /// `None` in the classic modes.
    pub fn decode_source(&self, views: u32) -> Option<String> {
        let p = self.path.indirect()?;
        Some(crate::shaders::decode_source_with(views, &p.windows()))
    }
}
