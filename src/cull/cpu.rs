//! The CPU reference culler: the same math as `wgsl/cull*.wgsl` (the plane test of
//! [`crate::frustum::sphere_in_planes`]), parallel with rayon.
//! It is both what the GPU path is tested against and the baseline it is profiled
//! against, so it is written to be fast: one pass that tests sphere columns into a
//! bitmask per display (every display at once, so each sphere is read once) and counts
//! per chunk, one that compacts, then per-mesh counts from the bitmask.

use rayon::prelude::*;

use glam::{Vec3, Vec4};

use super::coarse::{BLOCK, block_of};
use super::{BinDraws, CoarseCull, CullJob, CullOutput, HiddenArea, Split};
/// Their old path, kept for one release: they are the frame's, not the CPU culler's.
pub use super::{FrameCull, FrameLod};
use crate::cull::tiles::TileMask;
use crate::records::{CullLayout, DrawArgs, lod_level};
use crate::scene::MAX_LODS;

/// Instances per parallel task: large enough to amortise scheduling, a multiple of 64.
const CHUNK: usize = 1 << 14;
// One mask word per coarse block: the block tests skip whole words.
const _: () = assert!(BLOCK == 64);
const WORDS_PER_CHUNK: usize = CHUNK / 64;

mod groups;
use groups::{group_where, hidden_group, split_group, test_group};

/// Culls every instance for one job and builds its draws.
pub fn cull(layout: &CullLayout, job: &CullJob) -> CullOutput {
    cull_many(layout, std::slice::from_ref(job)).remove(0)
}

/// Culls for several displays (or eyes) at once: every sphere is read once for all of
/// them, which is what a frame with several displays wants.
pub fn cull_many(layout: &CullLayout, displays: &[CullJob]) -> Vec<CullOutput> {
    cull_many_lod(layout, displays, &FrameLod::OFF)
}

/// [`cull_many`] with levels of detail chosen per instance from the viewer (the same
/// level for every display), draws per (level, mesh) as the GPU's.
pub fn cull_many_lod(layout: &CullLayout, displays: &[CullJob], lod: &FrameLod) -> Vec<CullOutput> {
    let frame = FrameCull {
        lod: *lod,
        coarse: None,
    };
    cull_frame(layout, displays, &frame)
}

/// [`cull_many_lod`], with the frame's coarse cull first when it runs: each group of
/// [`BLOCK`] spheres is a block whose sphere is tested against the frame frustum and
/// then each display's (or eye's), and each display tests only its blocks' spheres.
/// The outputs are the same as without it; that is the block tests' guarantee.
pub fn cull_frame(layout: &CullLayout, displays: &[CullJob], frame: &FrameCull) -> Vec<CullOutput> {
    if displays.is_empty() {
        return Vec::new();
    }
    let (lod, coarse) = (&frame.lod, frame.coarse.as_ref());
    let levels = (lod.levels > 1).then(|| (position_levels(layout, lod), lod.levels));
    let n = layout.spheres.len();
    let words = n.div_ceil(64);
    let planes: Vec<[[f32; 4]; 6]> = displays
        .iter()
        .map(|job| job.planes.map(|v| v.to_array()))
        .collect();
    let splits: Vec<Option<Split>> = displays.iter().map(|job| job.split).collect();
    let hidden: Vec<Option<&HiddenArea>> = displays.iter().map(|j| j.hidden.as_deref()).collect();
    let tiles: Vec<Option<&TileMask>> = displays.iter().map(|j| j.tiles.as_deref()).collect();
    let blocks: Vec<CoarseCull> = match coarse {
        Some(_) => displays
            .iter()
            .map(|j| CoarseCull::around(j.planes))
            .collect(),
        None => Vec::new(),
    };
    let tests = FrameTests {
        planes: &planes,
        splits: &splits,
        hidden: &hidden,
        tiles: &tiles,
        coarse: coarse.map(|frame| (frame, &blocks[..])),
    };
    // One mask per display, chunk-interleaved so each task writes one contiguous run.
    let mut masks = vec![0u64; words * displays.len()];
    let counts: Vec<Vec<u32>> = masks
        .par_chunks_mut(WORDS_PER_CHUNK * displays.len())
        .enumerate()
        .map(|(chunk, out)| test_chunk(layout, tests, chunk * CHUNK, out))
        .collect();
    displays
        .iter()
        .enumerate()
        .map(|(d, job)| {
            let mask: Vec<u64> = masks
                .chunks(WORDS_PER_CHUNK * displays.len())
                .flat_map(|c| {
                    let per = c.len() / displays.len();
                    c[d * per..(d + 1) * per].iter().copied()
                })
                .collect();
            match &levels {
                None => {
                    let chunk_counts: Vec<u32> = counts.iter().map(|c| c[d]).collect();
                    let view = (job.instances_per_object, job.sort_origin);
                    build_output(layout, &mask, &chunk_counts, view)
                }
                Some((levels, n)) => {
                    let view = (job.instances_per_object, job.sort_origin);
                    build_output_lod(layout, &mask, levels, *n, view)
                }
            }
        })
        .collect()
}

