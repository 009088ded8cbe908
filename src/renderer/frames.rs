//! Two frames per submission: the multiview talk's "dt multiview", a view at another
//! time as well as another eye. Each display draws its eyes at the frame's time `t`
//! and at `t + dt` as one set of views (left and right now, then left and right next)
//! side by side in one target: one cull keeps what any of them may see, and one
//! multi-draw draws every visible object once per view, `instance_index % views` the
//! view. Each view's context says how far ahead its frame lies
//! ([`crate::contexts::EyeContext::time_ahead`]), so the draw animates each view's
//! instances at its own frame's time.
//!
//! What cannot join, and why, is [`check`]'s to say.

use crate::contexts::DisplayContext;
use crate::error::{Error, Result};
use crate::renderer::options::{OcclusionMode, RendererOptions, StereoMode};
use crate::rig::{Display, ResolvedRig, Rig, ViewLayout, VisibilityMask};
use crate::scene::Scene;

/// Where display `d`'s views lie in its target for `frames` frames per submission:
/// one frame's layout ([`Display::layout_in`]), or the second frame's views after the
/// first's, at the same sizes.
pub fn layout(d: &Display, layered: bool, frames: u32) -> ViewLayout {
    let one = d.layout_in(layered);
    if frames == 1 {
        return one;
    }
    let sizes: Vec<(u32, u32)> = (one.viewports().iter())
        .map(|&[_, _, w, h]| (w, h))
        .collect();
    ViewLayout::side_by_side(&sizes.repeat(frames as usize))
}

/// A display of `views` views' visibility mask as its views are masked: its outer
/// views' triangles (a foveated display's insets lie inside them), once per frame of
/// a submission (each frame's eyes are masked alike).
pub fn masked(mask: &VisibilityMask, views: u32, frames: u32) -> VisibilityMask {
    let outer = mask.views.len().min(views.min(2) as usize);
    VisibilityMask {
        views: (0..frames)
            .flat_map(|_| mask.views[..outer].iter().cloned())
            .collect(),
    }
}

/// The two frames' views as one resolved rig ([`ResolvedRig::followed_by`]).
pub(super) fn pair(now: &ResolvedRig, next: &ResolvedRig) -> Result<ResolvedRig> {
    now.followed_by(next).ok_or_else(|| {
        Error::rig(
            "frames",
            "no one display frustum holds a display's eyes at both frames' poses (they turn 180 degrees or more apart)",
        )
    })
}

/// Marks the second frame's views of display `d` (those past its own views) as
/// `ahead` seconds after the frame context's time; with one frame per submission,
/// every view's context keeps 0.
pub(super) fn time_views(context: &mut DisplayContext, d: &Display, ahead: f32) {
    let own = d.views() as usize;
    if context.views as usize > own {
        for eye in &mut context.eye[own..] {
            eye.time_ahead = ahead;
        }
    }
}

/// What two frames per submission cannot draw: it takes the `instanced` mode's one
/// multi-draw, content posed on the CPU for each frame (or by the draw, from the time),
/// and none of the features whose state belongs to a single frame.
pub(super) fn check(scene: &Scene, rig: &Rig, options: &RendererOptions) -> Result<()> {
    match options.frames_per_submit {
        1 => return Ok(()),
        2 => {}
        n => {
            return Err(Error::Unsupported(format!(
                "{n} frames per submission: 1 or 2"
            )));
        }
    }
    if !(options.dt.is_finite() && options.dt > 0.0) {
        return Err(Error::Unsupported(format!(
            "dt {} s between a submission's frames: it must be a positive number",
            options.dt
        )));
    }
    let why = unjoined_option(options).or_else(|| unjoined_content(scene, rig, options));
    match why {
        Some(why) => Err(Error::Unsupported(format!(
            "two frames per submission: {why}"
        ))),
        None => Ok(()),
    }
}

/// The options that keep state of a single frame.
fn unjoined_option(options: &RendererOptions) -> Option<&'static str> {
    Some(match options {
        o if o.mode != StereoMode::Instanced => {
            "the instanced mode draws both frames' views in one multi-draw; the other modes, kept to compare submission costs against, draw each frame in passes of its own: submit their frames one at a time"
        }
        o if o.occlusion == OcclusionMode::On => {
            "occlusion's early phase draws what the previous frame saw, and the second frame's previous is the first, drawn in the same pass: use --occlusion off or auto"
        }
        o if o.far_layer => {
            "the far layer is one shared image per frame, composited before the display's draw: the second frame would need a layer of its own"
        }
        o if o.motion_vectors => {
            "motion vectors measure each frame from the one before, and the second frame's is in the same target: not built yet"
        }
        _ => return None,
    })
}

/// The rig and scene content whose second frame cannot be drawn so: a foveated
/// display's views, and posed content ([`super::second_frame`]) where the lights or the
/// shadow are one per submission.
fn unjoined_content(scene: &Scene, rig: &Rig, options: &RendererOptions) -> Option<&'static str> {
    if rig.displays.iter().any(|d| d.views() > 2) {
        return Some(
            "a foveated display's four views would make eight, and a display context holds four",
        );
    }
    let posed = !scene.posing.clips.is_empty() || !scene.skins.is_empty();
    if !posed && scene.morphs.is_empty() {
        return None;
    }
    if !scene.posing.lights.is_empty() {
        return Some(
            "lights on animated nodes light both frames of a submission as one set: posed once per submission",
        );
    }
    options.shadows.then_some(
        "the shadow map is drawn once per submission, at the second frame's pose of node animations, skins and morph targets: use --shadows off",
    )
}
