//! Views as an XR runtime hands them over (OpenXR's `XrView`): per view a pose in
//! tracking space and four field-of-view angles, given fresh every frame, instead of a
//! head-fixed panel derived from the viewer's pose.

use glam::{DQuat, DVec3};
use serde::{Deserialize, Serialize};

use super::{Mount, Rig};
use crate::error::Result;
use crate::frustum::{Fov, View};

/// One view: where its eye is, which way it looks, and the angles of its window.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PosedView {
    /// Meters, in tracking space.
    pub position: [f32; 3],
    /// x, y, z, w, as `XrQuaternionf` orders them; normalized on use, so it must not be
    /// zero. At identity the view looks down -Z with +Y up, as the runtime's do.
    pub orientation: [f32; 4],
    /// The window's angles.
    pub fov: FovAngles,
}

/// `XrFovf`: radians from the view axis to each edge of the window, left and down
/// negative when the window spans the axis.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FovAngles {
    /// To the left edge; negative left of the axis.
    pub angle_left: f32,
    /// To the right edge.
    pub angle_right: f32,
    /// To the top edge.
    pub angle_up: f32,
    /// To the bottom edge; negative below the axis.
    pub angle_down: f32,
}

impl FovAngles {
    /// The window as tangents: OpenXR's projection divides by `tan(right) - tan(left)`
    /// and `tan(up) - tan(down)`, which is ours with `left = -tan(angle_left)` and
    /// `down = -tan(angle_down)`.
    pub fn tangents(&self) -> Fov {
        let tan = |a: f32| (a as f64).tan() as f32;
        Fov {
            left: -tan(self.angle_left),
            right: tan(self.angle_right),
            up: tan(self.angle_up),
            down: -tan(self.angle_down),
        }
    }

    fn check(&self) -> Result<(), String> {
        let angles = [
            self.angle_left,
            self.angle_right,
            self.angle_up,
            self.angle_down,
        ];
        let half_turn = std::f32::consts::FRAC_PI_2;
        if !angles.iter().all(|a| a.is_finite() && a.abs() < half_turn) {
            return Err(format!(
                "fov: angles must be finite and under 90 degrees from the axis, got {self:?}"
            ));
        }
        if self.angle_left >= self.angle_right || self.angle_down >= self.angle_up {
            return Err(format!(
                "fov: needs angle_left < angle_right and angle_down < angle_up, got {self:?}"
            ));
        }
        Ok(())
    }
}

impl PosedView {
    /// A resolved eye as a runtime hands it over: its pose, its window as angles.
    pub fn of(eye: &View) -> PosedView {
        let angle = |t: f32| (t as f64).atan() as f32;
        PosedView {
            position: eye.world_from_view.translation.as_vec3().to_array(),
            orientation: DQuat::from_mat3(&eye.world_from_view.matrix3)
                .as_quat()
                .to_array(),
            fov: FovAngles {
                angle_left: -angle(eye.fov.left),
                angle_right: angle(eye.fov.right),
                angle_up: angle(eye.fov.up),
                angle_down: -angle(eye.fov.down),
            },
        }
    }

    /// The eye's position in f64.
    pub fn position(&self) -> DVec3 {
        DVec3::from(self.position.map(f64::from))
    }

    /// The orientation, normalized (checked non-zero by [`check_views`]).
    pub fn rotation(&self) -> DQuat {
        let [x, y, z, w] = self.orientation.map(f64::from);
        DQuat::from_xyzw(x, y, z, w).normalize()
    }
}

impl Rig {
    /// The rig with every display's eyes at the current pose handed over as a runtime
    /// hands them (`Mount::Views`): the same views, to test or profile the posed path
    /// against the rig that describes them.
    pub fn as_posed(&self) -> Result<Rig> {
        let resolved = self.resolve()?;
        let mut posed = self.clone();
        for (display, r) in posed.displays.iter_mut().zip(&resolved.displays) {
            display.mount = Mount::Views(r.eyes.iter().map(PosedView::of).collect());
        }
        Ok(posed)
    }
}

/// What serde cannot check: as many views as the display has (1 mono, 2 stereo, 4
/// foveated, in the runtime's order: left, right, then the left and right insets),
/// finite poses, quaternions with a length, windows with area, insets inside their
/// eye's outer view.
pub(super) fn check_views(views: &[PosedView], expected: u32) -> Result<(), String> {
    if views.len() != expected as usize {
        return Err(format!(
            "views: {} given, the display has {expected} (1 mono, 2 stereo: left, then right; 4 foveated: left, right, left inset, right inset)",
            views.len()
        ));
    }
    check_each(views)?;
    for (i, (inset, outer)) in views.iter().skip(2).zip(views).enumerate() {
        let inside = super::foveation::inset_inside(
            inset.fov.tangents(),
            inset.rotation(),
            outer.fov.tangents(),
            outer.rotation(),
        );
        if !inside {
            return Err(format!(
                "views[{}]: the inset is not inside its eye's outer view (views[{i}])",
                i + 2
            ));
        }
    }
    Ok(())
}

fn check_each(views: &[PosedView]) -> Result<(), String> {
    views.iter().enumerate().try_for_each(|(i, v)| {
        let mut numbers = v.position.iter().chain(&v.orientation);
        if !numbers.all(|x| x.is_finite()) {
            return Err(format!(
                "views[{i}]: position and orientation must be finite"
            ));
        }
        let [x, y, z, w] = v.orientation.map(f64::from);
        if x * x + y * y + z * z + w * w < 1e-12 {
            return Err(format!(
                "views[{i}]: the orientation quaternion has zero length"
            ));
        }
        v.fov.check().map_err(|m| format!("views[{i}].{m}"))
    })
}

/// The display frustum's orientation for posed views: halfway between the left and
/// right eye's outer views (the eyes of a stereo pair may be canted apart).
pub(super) fn middle_rotation(views: &[PosedView]) -> DQuat {
    match views {
        [left, right, ..] => left.rotation().slerp(right.rotation(), 0.5),
        [only] => only.rotation(),
        [] => DQuat::IDENTITY,
    }
}

/// The display frustum's apex for posed views: the mean of the eyes' outer views.
pub(super) fn middle_position(views: &[PosedView]) -> DVec3 {
    let eyes = &views[..views.len().min(2)];
    let sum: DVec3 = eyes.iter().map(PosedView::position).sum();
    sum / eyes.len().max(1) as f64
}
