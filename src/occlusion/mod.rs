//! Occlusion culling's CPU twin: the depth pyramid of each eye and the test of a sphere
//! against it. The GPU reduces each eye's half of a display's depth into its pyramid
//! (`wgsl/occlusion_pyramid.wgsl`) and tests spheres in the late cull
//! (`wgsl/shared/occlusion.wgsl`); these functions do the same operations in the same
//! order, so that given the same depth both reach the same decisions.
//!
//! The pyramid is exact, not sampled: level `l` of an eye `w x h` pixels is
//! `ceil(w / 2^(l+1)) x ceil(h / 2^(l+1))` texels, texel `(x, y)` holding the farthest
//! depth of pixels `[x 2^(l+1), (x+1) 2^(l+1))` (clipped to the eye) in each axis, down
//! to one texel. So an odd size never drops a row: the last texel covers what is left.
//!
//! The test ([`occluded_in_eye`]) is conservative: the sphere's projected bounds (Mara
//! and McGuire's tangent construction, in view space) grown by a pixel each way, the
//! level where those pixels span at most two texels per axis, and the sphere's nearest
//! depth pulled nearer for rounding. Rounding may keep a hidden sphere, never drop a
//! visible one. A display's instance is occluded only if it is occluded in every eye
//! ([`occluded`]): the stereo rule.

use glam::{Mat4, UVec2, Vec4};

use crate::contexts::{DisplayContext, EyeContext};
use crate::cull::FrameLod;
use crate::cull::cpu;
use crate::cull::{CullJob, CullOutput};
use crate::records::CullLayout;
use crate::shaders::SPAN;
use crate::sphere_projection::{depth_at, grown_radius, tangent_slopes, view_center};

pub mod pyramid;

pub use crate::shaders::Phase;

/// How a display's pyramids lie in one buffer of `f32`: per eye, its levels finest first.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PyramidShape {
    /// Pixels of one eye's view.
    pub eye: UVec2,
    /// Eyes (views) with a pyramid each.
    pub eyes: u32,
}

impl PyramidShape {
    /// Texels of level `l` of one eye.
    pub fn level_size(&self, l: u32) -> UVec2 {
        let shift = l + 1;
        let half = (1u32 << shift) - 1;
        UVec2::new((self.eye.x + half) >> shift, (self.eye.y + half) >> shift)
    }

    /// Levels per eye: down to one texel.
    pub fn levels(&self) -> u32 {
        let mut l = 0;
        while self.level_size(l) != UVec2::ONE {
            l += 1;
        }
        l + 1
    }

    /// Texels of one eye's pyramid.
    pub fn eye_len(&self) -> u32 {
        (0..self.levels())
            .map(|l| self.level_size(l).element_product())
            .sum()
    }

    /// Where level `l` of eye `e` starts.
    pub fn offset(&self, e: u32, l: u32) -> u32 {
        e * self.eye_len()
            + (0..l)
                .map(|k| self.level_size(k).element_product())
                .sum::<u32>()
    }

    /// Texels of every eye's pyramid.
    pub fn len(&self) -> u32 {
        self.eyes * self.eye_len()
    }

