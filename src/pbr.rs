//! The built-in shading's CPU twin (`wgsl/shared/pbr.wgsl`, `wgsl/shared/lights.wgsl`):
//! glTF's metallic-roughness BRDF lit by the frame's light, the punctual lights and an
//! ambient term, with the same operations in the same order, so that tests can hold the GPU's pixels to it; and the tangents normal maps
//! need where a file has none.

use glam::{Vec2, Vec3, Vec4};

use crate::lights::LightRecord;
use crate::scene::{Vertex, pack_snorm8};

/// The light's radiance (`LIGHT_RADIANCE`): a white diffuse surface facing it reads 0.75.
pub const LIGHT_RADIANCE: f32 = 0.75 * std::f32::consts::PI;
/// The ambient light, as a share of the base color (`AMBIENT`).
pub const AMBIENT: f32 = 0.25;
/// The smallest perceptual roughness shaded (`MIN_ROUGHNESS`).
pub const MIN_ROUGHNESS: f32 = 0.045;

/// A surface point's material inputs, as `pbr_inputs` gives them (`Pbr` in WGSL).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pbr {
    /// Linear RGBA.
    pub base: Vec4,
    /// 0..=1.
    pub metallic: f32,
    /// Perceptual, `MIN_ROUGHNESS..=1`.
    pub roughness: f32,
    /// Unit, world space, the normal map applied, on the eye's side.
    pub normal: Vec3,
    /// 0..=1, of the ambient term.
    pub occlusion: f32,
    /// Linear RGB.
    pub emissive: Vec3,
}

/// The normal map's `texel` (0..1 per channel) on unit normal `n` with tangent `t`
/// (w: handedness), x and y scaled by `scale` (`perturbed_normal`).
pub fn perturbed_normal(n: Vec3, t: Vec4, texel: Vec3, scale: f32) -> Vec3 {
    let along = t.truncate() - n * n.dot(t.truncate());
    if along.dot(along) < 1e-12 {
        return n;
    }
    let tangent = along.normalize();
    let bitangent = n.cross(tangent) * if t.w >= 0.0 { 1.0 } else { -1.0 };
    let m = (texel * 2.0 - Vec3::ONE) * Vec3::new(scale, scale, 1.0);
    (tangent * m.x + bitangent * m.y + n * m.z).normalize()
}

/// The linear color of `p` seen along `to_eye` (from the surface to the eye, any
/// length), lit from unit direction `light`, `reaching` of the light arriving
/// (`pbr_shade`).
pub fn shade(p: &Pbr, to_eye: Vec3, light: Vec3, reaching: f32) -> Vec3 {
    let v = to_eye.normalize();
    let (terms, n_dot_l) = brdf(p, v, light);
    let direct = terms * (LIGHT_RADIANCE * n_dot_l * reaching);
    direct + p.base.truncate() * (AMBIENT * p.occlusion) + p.emissive
}

/// What the punctual `lights` bring to `p` at world point `at`, seen along `to_eye`
/// (`lights_shading`, every light summed in order: one outside a point's cluster gives
/// it nothing).
pub fn shade_lights(p: &Pbr, to_eye: Vec3, lights: &[LightRecord], at: Vec3) -> Vec3 {
    let v = to_eye.normalize();
    let mut sum = Vec3::ZERO;
    for l in lights {
        let (toward, radiance) = light_at(l, at);
        let (terms, n_dot_l) = brdf(p, v, toward);
        sum += terms * (radiance * n_dot_l);
    }
    sum
}

/// The direction toward light `l` from world point `p` and its radiance there
/// (`light_at` in WGSL): glTF's falloff, the inverse square windowed to zero at the
/// light's range, and a spot's cone.
pub fn light_at(l: &LightRecord, p: Vec3) -> (Vec3, Vec3) {
    if l.kind == 3 {
        return (-l.direction, l.color);
    }
    let to = l.position - p;
    let d2 = to.dot(to).max(1e-8);
    let d = d2.sqrt();
    let toward = to / d;
    let q = d2 / (l.range * l.range);
    let window = (1.0 - q * q).clamp(0.0, 1.0);
    let mut falloff = window * window / d2;
    if l.kind == 2 {
        let a = (l.direction.dot(-toward) * l.cone_scale + l.cone_offset).clamp(0.0, 1.0);
        falloff *= a * a;
    }
    (toward, l.color * falloff)
}

