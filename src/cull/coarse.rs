//! The frame-level coarse cull (the chapter's section 1.2.3): the cull order is cut into
//! blocks of [`BLOCK`] positions, each block's bounding sphere is tested once against
//! the frame frustum (which holds every display frustum) and, when it passes, its
//! bounding box against each display's frustum; each display's cull then runs over the
//! instances of its own blocks only. Blocks pay where the cull order is spatially coherent (ids near each
//! other lie near each other: the procedural scenes are generated so, and an engine
//! inserting in spatial order gets the same); in a scene shuffled in space every
//! block spans everything, and the cull stays exact but saves nothing.
//!
//! The display culls must come out byte-identical with and without it, so the block
//! tests must keep every block that holds a sphere any display's plane test keeps.
//! Containment of the frusta is not enough for the frame test: the plane test also
//! keeps spheres near a frustum's corners that lie outside it, and such a sphere can lie
//! wholly outside a frame plane that cuts past the corner at another angle. By Farkas'
//! lemma every frame plane is a non-negative combination `sum(l_i * display_plane_i)`
//! of each display's planes; a sphere passing every display plane then passes the frame
//! plane with its radius grown by `sum(l_i)`. [`CoarseCull::holding`] finds the smallest
//! such sum per plane (over every display) and grows radii by the largest, plus slack
//! for rounding on both sides, so the guarantee holds in f32 too (tests/coarse.rs tries
//! to break it); [`CoarseCull::around`] is the same for a display's own planes (weights
//! of one). A block's box, and the sphere through its corners, hold its members'
//! spheres with room for rounding ([`block_of`]), so a member that passes passes the
//! block too: the frame tests the block's sphere, each display its box.
//! `ResolvedRig::coarse_cull` builds the frame's test.

use glam::{DMat3, DVec3, Vec3, Vec4};

use crate::frustum::{View, plane_distance, round_up};

/// A grown sphere test: the frame frustum's (the frame test), or a display's (its
/// block test), planes pushed out and radii grown so that it keeps what it must. The
/// GPU reads the block tests as `CoarseTest` (`wgsl/shared/records.wgsl`); encase lays
/// them out.
#[derive(Clone, Copy, Debug, PartialEq, encase::ShaderType)]
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
        let magnitude = displays
            .iter()
            .flatten()
            .chain(&frame)
            .map(|p| p.w.abs() as f64)
            .fold(0.0, f64::max);
        Some(CoarseCull::grown(frame, offsets, inflation, magnitude))
    }

    /// The test of `planes` themselves, grown for rounding as [`CoarseCull::holding`]
    /// grows the frame's: what a block must pass to hold a sphere these planes keep.
    pub fn around(planes: [Vec4; 6]) -> CoarseCull {
        let magnitude = planes.iter().map(|p| p.w.abs() as f64).fold(0.0, f64::max);
        CoarseCull::grown(planes, planes.map(|p| p.w as f64), 1.0, magnitude)
    }

    /// `planes` pushed out to `offsets`, radii grown by `inflation`, and both grown by
    /// the slack that rounding needs: the display test errs by a few units of roundoff
    /// times `|center|_1 + |d|`, and so does this one; the weights carry the display's
    /// error over, grown.
    fn grown(planes: [Vec4; 6], offsets: [f64; 6], inflation: f64, magnitude: f64) -> CoarseCull {
        let slack = 8.0 * UNIT_ROUNDOFF * (inflation + 2.0);
        let inflation = inflation * (1.0 + 1e-6);
        let mut planes = planes;
        for (p, offset) in planes.iter_mut().zip(offsets) {
            p.w = round_up(offset + slack * (magnitude + offset.abs()));
        }
        CoarseCull {
            planes,
            inflation: round_up(inflation),
            slack: round_up(slack),
        }
    }

    /// Whether sphere `s` (center, radius) is a candidate. The CPU twin of
    /// `grown_test` in `wgsl/cull_coarse.wgsl`: same operations, same order.
    #[inline]
    pub fn test(&self, s: Vec4) -> bool {
        let reach = s.w * self.inflation + self.slack * (s.x.abs() + s.y.abs() + s.z.abs());
        self.planes
            .iter()
            .all(|p| plane_distance(p.to_array(), [s.x, s.y, s.z]) >= -reach)
    }

    /// Whether the box of `block` may hold a sphere that these planes keep. Meant for a
    /// display's own planes ([`CoarseCull::around`]): the box's reach is not grown by
    /// Farkas weights as a frame test's would need to be (the frame tests the block's
    /// sphere). The CPU twin of `block_test` in `wgsl/cull_coarse.wgsl`.
    #[inline]
    pub fn test_block(&self, block: &Block) -> bool {
        let (c, e) = (block.sphere, block.extent);
        let slack = self.slack * (c.x.abs() + c.y.abs() + c.z.abs());
        self.planes.iter().all(|p| {
            let reach = (p.x.abs() * e.x + p.y.abs() * e.y + p.z.abs() * e.z) * self.inflation;
            p.x * c.x + p.y * c.y + p.z * c.z + p.w >= -(reach + slack)
        })
    }
}

