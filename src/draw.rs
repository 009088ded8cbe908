//! Drawing: render passes, the pipelines (`wgsl/draw*.wgsl`) and the one
//! multi-draw-indirect call of the GPU-driven path. The renderer decides what to draw
//! (`renderer::indirect`, `renderer::classic`); this module knows how.

use std::collections::HashMap;
use std::num::NonZeroU32;

use crate::bins::{Bin, BinKind, BinRange};
use crate::buffers::{init_buffer, init_buffer_with_room};
use crate::cull::gpu_buffers::{COUNTS_BIN_OFFSET, CullTargets};
use crate::error::Result;
use crate::materials::{self, GpuMaterials};
use crate::records::{DrawArgs, InstanceRecord, instance_records};
use crate::scene::{Scene, Vertex};
use crate::shaders::{
    DRAW_BINDINGS, DrawKey, Shaders, Windows, bind_group, bind_group_layout, shadow_cutout_source,
    shadow_source,
};
use crate::shadow::{self, ShadowMap};

/// The depth format of the renderer's own targets, unless the options name another.
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// The attachment formats and sample count the draw pipelines are built for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TargetFormat {
    /// The color attachment's format.
    pub color: wgpu::TextureFormat,
    /// The depth attachment's format.
    pub depth: wgpu::TextureFormat,
    /// Samples per pixel (1: no MSAA).
    pub samples: u32,
}
/// Dark enough that any lit object stands out in tests.
pub const CLEAR_COLOR: wgpu::Color = wgpu::Color {
    r: 0.02,
    g: 0.02,
    b: 0.03,
    a: 1.0,
};

/// How the draw pipelines read a [`Vertex`]: `VertexInput` in
/// `wgsl/shared/decode.wgsl` (`tests/shaders.rs` checks both sides).
pub const VERTEX_ATTRIBUTES: [wgpu::VertexAttribute; 4] =
    wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x2, 3 => Uint32];

/// The scene's vertex buffer as every pipeline drawing it reads it (an engine's own
/// pipeline too).
pub const VERTEX_BUFFER: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: size_of::<Vertex>() as u64,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &VERTEX_ATTRIBUTES,
};

/// What a view's draw draws with: the pipelines and the scene on the GPU.
#[derive(Clone, Copy)]
pub struct Drawing<'a> {
    /// The pipelines and their layouts.
    pub drawer: &'a Drawer,
    /// The geometry, instance records, materials and shadow map.
    pub scene: &'a DrawScene,
}

/// The scene's geometry, instance records and materials on the GPU, uploaded once, and
/// the frame's shadow map the draws sample.
pub struct DrawScene {
    /// Every mesh's vertices, one buffer.
    pub vertices: wgpu::Buffer,
    /// Every mesh's indices (and levels of detail), one buffer.
    pub indices: wgpu::Buffer,
    /// One [`InstanceRecord`] per slot, with room.
    pub instances: wgpu::Buffer,
    /// Textures and material records (group 1).
    pub materials: GpuMaterials,
    /// The shadow map (group 2).
    pub shadow_map: ShadowMap,
}

impl DrawScene {
    /// Uploads `scene` with room for `slots` instance records. Fails when the scene's
    /// materials do not fit together or exceed the device.
    pub fn new(
        device: &wgpu::Device,
        drawer: &Drawer,
        scene: &Scene,
        slots: u32,
    ) -> Result<DrawScene> {
        let init =
            |label: &str, contents: &[u8], usage| init_buffer(device, label, contents, usage);
        let shadow_size = drawer.shadow.as_ref().map_or(1, |s| s.size);
        Ok(DrawScene {
            materials: GpuMaterials::new(device, &drawer.materials_layout, scene)?,
            shadow_map: ShadowMap::new(device, &drawer.shadow_layout, shadow_size),
            vertices: init(
                "stereocull.vertices",
                bytemuck::cast_slice(&scene.vertices),
                wgpu::BufferUsages::VERTEX,
            ),
            indices: init(
                "stereocull.indices",
                bytemuck::cast_slice(&scene.indices),
                wgpu::BufferUsages::INDEX,
            ),
            instances: init_buffer_with_room(
                device,
                "stereocull.instances",
                bytemuck::cast_slice(&instance_records(scene)),
                DrawScene::BYTES_PER_INSTANCE * slots as u64,
                wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            ),
        })
    }