/// The contract's buffers for the cull positions set in `mask` (bit `p % 64` of word
/// `p / 64`), with `lod`'s levels, for a view of `instances_per_object` whose blended
/// instances sort from `sort_origin`: what a cull that keeps those positions writes.
/// For tests that a filter of positions (occlusion's phases) keeps the contract.
pub fn cull_masked(
    layout: &CullLayout,
    mask: &[u64],
    lod: &FrameLod,
    view: (u32, Vec3),
) -> CullOutput {
    if lod.levels > 1 {
        let levels = position_levels(layout, lod);
        return build_output_lod(layout, mask, &levels, lod.levels, view);
    }
    let counts: Vec<u32> = (mask.chunks(WORDS_PER_CHUNK))
        .map(|c| c.iter().map(|w| w.count_ones()).sum())
        .collect();
    build_output(layout, mask, &counts, view)
}

/// Each cull position's level of detail under `lod`, in parallel.
fn position_levels(layout: &CullLayout, lod: &FrameLod) -> Vec<u8> {
    let level_of = |(s, &m): (&Vec4, &u32)| {
        let lods = &layout.lods[m as usize * MAX_LODS..][..MAX_LODS];
        lod_level(*s, lod.viewer, lods, lod.lod_scale) as u8
    };
    (layout.spheres.par_iter())
        .zip(&layout.mesh_of)
        .map(level_of)
        .collect()
}

/// What each sphere is tested against: every display's planes, far split and hidden
/// area, after its block's tests when the coarse cull runs (the frame's, then each
/// display's).
#[derive(Clone, Copy)]
struct FrameTests<'a> {
    planes: &'a [[[f32; 4]; 6]],
    splits: &'a [Option<Split>],
    hidden: &'a [Option<&'a HiddenArea>],
    tiles: &'a [Option<&'a TileMask>],
    coarse: Option<(&'a CoarseCull, &'a [CoarseCull])>,
}

/// Tests one chunk of spheres for every display (only the blocks that pass the coarse
/// tests, given them); `out` holds each display's words for the chunk one after another.
/// Returns the visible count per display.
fn test_chunk(
    layout: &CullLayout,
    FrameTests {
        planes,
        splits,
        hidden,
        tiles,
        coarse,
    }: FrameTests,
    start: usize,
    out: &mut [u64],
) -> Vec<u32> {
    let end = (start + CHUNK).min(layout.spheres.len());
    let per = out.len() / planes.len();
    let [x, y, z, neg_r] = &layout.columns;
    let mut counts = vec![0; planes.len()];
    for (w, group) in (start..end).step_by(BLOCK as usize).enumerate() {
        let g = group..(group + BLOCK as usize).min(end);
        let cols = [&x[g.clone()], &y[g.clone()], &z[g.clone()], &neg_r[g]];
        let block = coarse.map(|(frame, displays)| {
            let block = block_of(cols);
            (frame.test(block.sphere), displays, block)
        });
        for (d, (p, split)) in planes.iter().zip(splits).enumerate() {
            let listed =
                block.is_none_or(|(in_frame, tests, b)| in_frame && tests[d].test_block(&b));
            let bits = if listed { test_group(p, cols) } else { 0 };
            let bits = match split {
                Some(s) if bits != 0 => bits & split_group(s, cols),
                _ => bits,
            };
            let bits = match hidden[d] {
                Some(h) if bits != 0 => bits & !hidden_group(h, bits, cols),
                _ => bits,
            };
            let bits = match tiles[d] {
                Some(t) if bits != 0 => bits & group_where(bits, cols, |s| t.touches(s)),
                _ => bits,
            };
            out[d * per + w] = bits;
            counts[d] += bits.count_ones();
        }
    }
    counts
}