    /// Whether the pyramid holds nothing (no eyes).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// The pyramids of `depth`, a target `width` pixels wide holding `shape.eyes` views side
/// by side (each `shape.eye`), row by row: what `wgsl/occlusion_pyramid.wgsl` writes.
pub fn reduce(depth: &[f32], width: u32, shape: PyramidShape) -> Vec<f32> {
    let mut out = vec![0.0; shape.len() as usize];
    for e in 0..shape.eyes {
        let size = shape.level_size(0);
        for y in 0..size.y {
            for x in 0..size.x {
                let at = |px: u32, py: u32| {
                    let (px, py) = (px.min(shape.eye.x - 1), py.min(shape.eye.y - 1));
                    depth[(py * width + e * shape.eye.x + px) as usize]
                };
                let i = shape.offset(e, 0) + y * size.x + x;
                out[i as usize] = farthest4([
                    at(2 * x, 2 * y),
                    at(2 * x + 1, 2 * y),
                    at(2 * x, 2 * y + 1),
                    at(2 * x + 1, 2 * y + 1),
                ]);
            }
        }
        for l in 1..shape.levels() {
            let (from, src) = (shape.offset(e, l - 1), shape.level_size(l - 1));
            let (to, size) = (shape.offset(e, l), shape.level_size(l));
            for y in 0..size.y {
                for x in 0..size.x {
                    let at = |tx: u32, ty: u32| {
                        out[(from + ty.min(src.y - 1) * src.x + tx.min(src.x - 1)) as usize]
                    };
                    let v = farthest4([
                        at(2 * x, 2 * y),
                        at(2 * x + 1, 2 * y),
                        at(2 * x, 2 * y + 1),
                        at(2 * x + 1, 2 * y + 1),
                    ]);
                    out[(to + y * size.x + x) as usize] = v;
                }
            }
        }
    }
    out
}

/// The farthest of four depths, in the WGSL's order.
fn farthest4(d: [f32; 4]) -> f32 {
    d[0].max(d[1]).max(d[2].max(d[3]))
}

pub use crate::contexts::BOUNDS_GROWTH_PX;
pub use crate::sphere_projection::DEPTH_SLACK;
/// How far (in depth-buffer units) the sphere's nearest depth must lie beyond the
/// farthest occluder depth: covers the rasterizer's depth interpolation.
pub const DEPTH_MARGIN: f32 = 1.0 / 1048576.0;

/// Whether sphere `s` (world space) is hidden from eye `e` of a display whose context
/// holds `eye`, by that eye's pyramid in `pyramid` laid out as `shape`, its projected
/// bounds grown by `margin` pixels each way (the context's `occlusion_margin_px`,
/// [`BOUNDS_GROWTH_PX`] for a display's own cull).
pub fn occluded_in_eye(
    s: Vec4,
    eye: &EyeContext,
    (pyramid, shape): (&[f32], PyramidShape),
    (e, margin): (u32, f32),
) -> bool {
    let Some(bounds) = project(s, &eye.view_from_world, &eye.clip_from_view) else {
        return false;
    };
    let (w, h) = (shape.eye.x as f32, shape.eye.y as f32);
    // Pixel rectangle, y down, grown for rounding.
    let px0 = (bounds.x * 0.5 + 0.5) * w - margin;
    let px1 = (bounds.z * 0.5 + 0.5) * w + margin;
    let py0 = (0.5 - bounds.w * 0.5) * h - margin;
    let py1 = (0.5 - bounds.y * 0.5) * h + margin;
    if px1 < 0.0 || py1 < 0.0 || px0 >= w || py0 >= h {
        // Outside this eye's view: it cannot see the sphere.
        return true;
    }
    // Clamped as floats first: a shader's float-to-integer conversion of a value out
    // of range is not defined.
    let clamp = |v: f32, size: u32| v.clamp(0.0, (size - 1) as f32) as u32;
    let lo = UVec2::new(clamp(px0, shape.eye.x), clamp(py0, shape.eye.y));
    let hi = UVec2::new(clamp(px1, shape.eye.x), clamp(py1, shape.eye.y));
    let l = pyramid_level(lo, hi, shape.levels());
    let (lo, hi) = (lo >> (l + 1), hi >> (l + 1));
    let (base, width) = (shape.offset(e, l), shape.level_size(l).x);
    let at = |x: u32, y: u32| pyramid[(base + y * width + x) as usize];
    let farthest = farthest4([
        at(lo.x, lo.y),
        at(hi.x, lo.y),
        at(lo.x, hi.y),
        at(hi.x, hi.y),
    ]);
    bounds_depth(s, &eye.view_from_world, &eye.clip_from_view) > farthest + DEPTH_MARGIN
}

/// Whether sphere `s` is hidden from every eye of the display whose context (or a far
/// layer's tested context) is `display`: the stereo rule (an instance one eye sees
/// around an edge is kept).
pub fn occluded(
    s: Vec4,
    display: &DisplayContext,
    (pyramid, shape): (&[f32], PyramidShape),
) -> bool {
    let margin = display.occlusion_margin_px;
    (0..shape.eyes)
        .all(|e| occluded_in_eye(s, &display.eye[e as usize], (pyramid, shape), (e, margin)))
}

/// The finest level where pixels `lo..=hi` span at most two texels per axis (the last
/// level, one texel, always does).
pub fn pyramid_level(lo: UVec2, hi: UVec2, levels: u32) -> u32 {
    let mut l = 0;
    while l + 1 < levels
        && ((hi.x >> (l + 1)) - (lo.x >> (l + 1)) > 1 || (hi.y >> (l + 1)) - (lo.y >> (l + 1)) > 1)
    {
        l += 1;
    }
    l
}

/// The sphere's projected bounds in normalized device coordinates (min x, min y, max x,
/// max y), or `None` where it reaches the near plane (then it is never occluded).
fn project(s: Vec4, view: &Mat4, clip: &Mat4) -> Option<Vec4> {
    let c = view_center(s, view);
    let r = grown_radius(s, view, c);
    if near_depth(-c[2] - r, clip).is_none_or(|d| d < 0.0) {
        return None;
    }
    let z = -c[2];
    let (x0, x1) = tangent_slopes(c[0], z, r);
    let (y0, y1) = tangent_slopes(c[1], z, r);
    let (p00, p11) = (clip.x_axis.x, clip.y_axis.y);
    let (p20, p21) = (clip.z_axis.x, clip.z_axis.y);
    Some(Vec4::new(
        p00 * x0 - p20,
        p11 * y0 - p21,
        p00 * x1 - p20,
        p11 * y1 - p21,
    ))
}

/// Depth-buffer value at view distance `d` (positive), or `None` for `d <= 0`.
fn near_depth(d: f32, clip: &Mat4) -> Option<f32> {
    (d > 0.0).then(|| depth_at(d, clip))
}

/// The depth-buffer value of the sphere's nearest point (pulled nearer for rounding).
fn bounds_depth(s: Vec4, view: &Mat4, clip: &Mat4) -> f32 {
    let c = view_center(s, view);
    near_depth(-c[2] - grown_radius(s, view, c), clip).unwrap_or(0.0)
}

/// One display's two-phase cull on the CPU (the twin of the GPU's early and late cull
/// passes, without the coarse cull): the early phase's and the late phase's buffers
/// and the display's visibility words after the late phase.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Phases {
    /// What the display drew last frame and the frustum keeps.
    pub early: CullOutput,
    /// What it did not, and the pyramids do not hide.
    pub late: CullOutput,
    /// `drawn`'s words, each span of places the late phase ran over rewritten with
    /// which of its places the pyramids do not hide (within the frustum; never blended
    /// ones, [`crate::bins::Bins::first_blend_bin`]).
    pub seen: Vec<u32>,
}

