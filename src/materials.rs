//! Materials on the GPU, group 1 of the built-in draw pipelines: every texture of a
//! scene as one layer of one of two 2D texture arrays (resized to the array's common
//! size, with mipmaps), colors (sRGB, decoded before filtering) in one and data
//! (linear: metallic-roughness, normal and occlusion maps) in the other, so that a
//! textured scene still draws with one indirect call per bin and display; and one
//! [`MaterialRecord`] per material saying which layers it samples and its factors.
//!
//! Bindless texture arrays would skip the resize; lavapipe has none, and the arrays
//! work on every adapter, so they are the one path.

use bytemuck::{Pod, Zeroable};
use image::RgbaImage;
use image::imageops::FilterType;
use rayon::prelude::*;

use crate::basisu::BasisTexture;
use crate::bins::{check_override, mesh_material, vertex_material};
use crate::buffers::init_buffer;
use crate::error::{Error, Result};
use crate::scene::{AlphaMode, Encoding, Material, Scene, Texture};
use crate::shaders::Windows;

/// The largest layer side: bigger textures are scaled down to it.
pub const MAX_LAYER_SIZE: u32 = 1024;

// One record must fit the smallest buffer bound: an empty scene's.
const _: () = assert!(size_of::<MaterialRecord>() <= crate::buffers::MIN_BUFFER);

/// A material as the fragment stage reads it (`MaterialRecord` in
/// `wgsl/shared/records.wgsl`): layers of `color_textures` (base color, emissive) and
/// of `data_textures` (the rest), each [`MaterialRecord::UNTEXTURED`] when absent.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct MaterialRecord {
    /// [`Material::emissive`] times [`Material::emissive_strength`], linear RGB.
    pub emissive: [f32; 3],
    /// Layer of the color array.
    pub base_color_layer: u32,
    /// [`Material::uv_transform`]'s columns: `uv' = m[0] * u + m[1] * v + m[2]`.
    pub uv_transform: [[f32; 2]; 3],
    /// Fragments whose base color alpha is below this are discarded: a
    /// [`AlphaMode::Mask`]'s cutoff, 0 (nothing) otherwise.
    pub alpha_cutoff: f32,
    /// Layer of the data array: roughness in green, metalness in blue.
    pub metallic_roughness_layer: u32,
    /// Layer of the data array: the tangent-space normal map.
    pub normal_layer: u32,
    /// Layer of the data array: occlusion in red.
    pub occlusion_layer: u32,
    /// Layer of the color array.
    pub emissive_layer: u32,
    /// [`Material::metallic`].
    pub metallic: f32,
    /// [`Material::roughness`].
    pub roughness: f32,
    /// [`Material::normal_scale`].
    pub normal_scale: f32,
    /// [`Material::occlusion_strength`].
    pub occlusion_strength: f32,
    /// [`Material::second_uv`]: a bit per slot that reads the second coordinates.
    pub second_uv: u32,
}

impl MaterialRecord {
    /// No texture in this slot: the factor alone.
    pub const UNTEXTURED: u32 = u32::MAX;
}

/// Group 1's layout ([`crate::shaders::MATERIAL_BINDINGS`]).
pub fn bind_group_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    let list = &crate::shaders::MATERIAL_BINDINGS;
    crate::shaders::bind_group_layout(device, "stereocull.materials", list, &Windows::WHOLE)
}

/// The records of `scene`'s materials (one untextured record when it has none), after
/// checking that every vertex names a material, every mesh one material (its bin's,
/// [`crate::bins`]) and every material a texture.
pub fn records(scene: &Scene) -> Result<Vec<MaterialRecord>> {
    let count = scene.materials.len().max(1);
    for (m, mesh) in scene.meshes.iter().enumerate() {
        let material = mesh_material(scene, m);
        if material as usize >= count {
            return Err(Error::InvalidScene(format!(
                "mesh {m} ({:?}) names material {material} of {count}",
                mesh.name
            )));
        }
        check_one_material(scene, m)?;
    }
    if let Some(v) = scene.vertices.iter().find(|v| v.material as usize >= count) {
        return Err(Error::InvalidScene(format!(
            "a vertex names material {} of {count}",
            v.material
        )));
    }
    for instance in &scene.instances {
        check_override(scene, instance)?;
    }
    if scene.materials.is_empty() {
        return Ok(vec![record(scene, &Material::default())?]);
    }
    scene.materials.iter().map(|m| record(scene, m)).collect()
}

