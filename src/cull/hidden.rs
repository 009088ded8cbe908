//! The lens's hidden area as a cull test: an instance whose sphere lies wholly where
//! every view of its display shows nothing (outside the view's window, or inside one of
//! the visibility mask's triangles) is dropped by the display's cull, GPU and CPU alike
//! (`hidden_in_views` in `wgsl/shared/cull_math.wgsl`, [`HiddenArea::hides`]).
//!
//! Each view's hidden area is a list of regions, each the intersection of up to three
//! half-spaces through the eye: a mask triangle's edges, or (the window's outside) one
//! flipped frustum plane. A sphere is hidden in a view when some region holds it whole:
//! a sphere across two adjacent triangles is kept, which is what keeps the test as cheap
//! and as exact as the frustum's (the same plane arithmetic, planes built once in f64 on
//! the CPU). A triangle's edge that lies on the window's border bounds nothing the eye
//! sees, so it is left out: its region then reaches past the window, where the eye sees
//! nothing either.
//!
//! Conservative like the frustum cull: the triangles' other edges move inward by
//! [`MARGIN_PX`] before their planes are made (the mask is rasterized, and a pixel
//! center within a snapping step of its edge may fall either way), the planes are
//! pulled in for rounding, and a flipped frustum plane starts from the frustum's,
//! which rounding pushed out.

use encase::ShaderType;
use glam::{DVec2, DVec3, Vec4};

use crate::frustum::{ROUNDING_SLACK, View, plane_distance};

pub use crate::shaders::{MAX_HIDDEN_REGIONS, MAX_HIDDEN_VIEWS};

/// Pixels the hidden triangles' inner edges move inward (more than a rasterizer's
/// snapping of the mask's edges).
pub const MARGIN_PX: f64 = 1.0;

/// One hidden triangle in a view's normalized device coordinates
/// ([`crate::rig::MaskTriangle`]; not named here, so that culling does not import the
/// rig, which plans culls).
type MaskTriangle = [[f32; 2]; 3];

/// A plane every sphere passes: an unused plane of a region.
const ALWAYS: Vec4 = Vec4::new(0.0, 0.0, 0.0, 3.0e38);

/// One region of a view's hidden area (`HiddenRegion` in `wgsl/shared/records.wgsl`):
/// a sphere is in it when it is inside all three planes by its radius.
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub struct HiddenRegion {
    /// Inside when `dot(n, p) + d >= r`; unused planes pass every sphere.
    pub planes: [Vec4; 3],
}

/// One view's hidden area (`HiddenView`): its first `count` regions.
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub struct HiddenView {
    /// The window's outside (six flipped frustum planes), then the mask's triangles.
    pub regions: [HiddenRegion; MAX_HIDDEN_REGIONS],
    /// How many of `regions` are in use.
    pub count: u32,
}

/// A display's hidden area (`HiddenArea`, one per display slot in the cull's `hidden`
/// buffer): its first `count` views, each of which must hide a sphere for the cull to
/// drop it.
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub struct HiddenArea {
    /// The masked views: left and right, or a mono display's one; with two frames per
    /// submission, each frame's.
    pub views: [HiddenView; MAX_HIDDEN_VIEWS],
    /// How many of `views` are in use (0: the cull drops nothing by it).
    pub count: u32,
}

impl HiddenArea {
    /// Drops nothing: what a display slot without a mask cull holds.
    pub const NONE: HiddenArea = HiddenArea {
        views: [HiddenView::EMPTY; MAX_HIDDEN_VIEWS],
        count: 0,
    };

    /// The hidden area of `eyes` (a display's masked views, `size` pixels each) under
    /// a visibility mask's `views` ([`crate::rig::VisibilityMask::views`]: each view's
    /// hidden triangles, in the order of `eyes`); `None` when the mask has no view for
    /// them.
    pub fn new(eyes: &[View], views: &[Vec<MaskTriangle>], size: (u32, u32)) -> Option<HiddenArea> {
        let count = eyes.len().min(views.len()).min(MAX_HIDDEN_VIEWS);
        if count == 0 {
            return None;
        }
        let mut area = HiddenArea::NONE;
        for (slot, (eye, triangles)) in area.views.iter_mut().zip(eyes.iter().zip(views)) {
            *slot = HiddenView::new(eye, triangles, size);
        }
        area.count = count as u32;
        Some(area)
    }

    /// Whether every view in use holds `s` (center, radius) whole in one of its regions:
    /// the CPU twin of `hidden_in_views`, the same operations in the same order.
    pub fn hides(&self, s: Vec4) -> bool {
        self.count > 0 && self.views[..self.count as usize].iter().all(|v| v.hides(s))
    }
}

