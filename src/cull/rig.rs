//! The rig cull: every view of the frame that culls over every instance by its frustum
//! alone or in the early occlusion phase, culled by one set of dispatches (`cull_rig`,
//! `draws_rig`, `compact_rig` and, with blended bins, `blend_rig` in `wgsl/`). An
//! invocation reads each sphere once and chooses its level once for the whole rig, then
//! tests it against every member's planes (skipping a span whose box fails a member's
//! block test); each member keeps its own masks and sums and its own ranges of the rig's
//! shared targets, so its outputs are byte for byte what its own three dispatches write
//! (the cull contract and the CPU twin do not change).
//!
//! One set of dispatches takes up to [`MAX_RIG_VIEWS`] members: a member costs the cull
//! pass its plane tests, a mask per span and a quarter of a workgroup scan, the draws
//! and blend passes a workgroup, the compact pass two reads per position. A larger rig
//! culls in groups of that many members, one set of dispatches each.

use encase::ShaderType;
use glam::{Mat4, Vec2, Vec3, Vec4};

use crate::cull::coarse::CoarseCull;

pub use crate::shaders::MAX_RIG_VIEWS;

/// One member of the rig cull (`RigView` in `wgsl/shared/records.wgsl`): what its
/// context holds for culling and where its outputs start in the shared targets, in
/// elements.
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub struct RigView {
    /// Its frustum's planes ([`crate::contexts::DisplayContext::planes`]).
    pub planes: [Vec4; 6],
    /// The apex its far split is measured from.
    pub position: Vec3,
    /// Its far split: 0 none, 1 keep near, 2 keep far.
    pub split_keep: u32,
    /// Where its blended instances sort from
    /// ([`crate::contexts::DisplayContext::sort_origin`]).
    pub sort_origin: Vec3,
    /// The far split's distance.
    pub split_distance: f32,
    /// The cull contract's V.
    pub instances_per_object: u32,
    /// Its visible list's first word in the shared visible buffer.
    pub visible_at: u32,
    /// Its first draw in the shared draws buffer.
    pub draws_at: u32,
    /// Its counts' first word in the shared counts buffer.
    pub counts_at: u32,
    /// Its display's slot of occlusion visibility words.
    pub cull_slot: u32,
    /// 1 where it culls in the early occlusion phase: it keeps only what its display
    /// drew last frame (`Phase::Early`); else 0.
    pub early: u32,
    /// 1 where its display's hidden area culls too ([`crate::cull::HiddenArea`]).
    pub hidden: u32,
    /// Its planes grown for rounding ([`CoarseCull::around`]): the rig's cull skips
    /// the sphere tests of a span whose box fails it, as the coarse cull skips a block
    /// (a sphere the planes keep makes its box pass).
    pub block: CoarseCull,
}

impl Default for RigView {
    /// An unused record: it keeps nothing.
    fn default() -> RigView {
        RigView {
            planes: [Vec4::ZERO; 6],
            position: Vec3::ZERO,
            split_keep: 0,
            sort_origin: Vec3::ZERO,
            split_distance: 0.0,
            instances_per_object: 0,
            visible_at: 0,
            draws_at: 0,
            counts_at: 0,
            cull_slot: 0,
            early: 0,
            hidden: 0,
            block: CoarseCull::EVERYTHING,
        }
    }
}

/// What a member in the late occlusion phase tests against its display's pyramids
/// (`RigOcclusion` in `wgsl/shared/records.wgsl`): what its display's own late cull
/// reads from its context ([`crate::contexts::DisplayContext::rig_occlusion`]). The
/// pyramids are its display slot's region of the occlusion buffer.
#[derive(Clone, Copy, Debug, Default, PartialEq, ShaderType)]
pub struct RigOcclusion {
    /// Its first two views' `view_from_world`.
    pub view_from_world: [Mat4; 2],
    /// Its first two views' `clip_from_view`.
    pub clip_from_view: [Mat4; 2],
    /// One view's pixels.
    pub resolution: Vec2,
    /// How far projected bounds grow each way, in pixels.
    pub margin_px: f32,
    /// Its display's views: the first two (at most) are tested.
    pub views: u32,
}