fn check_one_material(scene: &Scene, m: usize) -> Result<()> {
    let mesh = &scene.meshes[m];
    let first = mesh.first_index as usize;
    let indices = scene.indices.get(first..first + mesh.index_count as usize);
    let own = mesh_material(scene, m);
    let other = |&i: &u32| vertex_material(scene, mesh, i).filter(|&x| x != own);
    match indices.into_iter().flatten().find_map(other) {
        Some(other) => Err(Error::InvalidScene(format!(
            "mesh {m} ({:?}) mixes materials {own} and {other}: a mesh is drawn by one material's pipeline",
            mesh.name
        ))),
        None => Ok(()),
    }
}

fn record(scene: &Scene, m: &Material) -> Result<MaterialRecord> {
    let layer = |slot: Option<u32>, encoding: Encoding, what: &str| match slot {
        None => Ok(MaterialRecord::UNTEXTURED),
        Some(t) => texture_layer(scene, t, encoding)
            .map_err(|e| Error::InvalidScene(format!("material {:?} {e} ({what})", m.name))),
    };
    let alpha_cutoff = match m.alpha {
        AlphaMode::Mask { cutoff } if !cutoff.is_finite() => {
            return Err(Error::InvalidScene(format!(
                "material {:?} has alpha cutoff {cutoff}, not a finite number",
                m.name
            )));
        }
        AlphaMode::Mask { cutoff } => cutoff,
        AlphaMode::Opaque | AlphaMode::Blend => 0.0,
    };
    check_factors(m)?;
    let t = m.uv_transform;
    Ok(MaterialRecord {
        emissive: (m.emissive * m.emissive_strength).into(),
        base_color_layer: layer(m.base_color_texture, Encoding::Srgb, "base color")?,
        uv_transform: [
            t.matrix2.x_axis.into(),
            t.matrix2.y_axis.into(),
            t.translation.into(),
        ],
        alpha_cutoff,
        metallic_roughness_layer: layer(
            m.metallic_roughness_texture,
            Encoding::Linear,
            "metallic-roughness",
        )?,
        normal_layer: layer(m.normal_texture, Encoding::Linear, "normal map")?,
        occlusion_layer: layer(m.occlusion_texture, Encoding::Linear, "occlusion")?,
        emissive_layer: layer(m.emissive_texture, Encoding::Srgb, "emissive")?,
        metallic: m.metallic,
        roughness: m.roughness,
        normal_scale: m.normal_scale,
        occlusion_strength: m.occlusion_strength,
        second_uv: m.second_uv.0,
    })
}

/// Every factor must be a finite number (JSON can spell an infinite one, `1e999`).
pub(crate) fn check_factors(m: &Material) -> Result<()> {
    let t = m.uv_transform;
    let factors = [
        ("metallicFactor", m.metallic),
        ("roughnessFactor", m.roughness),
        ("normal scale", m.normal_scale),
        ("occlusion strength", m.occlusion_strength),
        ("emissive strength", m.emissive_strength),
    ];
    let bad = factors.into_iter().find(|(_, f)| !f.is_finite());
    if let Some((what, f)) = bad {
        return Err(Error::InvalidScene(format!(
            "material {:?} has {what} {f}, not a finite number",
            m.name
        )));
    }
    if !(m.emissive.is_finite() && t.is_finite()) {
        return Err(Error::InvalidScene(format!(
            "material {:?} has an emissive factor or texture transform that is not finite",
            m.name
        )));
    }
    Ok(())
}

/// Texture `t`'s layer in the array of its encoding, which must be `encoding`.
fn texture_layer(scene: &Scene, t: u32, encoding: Encoding) -> std::result::Result<u32, String> {
    let Some(texture) = scene.textures.get(t as usize) else {
        return Err(format!("names texture {t} of {}", scene.textures.len()));
    };
    if texture.encoding != encoding {
        return Err(format!(
            "reads texture {t} ({:?}), which holds {:?} texels; this slot reads {encoding:?}",
            texture.name, texture.encoding
        ));
    }
    let before = scene.textures[..t as usize].iter();
    Ok(before.filter(|x| x.encoding == encoding).count() as u32)
}

/// The side of every layer of an array: its largest texture's, within
/// [`MAX_LAYER_SIZE`] and the device's limit; 1 with no textures.
fn layer_size<'a>(textures: impl Iterator<Item = &'a RgbaImage>, device_max: u32) -> (u32, u32) {
    let fit = |side: u32| side.clamp(1, MAX_LAYER_SIZE.min(device_max));
    textures.fold((1, 1), |(w, h), t| {
        (w.max(fit(t.width())), h.max(fit(t.height())))
    })
}

