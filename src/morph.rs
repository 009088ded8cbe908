//! Morph targets (glTF's blend shapes), frame-level work: once per frame, before the
//! skinning pass and every display, each morphed vertex becomes its rest plus every
//! target's offset times the target's weight (`wgsl/morph.wgsl`; [`morph_vertex`] is the
//! CPU twin), written into the one vertex buffer every display and eye draws from, or,
//! for a skinned mesh, into the skin's rest vertex, which the skinning pass then moves.
//!
//! Weights are the morph's defaults (the node's `weights`, else the mesh's) unless an
//! animation plays them: [`Morphs::set_time`] samples them on the CPU at the frame's
//! time (a few floats per morph), and the pass reads them from a small buffer.
//!
//! Culling: a morphed mesh is its node's own (the copies of one node share it), and its
//! bounding sphere holds every weighted pose the file can reach (and any of weights up
//! to 1): the rest sphere grown by the largest weight magnitude times the sum over
//! targets of the longest position offset ([`Morph::reach`]).

use bytemuck::{Pod, Zeroable};
use glam::{Vec3, Vec4};

use crate::pose::{Channel, Interpolation};

/// A morphed vertex at rest, as the pass reads it (`MorphVertex` in `wgsl/morph.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct MorphVertex {
    /// Its rest position (the mesh's space).
    pub position: [f32; 3],
    /// Its rest normal.
    pub normal: [f32; 3],
    /// Its rest tangent and handedness (`Snorm8x4`, as [`crate::scene::Vertex::tangent`]).
    pub tangent: [i8; 4],
    /// Its first offset in [`Morphs::deltas`]; one per target of its morph follows.
    pub first_delta: u32,
    /// Its morph's first weight in [`Morphs::weights`].
    pub first_weight: u32,
    /// Its morph's targets.
    pub targets: u32,
    /// What it writes: a vertex of the scene's vertices, or with `skinned` a skin's rest
    /// vertex ([`crate::skin::Skins::vertices`]).
    pub destination: u32,
    /// 1 where `destination` is a skin's rest vertex, else 0.
    pub skinned: u32,
}

/// One target's offsets of one vertex (`MorphDelta` in `wgsl/morph.wgsl`); zero for an
/// attribute the target does not move.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct MorphDelta {
    /// Added to the position, times the weight.
    pub position: [f32; 3],
    /// Added to the normal.
    pub normal: [f32; 3],
    /// Added to the tangent's xyz.
    pub tangent: [f32; 3],
}

/// One animation's channel of a morph's weights: four weights a [`Channel`] (its values
/// hold weights `4 * group ..`), looped over its animation's duration.
#[derive(Clone, Debug, PartialEq)]
pub struct WeightChannel {
    /// Which four of the morph's weights.
    pub group: u32,
    /// Its animation's duration (glTF: the latest key of any of its samplers).
    pub duration: f32,
    /// The keys.
    pub channel: Channel,
}

/// One node's morphed primitive (the node's copies draw it alike).
#[derive(Clone, Debug, PartialEq)]
pub struct Morph {
    /// The mesh it moves (a skinned one's: its skin's), which its instances draw.
    pub mesh: u32,
    /// Its weights when nothing plays them, one per target.
    pub defaults: Vec<f32>,
    /// What plays them, if anything.
    pub channels: Vec<WeightChannel>,
    /// Its first weight in [`Morphs::weights`].
    pub first_weight: u32,
}

/// A scene's morphed vertices, their targets' offsets, and the current weights.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Morphs {
    /// The morphs.
    pub morphs: Vec<Morph>,
    /// Every morph's vertices, in order.
    pub vertices: Vec<MorphVertex>,
    /// Every morphed vertex's offsets, per vertex its targets in order.
    pub deltas: Vec<MorphDelta>,
    /// Every morph's current weights, in order ([`Morphs::set_time`] writes them).
    pub weights: Vec<f32>,
}

impl Morphs {
    /// Whether nothing is morphed.
    pub fn is_empty(&self) -> bool {
        self.morphs.is_empty()
    }

    /// Sets every morph's weights to what its channels play at `time` seconds (its
    /// defaults where nothing plays a weight).
    pub fn set_time(&mut self, time: f32) {
        for m in &self.morphs {
            let first = m.first_weight as usize;
            let weights = &mut self.weights[first..first + m.defaults.len()];
            weights.copy_from_slice(&m.defaults);
            for c in &m.channels {
                let t = match c.duration > 0.0 {
                    true => time.rem_euclid(c.duration),
                    false => 0.0,
                };
                let value = c.channel.sample(t).to_array();
                let at = 4 * c.group as usize;
                for (w, v) in weights.iter_mut().skip(at).zip(value) {
                    *w = v;
                }
            }
        }
    }

