//! A kept frame's changed tiles marked on the GPU ([`crate::cull::tile_marks`]): the
//! culler arms its marking pass with the plan's listed slots, records its two phases
//! around the frame's pose, and tells the draw pass where the marked words lie.

use super::{Culler, Kind};
use crate::buffers::Upload;
use crate::cull::tile_marks::{TileDisplay, TileMarks};
use crate::renderer::plan::FramePlan;
use crate::renderer::plan::KeptTiles;

impl Culler {
    /// Records the marking pass's phase before the frame's scatter and pose (`after`
    /// false: every kept display's tiles cleared, the spheres as last drawn marked) or
    /// after them. Returns the dispatches (0 unless the frame keeps on the GPU).
    pub fn encode_marks(&mut self, encoder: &mut wgpu::CommandEncoder, after: bool) -> u32 {
        match &mut self.kind {
            Kind::Gpu {
                marks: Some(marks), ..
            } => match after {
                false => marks.encode_before(encoder),
                true => marks.encode_after(encoder),
            },
            _ => 0,
        }
    }

    /// Display slot `slot`'s `words` words of marked tiles: the buffer, the offset and
    /// the bytes (`None` where the GPU marks none).
    pub fn marked_words(&self, slot: u32, words: u32) -> Option<(&wgpu::Buffer, u64, u64)> {
        match &self.kind {
            Kind::Gpu {
                marks: Some(marks), ..
            } => Some(marks.words_of(slot, words)),
            _ => None,
        }
    }
}

/// Arms `marks` for `plan`'s frame where it keeps with the tiles marked on the GPU:
/// its listed slots, over its kept displays. Returns the bytes written.
pub(super) fn write_marks(queue: &impl Upload, marks: &mut TileMarks, plan: &FramePlan) -> u64 {
    let kept = (plan.displays.iter()).filter(|d| matches!(d.tiles, Some(KeptTiles::Gpu)));
    let displays: Vec<TileDisplay> = kept
        .map(|d| &d.context)
        .map(|c| TileDisplay {
            eyes: c.rig_occlusion(),
            planes: c.planes,
            base: marks.base(c.cull_slot),
        })
        .collect();
    match displays.is_empty() {
        true => 0,
        false => marks.write(queue, &plan.marks, &displays),
    }
}
