//! What a path (indirect or classic) is built from.

use super::frame::FramePlan;
use super::options::RendererOptions;
use crate::records::CullLayout;
use crate::scene::Scene;

/// The scene, its cull layout, the frame plan of the rig as made, and the options.
pub(super) struct PathInputs<'a> {
    pub(super) scene: &'a Scene,
    /// The scene's instances at their places of the cull order.
    pub(super) layout: CullLayout,
    /// The rig as made: its displays, coarse cull and far layer sizes.
    pub(super) plan: &'a FramePlan,
    /// The frame context's uniform, bound by every pass.
    pub(super) frame: &'a wgpu::Buffer,
    pub(super) options: &'a RendererOptions,
    /// Instance slots (and places) of room.
    pub(super) slots: u32,
}
