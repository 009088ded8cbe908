//! The frame level's global shadow map (the chapter's `DoRenderFrame`: view-independent
//! passes once per frame): one directional light, its orthographic view fitted to what
//! the displays can see, culled by the same cull passes as a display (the light is one
//! more view with its own box of planes), drawn depth-only with one indirect call, and
//! sampled with percentage-closer filtering by every display and both eyes.

use glam::{DMat4, DVec3, Mat4, Vec3, Vec4};

use crate::cull::CullJob;
use crate::frustum::ROUNDING_SLACK;
use crate::rig::ResolvedRig;

/// The frame's light and its shadow map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    /// Towards the light (any length but zero): light travels along its negation.
    pub direction: Vec3,
    /// Texels along each side of the shadow map.
    pub shadow_map_size: u32,
    /// Meters from the viewer that receive shadows: the shadow map covers every
    /// display frustum up to this distance (or its far plane, if nearer).
    pub shadow_distance: f32,
}

impl Default for Light {
    /// High and to one side, as the built-in shading has always lit scenes.
    fn default() -> Light {
        Light {
            direction: Vec3::new(0.371_390_7, 0.742_781_3, 0.557_086),
            shadow_map_size: 2048,
            shadow_distance: 40.0,
        }
    }
}

/// Meters beyond the lit volume, towards the light, whose casters still shade it.
const CASTER_REACH: f64 = 200.0;

impl Light {
    /// Towards the light, unit length, in f64: what a fitted box is oriented by and
    /// what every light view, fitted or not, shades with.
    fn towards(&self) -> DVec3 {
        self.direction.as_dvec3().normalize_or(DVec3::Y)
    }
}

/// The light's view for one frame: an orthographic box along the light, holding a
/// sphere around every display frustum (cut at the shadow distance) and reaching
/// `CASTER_REACH` further towards the light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightView {
    /// World to the shadow map's clip space (x, y in -1..1, depth 0..1).
    pub clip_from_world: Mat4,
    /// The box's planes, inside when `dot(n, p) + d >= 0`, pushed out by rounding slack:
    /// what the light's cull tests.
    pub planes: [Vec4; 6],
    /// Where light comes from (unit).
    pub direction: Vec3,
}

impl LightView {
    /// The frame's light without a shadow map: its direction alone. Nothing reads
    /// `clip_from_world` then (the draw tests `shadows` first), so it is the identity
    /// and the box holds everything; fitting the box takes a latch's time
    /// ([`crate::renderer::Renderer::latch`]) for nothing.
    pub fn unfitted(light: &Light) -> LightView {
        LightView {
            clip_from_world: Mat4::IDENTITY,
            planes: [Vec4::W; 6],
            direction: light.towards().as_vec3(),
        }
    }

    /// Fitted to `resolved`'s displays (every eye, each cut at the shadow distance).
    pub fn fit(light: &Light, resolved: &ResolvedRig) -> LightView {
        // Fitted to every display planned for, drawn or not: a subset casts the shadows
        // the whole rig does.
        let points: Vec<DVec3> = resolved
            .frame_displays()
            .flat_map(|d| d.eyes.iter())
            .flat_map(|e| {
                let mut near = *e;
                near.far = near.far.min(light.shadow_distance.max(near.near * 2.0));
                near.corners()
            })
            .collect();
        let center = points.iter().sum::<DVec3>() / points.len().max(1) as f64;
        let radius = points
            .iter()
            .map(|p| p.distance(center))
            .fold(1e-3, f64::max);
        Self::around(light.towards(), center, radius)
    }

    /// The box of half-width `radius` around `center` along `back` (unit, towards the
    /// light).
    fn around(back: DVec3, center: DVec3, radius: f64) -> LightView {
        let side = back.any_orthonormal_vector();
        let up = back.cross(side);
        let eye = center + back * (radius + CASTER_REACH);
        let depth = 2.0 * radius + CASTER_REACH;
        // Rows: x across (side), y across (up), depth along the light from `eye`, 0..1.
        let row = |axis: DVec3, scale: f64| (axis * scale).extend(-axis.dot(eye) * scale);
        let clip_from_world = DMat4::from_cols(
            row(side, 1.0 / radius),
            row(up, 1.0 / radius),
            row(-back, 1.0 / depth),
            glam::DVec4::W,
        )
        .transpose();
        // Inside: within `radius` of the axis across, and between the eye and `depth`.
        let offset = |n: DVec3, through: DVec3| {
            let magnitude = through.abs().element_sum() + radius;
            n.extend(-n.dot(through) + ROUNDING_SLACK as f64 * magnitude)
        };
        let planes = [
            offset(side, center - side * radius),
            offset(-side, center + side * radius),
            offset(up, center - up * radius),
            offset(-up, center + up * radius),
            offset(-back, eye),
            offset(back, eye - back * depth),
        ];
        LightView {
            clip_from_world: clip_from_world.as_mat4(),
            planes: planes.map(|p| p.as_vec4()),
            direction: back.as_vec3(),
        }
    }

    /// The light's cull: its box, one instance per visible object.
    pub fn cull_job(&self) -> CullJob {
        CullJob {
            planes: self.planes,
            instances_per_object: 1,
            split: None,
            hidden: None,
            tiles: None,
            // The light's context has its one view at the origin.
            sort_origin: Vec3::ZERO,
        }
    }
}

/// The shadow map's depth format.
pub const SHADOW_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