    /// GPU bytes per instance slot for drawing: its record.
    pub const BYTES_PER_INSTANCE: u64 = size_of::<InstanceRecord>() as u64;
}

/// How the draw call is issued, from the device's features.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DrawFeatures {
    /// `multi_draw_indexed_indirect_count`, else a fixed count over zeroed tails.
    pub indirect_count: bool,
    /// Hardware clip distances keep each eye in its half, else a fragment discard.
    pub clip_distances: bool,
}

impl DrawFeatures {
    /// What `device` has.
    pub fn of(device: &wgpu::Device) -> DrawFeatures {
        let f = device.features();
        DrawFeatures {
            indirect_count: f.contains(wgpu::Features::MULTI_DRAW_INDIRECT_COUNT),
            clip_distances: f.contains(wgpu::Features::CLIP_DISTANCES),
        }
    }
}

/// Draw pipelines by variant, for one color format, and the shadow pass's.
pub struct Drawer {
    layout: wgpu::BindGroupLayout,
    materials_layout: wgpu::BindGroupLayout,
    shadow_layout: wgpu::BindGroupLayout,
    pipelines: HashMap<DrawKey, wgpu::RenderPipeline>,
    /// With shadows: the depth-only pipeline and the shadow map's size.
    pub shadow: Option<ShadowPipeline>,
    /// How the instance records are bound.
    pub windows: Windows,
    /// How draws are issued on this device.
    pub features: DrawFeatures,
    /// Samples per pixel of the target (cutouts use alpha to coverage above 1).
    samples: u32,
}

/// The frame's shadow pass pipelines (`wgsl/shadow.wgsl`, `wgsl/shadow_cutout.wgsl`).
pub struct ShadowPipeline {
    /// The depth-only pipeline, for opaque bins.
    pub pipeline: wgpu::RenderPipeline,
    /// For cutout bins (when the scene has any): discards under the cutoff.
    pub cutout: Option<wgpu::RenderPipeline>,
    /// The shadow map's texels a side.
    pub size: u32,
}

impl Drawer {
    /// Group 0's layout ([`crate::shaders::DRAW_BINDINGS`]).
    pub fn layout(&self) -> &wgpu::BindGroupLayout {
        &self.layout
    }