/// Where a member's outputs start in the shared targets, in elements (words, draws,
/// words). [`crate::contexts::DisplayContext::rig_view`] makes a member's record.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MemberAt {
    /// Its visible list's first word.
    pub visible: u32,
    /// Its first draw.
    pub draws: u32,
    /// Its counts' first word.
    pub counts: u32,
}

/// One set of rig dispatches' members (`RigCull` in `wgsl/shared/records.wgsl`): the
/// first `members` of `views`, and in the late phase their `occlusion` tests.
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub struct RigCull {
    /// The members, then unused records.
    pub views: [RigView; MAX_RIG_VIEWS],
    /// In the late phase, each member's occlusion test (else unused).
    pub occlusion: [RigOcclusion; MAX_RIG_VIEWS],
    /// How many of `views` are members.
    pub members: u32,
}

impl RigCull {
    /// `views` (at most [`MAX_RIG_VIEWS`]; the rest are dropped) as one set's members.
    pub fn new(views: &[RigView]) -> RigCull {
        let mut all = [RigView::default(); MAX_RIG_VIEWS];
        let members = views.len().min(MAX_RIG_VIEWS);
        all[..members].copy_from_slice(&views[..members]);
        RigCull {
            views: all,
            occlusion: [RigOcclusion::default(); MAX_RIG_VIEWS],
            members: members as u32,
        }
    }

    /// Where member `index`'s record and occlusion test lie in a set's uniform, in
    /// bytes: the arrays' strides are their records' sizes (WGSL rounds a uniform
    /// array's stride up to 16, and both records' sizes are multiples of 16:
    /// `tests/shaders.rs` holds this to naga's layout).
    pub fn offsets(index: usize) -> (u64, u64) {
        let view = RigView::min_size().get();
        let test = RigOcclusion::min_size().get();
        let index = index as u64;
        (index * view, MAX_RIG_VIEWS as u64 * view + index * test)
    }
}

/// Sets of rig dispatches for `members` members: groups of [`MAX_RIG_VIEWS`].
pub fn groups(members: u32) -> u32 {
    members.div_ceil(MAX_RIG_VIEWS as u32)
}

/// The rig cull's members as the frame runs them: `first`, the frustum and early
/// members, culled at the frame level, then `late`, the displays' late occlusion
/// phases, culled once every display's early draw and pyramids are recorded. Each part
/// fills groups of its own (one set of dispatches each): a late member never shares a
/// set with the others, which run before its pyramids exist.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RigSets {
    /// Members culled at the frame level (member indices `0..first`).
    pub first: u32,
    /// Late members (member indices from `first` on).
    pub late: u32,
}

impl RigSets {
    /// Every member.
    pub fn members(self) -> u32 {
        self.first + self.late
    }

    /// The first part's groups (the late part's start there).
    pub fn first_groups(self) -> u32 {
        groups(self.first)
    }

    /// Every group.
    pub fn groups(self) -> u32 {
        groups(self.first) + groups(self.late)
    }

    /// Member `m`'s group and its index within it.
    pub fn place(self, m: u32) -> (u32, u32) {
        let max = MAX_RIG_VIEWS as u32;
        let (before, m) = match m < self.first {
            true => (0, m),
            false => (self.first_groups(), m - self.first),
        };
        (before + m / max, m % max)
    }

    /// How many members group `g` holds.
    pub fn members_in(self, g: u32) -> u32 {
        let max = MAX_RIG_VIEWS as u32;
        let (part, g) = match g < self.first_groups() {
            true => (self.first, g),
            false => (self.late, g - self.first_groups()),
        };
        part.saturating_sub(g * max).min(max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn late_members_start_a_group_of_their_own() {
        let max = MAX_RIG_VIEWS as u32;
        let sets = RigSets {
            first: max + 3,
            late: 5,
        };
        assert_eq!(sets.groups(), 3);
        assert_eq!(sets.place(max + 2), (1, 2));
        assert_eq!(sets.place(max + 3), (2, 0));
        assert_eq!(sets.place(max + 7), (2, 4));
        let held: Vec<u32> = (0..3).map(|g| sets.members_in(g)).collect();
        assert_eq!(held, [max, 3, 5]);
        let late_only = RigSets { first: 0, late: 2 };
        assert_eq!((late_only.groups(), late_only.place(1)), (1, (0, 1)));
    }
}
