//! Punctual lights (glTF's `KHR_lights_punctual`) and their clusters: clustered forward
//! shading, the clusters built once per display for both eyes.
//!
//! Each display divides its combined frustum (the one that holds both eyes, which the
//! cull already uses) into [`CLUSTERS`] froxels: [`CLUSTER_X`] x [`CLUSTER_Y`] tiles of
//! its normalized device coordinates, and [`CLUSTER_Z`] slices of view depth spaced
//! exponentially from [`CLUSTER_NEAR`] to [`CLUSTER_FAR`] (the first slice reaches
//! down to the apex, the last out to [`CLUSTER_BEYOND`]). A cluster keeps a bit per light
//! whose sphere of influence touches its box in the display's view space
//! ([`cluster_bits`], `wgsl/light_clusters.wgsl` on the GPU, byte for byte alike).
//!
//! Why one grid serves both eyes: a fragment looks its cluster up from its own world
//! position, carried into the display's combined frustum, never from the eye that
//! drew it. Both eyes' fragments lie inside that frustum (it holds both eyes'), and the
//! cluster a world point falls in is the same whichever eye sees it; its bits name
//! every light whose sphere reaches any point of the cluster, so the point's lights are
//! among them. A fragment on a cluster's face may round into its neighbour: a light
//! that reaches it reaches within rounding of that neighbour too, where its falloff
//! window is already near zero.
//!
//! Lights shade without shadows; the frame's directional light with its shadow map
//! stays what it was. A scene holds at most [`MAX_LIGHTS`]; more is an error naming
//! the budget.

use encase::ShaderType;
use glam::{Mat4, Vec3};

/// The most lights a scene may hold: a cluster keeps a bit for each (`rooms:20000`'s
/// lamps, one per room, and 256 more fit).
pub const MAX_LIGHTS: usize = 2048;
/// Tiles across a display's combined frustum.
pub const CLUSTER_X: u32 = 16;
/// Tiles down it.
pub const CLUSTER_Y: u32 = 16;
/// Depth slices.
pub const CLUSTER_Z: u32 = 24;
/// Clusters per display.
pub const CLUSTERS: u32 = CLUSTER_X * CLUSTER_Y * CLUSTER_Z;
/// Words of light bits per cluster.
pub const CLUSTER_WORDS: u32 = MAX_LIGHTS as u32 / 32;
/// Words of a cluster's record: a summary (bit `w` set where bit word `w` is not zero,
/// so that a fragment loads only the words that name lights), then the bit words.
pub const CLUSTER_RECORD_WORDS: u32 = CLUSTER_WORDS / 32 + CLUSTER_WORDS;
/// Meters of view depth where the second slice starts.
pub const CLUSTER_NEAR: f32 = 0.25;
/// Meters where the last slice starts.
pub const CLUSTER_FAR: f32 = 250.0;
/// Where the last slice's box ends: farther than anything a light reaches.
pub const CLUSTER_BEYOND: f32 = 1.0e6;
/// Words of a display's view in the views buffer: its combined frustum's view and
/// projection matrices, column by column.
pub const VIEW_WORDS: u32 = 32;
/// Words of the views buffer before the first display's view: the light count, then
/// each slice's starting depth and the last slice's end ([`slice_start`] of 0 to
/// [`CLUSTER_Z`]).
pub const HEADER_WORDS: u32 = 1 + CLUSTER_Z + 1;
/// Words of one display's cluster records in the clusters buffer.
pub const DISPLAY_WORDS: u32 = CLUSTERS * CLUSTER_RECORD_WORDS;
/// A light without a `range` reaches where its illuminance falls to this (lux).
pub const DIMMEST: f32 = 1.0 / 256.0;

/// What kind of light, with a spot's cone.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    /// From a point, in every direction.
    Point,
    /// From a point, within a cone around its direction: full inside `inner` radians
    /// of the axis, none past `outer`.
    Spot {
        /// Radians from the axis where the falloff starts.
        inner: f32,
        /// Radians from the axis where it ends.
        outer: f32,
    },
    /// From infinitely far, along its direction, everywhere (no shadow: the frame's
    /// shadowed light is its own).
    Directional,
}

