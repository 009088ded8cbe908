//! glTF materials: base color textures (decoded with `image` from buffer views, data
//! URIs or files), the materials that use them, and the UVs they are read at.

use std::path::Path;

use base64::Engine;
use base64::engine::general_purpose::STANDARD as BASE64;
use gltf::{Document, Semantic};
use image::RgbaImage;

use super::{Importer, Step, check_accessor};
use crate::scene::{AlphaMode, Material, Shading, Texture};

impl Importer<'_> {
    /// The texture coordinates the base color texture reads (its `texCoord` set), or
    /// zeros for untextured materials.
    pub(super) fn uvs(
        &self,
        primitive: &gltf::Primitive,
        where_: &str,
        count: usize,
    ) -> Step<Vec<[f32; 2]>> {
        let Some(info) = primitive
            .material()
            .pbr_metallic_roughness()
            .base_color_texture()
        else {
            return Ok(vec![[0.0; 2]; count]);
        };
        let set = info.tex_coord();
        if let Some(accessor) = primitive.get(&Semantic::TexCoords(set)) {
            let what = format!("{where_} TEXCOORD_{set}");
            check_accessor(&accessor, accessor.size(), &what)?;
            // The gltf crate's reader is `unreachable!` on any other component type, and
            // asserts two components.
            use gltf::accessor::DataType::{F32, U8, U16};
            let vec2 = accessor.dimensions() == gltf::accessor::Dimensions::Vec2;
            if !matches!(accessor.data_type(), F32 | U8 | U16) || !vec2 {
                return Err(format!(
                    "{what}: accessors[{}] holds {:?} {:?}; texture coordinates are VEC2 of float, unsigned byte or unsigned short",
                    accessor.index(),
                    accessor.dimensions(),
                    accessor.data_type()
                ));
            }
        }
        let buffers = self.buffers;
        let uvs: Vec<[f32; 2]> = primitive
            .reader(|b| buffers.get(b.index()).map(|d| &d.0[..]))
            .read_tex_coords(set)
            .ok_or_else(|| format!("{where_}: its material's base color texture reads TEXCOORD_{set}, which it lacks"))?
            .into_f32()
            .collect();
        if uvs.len() != count {
            return Err(format!(
                "{where_}: TEXCOORD_{set} and POSITION differ in count"
            ));
        }
        Ok(uvs)
    }

    /// Our material for a glTF material, created on first use (with its base color
    /// texture decoded).
    pub(super) fn material_id(&mut self, material: &gltf::Material) -> Step<u32> {
        if let Some(&id) = self.materials.get(&material.index()) {
            return Ok(id);
        }
        let base_color_texture = match material.pbr_metallic_roughness().base_color_texture() {
            Some(info) => Some(self.texture_id(info.texture().source())?),
            None => None,
        };
        let name = match material.index() {
            Some(i) => material
                .name()
                .map_or_else(|| format!("material {i}"), str::to_string),
            None => "default".into(),
        };
        let alpha = alpha_mode(material).map_err(|e| format!("material {name:?}: {e}"))?;
        self.scene.materials.push(Material {
            name,
            base_color_texture,
            alpha,
            shading: match material.unlit() {
                true => Shading::Unlit,
                false => Shading::Lit,
            },
        });
        let id = self.scene.materials.len() as u32 - 1;
        self.materials.insert(material.index(), id);
        Ok(id)
    }

    fn texture_id(&mut self, image: gltf::Image) -> Step<u32> {
        if let Some(&id) = self.textures.get(&image.index()) {
            return Ok(id);
        }
        let name = image
            .name()
            .map_or_else(|| format!("image {}", image.index()), str::to_string);
        let decoded = self
            .decode(&image)
            .map_err(|e| format!("image {} ({name}): {e}", image.index()))?;
        self.scene.textures.push(Texture {
            name,
            image: decoded,
        });
        let id = self.scene.textures.len() as u32 - 1;
        self.textures.insert(image.index(), id);
        Ok(id)
    }

    /// The image's pixels as sRGB RGBA8, from a buffer view, a data URI or a file.
    fn decode(&self, image: &gltf::Image) -> Step<RgbaImage> {
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
        let decoded = image::load_from_memory(bytes).map_err(|e| e.to_string())?;
        Ok(decoded.to_rgba8())
    }
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
