//! The CPU culler's tests of 64 spheres at once, given as columns (x, y, z, -r): the
//! plane test vectorized over fixed lanes, and the per-sphere tests (the far split, the
//! hidden area, the changed tiles) over the bits it kept.

use glam::Vec4;

use crate::cull::{HiddenArea, Split};
use crate::frustum::plane_distance;

/// Visibility bits of up to 64 spheres given as columns. Per sphere and plane the
/// arithmetic is exactly [`crate::frustum::sphere_in_planes`]'s (so the decisions are
/// the GPU's); the loops run plane by plane over 64 lanes of fixed size so that they
/// vectorize, with AVX2 where the processor has it (the same IEEE operations, wider).
pub(super) fn test_group(planes: &[[f32; 4]; 6], cols: [&[f32]; 4]) -> u64 {
    if let [Ok(x), Ok(y), Ok(z), Ok(r)] = cols.map(<&[f32; 64]>::try_from) {
        return test_lanes(planes, [x, y, z, r]);
    }
    // The last group of a scene is short: pad it, then drop the padding's bits.
    let n = cols[0].len();
    let lanes: [[f32; 64]; 4] = cols.map(|c| {
        let mut lane = [0.0; 64];
        lane[..n].copy_from_slice(c);
        lane
    });
    let [x, y, z, r] = &lanes;
    test_lanes(planes, [x, y, z, r]) & ((1u64 << n) - 1)
}

/// The bits of up to 64 spheres given as columns that `split` keeps ([`Split::keeps`]).
pub(super) fn split_group(split: &Split, [x, y, z, neg_r]: [&[f32]; 4]) -> u64 {
    let mut bits = 0u64;
    for i in 0..x.len() {
        let sphere = glam::Vec4::new(x[i], y[i], z[i], -neg_r[i]);
        bits |= (split.keeps(sphere) as u64) << i;
    }
    bits
}

/// Which of `bits` (spheres given as columns) `hidden` hides.
pub(super) fn hidden_group(hidden: &HiddenArea, bits: u64, cols: [&[f32]; 4]) -> u64 {
    group_where(bits, cols, |s| hidden.hides(s))
}

/// Which of `bits` (spheres given as columns) pass `test`.
pub(super) fn group_where(
    bits: u64,
    [x, y, z, neg_r]: [&[f32]; 4],
    test: impl Fn(Vec4) -> bool,
) -> u64 {
    let mut passed = 0u64;
    let mut rest = bits;
    while rest != 0 {
        let i = rest.trailing_zeros() as usize;
        let sphere = Vec4::new(x[i], y[i], z[i], -neg_r[i]);
        passed |= (test(sphere) as u64) << i;
        rest &= rest - 1;
    }
    passed
}

fn test_lanes(planes: &[[f32; 4]; 6], lanes: [&[f32; 64]; 4]) -> u64 {
    #[cfg(target_arch = "x86_64")]
    if std::is_x86_feature_detected!("avx2") {
        // SAFETY: the processor has AVX2, checked just above.
        return unsafe { test_lanes_avx2(planes, lanes) };
    }
    test_lanes_portable(planes, lanes)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn test_lanes_avx2(planes: &[[f32; 4]; 6], lanes: [&[f32; 64]; 4]) -> u64 {
    test_lanes_portable(planes, lanes)
}

#[inline(always)]
fn test_lanes_portable(planes: &[[f32; 4]; 6], [x, y, z, neg_r]: [&[f32; 64]; 4]) -> u64 {
    let mut inside = [u32::MAX; 64];
    for p in planes {
        for i in 0..64 {
            let dist = plane_distance(*p, [x[i], y[i], z[i]]);
            inside[i] &= ((dist >= neg_r[i]) as u32).wrapping_neg();
        }
    }
    let mut bits = 0u64;
    for (i, m) in inside.iter().enumerate() {
        bits |= ((m & 1) as u64) << i;
    }
    bits
}
