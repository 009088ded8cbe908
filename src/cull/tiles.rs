//! Keeping unchanged pixels ([`crate::keep`]) as a cull test: a display's changed
//! tiles, the target cut into [`TILE`] x [`TILE`] pixel tiles, a
//! bit per tile, set where a changed instance's bounds (before or after the change)
//! project in some eye. The GPU cull's `touches_changed_tiles`
//! (`wgsl/shared/keep.wgsl`) reads the same bits with the same projection
//! ([`TileMask::touches`] is its CPU twin: same operations, same order).

use glam::{Mat4, UVec2, Vec4};

use crate::sphere_projection::{depth_at, grown_radius, tangent_slopes, view_center};

pub use crate::shaders::{TILE, TILE_MARGIN_PX as MARGIN_PX};

/// `DisplayContext::hidden`'s bit for a cull that keeps only what touches a changed
/// tile (`CULL_TILES` in the WGSL; bit 1 is the hidden area's).
pub const CULL_TILES: u32 = 2;

/// One eye of a display as its tiles see it: its matrices and where its view lies in
/// the display's target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TileEye {
    /// The eye's view matrix.
    pub view_from_world: Mat4,
    /// The eye's projection.
    pub clip_from_view: Mat4,
    /// The view's first column in the target (its row is 0: views lie side by side).
    pub x: u32,
}

/// A display's changed tiles, over a target `views` views of `size` pixels wide.
#[derive(Clone, Debug, PartialEq)]
pub struct TileMask {
    /// The display's eyes (one or two).
    pub eyes: Vec<TileEye>,
    /// One view's pixels.
    pub size: UVec2,
    /// Tiles per row and rows of tiles over the whole target.
    pub grid: UVec2,
    /// Bit `i % 32` of word `i / 32`: tile `i` (row-major) changed.
    pub words: Vec<u32>,
}

impl TileMask {
    /// No tile changed yet, for `eyes` side by side, each `size` pixels.
    pub fn new(eyes: Vec<TileEye>, size: UVec2) -> TileMask {
        let grid = grid(size, eyes.len() as u32);
        TileMask {
            words: vec![0; tile_words(grid) as usize],
            eyes,
            size,
            grid,
        }
    }

    /// Marks every tile sphere `s` may cover in any eye.
    pub fn mark(&mut self, s: Vec4) {
        for e in 0..self.eyes.len() {
            if let Some((lo, hi)) = self.tiles_of(e, s) {
                for y in lo.y..=hi.y {
                    for x in lo.x..=hi.x {
                        let i = y * self.grid.x + x;
                        self.words[(i / 32) as usize] |= 1 << (i % 32);
                    }
                }
            }
        }
    }

    /// Whether sphere `s` may cover a changed tile in some eye: what the cull keeps.
    pub fn touches(&self, s: Vec4) -> bool {
        (0..self.eyes.len()).any(|e| {
            self.tiles_of(e, s).is_some_and(|(lo, hi)| {
                (lo.y..=hi.y).any(|y| (lo.x..=hi.x).any(|x| self.changed(y * self.grid.x + x)))
            })
        })
    }

    fn changed(&self, i: u32) -> bool {
        (self.words[(i / 32) as usize] >> (i % 32)) & 1 != 0
    }

    /// Tiles that changed.
    pub fn count(&self) -> u32 {
        self.words.iter().map(|w| w.count_ones()).sum()
    }

    /// The tiles (first and last, inclusive) of the pixels sphere `s` may cover in eye
    /// `e`: its projected bounds grown by [`MARGIN_PX`], or the eye's whole view
    /// where it reaches the near plane; `None` outside the view.
    fn tiles_of(&self, e: usize, s: Vec4) -> Option<(UVec2, UVec2)> {
        let eye = &self.eyes[e];
        let (lo, hi) = pixels_of(s, eye, self.size)?;
        let x = UVec2::new(eye.x, 0);
        Some(((lo + x) / TILE, (hi + x) / TILE))
    }
}

/// Tiles per row and rows of tiles over a target of `views` views of `size` pixels side
/// by side.
pub fn grid(size: UVec2, views: u32) -> UVec2 {
    UVec2::new((size.x * views).div_ceil(TILE), size.y.div_ceil(TILE))
}

/// Words of a mask over `grid` tiles.
pub fn tile_words(grid: UVec2) -> u32 {
    (grid.x * grid.y).div_ceil(32)
}

/// The first and last pixels (within one view of `size`) sphere `s` may cover in
/// `eye`: its projected bounds, or the whole view where it reaches the near plane;
/// `None` outside the view or behind the eye. `eye_pixels` in `wgsl/shared/keep.wgsl`.
fn pixels_of(s: Vec4, eye: &TileEye, size: UVec2) -> Option<(UVec2, UVec2)> {
    let (view, clip) = (&eye.view_from_world, &eye.clip_from_view);
    let c = view_center(s, view);
    let r = grown_radius(s, view, c);
    // Wholly behind the eye: it sees none of it.
    if c[2] - r >= 0.0 {
        return None;
    }
    let near = -c[2] - r;
    let whole = Some((UVec2::ZERO, size - 1));
    if near.is_nan() || near <= 0.0 || depth_at(near, clip) < 0.0 {
        return whole;
    }
    // A sphere reaching past 90 degrees off the view's axis has a tangent behind the
    // eye: its projection is unbounded on that side.
    let bounded = |a: f32| {
        let z = -c[2];
        (a * a + z * z - r * r).sqrt() * z > a.abs() * r
    };
    if !(bounded(c[0]) && bounded(c[1])) {
        return whole;
    }
    let xs = tangent_slopes(c[0], -c[2], r);
    let ys = tangent_slopes(c[1], -c[2], r);
    let x0 = clip.x_axis.x * xs.0 - clip.z_axis.x;
    let y0 = clip.y_axis.y * ys.0 - clip.z_axis.y;
    let x1 = clip.x_axis.x * xs.1 - clip.z_axis.x;
    let y1 = clip.y_axis.y * ys.1 - clip.z_axis.y;
    let (w, h) = (size.x as f32, size.y as f32);
    let margin = MARGIN_PX;
    let px0 = (x0 * 0.5 + 0.5) * w - margin;
    let px1 = (x1 * 0.5 + 0.5) * w + margin;
    let py0 = (0.5 - y1 * 0.5) * h - margin;
    let py1 = (0.5 - y0 * 0.5) * h + margin;
    if px1 < 0.0 || py1 < 0.0 || px0 >= w || py0 >= h {
        return None;
    }
    // Clamped as floats: a shader's conversion of a value out of range is not defined.
    let to = |v: f32, last: f32| v.clamp(0.0, last) as u32;
    Some((
        UVec2::new(to(px0, w - 1.0), to(py0, h - 1.0)),
        UVec2::new(to(px1, w - 1.0), to(py1, h - 1.0)),
    ))
}
