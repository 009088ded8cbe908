//! The binding lists of every pipeline's bind groups, and everything made from them:
//! WGSL declarations, bind-group layouts and bind groups, pipelines. No WGSL file
//! declares a binding of its own (`tests/shaders.rs` holds every pipeline's globals to
//! its lists).

use super::windows::{Windowed, Windows};

/// One binding of a bind group: its WGSL declaration and its layout entry both come
/// from here; its binding number is its position in the list (a windowed binding takes
/// one number per window, so windowed bindings come last).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Binding {
    /// The WGSL variable's name.
    pub name: &'static str,
    /// Its address space and access.
    pub access: Access,
    /// Its WGSL type (for textures and samplers, the one their kind spells).
    pub wgsl_type: &'static str,
    /// The stages that read it.
    pub stages: wgpu::ShaderStages,
    /// A per-instance array that may outgrow one binding: bound as [`Windows`] says,
    /// read (and written) through `<name>_at(i)` (and `<name>_set(i, v)`).
    pub windowed: Option<Windowed>,
}

/// The window count of each binding of `list`, in order (1 for plain ones).
fn window_counts<'a>(windows: &'a Windows, list: &'a [Binding]) -> impl Iterator<Item = u32> + 'a {
    list.iter()
        .map(|b| b.windowed.map_or(1, |w| windows.of(w).count))
}

/// A binding's kind: a buffer's address space and access, or a texture or sampler.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Access {
    /// `var<uniform>`.
    Uniform,
    /// `var<uniform>` bound at a dynamic offset (one buffer of records, one a dispatch).
    UniformDynamic,
    /// `var<storage, read>`.
    StorageRead,
    /// `var<storage, read_write>`.
    StorageReadWrite,
    /// A sampled texture.
    Texture(TextureKind),
    /// A sampler (`sampler_comparison` for [`wgpu::SamplerBindingType::Comparison`]).
    Sampler(wgpu::SamplerBindingType),
}

/// What a sampled texture binding holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TextureKind {
    /// Float (filterable or not) or depth.
    pub sample: wgpu::TextureSampleType,
    /// 2D or a 2D array.
    pub dimension: wgpu::TextureViewDimension,
    /// Several samples per texel.
    pub multisampled: bool,
}

impl TextureKind {
    /// A single-sampled 2D texture of `sample`.
    pub const fn d2(sample: wgpu::TextureSampleType) -> TextureKind {
        TextureKind {
            sample,
            dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        }
    }

    /// Its WGSL type.
    const fn wgsl_type(self) -> &'static str {
        use wgpu::TextureSampleType as S;
        use wgpu::TextureViewDimension as D;
        match (self.sample, self.dimension, self.multisampled) {
            (S::Depth, D::D2, false) => "texture_depth_2d",
            (S::Depth, D::D2, true) => "texture_depth_multisampled_2d",
            (S::Depth, D::D2Array, false) => "texture_depth_2d_array",
            (S::Float { .. }, D::D2, false) => "texture_2d<f32>",
            (S::Float { .. }, D::D2Array, false) => "texture_2d_array<f32>",
            _ => panic!("a texture kind no pipeline binds"),
        }
    }
}

const fn binding(
    name: &'static str,
    access: Access,
    wgsl_type: &'static str,
    stages: wgpu::ShaderStages,
) -> Binding {
    Binding {
        name,
        access,
        wgsl_type,
        stages,
        windowed: None,
    }
}

const fn windowed(
    name: &'static str,
    access: Access,
    wgsl_type: &'static str,
    stages: wgpu::ShaderStages,
    which: Windowed,
) -> Binding {
    Binding {
        windowed: Some(which),
        ..binding(name, access, wgsl_type, stages)
    }
}

const fn texture(name: &'static str, kind: TextureKind, stages: wgpu::ShaderStages) -> Binding {
    binding(name, Access::Texture(kind), kind.wgsl_type(), stages)
}

const fn sampler(
    name: &'static str,
    ty: wgpu::SamplerBindingType,
    stages: wgpu::ShaderStages,
) -> Binding {
    let wgsl_type = match ty {
        wgpu::SamplerBindingType::Comparison => "sampler_comparison",
        _ => "sampler",
    };
    binding(name, Access::Sampler(ty), wgsl_type, stages)
}

const COMPUTE: wgpu::ShaderStages = wgpu::ShaderStages::COMPUTE;
const FRAGMENT: wgpu::ShaderStages = wgpu::ShaderStages::FRAGMENT;
const FILTERABLE: wgpu::TextureSampleType = wgpu::TextureSampleType::Float { filterable: true };

