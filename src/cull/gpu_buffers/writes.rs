//! The GPU culler's per-frame writes into its buffers: the hidden areas, the coarse
//! cull's block tests and the rig cull's members.

use super::CullScene;
use crate::buffers::Upload;
use crate::cull::HiddenArea;
use crate::cull::coarse::CoarseCull;
use crate::cull::rig::{RigCull, RigOcclusion, RigView};
use crate::records::storage_bytes;
use glam::Vec4;

impl CullScene {
    /// Writes this frame's hidden areas, one per display slot (in order; `None` drops
    /// nothing). Returns the bytes written; nothing where no display's cull drops by one.
    pub fn write_hidden<'a>(
        &self,
        queue: &impl Upload,
        areas: impl Iterator<Item = Option<&'a HiddenArea>>,
    ) -> u64 {
        if self.hidden_slots == 0 {
            return 0;
        }
        let records: Vec<HiddenArea> = (areas.take(self.hidden_slots as usize))
            .map(|a| a.copied().unwrap_or(HiddenArea::NONE))
            .collect();
        let bytes = storage_bytes(&records);
        queue.write_buffer(&self.hidden, 0, &bytes);
        bytes.len() as u64
    }

    /// Writes this frame's block tests, one per coarse slot (display, in order): the
    /// display frustums' planes grown for rounding ([`CoarseCull::around`]). Returns the
    /// bytes written; nothing without the coarse cull.
    pub fn write_block_tests(&self, queue: &impl Upload, planes: &[[Vec4; 6]]) -> u64 {
        if self.coarse_slots == 0 {
            return 0;
        }
        let tests: Vec<CoarseCull> = planes.iter().map(|p| CoarseCull::around(*p)).collect();
        let bytes = storage_bytes(&tests);
        queue.write_buffer(&self.block_tests, 0, &bytes);
        bytes.len() as u64
    }

    /// Writes rig member `m`'s record for this frame, and a late member's occlusion
    /// test; returns the bytes written.
    pub fn write_rig_member(
        &self,
        queue: &impl Upload,
        m: u32,
        (record, test): (&RigView, Option<&RigOcclusion>),
    ) -> u64 {
        let (group, index) = self.rig_sets.place(m);
        let base = group as u64 * self.rig_stride;
        let (view_at, test_at) = RigCull::offsets(index as usize);
        let written = queue.write_uniform(&self.rig, base + view_at, record);
        written + test.map_or(0, |t| queue.write_uniform(&self.rig, base + test_at, t))
    }
}
