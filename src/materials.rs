//! Materials on the GPU, group 1 of the built-in draw pipelines: every base color
//! texture of a scene as one layer of a single 2D texture array (resized to a common
//! size, with mipmaps), so that a textured scene still draws with one indirect call per
//! display, and one [`MaterialRecord`] per material saying which layer it samples.
//!
//! Bindless texture arrays would skip the resize; lavapipe has none, and the array works
//! on every adapter, so it is the one path.

use bytemuck::{Pod, Zeroable};
use image::RgbaImage;
use image::imageops::FilterType;

use crate::bins::{mesh_material, vertex_material};
use crate::buffers::init_buffer;
use crate::error::{Error, Result};
use crate::scene::{AlphaMode, Material, Scene};

/// The largest layer side: bigger textures are scaled down to it.
pub const MAX_LAYER_SIZE: u32 = 1024;

/// A material as the fragment stage reads it (`MaterialRecord` in
/// `wgsl/shared/records.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct MaterialRecord {
    /// Layer of the base color array, or [`MaterialRecord::UNTEXTURED`].
    pub base_color_layer: u32,
    /// Fragments whose base color alpha is below this are discarded: a
    /// [`AlphaMode::Mask`]'s cutoff, 0 (nothing) otherwise.
    pub alpha_cutoff: f32,
}

impl MaterialRecord {
    /// No base color texture: the color alone.
    pub const UNTEXTURED: u32 = u32::MAX;
}

/// Group 1's WGSL declarations.
pub const DECLARATIONS: &str = "\
@group(1) @binding(0) var base_color_textures: texture_2d_array<f32>;
@group(1) @binding(1) var base_color_sampler: sampler;
@group(1) @binding(2) var<storage, read> materials: array<MaterialRecord>;
";

/// Group 1's layout, matching [`DECLARATIONS`].
pub fn bind_group_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    let fragment = wgpu::ShaderStages::FRAGMENT;
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("stereocull.materials"),
        entries: &[
            wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: fragment,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: true },
                    view_dimension: wgpu::TextureViewDimension::D2Array,
                    multisampled: false,
                },
                count: None,
            },
            wgpu::BindGroupLayoutEntry {
                binding: 1,
                visibility: fragment,
                ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                count: None,
            },
            wgpu::BindGroupLayoutEntry {
                binding: 2,
                visibility: fragment,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage { read_only: true },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            },
        ],
    })
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
    if scene.materials.is_empty() {
        return Ok(vec![MaterialRecord {
            base_color_layer: MaterialRecord::UNTEXTURED,
            alpha_cutoff: 0.0,
        }]);
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
    let base_color_layer = match m.base_color_texture {
        None => MaterialRecord::UNTEXTURED,
        Some(t) if (t as usize) < scene.textures.len() => t,
        Some(t) => {
            return Err(Error::InvalidScene(format!(
                "material {:?} names texture {t} of {}",
                m.name,
                scene.textures.len()
            )));
        }
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
    Ok(MaterialRecord {
        base_color_layer,
        alpha_cutoff,
    })
}

/// The side of every layer: the largest texture's, within [`MAX_LAYER_SIZE`] and the
/// device's limit; 1 with no textures.
fn layer_size(scene: &Scene, device_max: u32) -> (u32, u32) {
    let fit = |side: u32| side.clamp(1, MAX_LAYER_SIZE.min(device_max));
    scene.textures.iter().fold((1, 1), |(w, h), t| {
        (w.max(fit(t.image.width())), h.max(fit(t.image.height())))
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
    /// Group 1 of the draw pipelines: the texture array, its sampler, the material records.
    pub bind_group: wgpu::BindGroup,
    texture: wgpu::Texture,
    /// Per layer, its mip chain, until uploaded.
    pending: Vec<Vec<RgbaImage>>,
}

impl GpuMaterials {
    /// The GPU side of `scene`'s materials, its texels pending until the first upload.
    pub fn new(
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        scene: &Scene,
    ) -> Result<GpuMaterials> {
        let records = records(scene)?;
        let limits = device.limits();
        let layers = scene.textures.len().max(1) as u32;
        if layers > limits.max_texture_array_layers {
            return Err(Error::Limits(format!(
                "{layers} base color textures; the device's texture arrays hold {}",
                limits.max_texture_array_layers
            )));
        }
        let size = layer_size(scene, limits.max_texture_dimension_2d);
        let pending: Vec<_> = match scene.textures.is_empty() {
            true => vec![mip_chain(&RgbaImage::from_pixel(1, 1, WHITE), size)],
            false => scene
                .textures
                .iter()
                .map(|t| mip_chain(&t.image, size))
                .collect(),
        };
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("stereocull.base_color_textures"),
            size: wgpu::Extent3d {
                width: size.0,
                height: size.1,
                depth_or_array_layers: layers,
            },
            mip_level_count: pending[0].len() as u32,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba8UnormSrgb,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        let view = texture.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("stereocull.base_color_sampler"),
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
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("stereocull.materials"),
            layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&view),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::Sampler(&sampler),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: buffer.as_entire_binding(),
                },
            ],
        });
        Ok(GpuMaterials {
            bind_group,
            texture,
            pending,
        })
    }

    /// Writes the texels on first use; returns the bytes written (0 afterwards).
    pub fn upload(&mut self, queue: &wgpu::Queue) -> u64 {
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

const WHITE: image::Rgba<u8> = image::Rgba([255; 4]);