/// `image` at `size`, then each mip level below it (halving to 1 x 1).
pub fn mip_chain(image: &RgbaImage, (w, h): (u32, u32)) -> Vec<RgbaImage> {
    let mut levels = vec![image::imageops::resize(image, w, h, FilterType::Triangle)];
    while let Some(last) = levels.last().filter(|l| l.width() > 1 || l.height() > 1) {
        let next = image::imageops::resize(
            last,
            (last.width() / 2).max(1),
            (last.height() / 2).max(1),
            FilterType::Triangle,
        );
        levels.push(next);
    }
    levels
}

/// A scene's materials on the GPU. The texels are written by the first
/// [`GpuMaterials::upload`] (the renderer's first `prepare`), which has the queue.
pub struct GpuMaterials {
    /// Group 1 of the draw pipelines: the two texture arrays, their sampler, the
    /// material records.
    pub bind_group: wgpu::BindGroup,
    arrays: [TextureArray; 2],
}

/// One encoding's textures as one array texture.
struct TextureArray {
    texture: wgpu::Texture,
    /// Per layer, its levels, until uploaded.
    pending: Vec<Vec<Level>>,
}

/// One mip level of one layer: RGBA8 texels or BC7 blocks, rows top to bottom.
struct Level {
    bytes: Vec<u8>,
    /// In texels; BC7's rounded up to whole blocks (the copy's physical size).
    size: (u32, u32),
    bytes_per_row: u32,
}

impl Level {
    fn rgba(image: RgbaImage) -> Level {
        Level {
            size: image.dimensions(),
            bytes_per_row: 4 * image.width(),
            bytes: image.into_raw(),
        }
    }
}

impl TextureArray {
    /// The array of `scene`'s textures of `encoding` (one white layer when it has
    /// none): BC7 where [`bc7_layers`] can, else RGBA8.
    fn new(device: &wgpu::Device, scene: &Scene, encoding: Encoding) -> Result<TextureArray> {
        let textures: Vec<&Texture> = (scene.textures.iter())
            .filter(|t| t.encoding == encoding)
            .collect();
        let limits = device.limits();
        let layers = textures.len().max(1) as u32;
        if layers > limits.max_texture_array_layers {
            return Err(Error::Limits(format!(
                "{layers} {encoding:?} textures; the device's texture arrays hold {}",
                limits.max_texture_array_layers
            )));
        }
        let (size, pending, format) = match bc7_layers(device, &textures)? {
            Some((size, pending)) => (size, pending, bc7_format(encoding)),
            None => {
                let (size, pending) = rgba_layers(&textures, limits.max_texture_dimension_2d);
                (size, pending, rgba_format(encoding))
            }
        };
        let label = match encoding {
            Encoding::Srgb => "stereocull.color_textures",
            Encoding::Linear => "stereocull.data_textures",
        };
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width: size.0,
                height: size.1,
                depth_or_array_layers: layers,
            },
            mip_level_count: pending[0].len() as u32,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        Ok(TextureArray { texture, pending })
    }

    fn view(&self) -> wgpu::TextureView {
        self.texture.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        })
    }

    /// Writes the texels on first use; returns the bytes written (0 afterwards).
    fn upload(&mut self, queue: &wgpu::Queue) -> u64 {
        let mut bytes = 0;
        for (layer, levels) in std::mem::take(&mut self.pending).into_iter().enumerate() {
            for (level, texels) in levels.iter().enumerate() {
                queue.write_texture(
                    wgpu::TexelCopyTextureInfo {
                        texture: &self.texture,
                        mip_level: level as u32,
                        origin: wgpu::Origin3d {
                            x: 0,
                            y: 0,
                            z: layer as u32,
                        },
                        aspect: wgpu::TextureAspect::All,
                    },
                    &texels.bytes,
                    wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(texels.bytes_per_row),
                        rows_per_image: None,
                    },
                    wgpu::Extent3d {
                        width: texels.size.0,
                        height: texels.size.1,
                        depth_or_array_layers: 1,
                    },
                );
                bytes += texels.bytes.len() as u64;
            }
        }
        bytes
    }
}

fn rgba_format(encoding: Encoding) -> wgpu::TextureFormat {
    match encoding {
        Encoding::Srgb => wgpu::TextureFormat::Rgba8UnormSrgb,
        Encoding::Linear => wgpu::TextureFormat::Rgba8Unorm,
    }
}

fn bc7_format(encoding: Encoding) -> wgpu::TextureFormat {
    match encoding {
        Encoding::Srgb => wgpu::TextureFormat::Bc7RgbaUnormSrgb,
        Encoding::Linear => wgpu::TextureFormat::Bc7RgbaUnorm,
    }
}

/// An array's size, and per layer its levels.
type Layers = ((u32, u32), Vec<Vec<Level>>);

