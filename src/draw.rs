//! Drawing: per display, one render pass into its target (2W x H for stereo) with one
//! multi-draw-indirect call over the cull pass's draws (`wgsl/draw.wgsl`).

use std::collections::HashMap;

use wgpu::util::DeviceExt;

use crate::cull::gpu::CullTargets;
use crate::records::{InstanceRecord, instance_records};
use crate::scene::{Scene, Vertex};
use crate::shaders::DrawKey;

pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Dark enough that any lit object stands out in tests.
pub const CLEAR_COLOR: wgpu::Color = wgpu::Color {
    r: 0.02,
    g: 0.02,
    b: 0.03,
    a: 1.0,
};

/// The scene's geometry and instance records on the GPU, uploaded once.
pub struct DrawScene {
    pub vertices: wgpu::Buffer,
    pub indices: wgpu::Buffer,
    pub instances: wgpu::Buffer,
    pub mesh_count: u32,
}

impl DrawScene {
    pub fn new(device: &wgpu::Device, scene: &Scene) -> DrawScene {
        let init = |label: &str, contents: &[u8], usage| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            })
        };
        DrawScene {
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
            instances: init(
                "stereocull.instances",
                bytemuck::cast_slice(&instance_records(scene)),
                wgpu::BufferUsages::STORAGE,
            ),
            mesh_count: scene.meshes.len() as u32,
        }
    }

    pub const BYTES_PER_INSTANCE: u64 = size_of::<InstanceRecord>() as u64;
}

/// How the draw call is issued, from the device's features.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DrawFeatures {
    /// `multi_draw_indexed_indirect_count`, else a fixed count over zeroed tails.
    pub indirect_count: bool,
    pub clip_distances: bool,
}

impl DrawFeatures {
    pub fn of(device: &wgpu::Device) -> DrawFeatures {
        let f = device.features();
        DrawFeatures {
            indirect_count: f.contains(wgpu::Features::MULTI_DRAW_INDIRECT_COUNT),
            clip_distances: f.contains(wgpu::Features::CLIP_DISTANCES),
        }
    }
}

/// Draw pipelines by variant, for one color format.
pub struct Drawer {
    layout: wgpu::BindGroupLayout,
    pipelines: HashMap<DrawKey, wgpu::RenderPipeline>,
    pub features: DrawFeatures,
}

impl Drawer {
    /// Builds the variants for the given view counts (1 and/or 2).
    pub fn new(device: &wgpu::Device, color_format: wgpu::TextureFormat, views: &[u32]) -> Drawer {
        let features = DrawFeatures::of(device);
        let layout = bind_group_layout(device);
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("stereocull.draw"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipelines = views
            .iter()
            .map(|&v| DrawKey::new(v, features.clip_distances))
            .map(|key| (key, pipeline(device, &pipeline_layout, key, color_format)))
            .collect();
        Drawer {
            layout,
            pipelines,
            features,
        }
    }

    pub fn bind_group(
        &self,
        device: &wgpu::Device,
        display_context: &wgpu::Buffer,
        scene: &DrawScene,
        cull: &CullTargets,
    ) -> wgpu::BindGroup {
        let entries = [display_context, &scene.instances, &cull.visible]
            .iter()
            .enumerate()
            .map(|(i, b)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource: b.as_entire_binding(),
            })
            .collect::<Vec<_>>();
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("stereocull.draw"),
            layout: &self.layout,
            entries: &entries,
        })
    }

    /// One render pass and one multi-draw call for one display.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        target: &crate::renderer::TargetViews,
        views: u32,
        scene: &DrawScene,
        bind_group: &wgpu::BindGroup,
        cull: &CullTargets,
    ) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("stereocull.draw"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target.color,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(CLEAR_COLOR),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: target.depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            }),
            ..Default::default()
        });
        let key = DrawKey::new(views, self.features.clip_distances);
        pass.set_pipeline(&self.pipelines[&key]);
        pass.set_bind_group(0, bind_group, &[]);
        pass.set_vertex_buffer(0, scene.vertices.slice(..));
        pass.set_index_buffer(scene.indices.slice(..), wgpu::IndexFormat::Uint32);
        if self.features.indirect_count {
            pass.multi_draw_indexed_indirect_count(
                &cull.draws,
                0,
                &cull.count,
                0,
                scene.mesh_count,
            );
        } else {
            pass.multi_draw_indexed_indirect(&cull.draws, 0, scene.mesh_count);
        }
    }
}

fn bind_group_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    let storage = |binding| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::VERTEX,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only: true },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("stereocull.draw"),
        entries: &[
            wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            },
            storage(1),
            storage(2),
        ],
    })
}

fn pipeline(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    key: DrawKey,
    color_format: wgpu::TextureFormat,
) -> wgpu::RenderPipeline {
    let label = key.label();
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(&label),
        source: wgpu::ShaderSource::Wgsl(key.source().into()),
    });
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(&label),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs_main"),
            compilation_options: Default::default(),
            buffers: &[Some(wgpu::VertexBufferLayout {
                array_stride: size_of::<Vertex>() as u64,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3],
            })],
        },
        // No back-face culling: glTF double-sided materials and open shapes.
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: Some(wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Less),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs_main"),
            compilation_options: Default::default(),
            targets: &[Some(color_format.into())],
        }),
        multiview_mask: None,
        cache: None,
    })
}