/// The contract's buffers from one display's visibility bits.
fn build_output(
    layout: &CullLayout,
    mask: &[u64],
    counts: &[u32],
    (instances_per_object, sort_origin): (u32, Vec3),
) -> CullOutput {
    let chunk_start = exclusive_prefix(counts);
    let total = chunk_start.last().copied().unwrap_or(0) as usize;
    let mut visible = vec![0u32; total];
    let mut slices = Vec::with_capacity(counts.len());
    let mut rest = visible.as_mut_slice();
    for &c in counts {
        let (head, tail) = rest.split_at_mut(c as usize);
        slices.push(head);
        rest = tail;
    }
    slices
        .into_par_iter()
        .zip(mask.par_chunks(WORDS_PER_CHUNK))
        .zip(layout.order.par_chunks(CHUNK))
        .for_each(|((out, words), order)| compact_chunk(words, order, out));

    let visible_before = |pos: usize| -> u32 {
        let chunk = pos / CHUNK;
        let words = &mask[chunk * WORDS_PER_CHUNK..pos / 64];
        let partial = if pos.is_multiple_of(64) {
            0
        } else {
            mask[pos / 64] & ((1u64 << (pos % 64)) - 1)
        };
        chunk_start[chunk]
            + words.iter().map(|w| w.count_ones()).sum::<u32>()
            + partial.count_ones()
    };
    let ordered = layout.meshes.iter().filter_map(|m| {
        let offset = visible_before(m.cull_start as usize);
        let count = visible_before((m.cull_start + m.cull_count) as usize) - offset;
        (count > 0).then(|| {
            let draw = DrawArgs {
                index_count: m.index_count,
                instance_count: instances_per_object * count,
                first_index: m.first_index,
                base_vertex: m.base_vertex,
                first_instance: instances_per_object * offset,
            };
            (m.bin, draw)
        })
    });
    let (draws, bins) = into_bins(layout, 1, ordered);
    let mut out = CullOutput {
        visible,
        draw_count: 0,
        draws,
        bins,
    };
    sort_blended(layout, &mut out, |_| 0, (instances_per_object, sort_origin));
    out
}

/// Draws given in (level, mesh) order, each with its mesh's bin, placed in their bins'
/// ranges ([`CullLayout::bin_ranges`] for `levels`): the contract's `draws` and each
/// bin's count. Blended bins are left empty for [`sort_blended`].
fn into_bins(
    layout: &CullLayout,
    levels: u32,
    ordered: impl Iterator<Item = (u32, DrawArgs)>,
) -> (Vec<DrawArgs>, Vec<BinDraws>) {
    let ranges = layout.bin_ranges(levels);
    let entries = ranges.last().map_or(0, |r| r.first + r.capacity);
    let mut draws = vec![DrawArgs::default(); entries as usize];
    let mut bins: Vec<BinDraws> = (ranges.iter())
        .map(|r| BinDraws {
            first: r.first,
            count: 0,
        })
        .collect();
    let first_blend = layout.bins.first_blend_bin();
    for (bin, draw) in ordered.filter(|&(bin, _)| bin < first_blend) {
        let b = &mut bins[bin as usize];
        draws[(b.first + b.count) as usize] = draw;
        b.count += 1;
    }
    (draws, bins)
}

