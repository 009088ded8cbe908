//! Foveated stereo (OpenXR's `PRIMARY_STEREO_WITH_FOVEATED_INSET`, Varjo's quad views):
//! four views per display, an outer pair over each eye's whole window at a peripheral
//! density and an inner pair (an inset per eye, inside its outer view) at the focus
//! density, placed side by side in one target so that one indirect pass draws all four.
//!
//! Views 0 and 1 are the outer left and right, 2 and 3 the insets of the left and right
//! eye, as the runtime orders them. An inset is a rectangle of its eye's window (in
//! tangents, so its pixels have the focus density everywhere), centered on the eye's
//! gaze, or on the eye's axis without one, and moved back inside the window where the
//! gaze would push it out.

use glam::{DQuat, DVec3};
use serde::{Deserialize, Serialize};

use crate::frustum::Fov;

/// A display's foveation: the densities and the inset's share of the field of view.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Foveation {
    /// Pixels of the outer views per pixel of the display's resolution, along each axis.
    #[serde(default = "default_peripheral")]
    pub peripheral_density: f32,
    /// Pixels of the insets per pixel of the display's resolution over the same window.
    #[serde(default = "default_focus")]
    pub focus_density: f32,
    /// The inset's width and height as fractions of its eye's window (in tangents), when
    /// the display follows a gaze.
    #[serde(default = "default_inset_gaze")]
    pub inset_with_gaze: [f32; 2],
    /// The same without a gaze (fixed foveation: the inset must cover where the eye may
    /// look, so it is larger).
    #[serde(default = "default_inset_fixed")]
    pub inset_fixed: [f32; 2],
    /// Where each eye looks, relative to its view; `None` for fixed foveation. Whether a
    /// display has a gaze is fixed when a renderer is made (it sizes the insets' pixels);
    /// the direction may change every frame.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gaze: Option<Gaze>,
}

fn default_peripheral() -> f32 {
    0.5
}
fn default_focus() -> f32 {
    1.0
}
fn default_inset_gaze() -> [f32; 2] {
    [0.35, 0.35]
}
fn default_inset_fixed() -> [f32; 2] {
    [0.5, 0.45]
}

impl Default for Foveation {
    fn default() -> Foveation {
        Foveation {
            peripheral_density: default_peripheral(),
            focus_density: default_focus(),
            inset_with_gaze: default_inset_gaze(),
            inset_fixed: default_inset_fixed(),
            gaze: None,
        }
    }
}

/// Each eye's gaze: degrees of yaw (positive turns left) and pitch (positive looks up)
/// from the axis of that eye's view, as an eye tracker reports it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Gaze {
    /// The left eye's `[yaw, pitch]`.
    pub left: [f32; 2],
    /// The right eye's `[yaw, pitch]`.
    pub right: [f32; 2],
}

impl Gaze {
    /// Both eyes looking the same way.
    pub fn both(yaw_deg: f32, pitch_deg: f32) -> Gaze {
        Gaze {
            left: [yaw_deg, pitch_deg],
            right: [yaw_deg, pitch_deg],
        }
    }
}

/// Where a display's views lie in its target: pixel rectangles side by side from the
/// left (outer left, outer right, then the insets), top-aligned.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ViewLayout {
    /// The target's width and height in pixels.
    pub size: (u32, u32),
    /// `[x, y, width, height]` per view; only the first `views` are used.
    pub viewports: [[u32; 4]; 4],
    /// 1, 2 or 4.
    pub views: u32,
}

impl ViewLayout {
    /// Views of the given sizes placed left to right.
    pub fn side_by_side(sizes: &[(u32, u32)]) -> ViewLayout {
        let mut viewports = [[0; 4]; 4];
        let mut x = 0;
        for (slot, &(w, h)) in viewports.iter_mut().zip(sizes) {
            *slot = [x, 0, w, h];
            // Saturating: a rig file may ask for any size (the device then refuses it).
            x = x.saturating_add(w);
        }
        let height = sizes.iter().map(|s| s.1).max().unwrap_or(0);
        ViewLayout {
            size: (x, height),
            viewports,
            views: sizes.len() as u32,
        }
    }

    /// The used viewports.
    pub fn viewports(&self) -> &[[u32; 4]] {
        &self.viewports[..self.views as usize]
    }

    /// Pixels in all views together (what a frame shades at most, once per sample).
    pub fn pixels(&self) -> u64 {
        let area = |v: &[u32; 4]| v[2] as u64 * v[3] as u64;
        self.viewports().iter().map(area).sum()
    }
}

impl Foveation {
    /// The inset's share of its eye's window: with or without a gaze.
    pub fn inset_fraction(&self) -> [f32; 2] {
        match self.gaze {
            Some(_) => self.inset_with_gaze,
            None => self.inset_fixed,
        }
    }

