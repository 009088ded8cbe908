//! Two frames per submission: the multiview talk's "dt multiview", a view at another
//! time as well as another eye. Each display draws its eyes at the frame's time `t`
//! and at `t + dt` as one set of views (left and right now, then left and right next)
//! side by side in one target: one cull keeps what any of them may see, and one
//! multi-draw draws every visible object once per view, `instance_index % views` the
//! view. Each view's context says how far ahead its frame lies
//! ([`crate::contexts::EyeContext::time_ahead`]), so the draw animates each view's
//! instances at its own frame's time.
//!
//! What cannot join, and why, is `checks.rs`'s to say (`check_frames`).

use crate::contexts::DisplayContext;
use crate::error::{Error, Result};
use crate::rig::{Display, ResolvedRig, ViewLayout, VisibilityMask};

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