/// Every cull pass's bindings: the frame context, per display its context and outputs,
/// the scene data uploaded once, scratch shared by all displays, and the frame's coarse
/// cull results.
pub const CULL_BINDINGS: [Binding; 19] = [
    binding("frame", Access::Uniform, "FrameContext", COMPUTE),
    binding("display", Access::Uniform, "DisplayContext", COMPUTE),
    binding("params", Access::Uniform, "CullParams", COMPUTE),
    // Instance id at each cull position.
    binding("order", Access::StorageRead, "array<u32>", COMPUTE),
    binding("meshes", Access::StorageRead, "array<MeshRecord>", COMPUTE),
    // MAX_LODS levels per mesh.
    binding("lods", Access::StorageRead, "array<LodRecord>", COMPUTE),
    // Mesh of each cull position.
    binding("mesh_of", Access::StorageRead, "array<u32>", COMPUTE),
    // Per position culled: its entry (visible bit, level, per level its prefix in its
    // span; see ENTRY_VISIBLE in wgsl/shared/cull_math.wgsl).
    binding("entries", Access::StorageReadWrite, "array<u32>", COMPUTE),
    // Per level, each span's count then prefix in its group; then each group's total
    // then prefix.
    binding("span_sums", Access::StorageReadWrite, "array<u32>", COMPUTE),
    binding("visible", Access::StorageReadWrite, "array<u32>", COMPUTE),
    binding(
        "draws",
        Access::StorageReadWrite,
        "array<DrawArgs>",
        COMPUTE,
    ),
    // The draw count (what multi_draw_indexed_indirect_count reads), visible total.
    binding("counts", Access::StorageReadWrite, "array<u32, 2>", COMPUTE),
    // The frame's coarse cull (src/cull/coarse.rs), per slot and block of BLOCK cull
    // positions: its mark (kept bit, then listed blocks before it), the listed blocks
    // ascending, per slot the listed positions' count and each mesh's (start, count)
    // among them, and per slot the block test.
    binding(
        "block_marks",
        Access::StorageReadWrite,
        "array<u32>",
        COMPUTE,
    ),
    binding(
        "block_list",
        Access::StorageReadWrite,
        "array<u32>",
        COMPUTE,
    ),
    binding(
        "candidate_count",
        Access::StorageReadWrite,
        "array<u32>",
        COMPUTE,
    ),
    binding(
        "candidate_ranges",
        Access::StorageReadWrite,
        "array<vec2<u32>>",
        COMPUTE,
    ),
    binding(
        "block_tests",
        Access::StorageRead,
        "array<CoarseTest>",
        COMPUTE,
    ),
    // Occlusion (wgsl/shared/occlusion.wgsl): per display slot, a word per span of
    // places whose low SPAN bits say which places that display drew last frame; then,
    // from params.pyramid_offset, the display's eyes' depth pyramids (src/occlusion.rs,
    // f32 bits), rebuilt per display. One binding: GL has 16 storage buffers a stage.
    binding("occlusion", Access::StorageReadWrite, "array<u32>", COMPUTE),
    // World bounding spheres in cull order.
    windowed(
        "spheres",
        Access::StorageRead,
        "array<vec4<f32>>",
        COMPUTE,
        Windowed::Spheres,
    ),
];

/// The frame-level coarse passes' group 1: the display passes' indirect dispatch,
/// which they write and nothing else binds (a buffer read as dispatch arguments may not
/// be bound for writing in the same dispatch).
pub const COARSE_BINDINGS: [Binding; 1] = [binding(
    "coarse_args",
    Access::StorageReadWrite,
    "array<u32>",
    COMPUTE,
)];

/// Every draw pipeline's bindings.
pub const DRAW_BINDINGS: [Binding; 4] = [
    binding(
        "frame",
        Access::Uniform,
        "FrameContext",
        wgpu::ShaderStages::VERTEX_FRAGMENT,
    ),
    binding(
        "display",
        Access::Uniform,
        "DisplayContext",
        wgpu::ShaderStages::VERTEX_FRAGMENT,
    ),
    binding(
        "visible",
        Access::StorageRead,
        "array<u32>",
        wgpu::ShaderStages::VERTEX,
    ),
    windowed(
        "instances",
        Access::StorageRead,
        "array<InstanceRecord>",
        wgpu::ShaderStages::VERTEX_FRAGMENT,
        Windowed::Instances,
    ),
];