impl HiddenView {
    const EMPTY: HiddenView = HiddenView {
        regions: [HiddenRegion {
            planes: [ALWAYS; 3],
        }; MAX_HIDDEN_REGIONS],
        count: 0,
    };

    /// `eye`'s window outside, then its hidden `triangles` (normalized coordinates of a
    /// view of `size` pixels): where they cut a convex window out of the view's
    /// ([`convex_cut`]), the outside of each cutting edge; else each triangle, as the
    /// planes through the eye along its edges.
    fn new(eye: &View, triangles: &[MaskTriangle], size: (u32, u32)) -> HiddenView {
        let outside = eye.frustum().planes.map(|p| [-p, ALWAYS, ALWAYS]);
        let half = DVec2::new(size.0 as f64, size.1 as f64) * 0.5;
        let inside: Vec<[Vec4; 3]> = match convex_cut(triangles) {
            Some(cuts) => (cuts.into_iter())
                .map(|(a, b, hidden)| {
                    let (a, b) = (a * half, b * half);
                    let toward = (b - a).perp() * side((a, b), hidden * half);
                    [edge_plane(eye, (a, b), toward, half), ALWAYS, ALWAYS]
                })
                .collect(),
            None => (triangles.iter())
                .filter_map(|t| triangle_planes(eye, t, half))
                .collect(),
        };
        let mut view = HiddenView::EMPTY;
        for (slot, planes) in view
            .regions
            .iter_mut()
            .zip(outside.into_iter().chain(inside))
        {
            *slot = HiddenRegion { planes };
            view.count += 1;
        }
        view
    }

    fn hides(&self, s: Vec4) -> bool {
        let c = [s.x, s.y, s.z];
        self.regions[..self.count as usize].iter().any(|r| {
            r.planes
                .iter()
                .all(|p| plane_distance(p.to_array(), c) >= s.w)
        })
    }
}

/// The planes of triangle `t` of `eye`'s window (`half` its pixels over 2), its inside
/// positive: one per edge not on the window's border; `None` for a triangle whose
/// inradius (twice its area over its perimeter) is at most twice [`MARGIN_PX`], which
/// the margin would leave little or nothing of.
fn triangle_planes(eye: &View, t: &MaskTriangle, half: DVec2) -> Option<[Vec4; 3]> {
    // In pixels (y up), so that the margin is the same each way.
    let p = t.map(|[x, y]| DVec2::new(x as f64, y as f64) * half);
    let turn = (p[1] - p[0]).perp_dot(p[2] - p[0]);
    let perimeter: f64 = (0..3).map(|i| (p[(i + 1) % 3] - p[i]).length()).sum();
    if turn.abs() <= 2.0 * MARGIN_PX * perimeter {
        return None;
    }
    let mut planes = [ALWAYS; 3];
    for (i, plane) in planes.iter_mut().enumerate() {
        if !on_border(t[i], t[(i + 1) % 3]) {
            let (a, b) = (p[i], p[(i + 1) % 3]);
            // The edge's inward normal, whichever the winding.
            *plane = edge_plane(eye, (a, b), (b - a).perp() * turn.signum(), half);
        }
    }
    Some(planes)
}

/// Whether the edge from `a` to `b` lies on one side of the window's border.
fn on_border(a: [f32; 2], b: [f32; 2]) -> bool {
    (0..2).any(|k| a[k] == b[k] && a[k].abs() == 1.0)
}

/// The world plane through `eye`'s apex and the window's line from `a` to `b` (pixels
/// from the window's center, y up; `half` the window's half size), positive on the
/// side `toward` points to, the line moved [`MARGIN_PX`] that way, pulled in for
/// rounding.
fn edge_plane(eye: &View, (a, b): (DVec2, DVec2), toward: DVec2, half: DVec2) -> Vec4 {
    let shift = toward.normalize() * MARGIN_PX;
    let [l, r, u, d] = eye.fov.tangents();
    // The view-space direction through a window pixel: x/-z from -l to r, y from -d to u.
    let direction = |q: DVec2| {
        let q = q / half;
        let x = (q.x + 1.0) * 0.5 * (l + r) - l;
        let y = (q.y + 1.0) * 0.5 * (u + d) - d;
        DVec3::new(x, y, -1.0)
    };
    let (a, b) = (a + shift, b + shift);
    let mut n = direction(a).cross(direction(b)).normalize();
    if n.dot(direction(a + toward)) < 0.0 {
        n = -n;
    }
    let apex = eye.world_from_view.translation;
    let n = eye.world_from_view.transform_vector3(n);
    let w = -n.dot(apex) - ROUNDING_SLACK as f64 * apex.abs().element_sum();
    n.as_vec3().extend(w as f32)
}

