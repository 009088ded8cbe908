//! Distant geometry drawn once per display (the chapter's `DoRenderDisplay`: what "won't
//! benefit from stereo disparity and therefore can be rasterized once and shared between
//! both eye projections").
//!
//! Beyond some distance the two eyes' images of a point differ by less than a threshold
//! (half a pixel by default). Instances entirely beyond it are culled and drawn once,
//! from the display's apex, into a far layer (color and depth) whose window holds both
//! eyes' windows; each eye then takes the far layer through its exact mapping at infinity
//! (a direction is a direction from any eye: an offset between parallel windows, a
//! rotation between canted ones) before its near geometry is drawn, with the far points'
//! own depth from that eye so that far objects still hide the far ends of near objects.

use glam::{DVec3, Vec2};

use crate::contexts::{DisplayContext, EyeContext};
use crate::cull::Split;
use crate::frustum::View;
use crate::rig::{ResolvedDisplay, ResolvedRig, Rig};

/// Pixels two eyes' images of a far instance may differ by, unless the options say.
pub const FAR_THRESHOLD_PX: f32 = 0.5;

/// Far layer texels per eye pixel along each axis: re-projecting a raster moves edges
/// by up to half its texel, so the far layer is drawn finer than the eyes (and sampled
/// with filtering) to keep that well under the threshold.
const SUPERSAMPLE: f64 = 2.0;

/// The far layer never grows past this many texels a side.
const MAX_LAYER_SIDE: u32 = 4096;

/// One stereo display's far layer for a frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FarPlan {
    /// Instances entirely beyond this distance (meters) from the display's apex are far.
    pub distance: f32,
    /// The far layer's view: the display frustum, from its apex.
    pub view: View,
    /// Texels of the far layer: `SUPERSAMPLE` per pixel of the sharpest eye, across.
    pub size: (u32, u32),
    /// Pixels the eyes' images of a far point may move when taken from the far layer:
    /// the threshold the plan was made for.
    pub threshold_px: f32,
    /// The most eye pixels per radian of any eye (`f (1 + t^2)` in [`FarPlan::new`]).
    pub eye_px_per_radian: f32,
}

impl FarPlan {
    /// The plan for `display` at `resolution` pixels per eye and `threshold` pixels.
    ///
    /// A point at distance `z` from the apex is seen from an eye `d` meters away in a
    /// direction at most `d / (z - d)` radians off the apex's; a flat window of `f` pixels
    /// per unit of tangent maps that to at most `f (1 + t^2)` pixels per radian, `t` the
    /// tangent of its farthest corner. So the eyes' pixels err by at most `threshold` for
    /// `z >= d + f (1 + t^2) d / threshold` (and differ from each other by at most twice
    /// that, the eyes being on either side).
    pub fn new(display: &ResolvedDisplay, resolution: [u32; 2], threshold: f32) -> FarPlan {
        let view = display.combined;
        let apex = view.world_from_view.translation;
        let (mut reach, mut f_x, mut f_y, mut spread) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        for eye in &display.eyes {
            let [l, r, u, d] = eye.fov.tangents();
            let across = (
                resolution[0] as f64 / (l + r),
                resolution[1] as f64 / (u + d),
            );
            f_x = f_x.max(across.0);
            f_y = f_y.max(across.1);
            spread =
                spread.max(across.0.max(across.1) * (1.0 + l.max(r).powi(2) + u.max(d).powi(2)));
            reach = reach.max(eye.world_from_view.translation.distance(apex));
        }
        let distance = reach + spread * reach / threshold.max(1e-6) as f64;
        let [l, r, u, d] = view.fov.tangents();
        let side = |f: f64, t: f64| ((SUPERSAMPLE * f * t).ceil() as u32).clamp(1, MAX_LAYER_SIDE);
        FarPlan {
            distance: distance as f32,
            view,
            size: (side(f_x, l + r), side(f_y, u + d)),
            threshold_px: threshold,
            eye_px_per_radian: spread as f32,
        }
    }

