//! The GPU-driven path's occlusion half: after every display's early draw, every
//! display's pyramids and late culls (`Renderer::encode`'s order), each display's far
//! layer tested against its pyramids and its late draw, culling on the CPU the late
//! culls between the frame's halves, and what occlusion checks and costs.

use super::OcclusionBytes;
use super::{check_depth, occlusion_bytes};
use crate::error::Result;
use crate::occlusion::Phase;
use crate::renderer::display::indirect::IndirectPath;
use crate::renderer::frame_stats::FrameStats;
use crate::renderer::recorder::Recorder;
use crate::renderer::targets::TargetViews;

impl IndirectPath {
    /// With occlusion and the rig cull, every display's late cull in one set of
    /// dispatches, after every display's early draw and pyramids. Returns the
    /// dispatches.
    pub(in crate::renderer) fn encode_late_rig(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder,
    ) -> u32 {
        self.core.culler.encode_late_rig(encoder, rec)
    }

    /// With occlusion, after every display's [`IndirectPath::encode_early`]: every
    /// display's pyramids of its early depth (in `targets`), in sets of displays.
    /// Returns the dispatches.
    pub(in crate::renderer) fn encode_pyramids(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &[TargetViews],
        rec: &mut Recorder,
    ) -> u32 {
        (self.pyramids).encode(encoder, (&self.core.culler, targets), rec)
    }

    /// Whether display `index`'s late cull takes dispatches of its own (GPU culling
    /// with occlusion, where the rig cull does not take it).
    pub(in crate::renderer) fn culls_late_apart(&self, index: usize) -> bool {
        let late = self.displays[index].late.as_ref();
        late.is_some_and(|l| self.core.culler.records(l.view.view_cull()))
    }

    /// Display `index`'s late cull in its own dispatches (see
    /// [`IndirectPath::culls_late_apart`]), after every display's pyramids. Returns
    /// the dispatches.
    pub(in crate::renderer) fn encode_late_cull(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        index: usize,
        rec: &mut Recorder,
    ) -> u32 {
        match &self.displays[index].late {
            Some(late) => late.encode_cull(encoder, &self.core.culler, rec),
            None => 0,
        }
    }

    /// With occlusion, the rest of display `index`'s late phase after
    /// [`IndirectPath::encode_early`]: with a far layer its cull against the pyramids
    /// and its pass, then the late draw (opening with the far composite).
    pub(in crate::renderer) fn encode_rest(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        (index, target): (usize, &TargetViews),
        rec: &mut Recorder,
    ) -> FrameStats {
        let state = &self.displays[index];
        let Some(late) = &state.late else {
            return FrameStats::default();
        };
        let mut stats = self.encode_far(encoder, (index, Phase::Tested), rec);
        let with = (self.core.drawing(), &state.own, self.far_layer(index));
        stats.draw_calls += late.encode_draw(encoder, with, target, rec);
        stats
    }

    /// Whether display `index` has a late half ([`IndirectPath::encode_rest`]).
    pub(in crate::renderer) fn has_late(&self, index: usize) -> bool {
        self.displays[index].late.is_some()
    }

    /// Culling on the CPU with occlusion, after the frame's early half was submitted:
    /// each display's late phase and far layer culled against its pyramids, read back
    /// ([`Culler::cull_late`]).
    pub(in crate::renderer) fn cull_late(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<FrameStats> {
        let far = |i: usize| self.far.as_ref()?.displays[i].as_ref();
        let views: Vec<_> = (self.displays.iter().enumerate())
            .map(|(i, d)| {
                let late = d.late.as_ref().map(|l| l.view.view_cull());
                (late, far(i).map(|layer| layer.view.view_cull()))
            })
            .collect();
        self.core.culler.cull_late((device, queue), &views)
    }

    /// Whether each display with occlusion can read its depth target into its pyramids.
    pub(in crate::renderer) fn check_depth(&self, targets: &[TargetViews]) -> Result<()> {
        check_depth(self.displays.iter().map(|d| d.late.as_ref()), targets)
    }

    /// See [`crate::renderer::Renderer::occlusion_bytes`].
    pub(in crate::renderer) fn occlusion_bytes(&self) -> Option<OcclusionBytes> {
        let late = self.displays.iter().filter_map(|d| d.late.as_ref());
        occlusion_bytes(late, &self.core.culler)
    }
}
