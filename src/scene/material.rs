//! What a surface is made of: materials (glTF's metallic-roughness model, an alpha
//! mode and a shading function) and the textures they read.

use glam::Vec3;

/// What a surface is made of, beyond the instance's color (which multiplies it): glTF's
/// metallic-roughness model. Textures are indices into [`super::Scene::textures`]; base color
/// and emissive ones must be [`Encoding::Srgb`], the others [`Encoding::Linear`].
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// As the file names it (or empty).
    pub name: String,
    /// Index into [`super::Scene::textures`], sampled at the vertices' `uv`.
    pub base_color_texture: Option<u32>,
    /// How the base color's alpha covers what lies behind (glTF's `alphaMode`).
    pub alpha: AlphaMode,
    /// The shading function: its pipeline.
    pub shading: Shading,
    /// Metalness, 0 (dielectric) to 1 (metal); times the blue channel of
    /// `metallic_roughness_texture`.
    pub metallic: f32,
    /// Perceptual roughness, 0 (mirror) to 1; times the green channel of
    /// `metallic_roughness_texture`.
    pub roughness: f32,
    /// glTF's `metallicRoughnessTexture` (linear).
    pub metallic_roughness_texture: Option<u32>,
    /// A tangent-space normal map (linear), read through the vertices' tangents.
    pub normal_texture: Option<u32>,
    /// Scales the normal map's x and y.
    pub normal_scale: f32,
    /// Ambient occlusion in the red channel (linear).
    pub occlusion_texture: Option<u32>,
    /// How much of the occlusion applies: 0 none, 1 all.
    pub occlusion_strength: f32,
    /// Emitted linear RGB (glTF's `emissiveFactor` times `KHR_materials_emissive_strength`).
    pub emissive: Vec3,
    /// Times `emissive` (sRGB).
    pub emissive_texture: Option<u32>,
    /// Times `emissive`: glTF's `KHR_materials_emissive_strength`, for emission past 1.
    pub emissive_strength: f32,
    /// Maps the vertices' coordinates to every texture's (glTF's
    /// `KHR_texture_transform`, one per material): `uv' = matrix2 * uv + translation`.
    pub uv_transform: glam::Affine2,
    /// The texture slots that read the vertices' second set of coordinates
    /// ([`super::Vertex::uv1`]); the others read [`super::Vertex::uv`].
    pub second_uv: SecondUv,
}

/// A set of texture slots, a bit each: those of a material that read
/// [`super::Vertex::uv1`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct SecondUv(pub u32);

impl SecondUv {
    /// The base color texture (`BASE_COLOR_SLOT` in `wgsl/shared/base_color.wgsl`).
    pub const BASE_COLOR: SecondUv = SecondUv(1);
    /// The metallic-roughness texture.
    pub const METALLIC_ROUGHNESS: SecondUv = SecondUv(2);
    /// The normal map.
    pub const NORMAL: SecondUv = SecondUv(4);
    /// The occlusion texture.
    pub const OCCLUSION: SecondUv = SecondUv(8);
    /// The emissive texture.
    pub const EMISSIVE: SecondUv = SecondUv(16);
}

impl std::ops::BitOr for SecondUv {
    type Output = SecondUv;
    fn bitor(self, other: SecondUv) -> SecondUv {
        SecondUv(self.0 | other.0)
    }
}

impl Default for Material {
    /// Opaque, lit, untextured: a rough dielectric (what scenes without glTF materials
    /// draw with), not glTF's default of a metal, which needs an environment to show.
    fn default() -> Material {
        Material {
            name: String::new(),
            base_color_texture: None,
            alpha: AlphaMode::Opaque,
            shading: Shading::Lit,
            metallic: 0.0,
            roughness: 0.5,
            metallic_roughness_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
            occlusion_texture: None,
            occlusion_strength: 1.0,
            emissive: Vec3::ZERO,
            emissive_texture: None,
            emissive_strength: 1.0,
            uv_transform: glam::Affine2::IDENTITY,
            second_uv: SecondUv::default(),
        }
    }
}

/// Which function shades a material's fragments: each is its own pipeline, so each
/// (shading, alpha mode) pair of a scene is a material bin ([`crate::bins`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Shading {
    /// The built-in lighting (or `RendererOptions::material`, which replaces it).
    #[default]
    Lit,
    /// The base color alone (glTF's `KHR_materials_unlit`).
    Unlit,
    /// The caller's WGSL `RendererOptions::hooks[i]`, a `fn material(s: Surface) ->
    /// vec4<f32>`.
    Hook(u32),
    /// A render pipeline of the caller's own, set per display with
    /// `Renderer::set_own_pipeline(display, i, ..)`: the bin's one multi-draw is issued
    /// with it (the GPU-driven modes; the shadow pass draws the bin's depth with the
    /// built-in pipelines).
    Own(u32),
}

/// How a material's alpha (the base color's, texture included) is read: glTF's
/// `alphaMode` and `alphaCutoff`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum AlphaMode {
    /// Alpha is ignored: the surface hides what lies behind.
    #[default]
    Opaque,
    /// A cutout: fragments whose alpha is below `cutoff` are not drawn, the rest are
    /// opaque (glTF's `MASK`; its default cutoff is 0.5).
    Mask {
        /// Alpha below this is a hole.
        cutoff: f32,
    },
    /// Glass: blended over what lies behind, by alpha (glTF's `BLEND`).
    Blend,
}

/// An image a material samples: RGBA, straight alpha.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// As the file names it (or empty).
    pub name: String,
    /// The texels.
    pub image: image::RgbaImage,
    /// What the texels hold: colors (sRGB) or data (linear).
    pub encoding: Encoding,
    /// The file's Basis Universal texels, every level, when it gave them (`image` then
    /// holds the largest level transcoded): a device that samples BC7 keeps them
    /// block-compressed. Shared, as scenes are cloned.
    pub basis: Option<std::sync::Arc<crate::basisu::BasisTexture>>,
}

/// How a texture's bytes map to values: the GPU decodes sRGB colors before filtering,
/// and must not decode data (normals, roughness, occlusion), so each encoding is its
/// own texture array.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Encoding {
    /// Colors: base color, emissive.
    #[default]
    Srgb,
    /// Data: metallic-roughness, normal and occlusion maps.
    Linear,
}