/// [`Phases`] of the display whose context is `display` and cull `job`, given the words
/// `drawn` (what it drew last frame, [`SPAN`] places a word) and its pyramids.
pub fn cull_phases(
    layout: &CullLayout,
    (job, display): (&CullJob, &DisplayContext),
    lod: &FrameLod,
    drawn: &[u32],
    pyramid: (&[f32], PyramidShape),
) -> Phases {
    let (late, seen) = cull_late(layout, (job, display), lod, drawn, pyramid);
    Phases {
        early: cull_early(layout, job, lod, drawn),
        late,
        seen,
    }
}

/// The early phase alone: what `job`'s frustum keeps among the places set in `drawn`.
/// The CPU culler's first half of a frame, before any depth exists.
pub fn cull_early(layout: &CullLayout, job: &CullJob, lod: &FrameLod, drawn: &[u32]) -> CullOutput {
    let span = SPAN as usize;
    let early = mask(layout, |k, s| {
        job.keeps(s) && drawn[k / span] >> (k % span) & 1 == 1
    });
    cpu::cull_masked(
        layout,
        &early,
        lod,
        (job.instances_per_object, job.sort_origin),
    )
}

/// The late phase alone, and the visibility words after it (see [`Phases`]).
pub fn cull_late(
    layout: &CullLayout,
    (job, display): (&CullJob, &DisplayContext),
    lod: &FrameLod,
    drawn: &[u32],
    pyramid: (&[f32], PyramidShape),
) -> (CullOutput, Vec<u32>) {
    let mut late = vec![0u64; layout.spheres.len().div_ceil(64)];
    let mut seen = drawn.to_vec();
    let span = SPAN as usize;
    let first_blend = layout.bins.first_blend_bin();
    for (first, spheres) in layout
        .spheres
        .chunks(span)
        .enumerate()
        .map(|(i, c)| (i * span, c))
    {
        let mut bits = 0u32;
        for (i, &s) in spheres.iter().enumerate() {
            let k = first + i;
            if !job.keeps(s) || occluded(s, display, pyramid) {
                continue;
            }
            if drawn[k / span] >> (k % span) & 1 == 0 {
                late[k / 64] |= 1 << (k % 64);
            }
            let blended = layout.meshes[layout.mesh_of[k] as usize].bin >= first_blend;
            bits |= u32::from(!blended) << i;
        }
        seen[first / span] = bits;
    }
    let v = (job.instances_per_object, job.sort_origin);
    (cpu::cull_masked(layout, &late, lod, v), seen)
}