/// Every texture resampled to the array's size, with its mip chain.
fn rgba_layers(textures: &[&Texture], device_max: u32) -> Layers {
    let size = layer_size(textures.iter().map(|t| &t.image), device_max);
    let white = RgbaImage::from_pixel(1, 1, WHITE);
    let images: Vec<&RgbaImage> = match textures.is_empty() {
        true => vec![&white],
        false => textures.iter().map(|t| &t.image).collect(),
    };
    let chain = |image: &RgbaImage| {
        mip_chain(image, size)
            .into_iter()
            .map(Level::rgba)
            .collect()
    };
    (size, images.into_iter().map(chain).collect())
}

/// Every texture's own levels as BC7 blocks, when the device samples BC and every
/// texture is a Basis Universal one of one size in whole blocks: a Basis texture can be
/// transcoded, not resampled, so a layer of another size (or a PNG beside it) sends
/// the whole array down the RGBA8 road. Levels past the fewest any texture holds are
/// dropped, so that every layer has the array's levels.
fn bc7_layers(device: &wgpu::Device, textures: &[&Texture]) -> Result<Option<Layers>> {
    let bc = device
        .features()
        .contains(wgpu::Features::TEXTURE_COMPRESSION_BC);
    let basis: Option<Vec<&BasisTexture>> = textures.iter().map(|t| t.basis.as_deref()).collect();
    let Some(basis) = basis.filter(|b| bc && !b.is_empty()) else {
        return Ok(None);
    };
    let size = basis[0].size();
    let fits = size.0.max(size.1) <= device.limits().max_texture_dimension_2d;
    let whole = size.0 % 4 == 0 && size.1 % 4 == 0;
    if !(fits && whole && basis.iter().all(|b| b.size() == size)) {
        return Ok(None);
    }
    let levels = basis.iter().map(|b| b.levels()).min().unwrap_or(1);
    let layers = (textures.par_iter().zip(&basis))
        .map(|(texture, b)| {
            (0..levels)
                .map(|level| bc7_level(b, size, level))
                .collect::<std::result::Result<Vec<_>, String>>()
                .map_err(|e| Error::InvalidScene(format!("texture {:?}: {e}", texture.name)))
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(Some((size, layers)))
}

fn bc7_level(
    basis: &BasisTexture,
    size: (u32, u32),
    level: u32,
) -> std::result::Result<Level, String> {
    let blocks = |side: u32| crate::basisu::blocks((side >> level).max(1));
    let (x, y) = (blocks(size.0), blocks(size.1));
    Ok(Level {
        bytes: basis.bc7(level)?,
        size: (4 * x, 4 * y),
        bytes_per_row: crate::basisu::BC7_BLOCK * x,
    })
}

impl GpuMaterials {
    /// The GPU side of `scene`'s materials, its texels pending until the first upload.
    pub fn new(
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        scene: &Scene,
    ) -> Result<GpuMaterials> {
        let records = records(scene)?;
        let arrays = [
            TextureArray::new(device, scene, Encoding::Srgb)?,
            TextureArray::new(device, scene, Encoding::Linear)?,
        ];
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("stereocull.texture_sampler"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::Repeat,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Linear,
            ..Default::default()
        });
        let usage = wgpu::BufferUsages::STORAGE;
        let buffer = init_buffer(
            device,
            "stereocull.materials",
            bytemuck::cast_slice(&records),
            usage,
        );
        let (colors, data) = (arrays[0].view(), arrays[1].view());
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("stereocull.materials"),
            layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&colors),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::Sampler(&sampler),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: buffer.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: wgpu::BindingResource::TextureView(&data),
                },
            ],
        });
        Ok(GpuMaterials { bind_group, arrays })
    }

    /// Writes the texels on first use; returns the bytes written (0 afterwards).
    pub fn upload(&mut self, queue: &wgpu::Queue) -> u64 {
        self.arrays.iter_mut().map(|a| a.upload(queue)).sum()
    }

    /// The formats of the color and the data array: RGBA8, or BC7 where every texture
    /// of the encoding is a Basis Universal one the device keeps compressed.
    pub fn formats(&self) -> [wgpu::TextureFormat; 2] {
        self.arrays.each_ref().map(|a| a.texture.format())
    }
}

const WHITE: image::Rgba<u8> = image::Rgba([255; 4]);

/// The sRGB encoding of linear `l` (IEC 61966-2-1).
pub fn srgb_from_linear(l: f32) -> f32 {
    match l <= 0.003_130_8 {
        true => 12.92 * l,
        false => 1.055 * l.powf(1.0 / 2.4) - 0.055,
    }
}

/// The linear value of sRGB-encoded `s`.
pub fn linear_from_srgb(s: f32) -> f32 {
    match s <= 0.040_45 {
        true => s / 12.92,
        false => ((s + 0.055) / 1.055).powf(2.4),
    }
}