/// One light, in world space, in glTF's units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    /// Its kind.
    pub kind: LightKind,
    /// Linear RGB.
    pub color: Vec3,
    /// Candela for points and spots, lux for directional lights.
    pub intensity: f32,
    /// Meters past which it gives nothing (glTF's `range`); `None`: where its
    /// illuminance falls to [`DIMMEST`].
    pub range: Option<f32>,
    /// Where it is (points and spots).
    pub position: Vec3,
    /// Which way its light travels, unit (spots and directional lights).
    pub direction: Vec3,
}

impl Light {
    /// A point light.
    pub fn point(position: Vec3, color: Vec3, intensity: f32, range: Option<f32>) -> Light {
        Light {
            kind: LightKind::Point,
            color,
            intensity,
            range,
            position,
            direction: Vec3::NEG_Z,
        }
    }

    /// Placed as a glTF light on a node of world transform `world`: at its origin,
    /// shining along its -z.
    pub fn place(&mut self, world: glam::Affine3A) {
        self.position = world.translation.into();
        self.direction = world
            .transform_vector3(Vec3::NEG_Z)
            .normalize_or(Vec3::NEG_Z);
    }

    /// How far it reaches: its range, or where it dims to [`DIMMEST`]; infinity for a
    /// directional light.
    pub fn reach(&self) -> f32 {
        match (self.kind, self.range) {
            (LightKind::Directional, _) => f32::INFINITY,
            (_, Some(r)) => r,
            (_, None) => (self.intensity.max(0.0) / DIMMEST).sqrt(),
        }
    }

    /// An error naming what is wrong: a value that is not finite, a negative
    /// intensity, a range not above 0, a cone not within 0 <= inner < outer <= pi/2.
    pub fn check(&self) -> Result<(), String> {
        let finite = self.color.is_finite()
            && self.intensity.is_finite()
            && self.position.is_finite()
            && self.direction.is_finite();
        if !finite || self.intensity < 0.0 || self.color.min_element() < 0.0 {
            return Err(format!(
                "{self:?}: color, intensity, position and direction must be finite, not negative"
            ));
        }
        if let Some(r) = self.range.filter(|r| !(r.is_finite() && *r > 0.0)) {
            return Err(format!("range {r} is not a positive number"));
        }
        if let LightKind::Spot { inner, outer } = self.kind {
            let right = std::f32::consts::FRAC_PI_2;
            if !(0.0 <= inner && inner < outer && outer <= right) {
                return Err(format!(
                    "cone {inner}..{outer} is not within 0 <= inner < outer <= pi/2"
                ));
            }
        }
        Ok(())
    }

    /// Its record as the shaders read it.
    pub fn record(&self) -> LightRecord {
        let (kind, scale, offset) = match self.kind {
            LightKind::Point => (1, 0.0, 1.0),
            LightKind::Spot { inner, outer } => {
                let scale = 1.0 / (inner.cos() - outer.cos()).max(1e-3);
                (2, scale, -outer.cos() * scale)
            }
            LightKind::Directional => (3, 0.0, 1.0),
        };
        LightRecord {
            position: self.position,
            range: self.reach(),
            color: self.color * self.intensity,
            kind,
            direction: self.direction.normalize_or(Vec3::NEG_Z),
            cone_scale: scale,
            cone_offset: offset,
        }
    }
}

/// A light as the shaders read it (`LightRecord` in `wgsl/shared/lights.wgsl`).
#[derive(Clone, Copy, Debug, Default, PartialEq, ShaderType)]
pub struct LightRecord {
    /// Where it is.
    pub position: Vec3,
    /// How far it reaches ([`Light::reach`]).
    pub range: f32,
    /// Its color times its intensity.
    pub color: Vec3,
    /// 0 none (an unused record), 1 point, 2 spot, 3 directional.
    pub kind: u32,
    /// Which way its light travels.
    pub direction: Vec3,
    /// A spot's cone: the light along `d` (unit, from the light) is scaled by
    /// `clamp(dot(direction, d) * cone_scale + cone_offset, 0, 1)` squared (glTF's
    /// recommended falloff); 0 and 1 for other kinds.
    pub cone_scale: f32,
    /// See `cone_scale`.
    pub cone_offset: f32,
}