/// A far layer's cull with occlusion ([`Phase::Tested`]): what its frustum and split
/// keep (`job`) and its display's pyramids do not hide, tested with `context`
/// ([`crate::far_layer::FarPlan::tested_context`]: the display's eyes, the far layer's
/// margin). The twin of the GPU's tested cull pass.
pub fn cull_tested(
    layout: &CullLayout,
    (job, context): (&CullJob, &DisplayContext),
    lod: &FrameLod,
    pyramid: (&[f32], PyramidShape),
) -> CullOutput {
    let kept = mask(layout, |_, s| {
        job.keeps(s) && !occluded(s, context, pyramid)
    });
    let v = (job.instances_per_object, job.sort_origin);
    cpu::cull_masked(layout, &kept, lod, v)
}

/// The cull positions (64 a word) whose sphere `keep` keeps.
fn mask(layout: &CullLayout, keep: impl Fn(usize, Vec4) -> bool) -> Vec<u64> {
    let mut kept = vec![0u64; layout.spheres.len().div_ceil(64)];
    for (k, &s) in layout.spheres.iter().enumerate() {
        if keep(k, s) {
            kept[k / 64] |= 1 << (k % 64);
        }
    }
    kept
}

/// Whether `job`'s frustum and split keep sphere `s`.
#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_cover_odd_sizes_down_to_one_texel() {
        let shape = PyramidShape {
            eye: UVec2::new(1440, 1600),
            eyes: 2,
        };
        assert_eq!(shape.level_size(0), UVec2::new(720, 800));
        assert_eq!(shape.level_size(5), UVec2::new(23, 25));
        assert_eq!(shape.levels(), 11);
        let odd = PyramidShape {
            eye: UVec2::new(5, 3),
            eyes: 1,
        };
        let sizes: Vec<_> = (0..odd.levels()).map(|l| odd.level_size(l)).collect();
        assert_eq!(sizes, [UVec2::new(3, 2), UVec2::new(2, 1), UVec2::ONE]);
        assert_eq!(odd.offset(0, 2), 8);
    }

    #[test]
    fn reduction_keeps_the_farthest_of_each_footprint() {
        let shape = PyramidShape {
            eye: UVec2::new(5, 3),
            eyes: 2,
        };
        let width = 10;
        let depth: Vec<f32> = (0..30).map(|i| ((i * 7) % 30) as f32 / 30.0).collect();
        let pyramid = reduce(&depth, width, shape);
        for e in 0..2 {
            for l in 0..shape.levels() {
                let size = shape.level_size(l);
                let span = 1u32 << (l + 1);
                for y in 0..size.y {
                    for x in 0..size.x {
                        let mut want = f32::MIN;
                        for py in y * span..((y + 1) * span).min(3) {
                            for px in x * span..((x + 1) * span).min(5) {
                                want = want.max(depth[(py * width + e * 5 + px) as usize]);
                            }
                        }
                        let got = pyramid[(shape.offset(e, l) + y * size.x + x) as usize];
                        assert_eq!(got, want, "eye {e} level {l} texel {x},{y}");
                    }
                }
            }
        }
    }

    #[test]
    fn level_spans_at_most_two_texels() {
        for (lo, hi) in [(0, 0), (1, 2), (3, 4), (5, 12), (0, 1439), (700, 701)] {
            let l = pyramid_level(UVec2::new(lo, lo), UVec2::new(hi, hi), 11);
            assert!((hi >> (l + 1)) - (lo >> (l + 1)) <= 1);
            assert!(
                l == 0 || (hi >> l) - (lo >> l) > 1,
                "{lo}..{hi} could use {}",
                l - 1
            );
        }
    }
}
