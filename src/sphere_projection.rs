//! Projecting a sphere: the CPU twins of `wgsl/shared/occlusion.wgsl`'s helpers, which
//! occlusion's pyramids and the kept tiles test by.

use glam::{Mat4, Vec4};

/// How much a sphere's radius grows per unit of the magnitudes its view-space center is
/// summed from (see `grown_radius`): each coordinate of the center is three products
/// and three sums of a rotation's rows, rounded at most six times by 2^-24 of those
/// magnitudes (2^-21.4 in all), plus the rotation's own rounding; the distance error
/// stays under 2^-20 of them, and this is four times that.
pub const DEPTH_SLACK: f32 = 1.0 / 262144.0;

/// View-space center of `s`: products summed left to right, as the WGSL writes them.
pub(crate) fn view_center(s: Vec4, m: &Mat4) -> [f32; 3] {
    let row = |i: usize| m.x_axis[i] * s.x + m.y_axis[i] * s.y + m.z_axis[i] * s.z + m.w_axis[i];
    [row(0), row(1), row(2)]
}

/// The radius of `s`, grown by [`DEPTH_SLACK`] of every magnitude its view-space
/// center `c` was summed from (the world center, the view's translation, the result, the
/// radius): the f32 rounding of `c`, centimeters at a million meters from the origin.
/// Summed left to right, as the WGSL does.
pub(crate) fn grown_radius(s: Vec4, m: &Mat4, c: [f32; 3]) -> f32 {
    let t = m.w_axis;
    let magnitude = c[0].abs()
        + c[1].abs()
        + c[2].abs()
        + s.x.abs()
        + s.y.abs()
        + s.z.abs()
        + t.x.abs()
        + t.y.abs()
        + t.z.abs()
        + s.w;
    s.w + magnitude * DEPTH_SLACK
}

/// The slopes (`a / z`) of the two tangents from the eye to the circle of radius `r`
/// about `(a, z)`, least first; `z > r`.
pub(crate) fn tangent_slopes(a: f32, z: f32, r: f32) -> (f32, f32) {
    let t = (a * a + z * z - r * r).sqrt();
    let lo = (a * t - z * r) / (z * t + a * r);
    let hi = (a * t + z * r) / (z * t - a * r);
    (lo, hi)
}

/// Depth-buffer value at view distance `d` (`depth_at` in `wgsl/shared/occlusion.wgsl`).
pub(crate) fn depth_at(d: f32, clip: &Mat4) -> f32 {
    (clip.z_axis.z * -d + clip.w_axis.z) / d
}