    /// Morph `m`'s weights from now on `weights` (its channels stop): what an engine
    /// that plays its own blend shapes sets. An error where `weights` are not one per
    /// target, not finite, or past what the morph's culling sphere holds
    /// ([`Morph::weight_bound`]).
    pub fn set_weights(&mut self, m: usize, weights: &[f32]) -> Result<(), String> {
        let morph = (self.morphs.get_mut(m)).ok_or_else(|| format!("no morph {m}"))?;
        let bound = morph.weight_bound();
        if weights.len() != morph.defaults.len() {
            return Err(format!(
                "morph {m}: {} weights for {} targets",
                weights.len(),
                morph.defaults.len()
            ));
        }
        if let Some(w) = weights.iter().find(|w| !w.is_finite() || w.abs() > bound) {
            return Err(format!(
                "morph {m}: weight {w} is past {bound}, the largest its culling sphere holds (the file's own weights, or 1)"
            ));
        }
        morph.defaults = weights.to_vec();
        morph.channels.clear();
        let first = morph.first_weight as usize;
        self.weights[first..first + weights.len()].copy_from_slice(weights);
        Ok(())
    }

    /// Drops every channel: the weights stay at the defaults (`--animation off`).
    pub fn stop(&mut self) {
        for m in &mut self.morphs {
            m.channels.clear();
        }
        self.set_time(0.0);
    }
}

impl Morph {
    /// The largest magnitude any of its weights reaches: its defaults and every key of
    /// its channels; between two cubic keys at most the larger value plus 4/27 of the
    /// segment's length times the two tangents (the Hermite basis: the value terms are a
    /// convex blend, and each tangent's term peaks at 4/27).
    pub fn largest_weight(&self) -> f32 {
        let defaults = self.defaults.iter().fold(0.0f32, |m, w| m.max(w.abs()));
        (self.channels.iter()).fold(defaults, |m, c| m.max(channel_bound(&c.channel)))
    }

    /// The weights its culling sphere holds, in magnitude: [`Morph::largest_weight`],
    /// and at least 1 (glTF's customary range), so that an engine may play a file's
    /// blend shapes whose weights the file leaves at zero.
    pub fn weight_bound(&self) -> f32 {
        self.largest_weight().max(1.0)
    }

    /// How far its morph can move a vertex from rest: [`Morph::weight_bound`] times
    /// the sum over its targets of their longest position offset, given its vertices'
    /// offsets `deltas` (per vertex, its targets in order).
    pub fn reach(&self, deltas: &[MorphDelta]) -> f32 {
        let targets = self.defaults.len().max(1);
        let mut longest = vec![0.0f32; targets];
        for vertex in deltas.chunks(targets) {
            for (l, d) in longest.iter_mut().zip(vertex) {
                *l = l.max(Vec3::from(d.position).length());
            }
        }
        // Rounding in the weighted sums: grow by 2^-16 of the reach.
        let reach = self.weight_bound() * longest.iter().sum::<f32>();
        reach * (1.0 + 1.0 / 65536.0)
    }
}

/// The largest magnitude `c` reaches (see [`Morph::largest_weight`]).
fn channel_bound(c: &Channel) -> f32 {
    let size = |v: Vec4| v.abs().max_element();
    match c.interpolation {
        Interpolation::CubicSpline => {
            let keys: Vec<&[Vec4]> = c.values.chunks_exact(3).collect();
            let mut bound = keys.iter().fold(0.0f32, |m, k| m.max(size(k[1])));
            for (k, dt) in c.times.windows(2).enumerate() {
                let (a, b) = (keys[k], keys[k + 1]);
                let tangents = size(a[2]) + size(b[0]);
                let segment = size(a[1]).max(size(b[1])) + 4.0 / 27.0 * (dt[1] - dt[0]) * tangents;
                bound = bound.max(segment);
            }
            bound
        }
        _ => c.values.iter().fold(0.0, |m, &v| m.max(size(v))),
    }
}

/// The pass's CPU twin for one vertex: its position, normal and packed tangent with
/// `weights` (all of [`Morphs::weights`]) and `deltas` (all of [`Morphs::deltas`]), in
/// the pass's operations and order.
pub fn morph_vertex(
    v: &MorphVertex,
    deltas: &[MorphDelta],
    weights: &[f32],
) -> ([f32; 3], [f32; 3], [i8; 4]) {
    let mut position = Vec3::from(v.position);
    let mut normal = Vec3::from(v.normal);
    let rest = Vec4::from(v.tangent.map(|c| (f32::from(c) / 127.0).max(-1.0)));
    let mut tangent = rest.truncate();
    for t in 0..v.targets {
        let w = weights[(v.first_weight + t) as usize];
        let d = deltas[(v.first_delta + t) as usize];
        position += Vec3::from(d.position) * w;
        normal += Vec3::from(d.normal) * w;
        tangent += Vec3::from(d.tangent) * w;
    }
    let unit = tangent.normalize_or_zero().extend(rest.w);
    let packed = unit
        .to_array()
        .map(|c| (0.5 + 127.0 * c.clamp(-1.0, 1.0)).floor() as i8);
    (position.into(), normal.into(), packed)
}
