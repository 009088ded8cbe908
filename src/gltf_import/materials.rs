//! glTF materials: the metallic-roughness model's factors and textures (decoded with
//! `image`, or from KTX2 by `crate::basisu`, from buffer views, data URIs or files; colors
//! sRGB, data linear),
//! `KHR_materials_unlit`, `KHR_materials_emissive_strength` and `KHR_texture_transform`
//! (one per material), and the UVs the textures are read at.

use std::path::Path;

use base64::Engine;
use base64::engine::general_purpose::STANDARD as BASE64;
use gltf::{Document, Semantic};
use image::RgbaImage;

use super::{Importer, Step};
use crate::basisu::{self, BasisTexture};
use crate::ktx2_raw;
use crate::scene::{AlphaMode, Encoding, Material, SecondUv, Shading, Texture};

/// A material's texture slots: what it reads, and the set of coordinates and the
/// transform each reads them with.
fn slots<'a>(material: &gltf::Material<'a>) -> Vec<(gltf::texture::Info<'a>, Encoding)> {
    let pbr = material.pbr_metallic_roughness();
    [
        pbr.base_color_texture().map(|t| (t, Encoding::Srgb)),
        pbr.metallic_roughness_texture()
            .map(|t| (t, Encoding::Linear)),
        material.emissive_texture().map(|t| (t, Encoding::Srgb)),
    ]
    .into_iter()
    .flatten()
    .collect()
}

/// The coordinate set each texture slot of the material reads (its `texCoord`, or its
/// `KHR_texture_transform`'s override where the crate reads one: not for the normal and
/// occlusion maps), with the slot.
fn slot_sets(material: &gltf::Material) -> Vec<(u32, SecondUv)> {
    let info = |t: &gltf::texture::Info| {
        (t.texture_transform().and_then(|x| x.tex_coord())).unwrap_or(t.tex_coord())
    };
    let pbr = material.pbr_metallic_roughness();
    [
        pbr.base_color_texture()
            .map(|t| (info(&t), SecondUv::BASE_COLOR)),
        (pbr.metallic_roughness_texture()).map(|t| (info(&t), SecondUv::METALLIC_ROUGHNESS)),
        material
            .emissive_texture()
            .map(|t| (info(&t), SecondUv::EMISSIVE)),
        material
            .normal_texture()
            .map(|t| (t.tex_coord(), SecondUv::NORMAL)),
        (material.occlusion_texture()).map(|t| (t.tex_coord(), SecondUv::OCCLUSION)),
    ]
    .into_iter()
    .flatten()
    .collect()
}

/// The sets of coordinates a material's textures read, ascending (at most two: a vertex
/// keeps two), and the slots that read the second of them.
pub(super) fn uv_sets(material: &gltf::Material) -> Step<(Vec<u32>, SecondUv)> {
    let slots = slot_sets(material);
    let mut sets: Vec<u32> = slots.iter().map(|&(set, _)| set).collect();
    sets.sort_unstable();
    sets.dedup();
    if sets.len() > 2 {
        let named: Vec<String> = sets.iter().map(|s| format!("TEXCOORD_{s}")).collect();
        return Err(format!(
            "material {:?}'s textures read {}; two sets per material are read",
            material.name().unwrap_or(""),
            named.join(", ")
        ));
    }
    let second = (slots.iter())
        .filter(|&&(set, _)| sets.len() == 2 && set == sets[1])
        .fold(SecondUv::default(), |all, &(_, slot)| all | slot);
    Ok((sets, second))
}