/// The contract's buffers with levels of detail: visible ids grouped by level (finest
/// first), then mesh, then cull position; one draw per non-empty (level, mesh) in that
/// order with the level's index range.
fn build_output_lod(
    layout: &CullLayout,
    mask: &[u64],
    levels: &[u8],
    level_count: u32,
    (instances_per_object, sort_origin): (u32, Vec3),
) -> CullOutput {
    let l_count = level_count as usize;
    let mut buckets = vec![Vec::new(); l_count];
    let mut counts = vec![[0u32; MAX_LODS]; layout.meshes.len()];
    for (m, mesh) in layout.meshes.iter().enumerate() {
        let range = mesh.cull_start as usize..(mesh.cull_start + mesh.cull_count) as usize;
        for pos in range.filter(|&p| mask[p / 64] >> (p % 64) & 1 == 1) {
            let level = levels[pos] as usize;
            buckets[level].push(layout.order[pos]);
            counts[m][level] += 1;
        }
    }
    let mut ordered = Vec::new();
    let mut offset = 0;
    for level in 0..l_count {
        for ((m, mesh), per_level) in layout.meshes.iter().enumerate().zip(&counts) {
            let count = per_level[level];
            if count == 0 {
                continue;
            }
            let lod = layout.lods[m * MAX_LODS + level];
            let draw = DrawArgs {
                index_count: lod.index_count,
                instance_count: instances_per_object * count,
                first_index: lod.first_index,
                base_vertex: mesh.base_vertex,
                first_instance: instances_per_object * offset,
            };
            ordered.push((mesh.bin, draw));
            offset += count;
        }
    }
    let (draws, bins) = into_bins(layout, level_count, ordered.into_iter());
    let starts = exclusive_prefix(&buckets.iter().map(|b| b.len() as u32).collect::<Vec<_>>());
    let mut out = CullOutput {
        visible: buckets.concat(),
        draw_count: 0,
        draws,
        bins,
    };
    let level_of = |slot: usize| starts.partition_point(|&s| s as usize <= slot) - 1;
    sort_blended(
        layout,
        &mut out,
        level_of,
        (instances_per_object, sort_origin),
    );
    out
}

/// Fills the blended bins of `out` (whose visible list is written): every visible
/// instance of a blended bin is its own draw (`level_of` its slot's level), back to
/// front from `origin` (the squared distance of its sphere's center, farthest first),
/// ties by ascending id. Then counts every bin's draws. The twin of
/// `wgsl/cull_blend.wgsl`.
fn sort_blended(
    layout: &CullLayout,
    out: &mut CullOutput,
    level_of: impl Fn(usize) -> usize,
    (instances_per_object, origin): (u32, Vec3),
) {
    let first_blend = layout.bins.first_blend_bin() as usize;
    for b in first_blend..out.bins.len() {
        // (key, id) orders them; the slot and mesh come along.
        let mut records: Vec<(u32, u32, usize, usize)> = (out.visible.iter().enumerate())
            .filter_map(|(slot, &id)| {
                let place = layout.positions[id as usize] as usize;
                let mesh = layout.mesh_of[place] as usize;
                let key = sort_key(layout.spheres[place], origin);
                (layout.meshes[mesh].bin == b as u32).then_some((key, id, slot, mesh))
            })
            .collect();
        records.sort_unstable();
        let first = out.bins[b].first as usize;
        for (i, &(_, _, slot, mesh)) in records.iter().enumerate() {
            let lod = layout.lods[mesh * MAX_LODS + level_of(slot)];
            out.draws[first + i] = DrawArgs {
                index_count: lod.index_count,
                instance_count: instances_per_object,
                first_index: lod.first_index,
                base_vertex: layout.meshes[mesh].base_vertex,
                first_instance: instances_per_object * slot as u32,
            };
        }
        out.bins[b].count = records.len() as u32;
    }
    out.draw_count = out.bins.iter().map(|b| b.count).sum();
}

/// A blended instance's sort key: its sphere center's squared distance from `origin`
/// (`(dx dx + dy dy) + dz dz`), bits inverted so that ascending keys run back to front.
/// Non-negative floats order as their bits.
pub fn sort_key(sphere: Vec4, origin: Vec3) -> u32 {
    let (dx, dy, dz) = (
        sphere.x - origin.x,
        sphere.y - origin.y,
        sphere.z - origin.z,
    );
    !(dx * dx + dy * dy + dz * dz).to_bits()
}

fn compact_chunk(words: &[u64], order: &[u32], out: &mut [u32]) {
    let mut next = 0;
    for (w, &word) in words.iter().enumerate() {
        let mut bits = word;
        while bits != 0 {
            out[next] = order[w * 64 + bits.trailing_zeros() as usize];
            next += 1;
            bits &= bits - 1;
        }
    }
}

/// `[0, a0, a0 + a1, ..., total]`: one longer than the input.
fn exclusive_prefix(counts: &[u32]) -> Vec<u32> {
    let mut out = Vec::with_capacity(counts.len() + 1);
    let mut sum = 0;
    out.push(0);
    for c in counts {
        sum += c;
        out.push(sum);
    }
    out
}