/// The records of every cluster of a display whose combined frustum has
/// `view_from_world` and projection `clip_from_view`, for `lights`: per cluster (x
/// fastest, then y, then slice) [`CLUSTER_RECORD_WORDS`] words, the summary then bit
/// `i % 32` of bit word `i / 32` for light `i`, set where the light's sphere touches the
/// cluster's box. The GPU's pass sets the same bits (`wgsl/light_clusters.wgsl`),
/// testing only the clusters near each light; this twin tests every pair.
pub fn cluster_bits(
    lights: &[LightRecord],
    view_from_world: &Mat4,
    clip_from_view: &Mat4,
) -> Vec<u32> {
    let centers: Vec<Vec3> = (lights.iter())
        .map(|l| view_point(view_from_world, l.position))
        .collect();
    let summary = (CLUSTER_WORDS / 32) as usize;
    let mut records = vec![0u32; (CLUSTERS * CLUSTER_RECORD_WORDS) as usize];
    for (c, record) in records
        .chunks_exact_mut(CLUSTER_RECORD_WORDS as usize)
        .enumerate()
    {
        let (lo, hi) = cluster_box(c as u32, clip_from_view);
        for (i, (l, center)) in lights.iter().zip(&centers).enumerate() {
            if touches(l, *center, lo, hi) {
                let w = i / 32;
                record[summary + w] |= 1 << (i % 32);
                record[w / 32] |= 1 << (w % 32);
            }
        }
    }
    records
}

/// `m` times point `p`, summed left to right as `view_point` in WGSL.
fn view_point(m: &Mat4, p: Vec3) -> Vec3 {
    let (x, y, z, w) = (m.x_axis, m.y_axis, m.z_axis, m.w_axis);
    Vec3::new(
        x.x * p.x + y.x * p.y + z.x * p.z + w.x,
        x.y * p.x + y.y * p.y + z.y * p.z + w.y,
        x.z * p.x + y.z * p.y + z.z * p.z + w.z,
    )
}

/// The view depth where slice `k` starts (0 for the first).
pub fn slice_start(k: u32) -> f32 {
    match k {
        0 => 0.0,
        _ if k >= CLUSTER_Z => CLUSTER_BEYOND,
        _ => {
            CLUSTER_NEAR
                * (CLUSTER_FAR / CLUSTER_NEAR).powf((k - 1) as f32 / (CLUSTER_Z - 2) as f32)
        }
    }
}

/// Cluster `c`'s box in the display's view space (least and greatest corners).
fn cluster_box(c: u32, p: &Mat4) -> (Vec3, Vec3) {
    let (x, y, k) = (
        c % CLUSTER_X,
        (c / CLUSTER_X) % CLUSTER_Y,
        c / (CLUSTER_X * CLUSTER_Y),
    );
    let ndc = |i: u32, n: u32| 2.0 * i as f32 / n as f32 - 1.0;
    let (d0, d1) = (slice_start(k), slice_start(k + 1));
    // Off-axis perspective: ndc.x * d = p00 * x - p20 * d, so x = d * (ndc.x + p20) / p00.
    let across = |n0: f32, n1: f32, scale: f32, shift: f32| {
        let at = [
            d0 * (n0 + shift) / scale,
            d0 * (n1 + shift) / scale,
            d1 * (n0 + shift) / scale,
            d1 * (n1 + shift) / scale,
        ];
        let lo = at[0].min(at[1]).min(at[2].min(at[3]));
        let hi = at[0].max(at[1]).max(at[2].max(at[3]));
        (lo, hi)
    };
    let (x0, x1) = across(
        ndc(x, CLUSTER_X),
        ndc(x + 1, CLUSTER_X),
        p.x_axis.x,
        p.z_axis.x,
    );
    let (y0, y1) = across(
        ndc(y, CLUSTER_Y),
        ndc(y + 1, CLUSTER_Y),
        p.y_axis.y,
        p.z_axis.y,
    );
    (Vec3::new(x0, y0, -d1), Vec3::new(x1, y1, -d0))
}

/// Whether light `l` (its center in view space) reaches into the box.
fn touches(l: &LightRecord, center: Vec3, lo: Vec3, hi: Vec3) -> bool {
    match l.kind {
        0 => false,
        3 => true,
        _ => {
            let d = center - center.clamp(lo, hi);
            d.x * d.x + d.y * d.y + d.z * d.z <= l.range * l.range
        }
    }
}
