//! Per-display frustum culling into draw lists, on the CPU ([`cpu`]) or the GPU
//! ([`gpu`]). Both honour one contract, byte for byte (the README's cull contract):
//!
//! - one draw per (level of detail, mesh) with at least one visible instance, grouped
//!   by the mesh's material bin ([`crate::bins`]): each bin owns a fixed range of
//!   `draws` (its meshes times the levels, bins in order), its draws packed at the
//!   front of that range, levels finest first, then ascending mesh id, the rest of the
//!   range zero; `draw_count` is their number, [`CullOutput::bins`] each bin's;
//! - within a draw, visible instances in place order (ids ascending for a scene laid
//!   out afresh);
//! - `instance_count = V * visible_in_group`, `first_instance = V * offset`, where V is
//!   [`CullJob::instances_per_object`].

pub mod coarse;
pub mod cpu;
pub mod gpu;
pub mod gpu_buffers;
pub mod hidden;
pub mod rig;
pub mod targets;
pub mod tiles;

pub use coarse::CoarseCull;
pub use hidden::HiddenArea;

use glam::{Vec3, Vec4};

use crate::records::DrawArgs;

/// One cull: a display's frustum planes and how many instances each visible object
/// becomes in its draws.
#[derive(Clone, Debug, PartialEq)]
pub struct CullJob {
    /// Left, right, bottom, top, near, far; inside when `dot(n, p) + d >= 0`.
    pub planes: [Vec4; 6],
    /// 2 for instanced stereo (counts doubled), else 1.
    pub instances_per_object: u32,
    /// With a far layer: which side of the display's far distance this cull keeps.
    pub split: Option<Split>,
    /// With the visibility mask: the lens's hidden area, which drops what every masked
    /// view hides ([`HiddenArea::hides`]).
    pub hidden: Option<std::sync::Arc<HiddenArea>>,
    /// Keeping unchanged pixels: the display's changed tiles, which a kept sphere must
    /// touch ([`crate::cull::tiles::TileMask::touches`]).
    pub tiles: Option<std::sync::Arc<crate::cull::tiles::TileMask>>,
    /// Where blended instances are sorted from, back to front: the midpoint of the
    /// display's two eyes (its one view's position for mono, far and light views;
    /// [`crate::contexts::DisplayContext::sort_origin`]).
    pub sort_origin: Vec3,
}

impl CullJob {
    /// Whether the job keeps sphere `s`: its frustum, its split, then its hidden area,
    /// as the GPU's `cull_entry` tests them.
    pub fn keeps(&self, s: Vec4) -> bool {
        crate::frustum::sphere_in_planes(&self.planes, s)
            && self.split.is_none_or(|split| split.keeps(s))
            && self.hidden.as_ref().is_none_or(|h| !h.hides(s))
            && self.tiles.as_ref().is_none_or(|t| t.touches(s))
    }
}

/// A display's far split ([`crate::far_layer`]): instances entirely beyond `distance`
/// from `origin` (the display's apex) are far, the rest near.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Split {
    /// The display's apex.
    pub origin: Vec3,
    /// The far distance in meters.
    pub distance: f32,
    /// Keep the far instances (the far layer's cull), else the near ones.
    pub keep_far: bool,
}

impl Split {
    /// Whether the cull keeps sphere `s`. The CPU twin of `in_split` in
    /// `wgsl/shared/cull_math.wgsl`: same operations, same order, no square root.
    #[inline]
    pub fn keeps(&self, s: Vec4) -> bool {
        let (dx, dy, dz) = (
            s.x - self.origin.x,
            s.y - self.origin.y,
            s.z - self.origin.z,
        );
        let d2 = dx * dx + dy * dy + dz * dz;
        let reach = self.distance + s.w;
        (d2 >= reach * reach) == self.keep_far
    }
}

/// One display's cull result, as the draw pass consumes it.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct CullOutput {
    /// Visible instance ids (exactly the visible ones; the GPU buffer's capacity is
    /// the instance count and its tail past these is unspecified).
    pub visible: Vec<u32>,
    /// One entry per (level, mesh), meshes times levels in all: the packed draws, then
    /// zeros.
    pub draws: Vec<DrawArgs>,
    /// How many of `draws` are packed draws, in all bins.
    pub draw_count: u32,
    /// Per material bin, in order: where its range of `draws` starts and how many
    /// packed draws it holds.
    pub bins: Vec<BinDraws>,
}

/// One material bin's draws in a [`CullOutput`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BinDraws {
    /// Its first entry of `draws`.
    pub first: u32,
    /// Its packed draws, from `first` on.
    pub count: u32,
}

impl CullOutput {
    /// The packed draws, bin by bin.
    pub fn packed_draws(&self) -> impl Iterator<Item = &DrawArgs> {
        (self.bins.iter()).flat_map(|b| &self.draws[b.first as usize..(b.first + b.count) as usize])
    }

    /// The mesh each packed draw draws, recovered from its first visible instance.
    pub fn draw_meshes(
        &self,
        instances_per_object: u32,
        instance_mesh: impl Fn(u32) -> u32,
    ) -> Vec<u32> {
        self.packed_draws()
            .map(|d| {
                let slot = d.first_instance / instances_per_object;
                instance_mesh(self.visible[slot as usize])
            })
            .collect()
    }
}

/// The frame's level-of-detail choice (what the frame context carries to the GPU): the
/// viewer's position, the scale, and how many levels are culled into (1: LOD off).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameLod {
    /// The viewer's position: distances are measured from it, not from an eye.
    pub viewer: Vec3,
    /// (pixels per radian / pixels of error allowed)^2 on the sharpest display.
    pub lod_scale: f32,
    /// Levels culled into: 1 with LOD off.
    pub levels: u32,
}

impl FrameLod {
    /// One level: every instance at its mesh's own triangles.
    pub const OFF: FrameLod = FrameLod {
        viewer: Vec3::ZERO,
        lod_scale: 0.0,
        levels: 1,
    };
}

/// What the frame level decides for every display's cull: the levels of detail, and
/// the coarse cull's test when it runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameCull {
    /// The levels of detail every cull of the frame picks.
    pub lod: FrameLod,
    /// The coarse cull's frame test, when it runs.
    pub coarse: Option<CoarseCull>,
}
