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
use glam::{Vec3, Vec4};

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
/// first `members` of `views`.
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub struct RigCull {
    /// The members, then unused records.
    pub views: [RigView; MAX_RIG_VIEWS],
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
            members: members as u32,
        }
    }
}

/// Sets of rig dispatches for `members` members: groups of [`MAX_RIG_VIEWS`].
pub fn groups(members: u32) -> u32 {
    members.div_ceil(MAX_RIG_VIEWS as u32)
}