/// The scatter pass's bindings (`wgsl/scatter_*.wgsl`): the frame's edits, and where
/// they go.
pub const SCATTER_BINDINGS: [Binding; 7] = [
    // The header and one kind's edits (`Edits` in each wgsl/scatter_*.wgsl).
    binding("edits", Access::StorageRead, "Edits", COMPUTE),
    // Cull position of each slot (the places scatter writes, the moves read).
    binding("positions", Access::StorageReadWrite, "array<u32>", COMPUTE),
    // Slot at each cull position.
    binding("order", Access::StorageReadWrite, "array<u32>", COMPUTE),
    // The GPU culler's occlusion words (CULL_BINDINGS' `occlusion`): places filled or
    // vacated lose their visibility bits.
    binding(
        "visibility",
        Access::StorageReadWrite,
        "array<atomic<u32>>",
        COMPUTE,
    ),
    // Each mesh's local bounding sphere (center, radius): where a moved sphere's
    // center comes from.
    binding(
        "mesh_bounds",
        Access::StorageRead,
        "array<vec4<f32>>",
        COMPUTE,
    ),
    windowed(
        "instances",
        Access::StorageReadWrite,
        "array<InstanceRecord>",
        COMPUTE,
        Windowed::Instances,
    ),
    // World bounding spheres in cull order (the GPU culler's; a stand-in otherwise).
    windowed(
        "spheres",
        Access::StorageReadWrite,
        "array<vec4<f32>>",
        COMPUTE,
        Windowed::Spheres,
    ),
];

/// Group 1 of the draw pipelines (and the shadow's cutouts): the materials' textures,
/// their sampler and records (`crate::materials`).
pub const MATERIAL_BINDINGS: [Binding; 4] = [
    texture(
        "color_textures",
        TextureKind {
            dimension: wgpu::TextureViewDimension::D2Array,
            ..TextureKind::d2(FILTERABLE)
        },
        FRAGMENT,
    ),
    sampler(
        "texture_sampler",
        wgpu::SamplerBindingType::Filtering,
        FRAGMENT,
    ),
    binding(
        "materials",
        Access::StorageRead,
        "array<MaterialRecord>",
        FRAGMENT,
    ),
    texture(
        "data_textures",
        TextureKind {
            dimension: wgpu::TextureViewDimension::D2Array,
            ..TextureKind::d2(FILTERABLE)
        },
        FRAGMENT,
    ),
];

/// Group 2 of the built-in draw pipelines: the frame's shadow map and its comparison
/// sampler (`light_reaching` in `wgsl/shared/draw_common.wgsl`).
pub const SHADOW_MAP_BINDINGS: [Binding; 2] = [
    texture(
        "shadow_map",
        TextureKind::d2(wgpu::TextureSampleType::Depth),
        FRAGMENT,
    ),
    sampler(
        "shadow_sampler",
        wgpu::SamplerBindingType::Comparison,
        FRAGMENT,
    ),
];

/// The far layer's composite (`wgsl/far_composite.wgsl`): the display's and the far
/// layer's contexts, the far layer's color and depth.
pub const FAR_COMPOSITE_BINDINGS: [Binding; 5] = [
    binding("display", Access::Uniform, "DisplayContext", FRAGMENT),
    binding("far", Access::Uniform, "DisplayContext", FRAGMENT),
    texture("far_color", TextureKind::d2(FILTERABLE), FRAGMENT),
    texture(
        "far_depth",
        TextureKind::d2(wgpu::TextureSampleType::Depth),
        FRAGMENT,
    ),
    sampler("far_sampler", wgpu::SamplerBindingType::Filtering, FRAGMENT),
];

/// A foveated display's composite (`wgsl/foveated_composite.wgsl`): its parameters and
/// the display's target, read texel by texel.
pub const FOVEATED_COMPOSITE_BINDINGS: [Binding; 2] = [
    binding("params", Access::Uniform, "CompositeParams", FRAGMENT),
    texture(
        "source",
        TextureKind::d2(wgpu::TextureSampleType::Float { filterable: false }),
        FRAGMENT,
    ),
];

/// The frame's skinning pass (`wgsl/skin.wgsl`).
pub const SKIN_BINDINGS: [Binding; 4] = [
    binding("rest", Access::StorageRead, "array<SkinVertex>", COMPUTE),
    // Each joint's matrix, three rows.
    binding(
        "joints",
        Access::StorageRead,
        "array<array<vec4<f32>, 3>>",
        COMPUTE,
    ),
    // The vertex buffer every later pass draws, as words (its Vertex layout).
    binding("vertices", Access::StorageReadWrite, "array<u32>", COMPUTE),
    binding("params", Access::Uniform, "SkinParams", COMPUTE),
];

