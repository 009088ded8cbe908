//! The draw pipelines' state: the formats they render into, how they read a vertex,
//! and the render pipelines of a draw variant and of the shadow pass.

use crate::bins::BinKind;
use crate::scene::Vertex;
use crate::shaders::DrawKey;
use crate::shadow;

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
    /// A second color attachment of [`crate::motion::MOTION_FORMAT`] takes each
    /// pixel's motion.
    pub motion: bool,
    /// Two frames per submission: the first frame's views read the first pose
    /// ([`DrawKey::first_pose`]).
    pub first_pose: bool,
}
/// How the draw pipelines read a [`Vertex`]: `VertexInput` in
/// `wgsl/shared/decode.wgsl` (`tests/shaders.rs` checks both sides).
pub const VERTEX_ATTRIBUTES: [wgpu::VertexAttribute; 6] = wgpu::vertex_attr_array![
    0 => Float32x3, 1 => Float32x3, 2 => Float32x2, 3 => Uint32, 4 => Snorm8x4, 5 => Float32x2
];

/// The previous frame's vertices as the draw pipelines with motion vectors read them:
/// the position alone, as `previous_position` (`wgsl/draw_motion.wgsl`).
pub const PREVIOUS_VERTEX_BUFFER: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: size_of::<Vertex>() as u64,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &wgpu::vertex_attr_array![6 => Float32x3],
};

/// The first frame's vertices as the first-pose pipelines read them
/// (`wgsl/draw_first_pose.wgsl`): what skins and morph targets rewrite, at the offsets
/// of [`VERTEX_ATTRIBUTES`]' position, normal and tangent.
pub const FIRST_POSE_VERTEX_BUFFER: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: size_of::<Vertex>() as u64,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &[
        wgpu::VertexAttribute {
            format: wgpu::VertexFormat::Float32x3,
            offset: std::mem::offset_of!(Vertex, position) as u64,
            shader_location: 6,
        },
        wgpu::VertexAttribute {
            format: wgpu::VertexFormat::Float32x3,
            offset: std::mem::offset_of!(Vertex, normal) as u64,
            shader_location: 7,
        },
        wgpu::VertexAttribute {
            format: wgpu::VertexFormat::Snorm8x4,
            offset: std::mem::offset_of!(Vertex, tangent) as u64,
            shader_location: 8,
        },
    ],
};

/// The scene's vertex buffer as every pipeline drawing it reads it (an engine's own
/// pipeline too).
pub const VERTEX_BUFFER: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: size_of::<Vertex>() as u64,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &VERTEX_ATTRIBUTES,
};

/// Depth only, both faces (open meshes cast shadows too), biased by slope so that lit
/// surfaces do not shadow themselves; `layouts` are group 0's and, for the cutout
/// variant, group 1's (the materials).
pub(super) fn shadow_pipeline(
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

pub(super) fn pipeline(
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
    let earlier = match key.first_pose {
        true => FIRST_POSE_VERTEX_BUFFER,
        false => PREVIOUS_VERTEX_BUFFER,
    };
    let buffers = [Some(VERTEX_BUFFER), Some(earlier)];
    let blend = key.alpha == BinKind::Blend;
    let targets = [
        Some(wgpu::ColorTargetState {
            format: target.color,
            blend: blend.then_some(wgpu::BlendState::ALPHA_BLENDING),
            write_mask: wgpu::ColorWrites::ALL,
        }),
        // Blended surfaces write no motion, as they write no depth: the pixel keeps
        // the motion of what is seen through them.
        Some(wgpu::ColorTargetState {
            format: crate::motion::MOTION_FORMAT,
            blend: None,
            write_mask: match blend {
                true => wgpu::ColorWrites::empty(),
                false => wgpu::ColorWrites::ALL,
            },
        }),
    ];
    let used = 1 + usize::from(key.motion);
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(&label),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs_main"),
            compilation_options: Default::default(),
            buffers: &buffers[..1 + usize::from(key.motion || key.first_pose)],
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
            targets: &targets[..used],
        }),
        multiview_mask: key.multiview_mask(),
        cache: None,
    })
}