impl Importer<'_> {
    /// The texture coordinates the material's textures read: the first set of
    /// [`uv_sets`] (zeros for untextured materials) and the second (zeros where one set
    /// is read).
    pub(super) fn uvs(
        &self,
        primitive: &gltf::Primitive,
        where_: &str,
        count: usize,
    ) -> Step<[Vec<[f32; 2]>; 2]> {
        let (sets, _) = uv_sets(&primitive.material()).map_err(|e| format!("{where_}: {e}"))?;
        let mut read = [vec![[0.0; 2]; count], vec![[0.0; 2]; count]];
        for (uvs, &set) in read.iter_mut().zip(&sets) {
            let accessor = primitive.get(&Semantic::TexCoords(set)).ok_or_else(|| {
                format!("{where_}: its material's textures read TEXCOORD_{set}, which it lacks")
            })?;
            *uvs = self.floats::<2>(&accessor, &format!("{where_} TEXCOORD_{set}"))?;
            if uvs.len() != count {
                return Err(format!(
                    "{where_}: TEXCOORD_{set} and POSITION differ in count"
                ));
            }
        }
        Ok(read)
    }

    /// Our material for a glTF material, created on first use (with its base color
    /// texture decoded).
    pub(super) fn material_id(&mut self, material: &gltf::Material) -> Step<u32> {
        if let Some(&id) = self.materials.get(&material.index()) {
            return Ok(id);
        }
        let name = match material.index() {
            Some(i) => material
                .name()
                .map_or_else(|| format!("material {i}"), str::to_string),
            None => "default".into(),
        };
        let alpha = alpha_mode(material).map_err(|e| format!("material {name:?}: {e}"))?;
        let (_, second_uv) = uv_sets(material)?;
        let pbr = material.pbr_metallic_roughness();
        let mut texture = |info: Option<gltf::Texture>, encoding| match info {
            Some(t) => {
                let image = texture_source(&t, self.document)?;
                self.texture_id(image, encoding).map(Some)
            }
            None => Ok(None),
        };
        let normal = material.normal_texture();
        let occlusion = material.occlusion_texture();
        let built = Material {
            base_color_texture: texture(
                pbr.base_color_texture().map(|t| t.texture()),
                Encoding::Srgb,
            )?,
            metallic_roughness_texture: texture(
                pbr.metallic_roughness_texture().map(|t| t.texture()),
                Encoding::Linear,
            )?,
            normal_texture: texture(normal.as_ref().map(|t| t.texture()), Encoding::Linear)?,
            occlusion_texture: texture(occlusion.as_ref().map(|t| t.texture()), Encoding::Linear)?,
            emissive_texture: texture(
                material.emissive_texture().map(|t| t.texture()),
                Encoding::Srgb,
            )?,
            alpha,
            shading: match material.unlit() {
                true => Shading::Unlit,
                false => Shading::Lit,
            },
            metallic: pbr.metallic_factor(),
            roughness: pbr.roughness_factor(),
            normal_scale: normal.map_or(1.0, |t| t.scale()),
            occlusion_strength: occlusion.map_or(1.0, |t| t.strength()),
            emissive: glam::Vec3::from(material.emissive_factor()),
            emissive_strength: material.emissive_strength().unwrap_or(1.0),
            uv_transform: uv_transform(material, &name),
            second_uv,
            name,
        };
        crate::materials::check_factors(&built).map_err(|e| e.to_string())?;
        self.scene.materials.push(built);
        let id = self.scene.materials.len() as u32 - 1;
        self.materials.insert(material.index(), id);
        Ok(id)
    }

    /// Our texture for a glTF image read as `encoding` (an image read both ways is
    /// two textures, one in each array).
    fn texture_id(&mut self, image: gltf::Image, encoding: Encoding) -> Step<u32> {
        if let Some(&id) = self.textures.get(&(image.index(), encoding)) {
            return Ok(id);
        }
        let name = image
            .name()
            .map_or_else(|| format!("image {}", image.index()), str::to_string);
        let (decoded, basis) = self
            .decode(&image, encoding)
            .map_err(|e| format!("image {} ({name}): {e}", image.index()))?;
        self.scene.textures.push(Texture {
            name,
            image: decoded,
            encoding,
            basis: basis.map(std::sync::Arc::new),
        });
        let id = self.scene.textures.len() as u32 - 1;
        self.textures.insert((image.index(), encoding), id);
        Ok(id)
    }

    /// The image's pixels as RGBA8 (PNG, JPEG, KTX2 of plain texels read as `encoding`,
    /// or KTX2 with Basis Universal texels, then kept too), from a buffer view, a data
    /// URI or a file.
    fn decode(
        &self,
        image: &gltf::Image,
        encoding: Encoding,
    ) -> Step<(RgbaImage, Option<BasisTexture>)> {
        let owned;
        let bytes: &[u8] = match image.source() {
            gltf::image::Source::View { view, .. } => {
                let buffer = self.buffers.get(view.buffer().index()).map(|d| &d.0[..]);
                buffer
                    .and_then(|b| b.get(view.offset()..view.offset() + view.length()))
                    .ok_or_else(|| {
                        format!("bufferViews[{}] lies outside its buffer", view.index())
                    })?
            }
            gltf::image::Source::Uri { uri, .. } => {
                owned = match uri.strip_prefix("data:") {
                    Some(data) => {
                        let (_, payload) = data
                            .split_once(";base64,")
                            .ok_or("a data URI that is not base64")?;
                        BASE64.decode(payload).map_err(|e| e.to_string())?
                    }
                    None => {
                        let base = self
                            .base
                            .ok_or("an external file, but the scene has no directory")?;
                        let path = base.join(uri);
                        std::fs::read(&path).map_err(|e| format!("{}: {e}", path.display()))?
                    }
                };
                &owned
            }
        };
        if basisu::is_ktx2(bytes) {
            if let Some(texels) = ktx2_raw::decode(bytes, encoding)? {
                return Ok((texels, None));
            }
            let basis = BasisTexture::from_ktx2(bytes)?;
            return Ok((basis.rgba()?, Some(basis)));
        }
        let decoded = image::load_from_memory(bytes).map_err(|e| e.to_string())?;
        Ok((decoded.to_rgba8(), None))
    }
}

