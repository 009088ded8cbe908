//! Frame, display and eye contexts (the chapter's Listing 1.3): what is computed once per
//! frame, once per display, and per eye. The WGSL twins live in
//! `wgsl/shared/contexts.wgsl`; encase lays these out to match.

use encase::ShaderType;
use glam::{Mat4, Vec2, Vec3, Vec4};

use crate::error::Result;
use crate::frustum::View;
use crate::rig::Rig;

/// One eye of a display: only what truly differs per eye.
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub struct EyeContext {
    pub view_from_world: Mat4,
    pub world_from_view: Mat4,
    pub clip_from_view: Mat4,
    pub view_from_clip: Mat4,
    pub position: Vec3,
}

impl EyeContext {
    pub fn from_view(v: &View) -> EyeContext {
        let clip_from_view = v.clip_from_view();
        EyeContext {
            view_from_world: v.view_from_world(),
            world_from_view: v.world_from_view.into(),
            clip_from_view,
            view_from_clip: clip_from_view.inverse(),
            position: v.position(),
        }
    }
}

/// One display: its combined frustum, both eyes, and what the cull pass needs.
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub struct DisplayContext {
    pub view_from_world: Mat4,
    pub world_from_view: Mat4,
    pub clip_from_view: Mat4,
    pub view_from_clip: Mat4,
    /// Left then right; a mono display repeats its one eye.
    pub eye: [EyeContext; 2],
    pub position: Vec3,
    pub resolution: Vec2,
    pub planes: [Vec4; 6],
    pub views: u32,
}

impl DisplayContext {
    /// Builds display `index` of `rig`: the display frustum from its eyes, then the
    /// eyes themselves.
    pub fn new(rig: &Rig, index: usize) -> Result<DisplayContext> {
        let display = &rig.displays[index];
        let eyes = rig.eyes(index)?;
        let combined = rig.display_view(index)?;
        let eye_context = |e: usize| EyeContext::from_view(&eyes[e.min(eyes.len() - 1)]);
        Ok(DisplayContext::from_views(
            &combined,
            [eye_context(0), eye_context(1)],
            display.resolution,
            display.views(),
        ))
    }

    pub fn from_views(
        combined: &View,
        eye: [EyeContext; 2],
        resolution: [u32; 2],
        views: u32,
    ) -> DisplayContext {
        let display = EyeContext::from_view(combined);
        DisplayContext {
            view_from_world: display.view_from_world,
            world_from_view: display.world_from_view,
            clip_from_view: display.clip_from_view,
            view_from_clip: display.view_from_clip,
            eye,
            position: display.position,
            resolution: Vec2::new(resolution[0] as f32, resolution[1] as f32),
            planes: combined.frustum().planes,
            views,
        }
    }
}

/// Once per frame: the viewer, not any eye (LOD and animation use this).
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub struct FrameContext {
    pub view_from_world: Mat4,
    pub world_from_view: Mat4,
    pub viewer_position: Vec3,
    pub viewer_direction: Vec3,
    pub time: f32,
}

impl FrameContext {
    pub fn new(rig: &Rig, time: f32) -> FrameContext {
        let orientation = rig.viewer.orientation();
        let world_from_view = Mat4::from_rotation_translation(orientation, rig.viewer.position());
        FrameContext {
            view_from_world: world_from_view.inverse(),
            world_from_view,
            viewer_position: rig.viewer.position(),
            viewer_direction: orientation * -Vec3::Z,
            time,
        }
    }
}

/// Serializes a context into the uniform-buffer bytes the WGSL struct expects.
pub fn uniform_bytes<T: ShaderType + encase::internal::WriteInto>(value: &T) -> Vec<u8> {
    let mut buffer = encase::UniformBuffer::new(Vec::new());
    buffer
        .write(value)
        .expect("writing into a growable Vec cannot fail");
    buffer.into_inner()
}