/// The frame's pose pass (`wgsl/pose.wgsl`), one group for its three entry points:
/// the frame, the tables, each node's local and world rows, and what it writes for the
/// skins and the scatter of moves.
pub const POSE_BINDINGS: [Binding; 12] = [
    binding("frame", Access::Uniform, "FrameContext", COMPUTE),
    binding("nodes", Access::StorageRead, "array<PoseNode>", COMPUTE),
    binding(
        "channels",
        Access::StorageRead,
        "array<PoseChannel>",
        COMPUTE,
    ),
    binding("times", Access::StorageRead, "array<f32>", COMPUTE),
    binding("values", Access::StorageRead, "array<vec4<f32>>", COMPUTE),
    binding("locals", Access::StorageReadWrite, "array<Rows>", COMPUTE),
    binding("worlds", Access::StorageReadWrite, "array<Rows>", COMPUTE),
    binding("targets", Access::StorageRead, "array<PoseTarget>", COMPUTE),
    binding(
        "skin_joints",
        Access::StorageRead,
        "array<SkinJoint>",
        COMPUTE,
    ),
    binding(
        "joint_matrices",
        Access::StorageReadWrite,
        "array<Rows>",
        COMPUTE,
    ),
    binding("edits", Access::StorageReadWrite, "Edits", COMPUTE),
    binding("params", Access::Uniform, "PoseParams", COMPUTE),
];

/// The occlusion pyramids' pass (`wgsl/occlusion_pyramid.wgsl`) over a depth target of
/// `samples` per pixel, its eyes side by side or (`layered`) a layer each: the
/// display's context, each dispatch's level record (a dynamic offset), the pyramids,
/// the depth.
pub fn pyramid_bindings(samples: u32, layered: bool) -> [Binding; 4] {
    let depth = TextureKind {
        dimension: match layered {
            true => wgpu::TextureViewDimension::D2Array,
            false => wgpu::TextureViewDimension::D2,
        },
        multisampled: samples > 1,
        ..TextureKind::d2(wgpu::TextureSampleType::Depth)
    };
    [
        binding("display", Access::Uniform, "DisplayContext", COMPUTE),
        binding("level", Access::UniformDynamic, "PyramidLevel", COMPUTE),
        binding("pyramid", Access::StorageReadWrite, "array<f32>", COMPUTE),
        texture("depth", depth, COMPUTE),
    ]
}

/// A pipeline layout of one bind group, `group`.
pub(crate) fn pipeline_layout(
    device: &wgpu::Device,
    label: &str,
    group: &wgpu::BindGroupLayout,
) -> wgpu::PipelineLayout {
    device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: &[Some(group)],
        immediate_size: 0,
    })
}

/// The compute pipeline of `entry` in WGSL `source`.
pub(crate) fn compute_pipeline(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::PipelineLayout,
    source: String,
    entry: &str,
) -> wgpu::ComputePipeline {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(label),
        layout: Some(layout),
        module: &module,
        entry_point: Some(entry),
        compilation_options: Default::default(),
        cache: None,
    })
}

/// Splits `groups` workgroups into x * y with x within the per-dimension limit.
pub(crate) fn dispatch_size(groups: u32, max_per_dimension: u32) -> (u32, u32) {
    let x = groups.clamp(1, max_per_dimension);
    (x, groups.div_ceil(x).max(1))
}

/// The WGSL declarations of `bindings`, in `group`, windowed ones as `windows` says,
/// each with its accessors.
pub fn declarations(bindings: &[Binding], group: u32, windows: &Windows) -> String {
    let mut number = 0;
    let mut out = String::new();
    for (b, count) in bindings.iter().zip(window_counts(windows, bindings)) {
        let space = match b.access {
            Access::Uniform | Access::UniformDynamic => "<uniform>",
            Access::StorageRead => "<storage, read>",
            Access::StorageReadWrite => "<storage, read_write>",
            Access::Texture(_) | Access::Sampler(_) => "",
        };
        let names = window_names(b.name, count);
        for name in &names {
            out += &format!(
                "@group({group}) @binding({number}) var{space} {name}: {};\n",
                b.wgsl_type
            );
            number += 1;
        }
        if let Some(w) = b.windowed {
            out += &accessors(b, &names, windows.of(w).shift);
        }
    }
    out
}

fn window_names(name: &str, count: u32) -> Vec<String> {
    match count {
        1 => vec![name.to_string()],
        n => (0..n).map(|k| format!("{name}_{k}")).collect(),
    }
}

