//! Motion vectors for a compositor's reprojection (OpenXR's space warp): each pixel's
//! screen motion since the previous frame, current minus previous, in pixels of the
//! display's target, written by the draw into a second color target
//! ([`MOTION_FORMAT`]) of the same pass (`wgsl/draw_motion.wgsl`,
//! `wgsl/shared/motion.wgsl`).
//!
//! Every source of motion reaches the vertex stage: the eye's previous
//! `clip_from_world` ([`crate::contexts::EyeContext::previous_clip_from_world`]), the
//! instance's previous record (kept on the GPU: the records as the previous frame
//! drew them, copied before this frame's scatter and posing, so that moved, GPU-posed
//! and animated instances all have one), its animation at the previous time
//! ([`crate::contexts::FrameContext::previous_time`]) and, for skinned and morphed
//! meshes, the previous frame's vertices. The vertex passes its previous clip
//! position; the fragment divides it (the interpolation is perspective-correct, so the
//! previous position of the surface point under each pixel is exact up to rounding).
//!
//! What each pixel holds:
//! - a surface: its motion, as above;
//! - an instance inserted this frame (a slot whose previous record has another
//!   generation): no previous transform of its own, so its current one: the head's
//!   motion and its animation's alone, as if it had stood there;
//! - a point that was behind the previous eye (previous clip w <= 0), blended surfaces
//!   (they write no depth either), the lens's hidden area and the background: zero.
//!
//! With MSAA the target is multisampled and resolved by the hardware's average of each
//! pixel's samples (a pixel on an edge gets the mean of its surfaces' motions).
//!
//! Here: the format, what a frame's motion is measured from ([`PreviousFrame`]), and
//! the CPU twin of the fragment's arithmetic ([`motion_at`]).

use glam::{DMat4, DVec2, DVec3, DVec4, Mat4, Vec4};

use crate::contexts::{DisplayContext, EyeContext, FrameContext, MAX_VIEWS};

/// The motion target's format: two half floats, x then y, in pixels (11 significant
/// bits: a 100-pixel motion to about 0.05 pixels).
pub const MOTION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg16Float;

/// What a frame's motion is measured from: the previous frame's time and every view's
/// `clip_from_world` then, per display in the rig's order.
#[derive(Clone, Debug, PartialEq)]
pub struct PreviousFrame {
    /// The previous frame's time.
    pub time: f32,
    /// Per display, each view's `clip_from_world` ([`EyeContext`]'s slots).
    pub views: Vec<[Mat4; MAX_VIEWS]>,
}

impl PreviousFrame {
    /// The frame of these contexts, as the next frame's previous
    /// ([`crate::renderer::FramePlan::as_previous`]).
    pub fn of<'a>(
        frame: &FrameContext,
        displays: impl Iterator<Item = &'a DisplayContext>,
    ) -> PreviousFrame {
        PreviousFrame {
            time: frame.time,
            views: displays.map(|d| d.eye.map(|e| e.clip_from_world)).collect(),
        }
    }

    /// These contexts measured from this frame: the previous time and matrices set (a
    /// display this frame lacks keeps its own: no motion of the head).
    pub fn carry_into<'a>(
        &self,
        frame: &mut FrameContext,
        displays: impl Iterator<Item = &'a mut DisplayContext>,
    ) {
        frame.previous_time = self.time;
        for (display, views) in displays.zip(&self.views) {
            for (eye, &previous) in display.eye.iter_mut().zip(views) {
                eye.previous_clip_from_world = previous;
            }
        }
    }
}

/// Where world point `world` lands through `clip_from_world` in the view drawn into
/// `viewport` (x, y, width, height pixels of the target): pixel coordinates, rows from
/// the top; `None` behind the eye (clip w <= 0).
pub fn pixel_of(clip_from_world: Mat4, viewport: Vec4, world: DVec3) -> Option<DVec2> {
    let clip = dmat(clip_from_world) * world.extend(1.0);
    if clip.w <= 0.0 {
        return None;
    }
    let v = viewport.as_dvec4();
    let ndc = clip.truncate().truncate() / clip.w;
    Some(DVec2::new(
        v.x + (ndc.x * 0.5 + 0.5) * v.z,
        v.y + (0.5 - ndc.y * 0.5) * v.w,
    ))
}

/// The world point under pixel center `pixel` (target coordinates) of view `eye` at
/// depth `depth` (its depth buffer's value): what the fragment stage rebuilds.
pub fn world_at(eye: &EyeContext, pixel: DVec2, depth: f32) -> DVec3 {
    let v = eye.viewport.as_dvec4();
    let at = pixel - DVec2::new(v.x, v.y);
    let ndc = DVec4::new(
        at.x / v.z * 2.0 - 1.0,
        1.0 - at.y / v.w * 2.0,
        f64::from(depth),
        1.0,
    );
    let world = dmat(eye.world_from_clip) * ndc;
    world.truncate() / world.w
}

/// The motion the draw writes at pixel center `pixel` of view `eye` whose depth is
/// `depth`, for a surface whose point `p` stood at `previous(p)` in the previous frame
/// (the identity for a static surface): current minus previous pixel, or zero where
/// the previous point was behind the eye.
pub fn motion_at(
    eye: &EyeContext,
    (pixel, depth): (DVec2, f32),
    previous: impl Fn(DVec3) -> DVec3,
) -> DVec2 {
    let was = previous(world_at(eye, pixel, depth));
    match pixel_of(eye.previous_clip_from_world, eye.viewport, was) {
        Some(p) => pixel - p,
        None => DVec2::ZERO,
    }
}

fn dmat(m: Mat4) -> DMat4 {
    DMat4::from_cols_array(&m.to_cols_array().map(f64::from))
}