    /// Builds the pipelines for the given variants, one per bin of `kinds` (the
    /// scene's), rendering into `target`, shaded by each bin's function of `shaders`
    /// (see [`DrawKey::source_with`]), and with
    /// `shadow_size` the shadow pass's, into a map of that many texels a side.
    pub fn new(
        device: &wgpu::Device,
        target: TargetFormat,
        (keys, kinds): (&[DrawKey], &[Bin]),
        shaders: Shaders,
        shadow_size: Option<u32>,
        windows: Windows,
    ) -> Drawer {
        let layout = bind_group_layout(device, "stereocull.draw", &DRAW_BINDINGS, &windows);
        let materials_layout = materials::bind_group_layout(device);
        let shadow_layout = shadow::bind_group_layout(device);
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("stereocull.draw"),
            bind_group_layouts: &[Some(&layout), Some(&materials_layout), Some(&shadow_layout)],
            immediate_size: 0,
        });
        let pipelines = (keys.iter())
            .flat_map(|&key| kinds.iter().map(move |&k| key.with_bin(k, target.samples)))
            .map(|key| {
                let source = key.source_with(shaders.function(key.shading), &windows);
                (
                    key,
                    pipeline(device, &pipeline_layout, key, &source, target),
                )
            })
            .collect();
        let shadow = shadow_size.map(|size| ShadowPipeline {
            pipeline: shadow_pipeline(
                device,
                &[Some(&layout)],
                ("stereocull.shadow", shadow_source(&windows)),
            ),
            cutout: kinds.iter().any(|k| k.alpha == BinKind::Mask).then(|| {
                shadow_pipeline(
                    device,
                    &[Some(&layout), Some(&materials_layout)],
                    ("stereocull.shadow.cutout", shadow_cutout_source(&windows)),
                )
            }),
            size,
        });
        Drawer {
            layout,
            materials_layout,
            shadow_layout,
            pipelines,
            shadow,
            windows,
            features: DrawFeatures::of(device),
            samples: target.samples,
        }
    }

    /// The variant for `views` views per instance on this device.
    pub fn key(&self, views: u32) -> DrawKey {
        DrawKey::new(views, self.features.clip_distances)
    }

    /// Binds the frame and a display context, the instances and a visible list.
    pub fn bind_group(
        &self,
        device: &wgpu::Device,
        [frame_context, display_context]: [&wgpu::Buffer; 2],
        scene: &DrawScene,
        visible: &wgpu::Buffer,
    ) -> wgpu::BindGroup {
        // In DRAW_BINDINGS order.
        let buffers = [frame_context, display_context, visible, &scene.instances];
        let (label, layout) = ("stereocull.draw", &self.layout);
        bind_group(
            device,
            label,
            layout,
            &DRAW_BINDINGS,
            &self.windows,
            buffers,
        )
    }

    /// Sets the geometry and the bindings of the built-in pipelines on `pass`: group
    /// 0, the materials (group 1) and the shadow map (group 2).
    pub fn bind(pass: &mut wgpu::RenderPass, scene: &DrawScene, bind_group: &wgpu::BindGroup) {
        Drawer::bind_resources(pass, scene, bind_group);
        pass.set_bind_group(1, &scene.materials.bind_group, &[]);
        pass.set_bind_group(2, &scene.shadow_map.bind_group, &[]);
    }

    /// The geometry and group 0 on `pass`, for whatever pipeline it has (an engine's
    /// own keeps its groups from 1 on).
    pub fn bind_resources(
        pass: &mut wgpu::RenderPass,
        scene: &DrawScene,
        bind_group: &wgpu::BindGroup,
    ) {
        pass.set_bind_group(0, bind_group, &[]);
        pass.set_vertex_buffer(0, scene.vertices.slice(..));
        pass.set_index_buffer(scene.indices.slice(..), wgpu::IndexFormat::Uint32);
    }

    /// The pipeline of `with` for bins of `kind`: `None` skips the bin (blended bins
    /// cast no shadow), `Some(None)` keeps the pass's own.
    pub fn bin_pipeline(
        &self,
        with: BinPipelines,
        kind: Bin,
    ) -> Option<Option<&wgpu::RenderPipeline>> {
        match with {
            BinPipelines::Draw(key) => {
                Some(Some(&self.pipelines[&key.with_bin(kind, self.samples)]))
            }
            BinPipelines::Own => Some(None),
            BinPipelines::Shadow => {
                let shadow = self.shadow.as_ref()?;
                match kind.alpha {
                    BinKind::Opaque => Some(Some(&shadow.pipeline)),
                    BinKind::Mask => shadow.cutout.as_ref().map(Some),
                    BinKind::Blend => None,
                }
            }
        }
    }

    /// The GPU-driven path's draws: per material bin, its pipeline (of `with`) and one
    /// multi-draw over the bin's range. Returns the draw calls.
    pub fn draw_bins(
        &self,
        pass: &mut wgpu::RenderPass,
        bins: &[BinRange],
        with: BinPipelines,
        cull: &CullTargets,
    ) -> u32 {
        let mut calls = 0;
        for (b, range) in bins.iter().enumerate() {
            let Some(pipeline) = self.bin_pipeline(with, range.kind) else {
                continue;
            };
            if let Some(pipeline) = pipeline {
                pass.set_pipeline(pipeline);
            }
            let offset = range.first as u64 * size_of::<DrawArgs>() as u64;
            if self.features.indirect_count {
                let count_offset = COUNTS_BIN_OFFSET + 4 * b as u64;
                pass.multi_draw_indexed_indirect_count(
                    &cull.draws,
                    offset,
                    &cull.counts,
                    count_offset,
                    range.capacity,
                );
            } else {
                pass.multi_draw_indexed_indirect(&cull.draws, offset, range.capacity);
            }
            calls += 1;
        }
        calls
    }
}

/// Which pipelines a view's material bins are drawn with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BinPipelines {
    /// The built-in draw pipelines of this variant, each bin its own.
    Draw(DrawKey),
    /// The frame's shadow pass: depth only, cutouts discarding, blended bins skipped.
    Shadow,
    /// The pipeline the pass already has (an engine's own), for every bin.
    Own,
}

/// What a draw pass renders into.
#[derive(Clone, Copy)]
pub struct Attachments<'a> {
    /// Where color is drawn (multisampled under MSAA).
    pub color: &'a wgpu::TextureView,
    /// The depth attachment.
    pub depth: &'a wgpu::TextureView,
    /// Where a multisampled `color` is resolved at the end of the pass.
    pub resolve: Option<&'a wgpu::TextureView>,
}

