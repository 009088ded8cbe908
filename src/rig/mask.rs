//! The lens's hidden area: what an XR runtime's visibility mask gives
//! (`xrGetVisibilityMaskKHR`, `XR_VISIBILITY_MASK_TYPE_HIDDEN_TRIANGLE_MESH_KHR`):
//! per view, triangles in the view's normalized coordinates covering the pixels the
//! lenses never show. A renderer writes them to depth before the scene, so that no
//! fragment is shaded there.

use serde::{Deserialize, Serialize};

/// The most hidden triangles a view may have (what the mask pass's buffer holds).
pub const MAX_MASK_TRIANGLES: usize = crate::shaders::MAX_MASK_TRIANGLES;

/// One triangle in a view's normalized device coordinates: x from -1 (left) to 1
/// (right), y from -1 (bottom) to 1 (top).
pub type MaskTriangle = [[f32; 2]; 3];

/// A display's hidden area, per view in the runtime's order (left, right; a mono
/// display's one view; a foveated display's outer pair, whose insets lie inside).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VisibilityMask {
    /// Each view's hidden triangles.
    pub views: Vec<Vec<MaskTriangle>>,
}

impl VisibilityMask {
    /// A headset's mask, shaped as the hidden-area meshes that consumer headsets'
    /// runtimes return: each corner of an eye's window cut away along the lens's round
    /// edge (an ellipse, (x / 1.045)^2 + (y / 1.065)^2 = 1), the corner below the nose
    /// cut deeper ((x / 1.015)^2 + (y / 1.035)^2 = 1 there). Its share is the one
    /// published figure for a consumer headset's mesh: the HTC Vive's hides 17 % of
    /// each eye's pixels (Vlachos, "Advanced VR Rendering", GDC 2015); this one hides
    /// 16.8 %. Modeled on that figure and shape, not measured from a device.
    pub fn headset() -> VisibilityMask {
        let left: Vec<MaskTriangle> = [(-1.0, 1.0), (1.0, 1.0), (-1.0, -1.0), (1.0, -1.0)]
            .into_iter()
            .flat_map(|(sx, sy)| {
                // The left eye's nose is on its right, below.
                let nose = sx > 0.0 && sy < 0.0;
                let (a, b) = if nose { (1.015, 1.035) } else { (1.045, 1.065) };
                corner(sx, sy, (a, b))
            })
            .collect();
        let right = left
            .iter()
            .map(|t| t.map(|[x, y]| [-x, y]))
            .map(|[a, b, c]| [a, c, b])
            .collect();
        VisibilityMask {
            views: vec![left, right],
        }
    }

    /// Whether the view's point `(x, y)` (normalized coordinates) is hidden.
    pub fn hides(&self, view: usize, (x, y): (f32, f32)) -> bool {
        (self.views.get(view).into_iter().flatten()).any(|t| inside(t, (x, y)))
    }

    /// Pixels of view `view` (`width` x `height`, rows from the top) whose centers are
    /// hidden: what the mask pass covers at one sample per pixel.
    pub fn hidden_pixels(&self, view: usize, (width, height): (u32, u32)) -> u64 {
        let ndc = |p: u32, n: u32| (p as f32 + 0.5) / n as f32 * 2.0 - 1.0;
        (0..height)
            .flat_map(|y| (0..width).map(move |x| (x, y)))
            .filter(|&(x, y)| self.hides(view, (ndc(x, width), -ndc(y, height))))
            .count() as u64
    }

    /// What serde cannot check: a view's triangles for each of `views` (the outer
    /// pair of a foveated display), at most [`MAX_MASK_TRIANGLES`] each, finite and
    /// within the window. Views past the display's are left unused (a stereo display
    /// made mono keeps its left eye's mask).
    pub(super) fn check(&self, views: u32) -> Result<(), String> {
        let outer = views.min(2) as usize;
        if self.views.len() < outer {
            return Err(format!(
                "visibility_mask: {} views given, the display has {outer}",
                self.views.len()
            ));
        }
        for (v, triangles) in self.views.iter().enumerate() {
            if triangles.len() > MAX_MASK_TRIANGLES {
                return Err(format!(
                    "visibility_mask.views[{v}]: {} triangles, at most {MAX_MASK_TRIANGLES}",
                    triangles.len()
                ));
            }
            let coordinates = triangles.iter().flatten().flatten();
            if !coordinates
                .into_iter()
                .all(|c| c.is_finite() && c.abs() <= 1.0)
            {
                return Err(format!(
                    "visibility_mask.views[{v}]: coordinates must be finite, within -1 to 1"
                ));
            }
        }
        Ok(())
    }
}

/// The hidden corner `(sx, sy)` (each -1 or 1) of the left eye's window: a fan of three
/// triangles from the corner along the lens edge (x / a)^2 + (y / b)^2 = 1 (`a`,
/// `b` above 1: the edge crosses the window's sides).
fn corner(sx: f32, sy: f32, (a, b): (f32, f32)) -> Vec<MaskTriangle> {
    let n = 2.0f32;
    // In the first quadrant the edge is (a cos^(2/n) t, b sin^(2/n) t); it leaves the
    // window's side x = 1 at t0 and its top y = 1 at t1.
    let t0 = (1.0 / a).powf(n / 2.0).acos();
    let t1 = (1.0 / b).powf(n / 2.0).asin();
    let edge: Vec<[f32; 2]> = (0..4)
        .map(|i| {
            let t = t0 + (t1 - t0) * i as f32 / 3.0;
            let x = a * t.cos().powf(2.0 / n);
            let y = b * t.sin().powf(2.0 / n);
            [sx * x.min(1.0), sy * y.min(1.0)]
        })
        .collect();
    let c = [sx, sy];
    let fan: Vec<MaskTriangle> = edge.windows(2).map(|w| [c, w[0], w[1]]).collect();
    // Counter-clockwise, whichever the corner.
    fan.into_iter()
        .map(|t| {
            if area(&t) < 0.0 {
                [t[0], t[2], t[1]]
            } else {
                t
            }
        })
        .collect()
}

fn area([a, b, c]: &MaskTriangle) -> f32 {
    (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])
}

/// Whether `p` lies inside `t` or on its edges (either winding; never inside one
/// without area).
fn inside(t: &MaskTriangle, (x, y): (f32, f32)) -> bool {
    if area(t) == 0.0 {
        return false;
    }
    let side = |a: [f32; 2], b: [f32; 2]| (b[0] - a[0]) * (y - a[1]) - (b[1] - a[1]) * (x - a[0]);
    let s = [side(t[0], t[1]), side(t[1], t[2]), side(t[2], t[0])];
    s.iter().all(|&v| v >= 0.0) || s.iter().all(|&v| v <= 0.0)
}
