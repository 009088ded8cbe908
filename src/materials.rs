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

use crate::bins::{check_override, mesh_material, vertex_material};
use crate::buffers::init_buffer;
use crate::error::{Error, Result};
use crate::scene::{AlphaMode, Encoding, Material, Scene};
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
    /// Per layer, its mip chain, until uploaded.
    pending: Vec<Vec<RgbaImage>>,
}

impl TextureArray {
    /// The array of `scene`'s textures of `encoding` (one white layer when it has none).
    fn new(device: &wgpu::Device, scene: &Scene, encoding: Encoding) -> Result<TextureArray> {
        let images: Vec<&RgbaImage> = (scene.textures.iter())
            .filter(|t| t.encoding == encoding)
            .map(|t| &t.image)
            .collect();
        let limits = device.limits();
        let layers = images.len().max(1) as u32;
        if layers > limits.max_texture_array_layers {
            return Err(Error::Limits(format!(
                "{layers} {encoding:?} textures; the device's texture arrays hold {}",
                limits.max_texture_array_layers
            )));
        }
        let size = layer_size(images.iter().copied(), limits.max_texture_dimension_2d);
        let white = RgbaImage::from_pixel(1, 1, WHITE);
        let pending: Vec<_> = match images.is_empty() {
            true => vec![mip_chain(&white, size)],
            false => images.iter().map(|image| mip_chain(image, size)).collect(),
        };
        let (label, format) = match encoding {
            Encoding::Srgb => (
                "stereocull.color_textures",
                wgpu::TextureFormat::Rgba8UnormSrgb,
            ),
            Encoding::Linear => ("stereocull.data_textures", wgpu::TextureFormat::Rgba8Unorm),
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
            for (level, image) in levels.iter().enumerate() {
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
                    image.as_raw(),
                    wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(4 * image.width()),
                        rows_per_image: None,
                    },
                    wgpu::Extent3d {
                        width: image.width(),
                        height: image.height(),
                        depth_or_array_layers: 1,
                    },
                );
                bytes += image.as_raw().len() as u64;
            }
        }
        bytes
    }
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
}

const WHITE: image::Rgba<u8> = image::Rgba([255; 4]);
