//! The display level: everything recorded once per display, for both eyes. The path
//! chosen once in `Renderer::new` ([`indirect`]: the GPU-driven `instanced` and
//! `multiview`, one cull and one multi-draw per display; [`classic`]: the per-instance
//! modes, the only ones with passes per eye), the far layer (`far_layer.rs`) and
//! occlusion's passes (`occlusion/`), and what a path is built from.

pub(in crate::renderer) mod classic;
mod diagnostics;
pub(in crate::renderer) mod far_layer;
pub(in crate::renderer) mod indirect;
pub(in crate::renderer) mod occlusion;

use crate::draw::{DrawScene, Drawer, Drawing};
use crate::records::{CullLayout, InstanceRecord};
use crate::renderer::culler::Culler;
use crate::renderer::options::RendererOptions;
use crate::renderer::plan::FramePlan;
use crate::scene::Scene;

/// The scene, its cull layout, the frame plan of the rig as made, and the options.
pub(in crate::renderer) struct PathInputs<'a> {
    pub(in crate::renderer) scene: &'a Scene,
    /// The instance records the draw starts from: the scene's, or a live scene's (with
    /// its slots' generations) when a sync reallocates.
    pub(in crate::renderer) records: &'a [InstanceRecord],
    /// The scene's instances at their places of the cull order.
    pub(in crate::renderer) layout: CullLayout,
    /// The rig as made: its displays, coarse cull and far layer sizes.
    pub(in crate::renderer) plan: &'a FramePlan,
    /// The frame context's uniform, bound by every pass.
    pub(in crate::renderer) frame: &'a wgpu::Buffer,
    pub(in crate::renderer) options: &'a RendererOptions,
    /// Instance slots (and places) of room.
    pub(in crate::renderer) slots: u32,
    /// Group 2 of the draw pipelines: the frame's shadow map.
    pub(in crate::renderer) shadow_group: &'a wgpu::BindGroup,
}

/// What every path has: the one culler all its views cull through, the draw pipelines,
/// and the scene as the GPU draws it.
pub(in crate::renderer) struct PathCore {
    pub(in crate::renderer) culler: Culler,
    pub(in crate::renderer) drawer: Drawer,
    pub(in crate::renderer) draw_scene: DrawScene,
}

impl PathCore {
    /// The pipelines and the scene, as a pass draws them.
    pub(in crate::renderer) fn drawing(&self) -> Drawing<'_> {
        Drawing {
            drawer: &self.drawer,
            scene: &self.draw_scene,
        }
    }
}