/// glTF's BRDF for unit `v` (to the eye) and `l` (to the light): the diffuse and
/// specular terms, and n . l (`brdf` in WGSL).
fn brdf(p: &Pbr, v: Vec3, l: Vec3) -> (Vec3, f32) {
    let clamp = |x: f32| x.clamp(0.0, 1.0);
    let light = l;
    let n = p.normal;
    let h = (light + v).normalize();
    let n_dot_l = clamp(n.dot(light));
    let n_dot_v = n.dot(v).clamp(1e-4, 1.0);
    let n_dot_h = clamp(n.dot(h));
    let v_dot_h = clamp(v.dot(h));
    let alpha = p.roughness * p.roughness;
    let a2 = alpha * alpha;
    let base = p.base.truncate();
    let f0 = Vec3::splat(0.04).lerp(base, p.metallic);
    let f1 = 1.0 - v_dot_h;
    let f2 = f1 * f1;
    let fresnel = f0 + (Vec3::ONE - f0) * (f2 * f2 * f1);
    let d = n_dot_h * n_dot_h * (a2 - 1.0) + 1.0;
    let distribution = a2 / (std::f32::consts::PI * d * d);
    let from_light = n_dot_v * (n_dot_l * n_dot_l * (1.0 - a2) + a2).sqrt();
    let from_eye = n_dot_l * (n_dot_v * n_dot_v * (1.0 - a2) + a2).sqrt();
    let visibility = 0.5 / (from_light + from_eye);
    let diffuse = (Vec3::ONE - fresnel) * (base * (1.0 - p.metallic)) / std::f32::consts::PI;
    let specular = fresnel * (distribution * visibility);
    (diffuse + specular, n_dot_l)
}

/// Per-vertex tangents from the triangles' texture coordinates (each triangle's
/// direction of +u, weighted by its area in uv, summed at its corners, then made
/// perpendicular to the vertex normal), with the handedness that makes the bitangent
/// point up the image (glTF's `v` runs down, a normal map's green up); a vertex whose
/// triangles give none keeps the tangent it has. For glTF primitives with a normal
/// map and no TANGENT.
pub fn generate_tangents(vertices: &mut [Vertex], indices: &[u32]) {
    let mut sums = vec![(Vec3::ZERO, Vec3::ZERO); vertices.len()];
    for t in indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| vertices[i as usize]);
        let (e1, e2) = (
            Vec3::from(b.position) - Vec3::from(a.position),
            Vec3::from(c.position) - Vec3::from(a.position),
        );
        let (d1, d2) = (
            Vec2::from(b.uv) - Vec2::from(a.uv),
            Vec2::from(c.uv) - Vec2::from(a.uv),
        );
        // Unnormalized by the uv area's determinant: larger triangles in uv weigh more.
        let sign = if d1.perp_dot(d2) < 0.0 { -1.0 } else { 1.0 };
        let along_u = (e1 * d2.y - e2 * d1.y) * sign;
        let along_v = (e2 * d1.x - e1 * d2.x) * sign;
        for &i in t {
            let sum = &mut sums[i as usize];
            *sum = (sum.0 + along_u, sum.1 + along_v);
        }
    }
    for (v, (u_dir, v_dir)) in vertices.iter_mut().zip(sums) {
        let n = Vec3::from(v.normal).normalize_or_zero();
        let along = u_dir - n * n.dot(u_dir);
        if along.length_squared() > 1e-20 && n != Vec3::ZERO {
            let handedness = if n.cross(along).dot(v_dir) > 0.0 {
                -1.0
            } else {
                1.0
            };
            v.tangent = pack_snorm8(along.normalize().extend(handedness));
        }
    }
}