/// `<name>_at(i)`, and for writable arrays `<name>_set(i, v)`: element `i` in window
/// `i >> shift`.
fn accessors(b: &Binding, names: &[String], shift: u32) -> String {
    let element = b
        .wgsl_type
        .strip_prefix("array<")
        .and_then(|t| t.strip_suffix('>'))
        .unwrap_or(b.wgsl_type);
    let name = b.name;
    let pick = |body: &dyn Fn(&str) -> String| match names {
        [one] => body(&format!("{one}[i]")),
        _ => {
            let mask = (1u64 << shift) - 1;
            let cases: String = names
                .iter()
                .enumerate()
                .map(|(k, n)| {
                    let label = if k + 1 == names.len() {
                        "default".to_string()
                    } else {
                        format!("case {k}u")
                    };
                    format!(
                        "        {label}: {{ {} }}\n",
                        body(&format!("{n}[i & {mask}u]"))
                    )
                })
                .collect();
            format!("    switch (i >> {shift}u) {{\n{cases}    }}\n")
        }
    };
    let wrap = |body: String| match names {
        [_] => format!("    {body}\n"),
        _ => body,
    };
    let mut out = format!(
        "fn {name}_at(i: u32) -> {element} {{\n{}}}\n",
        wrap(pick(&|at| format!("return {at};")))
    );
    if b.access == Access::StorageReadWrite {
        out += &format!(
            "fn {name}_set(i: u32, v: {element}) {{\n{}}}\n",
            wrap(pick(&|at| format!("{at} = v;")))
        );
    }
    out
}

/// The bind-group layout of `bindings`, windowed ones as `windows` says.
pub fn bind_group_layout(
    device: &wgpu::Device,
    label: &str,
    bindings: &[Binding],
    windows: &Windows,
) -> wgpu::BindGroupLayout {
    let mut entries = Vec::new();
    for (b, count) in bindings.iter().zip(window_counts(windows, bindings)) {
        for _ in 0..count {
            entries.push(wgpu::BindGroupLayoutEntry {
                binding: entries.len() as u32,
                visibility: b.stages,
                ty: binding_type(b.access),
                count: None,
            });
        }
    }
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries: &entries,
    })
}

/// The layout entry's type of a binding of kind `access`. No minimum sizes: wgpu checks
/// the bound sizes against the shader when a pipeline is made.
fn binding_type(access: Access) -> wgpu::BindingType {
    let buffer = |ty, has_dynamic_offset| wgpu::BindingType::Buffer {
        ty,
        has_dynamic_offset,
        min_binding_size: None,
    };
    let storage = |read_only| wgpu::BufferBindingType::Storage { read_only };
    match access {
        Access::Uniform => buffer(wgpu::BufferBindingType::Uniform, false),
        Access::UniformDynamic => buffer(wgpu::BufferBindingType::Uniform, true),
        Access::StorageRead => buffer(storage(true), false),
        Access::StorageReadWrite => buffer(storage(false), false),
        Access::Texture(kind) => wgpu::BindingType::Texture {
            sample_type: kind.sample,
            view_dimension: kind.dimension,
            multisampled: kind.multisampled,
        },
        Access::Sampler(ty) => wgpu::BindingType::Sampler(ty),
    }
}

/// A bind group with `buffers[i]` for `bindings[i]` (the list `layout` was made from):
/// whole, or a windowed one as its windows, each `1 << shift` elements further.
pub fn bind_group<const N: usize>(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    bindings: &[Binding],
    windows: &Windows,
    buffers: [&wgpu::Buffer; N],
) -> wgpu::BindGroup {
    let mut entries = Vec::new();
    for (b, buffer) in bindings.iter().zip(buffers) {
        let window = b.windowed.map(|w| (windows.of(w), w.stride()));
        match window {
            Some((w, stride)) if w.count > 1 => {
                let bytes = stride << w.shift;
                for k in 0..w.count as u64 {
                    // A window past the buffer's end (a stand-in) binds it whole.
                    let resource = match k * bytes {
                        offset if offset < buffer.size() => {
                            wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                                buffer,
                                offset,
                                size: wgpu::BufferSize::new(bytes.min(buffer.size() - offset)),
                            })
                        }
                        _ => buffer.as_entire_binding(),
                    };
                    entries.push(wgpu::BindGroupEntry {
                        binding: entries.len() as u32,
                        resource,
                    });
                }
            }
            _ => entries.push(wgpu::BindGroupEntry {
                binding: entries.len() as u32,
                resource: buffer.as_entire_binding(),
            }),
        }
    }
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout,
        entries: &entries,
    })
}