/// The texture's image: its `KHR_texture_basisu` source where it names one (the
/// extension's own choice when both are given), else its core `source`.
fn texture_source<'a>(
    texture: &gltf::Texture<'a>,
    document: &'a Document,
) -> Step<gltf::Image<'a>> {
    const BASISU: &str = "KHR_texture_basisu";
    let basisu =
        (texture.extension_value(BASISU)).map(|e| e.get("source").and_then(|s| s.as_u64()));
    let index = match basisu {
        Some(Some(i)) => Some(i as usize),
        Some(None) => {
            return Err(format!(
                "textures[{}]: its {BASISU} names no image source",
                texture.index()
            ));
        }
        None => texture.source().map(|i| i.index()),
    };
    let index = index.ok_or_else(|| format!("textures[{}] has no image", texture.index()))?;
    document.images().nth(index).ok_or_else(|| {
        format!(
            "textures[{}] names images[{index}], which does not exist",
            texture.index()
        )
    })
}

/// The material's `KHR_texture_transform`: its base color texture's, else the first
/// of its textures that has one (we keep one transform per material; a material whose
/// textures differ is drawn with the first and logged). Its `texCoord` override is not
/// read: one set of coordinates per vertex.
fn uv_transform(material: &gltf::Material, name: &str) -> glam::Affine2 {
    let transforms: Vec<glam::Affine2> = slots(material)
        .iter()
        .filter_map(|(t, _)| t.texture_transform())
        .map(|t| {
            let (s, c) = t.rotation().sin_cos();
            // glTF: T * R * S, R's rows (cos, sin) and (-sin, cos).
            let rotation = glam::Mat2::from_cols(glam::Vec2::new(c, -s), glam::Vec2::new(s, c));
            let scale = glam::Mat2::from_diagonal(t.scale().into());
            glam::Affine2::from_mat2_translation(rotation * scale, t.offset().into())
        })
        .collect();
    if transforms.windows(2).any(|w| w[0] != w[1]) {
        log::warn!("material {name:?}: its textures' transforms differ; the first applies to all");
    }
    transforms
        .first()
        .copied()
        .unwrap_or(glam::Affine2::IDENTITY)
}

/// The material's alpha mode; a cutoff must be a finite number (JSON can spell an
/// infinite one, `1e999`).
fn alpha_mode(material: &gltf::Material) -> Step<AlphaMode> {
    Ok(match material.alpha_mode() {
        gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
        gltf::material::AlphaMode::Blend => AlphaMode::Blend,
        gltf::material::AlphaMode::Mask => {
            let cutoff = material.alpha_cutoff().unwrap_or(0.5);
            if !cutoff.is_finite() {
                return Err(format!("alphaCutoff {cutoff} is not a finite number"));
            }
            AlphaMode::Mask { cutoff }
        }
    })
}

/// Every external image must exist, base color texture or not: a file whose images are
/// missing is broken, and saying so before importing beats rendering it half-textured.
pub(super) fn check_images(document: &Document, base: Option<&Path>) -> Step<()> {
    for image in document.images() {
        if let gltf::image::Source::Uri { uri, .. } = image.source()
            && !uri.starts_with("data:")
        {
            let path = base.unwrap_or(Path::new(".")).join(uri);
            if !path.exists() {
                return Err(format!(
                    "image {}: {} does not exist",
                    image.index(),
                    path.display()
                ));
            }
        }
    }
    Ok(())
}