/// Where the mask hides exactly what lies outside a convex window within the view's:
/// that window's edges cut by the mask (each as its ends and a point on its hidden
/// side), else `None`. Then a sphere wholly beyond one cut is hidden, wherever the
/// mask's triangles meet inside the hidden part (a corner's fan meets at the corner,
/// and no sphere across a fan's inner edges would be held by one triangle).
///
/// The cuts are the triangles' edges that no other triangle shares and the border does
/// not hold. Checked, not assumed: the triangles must not overlap one another nor the
/// window the cuts leave, and their areas must sum to all the view's window outside it;
/// then they cover it.
fn convex_cut(triangles: &[MaskTriangle]) -> Option<Vec<(DVec2, DVec2, DVec2)>> {
    let point = |[x, y]: [f32; 2]| DVec2::new(x as f64, y as f64);
    let edges = || {
        (triangles.iter())
            .filter(|t| signed_area(&t.map(point)) != 0.0)
            .flat_map(|t| (0..3).map(move |i| (t[i], t[(i + 1) % 3], t[(i + 2) % 3])))
    };
    let uses = |a, b| {
        (edges())
            .filter(|&(p, q, _)| (p, q) == (a, b) || (p, q) == (b, a))
            .count()
    };
    let cuts: Vec<(DVec2, DVec2, DVec2)> = edges()
        .filter(|&(a, b, _)| !on_border(a, b) && uses(a, b) == 1)
        .map(|(a, b, c)| (point(a), point(b), point(c)))
        .collect();
    if cuts.is_empty() {
        return None;
    }
    let square = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)].map(DVec2::from);
    let window = (cuts.iter()).fold(square.to_vec(), |w, &(a, b, hidden)| {
        clip(&w, (a, b), -side((a, b), hidden))
    });
    let shapes: Vec<[DVec2; 3]> = (triangles.iter())
        .map(|t| t.map(point))
        .filter(|t| signed_area(t) != 0.0)
        .collect();
    let hidden: f64 = shapes.iter().map(|t| signed_area(t).abs()).sum();
    let within = |a: &[DVec2], b: &[DVec2]| signed_area(&intersect(a, b)).abs();
    let overlaps: f64 = (shapes.iter().enumerate())
        .flat_map(|(i, a)| shapes[i + 1..].iter().map(move |b| (a, b)))
        .map(|(a, b)| within(a, b))
        .chain(shapes.iter().map(|t| within(t, &window)))
        .sum();
    // Areas from f32 corners in f64 agree to about 1e-15; a pixel of a 1440 x 1600
    // view is 1.7e-6.
    let exact = |x: f64| x.abs() <= 1e-9;
    (exact(overlaps) && exact(4.0 - signed_area(&window).abs() - hidden)).then_some(cuts)
}

/// Which side of the line through `a` and `b` the point `p` lies: 1, -1, or 0 on it.
fn side((a, b): (DVec2, DVec2), p: DVec2) -> f64 {
    let s = (b - a).perp_dot(p - a);
    if s == 0.0 { 0.0 } else { s.signum() }
}

/// The convex polygon `poly` cut to the side `keep` (1 or -1) of the line through `a`
/// and `b`.
fn clip(poly: &[DVec2], (a, b): (DVec2, DVec2), keep: f64) -> Vec<DVec2> {
    let at = |p: DVec2| keep * (b - a).perp_dot(p - a);
    let mut out = Vec::new();
    for (i, &p) in poly.iter().enumerate() {
        let q = poly[(i + 1) % poly.len()];
        let (dp, dq) = (at(p), at(q));
        if dp >= 0.0 {
            out.push(p);
        }
        if (dp >= 0.0) != (dq >= 0.0) {
            out.push(p + (q - p) * (dp / (dp - dq)));
        }
    }
    out
}

/// The intersection of convex polygons `a` and `b`.
fn intersect(a: &[DVec2], b: &[DVec2]) -> Vec<DVec2> {
    let inward = signed_area(b).signum();
    (0..b.len()).fold(a.to_vec(), |poly, k| {
        clip(&poly, (b[k], b[(k + 1) % b.len()]), inward)
    })
}

/// The polygon's area, positive counter-clockwise.
fn signed_area(poly: &[DVec2]) -> f64 {
    let n = poly.len();
    (0..n)
        .map(|i| poly[i].perp_dot(poly[(i + 1) % n]))
        .sum::<f64>()
        * 0.5
}
