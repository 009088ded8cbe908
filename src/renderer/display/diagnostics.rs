//! What a frame of the GPU-driven path holds after it was submitted, read back for
//! [`crate::renderer::Diagnostics`]: each display's cull buffers (its early and late
//! phases, its far layer's and inset pair's), visible totals and occlusion counts.

use super::indirect::IndirectPath;
use crate::cull::targets::{COUNTS_BYTES, CullTargets};
use crate::cull::{BinDraws, CullOutput};
use crate::draw::keep_tiles::TileGrid;
use crate::error::Result;
use crate::occlusion::PyramidShape;
use crate::readback::read_pod_at;
use crate::records::DrawArgs;
use crate::renderer::culler::ViewCull;
use crate::renderer::diagnostics::OcclusionCounts;
use crate::renderer::view::ViewPass;

impl IndirectPath {
    /// Display `index`'s cull buffers, read back after the frame was submitted.
    pub(in crate::renderer) fn read_cull(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        index: usize,
    ) -> Result<CullOutput> {
        self.read_targets(device, queue, self.displays[index].view.cull())
    }

    /// Display `index`'s changed tiles in the last frame (`None`: drawn whole), as its
    /// tile pass read them (marked on the CPU or the GPU), read back, with its grid.
    pub(in crate::renderer) fn read_changed_tiles(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        index: usize,
    ) -> Result<Option<(Vec<u32>, TileGrid)>> {
        let (Some(keep), Some(kept)) = (&self.keep, self.kept[index]) else {
            return Ok(None);
        };
        let (at, Some(grid)) = keep.words(index) else {
            return Ok(None);
        };
        let words = read_pod_at(device, queue, at, 4 * u64::from(kept.words))?;
        Ok(Some((words, grid)))
    }

    /// Display `index`'s far layer's cull buffers (`None` without one), read back after
    /// the frame was submitted.
    pub(in crate::renderer) fn read_far_cull(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        index: usize,
    ) -> Result<Option<CullOutput>> {
        match self.far.as_ref().and_then(|f| f.displays[index].as_ref()) {
            Some(far) => self.read_targets(device, queue, far.view.cull()).map(Some),
            None => Ok(None),
        }
    }

    /// Display `index`'s inset cull buffers (`None` without an inset cull), read back
    /// after the frame was submitted.
    pub(in crate::renderer) fn read_inset_cull(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        index: usize,
    ) -> Result<Option<CullOutput>> {
        match &self.displays[index].inset {
            Some(inset) => self.read_targets(device, queue, inset.cull()).map(Some),
            None => Ok(None),
        }
    }

    /// This frame's far distance per display, with the far layer (`None` per display
    /// without one).
    pub(in crate::renderer) fn far_distances(&self) -> Vec<Option<f32>> {
        match &self.far {
            Some(far) => far.distances.clone(),
            None => vec![None; self.displays.len()],
        }
    }

    pub(super) fn read_targets(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        cull: &CullTargets,
    ) -> Result<CullOutput> {
        let counts = read_counts(device, queue, cull)?;
        let [draw_count, visible_total] = [counts[0], counts[1]];
        let visible = match visible_total {
            0 => Vec::new(),
            n => read_pod_at(
                device,
                queue,
                (&cull.visible, cull.visible_at),
                4 * n as u64,
            )?,
        };
        let draws_bytes = (size_of::<DrawArgs>() as u32 * self.core.culler.draws()) as u64;
        Ok(CullOutput {
            visible,
            draws: read_pod_at(device, queue, (&cull.draws, cull.draws_at), draws_bytes)?,
            draw_count,
            bins: (self.core.culler.bins().iter().zip(&counts[2..]))
                .map(|(r, &count)| BinDraws {
                    first: r.first,
                    count,
                })
                .collect(),
        })
    }

    /// Every display's visible total, from its counts buffer (with occlusion, both
    /// phases': what it drew).
    pub(in crate::renderer) fn visible_counts(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Vec<u32>> {
        let count =
            |view: &ViewPass| -> Result<u32> { Ok(read_counts(device, queue, view.cull())?[1]) };
        (self.displays.iter())
            .map(|d| {
                let late = d.late.as_ref().map_or(Ok(0), |late| count(&late.view))?;
                Ok(count(&d.view)? + late)
            })
            .collect()
    }
}

impl IndirectPath {
    /// Display `index`'s late phase's cull buffers (`None` without occlusion), read
    /// back after the frame was submitted.
    pub(in crate::renderer) fn read_late_cull(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        index: usize,
    ) -> Result<Option<CullOutput>> {
        match &self.displays[index].late {
            Some(late) => self.read_targets(device, queue, late.view.cull()).map(Some),
            None => Ok(None),
        }
    }

    /// Per display, what its two occlusion phases drew (`None` without occlusion).
    pub(in crate::renderer) fn read_occlusion_counts(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Vec<Option<OcclusionCounts>>> {
        (self.displays.iter())
            .map(|d| {
                let Some(late) = &d.late else {
                    return Ok(None);
                };
                let early = read_counts(device, queue, d.view.cull())?[1];
                let late = read_counts(device, queue, late.view.cull())?[1];
                Ok(Some(OcclusionCounts { early, late }))
            })
            .collect()
    }

    /// Per display, its pyramids' shape (`None` without occlusion).
    pub(in crate::renderer) fn pyramid_shapes(&self) -> Vec<Option<PyramidShape>> {
        (self.displays.iter())
            .map(|d| Some(d.late.as_ref()?.shape))
            .collect()
    }

    /// Each display's (first) cull.
    pub(in crate::renderer) fn display_culls(&self) -> Vec<&ViewCull> {
        self.displays.iter().map(|d| d.view.view_cull()).collect()
    }
}

/// The counts buffer: the draw count, the visible total, each bin's draw count.
fn read_counts(device: &wgpu::Device, queue: &wgpu::Queue, cull: &CullTargets) -> Result<Vec<u32>> {
    read_pod_at(device, queue, (&cull.counts, cull.counts_at), COUNTS_BYTES)
}