    /// Pixel sizes of an outer view and of an inset for a display of `resolution`.
    pub fn view_sizes(&self, resolution: [u32; 2]) -> [(u32, u32); 2] {
        let scale = |r: u32, s: f32| ((r as f64 * s as f64).round() as u32).max(1);
        let [fx, fy] = self.inset_fraction();
        let focus = self.focus_density;
        let outer = (
            scale(resolution[0], self.peripheral_density),
            scale(resolution[1], self.peripheral_density),
        );
        let inset = (
            scale(resolution[0], fx * focus),
            scale(resolution[1], fy * focus),
        );
        [outer, inset]
    }

    /// What serde cannot check.
    pub(super) fn check(&self) -> Result<(), String> {
        let densities = [self.peripheral_density, self.focus_density];
        if !densities
            .iter()
            .all(|d| d.is_finite() && *d > 0.0 && *d <= 4.0)
        {
            return Err(format!(
                "foveation: densities must be in (0, 4], got peripheral {} and focus {}",
                self.peripheral_density, self.focus_density
            ));
        }
        for (name, f) in [
            ("inset_with_gaze", self.inset_with_gaze),
            ("inset_fixed", self.inset_fixed),
        ] {
            if !f.iter().all(|v| v.is_finite() && *v > 0.0 && *v <= 1.0) {
                return Err(format!(
                    "foveation.{name}: fractions of the window must be in (0, 1], got {f:?}"
                ));
            }
        }
        if let Some(g) = self.gaze {
            let angles = g.left.iter().chain(&g.right);
            if !angles.clone().all(|a| a.is_finite() && a.abs() < 89.0) {
                return Err(format!(
                    "foveation.gaze: yaw and pitch must be finite and under 89 degrees, got {g:?}"
                ));
            }
        }
        Ok(())
    }

    /// Eye `eye`'s inset window inside its outer `window`, and whether the gaze had to be
    /// moved to keep the inset inside.
    pub fn inset(&self, window: Fov, eye: usize) -> (Fov, bool) {
        let center = match self.gaze {
            Some(g) => gaze_tangent(if eye == 0 { g.left } else { g.right }),
            None => [0.0, 0.0],
        };
        let [fx, fy] = self.inset_fraction().map(f64::from);
        let [left, right, up, down] = window.tangents();
        let (w, h) = (fx * (left + right), fy * (up + down));
        let (cx, x_moved) = clamp(center[0], -left + 0.5 * w, right - 0.5 * w);
        let (cy, y_moved) = clamp(center[1], -down + 0.5 * h, up - 0.5 * h);
        let inset = Fov {
            left: (0.5 * w - cx) as f32,
            right: (cx + 0.5 * w) as f32,
            up: (cy + 0.5 * h) as f32,
            down: (0.5 * h - cy) as f32,
        };
        (inset, x_moved || y_moved)
    }
}

/// `v` within `[lo, hi]` (the middle when the range is empty), and whether it moved.
fn clamp(v: f64, lo: f64, hi: f64) -> (f64, bool) {
    let c = if lo > hi {
        0.5 * (lo + hi)
    } else {
        v.clamp(lo, hi)
    };
    (c, c != v)
}

/// Where a gaze of `[yaw, pitch]` degrees meets the view's image plane, in tangents.
fn gaze_tangent([yaw, pitch]: [f32; 2]) -> [f64; 2] {
    let rad = |deg: f32| (deg as f64).to_radians();
    let d = DQuat::from_euler(glam::EulerRot::YXZ, rad(yaw), rad(pitch), 0.0) * DVec3::NEG_Z;
    [d.x / -d.z, d.y / -d.z]
}

/// Whether `inset` (seen from `inset_rotation`) lies inside `outer` (from
/// `outer_rotation`), both from one eye: each corner's direction within the outer
/// window, allowing for the rounding of angles given in f32.
pub(super) fn inset_inside(
    inset: Fov,
    inset_rotation: DQuat,
    outer: Fov,
    outer_rotation: DQuat,
) -> bool {
    let [l, r, u, d] = inset.tangents();
    let [ol, or, ou, od] = outer.tangents();
    let to_outer = outer_rotation.inverse() * inset_rotation;
    let slack = 1e-5;
    [(-l, -d), (r, -d), (-l, u), (r, u)].iter().all(|&(x, y)| {
        let p = to_outer * DVec3::new(x, y, -1.0);
        if p.z >= 0.0 {
            return false;
        }
        let (tx, ty) = (p.x / -p.z, p.y / -p.z);
        tx >= -ol - slack && tx <= or + slack && ty >= -od - slack && ty <= ou + slack
    })
}