/// Opens a render pass on `target`, clearing it or keeping what earlier passes drew
/// (multisampled color is kept too, then resolved again); `multiview_mask` renders
/// those layers of a layered target (multiview; `DrawKey::multiview_mask`).
pub fn begin_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    target: Attachments,
    clear: bool,
    multiview_mask: Option<NonZeroU32>,
    timestamp_writes: Option<wgpu::RenderPassTimestampWrites>,
) -> wgpu::RenderPass<'e> {
    let (color_load, depth_load) = if clear {
        (wgpu::LoadOp::Clear(CLEAR_COLOR), wgpu::LoadOp::Clear(1.0))
    } else {
        (wgpu::LoadOp::Load, wgpu::LoadOp::Load)
    };
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("stereocull.draw"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: target.color,
            depth_slice: None,
            resolve_target: target.resolve,
            ops: wgpu::Operations {
                load: color_load,
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: target.depth,
            depth_ops: Some(wgpu::Operations {
                load: depth_load,
                store: wgpu::StoreOp::Store,
            }),
            stencil_ops: None,
        }),
        timestamp_writes,
        occlusion_query_set: None,
        multiview_mask,
    })
}

/// `view` as a depth attachment cleared to the far plane and kept.
pub fn cleared_depth(view: &wgpu::TextureView) -> wgpu::RenderPassDepthStencilAttachment<'_> {
    wgpu::RenderPassDepthStencilAttachment {
        view,
        depth_ops: Some(wgpu::Operations {
            load: wgpu::LoadOp::Clear(1.0),
            store: wgpu::StoreOp::Store,
        }),
        stencil_ops: None,
    }
}

/// Restricts drawing to one view's `[x, y, width, height]` of its display's target (an
/// eye's half of a double-wide target, a foveated display's viewport).
pub fn set_viewport(pass: &mut wgpu::RenderPass, [x, y, w, h]: [u32; 4]) {
    pass.set_viewport(x as f32, y as f32, w as f32, h as f32, 0.0, 1.0);
    pass.set_scissor_rect(x, y, w, h);
}

/// Depth only, both faces (open meshes cast shadows too), biased by slope so that lit
/// surfaces do not shadow themselves; `layouts` are group 0's and, for the cutout
/// variant, group 1's (the materials).
fn shadow_pipeline(
    device: &wgpu::Device,
    layouts: &[Option<&wgpu::BindGroupLayout>],
    (label, source): (&str, String),
) -> wgpu::RenderPipeline {
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: layouts,
        immediate_size: 0,
    });
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let cutout = layouts.len() > 1;
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs_main"),
            compilation_options: Default::default(),
            buffers: &[Some(VERTEX_BUFFER)],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: Some(wgpu::DepthStencilState {
            format: shadow::SHADOW_FORMAT,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Less),
            stencil: Default::default(),
            bias: wgpu::DepthBiasState {
                constant: 2,
                slope_scale: 2.0,
                clamp: 0.0,
            },
        }),
        multisample: Default::default(),
        fragment: cutout.then(|| wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs_main"),
            compilation_options: Default::default(),
            targets: &[],
        }),
        multiview_mask: None,
        cache: None,
    })
}

fn pipeline(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    key: DrawKey,
    source: &str,
    target: TargetFormat,
) -> wgpu::RenderPipeline {
    let label = key.label();
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(&label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(&label),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs_main"),
            compilation_options: Default::default(),
            buffers: &[Some(VERTEX_BUFFER)],
        },
        primitive: wgpu::PrimitiveState {
            cull_mode: key.face_culling(),
            ..Default::default()
        },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: target.depth,
            // Blended surfaces are seen through, so they hide nothing.
            depth_write_enabled: Some(key.alpha != BinKind::Blend),
            depth_compare: Some(wgpu::CompareFunction::Less),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: wgpu::MultisampleState {
            count: target.samples,
            alpha_to_coverage_enabled: key.coverage,
            ..Default::default()
        },
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs_main"),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::ColorTargetState {
                format: target.color,
                blend: (key.alpha == BinKind::Blend).then_some(wgpu::BlendState::ALPHA_BLENDING),
                write_mask: wgpu::ColorWrites::ALL,
            })],
        }),
        multiview_mask: key.multiview_mask(),
        cache: None,
    })
}