/// A block of the cull order as the coarse cull sees it: a box holding every member's
/// sphere, and the sphere through its corners.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Block {
    /// Center and radius.
    pub sphere: Vec4,
    /// The box's half extents.
    pub extent: Vec3,
}

pub use crate::shaders::{BLOCK, BLOCK_GROWTH, BLOCK_SLACK};

/// The block of spheres given as columns (x, y, z, -radius): the box of their spheres,
/// grown by [`BLOCK_GROWTH`] and [`BLOCK_SLACK`], and the sphere through its corners.
/// The twin of `coarse_blocks` in `wgsl/cull_coarse.wgsl`; they need not agree bit for
/// bit, each holds its members.
pub fn block_of([x, y, z, neg_r]: [&[f32]; 4]) -> Block {
    let [(lx, hx), (ly, hy), (lz, hz)] = [x, y, z].map(|c| bounds(c, neg_r));
    let (low, high) = (Vec3::new(lx, ly, lz), Vec3::new(hx, hy, hz));
    let center = (low + high) * 0.5;
    let magnitude = center.abs().element_sum();
    let extent = (high - low) * 0.5 * BLOCK_GROWTH + magnitude * BLOCK_SLACK;
    Block {
        sphere: center.extend(extent.length() * BLOCK_GROWTH),
        extent,
    }
}

/// The lowest `v - r` and highest `v + r` over paired entries: eight lanes at a time
/// with AVX2 where the processor has it (a full block's 64 entries), as the culler's
/// plane tests run.
fn bounds(values: &[f32], neg_r: &[f32]) -> (f32, f32) {
    #[cfg(target_arch = "x86_64")]
    if let (Ok(v), Ok(r)) = (
        <&[f32; 64]>::try_from(values),
        <&[f32; 64]>::try_from(neg_r),
    ) && std::is_x86_feature_detected!("avx2")
    {
        // SAFETY: the processor has AVX2, checked just above.
        return unsafe { bounds_avx2(v, r) };
    }
    bounds_portable(values, neg_r)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn bounds_avx2(values: &[f32; 64], neg_r: &[f32; 64]) -> (f32, f32) {
    bounds_portable(values, neg_r)
}

/// Comparisons and selects rather than `f32::min`, whose NaN rules keep it from
/// vectorizing; no entry is NaN (a vacant place's infinite radius makes `+inf` and
/// `-inf`, which drop out).
#[inline(always)]
fn bounds_portable(values: &[f32], neg_r: &[f32]) -> (f32, f32) {
    let (mut low, mut high) = ([f32::MAX; 8], [f32::MIN; 8]);
    let (vs, rs) = (values.chunks_exact(8), neg_r.chunks_exact(8));
    let tail = vs.remainder().iter().zip(rs.remainder());
    for (v, r) in vs.zip(rs) {
        for k in 0..8 {
            let (near, far) = (v[k] + r[k], v[k] - r[k]);
            low[k] = if near < low[k] { near } else { low[k] };
            high[k] = if far > high[k] { far } else { high[k] };
        }
    }
    let mut bound = (f32::MAX, f32::MIN);
    for k in 0..8 {
        bound = (bound.0.min(low[k]), bound.1.max(high[k]));
    }
    for (v, r) in tail {
        bound = (bound.0.min(v + r), bound.1.max(v - r));
    }
    bound
}

/// Sphere tests per frame with the coarse cull divided by those without, for a scene
/// spread evenly around the viewer in a spatially coherent order: every sphere is read
/// once for the blocks, then each display tests about what its own frustum holds,
/// `(1 + sum(share)) / displays`, where a display's `share` is its frustum's share of
/// all directions (its solid angle over 4 pi; blocks across its edges left out).
pub fn expected_tests(displays: &[View]) -> f64 {
    let share = |view: &View| {
        let [left, right, up, down] = view.fov.tangents();
        // A pyramid's solid angle, quadrant by quadrant: atan(a b / sqrt(1 + a^2 + b^2)).
        let quadrant = |a: f64, b: f64| (a * b / (1.0 + a * a + b * b).sqrt()).atan();
        let solid_angle: f64 = [left, right]
            .iter()
            .flat_map(|&a| [up, down].map(|b| quadrant(a, b)))
            .sum();
        solid_angle / (4.0 * std::f64::consts::PI)
    };
    let shares: f64 = displays.iter().map(share).sum();
    (1.0 + shares) / displays.len().max(1) as f64
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
