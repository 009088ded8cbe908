//! The CPU reference culler: the same math as `wgsl/cull*.wgsl`, parallel with rayon.
//! It is both what the GPU path is tested against and the baseline it is profiled
//! against, so it is written to be fast: one pass that tests spheres into a bitmask
//! and counts per chunk, one that compacts, then per-mesh counts from the bitmask.

use glam::Vec4;
use rayon::prelude::*;

use super::CullOutput;
use crate::frustum::sphere_in_planes;
use crate::records::{CullLayout, DrawArgs};

/// Instances per parallel task: large enough to amortise scheduling, a multiple of 64.
const CHUNK: usize = 1 << 14;
const WORDS_PER_CHUNK: usize = CHUNK / 64;

/// Culls every instance against `planes` and builds the draws for a display of
/// `views` views (2 stereo, 1 mono).
pub fn cull(layout: &CullLayout, planes: &[Vec4; 6], views: u32) -> CullOutput {
    let n = layout.spheres.len();
    let mut mask = vec![0u64; n.div_ceil(64)];
    let counts: Vec<u32> = mask
        .par_chunks_mut(WORDS_PER_CHUNK)
        .zip(layout.spheres.par_chunks(CHUNK))
        .map(|(words, spheres)| test_chunk(planes, spheres, words))
        .collect();
    let chunk_start = exclusive_prefix(&counts);
    let total = chunk_start.last().copied().unwrap_or(0) as usize;

    let mut visible = vec![0u32; total];
    let mut slices = Vec::with_capacity(counts.len());
    let mut rest = visible.as_mut_slice();
    for &c in &counts {
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
    let mut draws = vec![DrawArgs::default(); layout.meshes.len()];
    let mut draw_count = 0;
    for m in &layout.meshes {
        let offset = visible_before(m.cull_start as usize);
        let count = visible_before((m.cull_start + m.cull_count) as usize) - offset;
        if count > 0 {
            draws[draw_count] = DrawArgs {
                index_count: m.index_count,
                instance_count: views * count,
                first_index: m.first_index,
                base_vertex: m.base_vertex,
                first_instance: views * offset,
            };
            draw_count += 1;
        }
    }
    CullOutput {
        visible,
        draws,
        draw_count: draw_count as u32,
    }
}

fn test_chunk(planes: &[Vec4; 6], spheres: &[Vec4], words: &mut [u64]) -> u32 {
    let mut count = 0;
    for (word, group) in words.iter_mut().zip(spheres.chunks(64)) {
        let mut bits = 0u64;
        for (i, s) in group.iter().enumerate() {
            bits |= (sphere_in_planes(planes, *s) as u64) << i;
        }
        *word = bits;
        count += bits.count_ones();
    }
    count
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
