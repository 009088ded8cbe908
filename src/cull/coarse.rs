//! The frame-level coarse cull (the chapter's section 1.2.3): one test of every instance
//! against the frame frustum, which holds every display frustum, narrows each
//! display's cull to the candidates that pass.
//!
//! The display culls must come out byte-identical with and without it, so the coarse
//! test must keep every sphere that any display's plane test keeps. Containment of the
//! frusta is not enough for that: the plane test also keeps spheres near a frustum's
//! corners that lie outside it, and such a sphere can lie wholly outside a frame plane
//! that cuts past the corner at another angle. By Farkas' lemma every frame plane is a
//! non-negative combination `sum(l_i * display_plane_i)` of each display's planes; a
//! sphere passing every display plane then passes the frame plane with its radius
//! grown by `sum(l_i)`. [`CoarseCull::new`] finds the smallest such sum per plane
//! (over every display) and grows radii by the largest, plus slack for rounding on both
//! sides, so the guarantee holds in f32 too (tests/coarse.rs tries to break it).
//! `ResolvedRig::coarse_cull` builds it for a frame.

use glam::{DMat3, DVec3, Vec4};

use crate::frustum::{View, round_up};

/// The frame-level test: the frame frustum's planes and how much radii grow.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoarseCull {
    /// Left, right, bottom, top, near, far of the frame frustum, each pushed out far
    /// enough that it holds every display plane's test (see the module docs).
    pub planes: [Vec4; 6],
    /// How much a radius grows: the largest plane-combination weight, at least 1.
    pub inflation: f32,
    /// Rounding slack per unit of `|center|` (the sum of its coordinates' magnitudes).
    pub slack: f32,
}

/// Units in the last place of f32's 1.0, times 2: `f32::EPSILON / 2`.
const UNIT_ROUNDOFF: f64 = f32::EPSILON as f64 / 2.0;

impl CoarseCull {
    /// A test that keeps every sphere: for frames with no frame frustum (displays around
    /// the viewer), so the two-step structure still runs and stays exact.
    pub const EVERYTHING: CoarseCull = CoarseCull {
        planes: [Vec4::W; 6],
        inflation: 1.0,
        slack: 0.0,
    };

    /// `frame` made to hold every one of `displays`' plane tests, or `None` when some
    /// frame plane is no non-negative combination of a display's planes (the frame
    /// frustum does not hold that display).
    pub fn holding(frame: [Vec4; 6], displays: &[[Vec4; 6]]) -> Option<CoarseCull> {
        let mut inflation = 1.0f64;
        let mut offsets = frame.map(|p| p.w as f64);
        for display in displays {
            for (plane, offset) in frame.iter().zip(&mut offsets) {
                let weights = smallest_combination(plane.truncate().as_dvec3(), display)?;
                let sum: f64 = weights.iter().sum();
                let needed: f64 = weights
                    .iter()
                    .zip(display)
                    .map(|(l, p)| l * p.w as f64)
                    .sum();
                inflation = inflation.max(sum);
                *offset = offset.max(needed);
            }
        }
        // The display test errs by a few units of roundoff times |center|_1 + |d|, and
        // so does this one; the weights carry the display's error over, grown.
        let slack = 8.0 * UNIT_ROUNDOFF * (inflation + 2.0);
        let magnitude = displays
            .iter()
            .flatten()
            .chain(&frame)
            .map(|p| p.w.abs() as f64)
            .fold(0.0, f64::max);
        let inflation = inflation * (1.0 + 1e-6);
        let mut planes = frame;
        for (p, offset) in planes.iter_mut().zip(offsets) {
            p.w = round_up(offset + slack * (magnitude + offset.abs()));
        }
        Some(CoarseCull {
            planes,
            inflation: round_up(inflation),
            slack: round_up(slack),
        })
    }

    /// Whether sphere `s` (center, radius) is a candidate. The CPU twin of
    /// `coarse_test` in `wgsl/shared/cull_math.wgsl`: same operations, same order.
    #[inline]
    pub fn test(&self, s: Vec4) -> bool {
        let reach = s.w * self.inflation + self.slack * (s.x.abs() + s.y.abs() + s.z.abs());
        self.planes
            .iter()
            .all(|p| p.x * s.x + p.y * s.y + p.z * s.z + p.w >= -reach)
    }
}

/// Sphere tests per frame with the coarse cull divided by those without, for a scene
/// spread evenly around the viewer: `(1 + displays * share) / displays`, where `share`
/// is the `frame` frustum's share of all directions (its solid angle over 4 pi).
pub fn expected_tests(frame: &View, displays: usize) -> f64 {
    let [left, right, up, down] = frame.fov.tangents();
    // A pyramid's solid angle, quadrant by quadrant: atan(a b / sqrt(1 + a^2 + b^2)).
    let quadrant = |a: f64, b: f64| (a * b / (1.0 + a * a + b * b).sqrt()).atan();
    let solid_angle: f64 = [left, right]
        .iter()
        .flat_map(|&a| [up, down].map(|b| quadrant(a, b)))
        .sum();
    let share = solid_angle / (4.0 * std::f64::consts::PI);
    let displays = displays as f64;
    (1.0 + displays * share) / displays
}

/// The non-negative weights, one per display plane, whose combination of the display's
/// normals is `normal` with the smallest sum; `None` when there are none. A vertex of
/// that linear program uses at most three planes, so every set of one to three is tried.
fn smallest_combination(normal: DVec3, display: &[Vec4; 6]) -> Option<[f64; 6]> {
    let normals = display.map(|p| p.truncate().as_dvec3());
    let mut best: Option<[f64; 6]> = None;
    let mut consider = |weights: [f64; 6]| {
        let combined: DVec3 = weights.iter().zip(&normals).map(|(l, n)| *l * *n).sum();
        let exact = (combined - normal).length() <= 1e-9;
        let sum = |w: &[f64; 6]| w.iter().sum::<f64>();
        if exact
            && weights.iter().all(|&l| l >= 0.0)
            && best.is_none_or(|b| sum(&weights) < sum(&b))
        {
            best = Some(weights);
        }
    };
    // Every set of one, two or three planes once (repeats stand for the smaller sets).
    for i in 0..6 {
        for j in i..6 {
            for k in j..6 {
                let pair_again = i == j && j < k;
                if pair_again {
                    continue;
                }
                if let Some(weights) = solve([i, j, k], &normals, normal) {
                    consider(weights);
                }
            }
        }
    }
    best
}

/// Weights on planes `set` (repeats allowed, for fewer than three) that combine
/// `normals` into `target` in the least-squares sense; `None` when degenerate.
fn solve(set: [usize; 3], normals: &[DVec3; 6], target: DVec3) -> Option<[f64; 6]> {
    let mut distinct = set.to_vec();
    distinct.dedup();
    // Normal equations (A^T A) x = A^T b, padded to 3x3 with identity where fewer.
    let column = |a: usize| distinct.get(a).map(|&i| normals[i]);
    let gram = DMat3::from_cols_array_2d(&std::array::from_fn(|a| {
        std::array::from_fn(|b| match (column(a), column(b)) {
            (Some(u), Some(v)) => u.dot(v),
            _ => f64::from(a == b),
        })
    }));
    if gram.determinant().abs() < 1e-12 {
        return None;
    }
    let rhs = DVec3::from_array(std::array::from_fn(|a| {
        column(a).map_or(0.0, |u| u.dot(target))
    }));
    let x = gram.inverse() * rhs;
    let mut weights = [0.0; 6];
    for (&i, l) in distinct.iter().zip(x.to_array()) {
        weights[i] = l;
    }
    Some(weights)
}