    /// Eye pixels from where an eye sees a far point to the farthest pixel whose
    /// composite reads it: the threshold, plus a far texel (the reach of the composite's
    /// filtered read, and of its depth texel) in eye pixels. A far texel spans at most
    /// `1 / f` radians, `f` its fewer texels per unit of tangent (at least that many
    /// per radian), which an eye sees across at most `eye_px_per_radian / f` pixels.
    pub fn composite_reach_px(&self) -> f32 {
        let [l, r, u, d] = self.view.fov.tangents();
        let texels = (self.size.0 as f64 / (l + r)).min(self.size.1 as f64 / (u + d));
        self.threshold_px + (self.eye_px_per_radian as f64 / texels) as f32
    }

    /// The context of the far layer's cull with occlusion: its frustum, split and one
    /// instance per object, with `display`'s eyes and pyramids to test against (see
    /// [`crate::occlusion::Phase::Tested`]), the bounds grown by the composite's reach
    /// so that a far instance whose removal could change a composited pixel is kept.
    pub fn tested_context(&self, display: &DisplayContext) -> DisplayContext {
        let far = self.context(display.cull_slot);
        DisplayContext {
            planes: far.planes,
            position: far.position,
            instances_per_object: 1,
            split_keep: far.split_keep,
            split_distance: far.split_distance,
            occlusion_margin_px: display.occlusion_margin_px + self.composite_reach_px(),
            // Its composite may carry a far point across the mask's edge.
            hidden: 0,
            ..*display
        }
    }

    /// The split of the display's cull (near) or of the far layer's (far).
    pub fn split(&self, keep_far: bool) -> Split {
        Split {
            origin: self.view.position(),
            distance: self.distance,
            keep_far,
        }
    }

    /// The far layer's display context: its one view in every eye slot, culling the far
    /// instances of the display frustum, each drawn once, over the coarse cull's
    /// `cull_slot` (its display's).
    pub fn context(&self, cull_slot: u32) -> DisplayContext {
        let eye =
            EyeContext::from_view(&self.view).placed([0, 0, self.size.0, self.size.1], self.size);
        DisplayContext {
            view_from_world: eye.view_from_world,
            world_from_view: eye.world_from_view,
            clip_from_view: eye.clip_from_view,
            view_from_clip: eye.view_from_clip,
            eye: [eye; crate::contexts::MAX_VIEWS],
            position: eye.position,
            resolution: Vec2::new(self.size.0 as f32, self.size.1 as f32),
            planes: self.view.frustum().planes,
            instances_per_object: 1,
            first_eye: 0,
            split_keep: 2,
            split_distance: self.distance,
            cull_slot,
            views: 1,
            occlusion_margin_px: crate::contexts::BOUNDS_GROWTH_PX,
            hidden: 0,
        }
    }

    /// Where eye pixel `(x, y)` (of `size` pixels, from the top left) takes the far
    /// layer: the far layer's normalized coordinates (0..1 from the top left) of the
    /// direction through that pixel, `None` outside it. The CPU twin of
    /// `far_uv` in `wgsl/far_composite.wgsl`.
    pub fn far_uv(&self, eye: &View, (x, y): (f64, f64), size: (u32, u32)) -> Option<(f64, f64)> {
        let [l, r, u, d] = eye.fov.tangents();
        let tx = -l + (l + r) * x / size.0 as f64;
        let ty = u - (u + d) * y / size.1 as f64;
        let direction = eye.world_from_view.matrix3 * DVec3::new(tx, ty, -1.0);
        let local = self.view.world_from_view.matrix3.transpose() * direction;
        if local.z >= 0.0 {
            return None;
        }
        let [fl, fr, fu, fd] = self.view.fov.tangents();
        let (fx, fy) = (local.x / -local.z, local.y / -local.z);
        let uv = ((fx + fl) / (fl + fr), (fu - fy) / (fu + fd));
        ((0.0..=1.0).contains(&uv.0) && (0.0..=1.0).contains(&uv.1)).then_some(uv)
    }
}

/// Each display's far plan for a frame: two-view stereo displays only (a mono display
/// has no two images to share; a foveated one's views differ in density, so one far
/// image would be too coarse for the insets or wasted on the outer views).
pub fn plans(rig: &Rig, resolved: &ResolvedRig, threshold: f32) -> Vec<Option<FarPlan>> {
    rig.displays
        .iter()
        .zip(&resolved.displays)
        .map(|(d, r)| (d.views() == 2).then(|| FarPlan::new(r, d.resolution, threshold)))
        .collect()
}
