//! The binding lists of the buffer-bound pipeline families, and everything made from
//! them: WGSL declarations, bind-group layouts and bind groups, pipelines.

/// One buffer binding of group 0: its WGSL declaration and its layout entry both come
/// from here; its binding number is its position in the list.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Binding {
    pub name: &'static str,
    pub access: Access,
    pub wgsl_type: &'static str,
    pub stages: wgpu::ShaderStages,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Access {
    Uniform,
    StorageRead,
    StorageReadWrite,
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
    }
}

const COMPUTE: wgpu::ShaderStages = wgpu::ShaderStages::COMPUTE;

/// Every cull pass's bindings: the frame context, per display its context and outputs,
/// the scene data uploaded once, scratch shared by all displays, and the frame's coarse
/// cull results.
pub const CULL_BINDINGS: [Binding; 16] = [
    binding("frame", Access::Uniform, "FrameContext", COMPUTE),
    binding("display", Access::Uniform, "DisplayContext", COMPUTE),
    binding("params", Access::Uniform, "CullParams", COMPUTE),
    // World bounding spheres in cull order.
    binding("spheres", Access::StorageRead, "array<vec4<f32>>", COMPUTE),
    // Instance id at each cull position.
    binding("order", Access::StorageRead, "array<u32>", COMPUTE),
    binding("meshes", Access::StorageRead, "array<MeshRecord>", COMPUTE),
    // MAX_LODS levels per mesh.
    binding("lods", Access::StorageRead, "array<LodRecord>", COMPUTE),
    // Mesh of each cull position.
    binding("mesh_of", Access::StorageRead, "array<u32>", COMPUTE),
    // Per level of detail and instance: visibility bit and prefix within the workgroup.
    binding(
        "local_prefix",
        Access::StorageReadWrite,
        "array<u32>",
        COMPUTE,
    ),
    // Per level of detail and workgroup: its total, then (after the draws pass) its prefix.
    binding(
        "block_sums",
        Access::StorageReadWrite,
        "array<u32>",
        COMPUTE,
    ),
    binding("visible", Access::StorageReadWrite, "array<u32>", COMPUTE),
    binding(
        "draws",
        Access::StorageReadWrite,
        "array<DrawArgs>",
        COMPUTE,
    ),
    // The draw count (what multi_draw_indexed_indirect_count reads), visible total.
    binding("counts", Access::StorageReadWrite, "array<u32, 2>", COMPUTE),
    // The frame's coarse cull: candidate cull positions, ascending, their number, and
    // each mesh's (start, count) among them.
    binding(
        "candidates",
        Access::StorageReadWrite,
        "array<u32>",
        COMPUTE,
    ),
    binding(
        "candidate_count",
        Access::StorageReadWrite,
        "array<u32, 1>",
        COMPUTE,
    ),
    binding(
        "candidate_ranges",
        Access::StorageReadWrite,
        "array<vec2<u32>>",
        COMPUTE,
    ),
];

/// The frame-level coarse passes' group 1: the display passes' indirect dispatch,
/// which they write and nothing else binds (a buffer read as dispatch arguments may not
/// be bound for writing in the same dispatch).
pub const COARSE_BINDINGS: [Binding; 1] = [binding(
    "coarse_args",
    Access::StorageReadWrite,
    "array<u32, 3>",
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
        "instances",
        Access::StorageRead,
        "array<InstanceRecord>",
        wgpu::ShaderStages::VERTEX_FRAGMENT,
    ),
    binding(
        "visible",
        Access::StorageRead,
        "array<u32>",
        wgpu::ShaderStages::VERTEX,
    ),
];

/// The scatter pass's bindings (`wgsl/scatter.wgsl`): the frame's edits, and where
/// they go.
pub const SCATTER_BINDINGS: [Binding; 4] = [
    binding("edits", Access::StorageRead, "array<u32>", COMPUTE),
    binding(
        "instances",
        Access::StorageReadWrite,
        "array<InstanceRecord>",
        COMPUTE,
    ),
    // World bounding spheres in cull order (the GPU culler's; a stand-in otherwise).
    binding(
        "spheres",
        Access::StorageReadWrite,
        "array<vec4<f32>>",
        COMPUTE,
    ),
    // Cull position of each slot.
    binding("positions", Access::StorageRead, "array<u32>", COMPUTE),
];

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
    (source, entry): (String, &str),
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

/// The WGSL declarations of `bindings`, in `group`.
pub(super) fn declarations(bindings: &[Binding], group: u32) -> String {
    bindings
        .iter()
        .enumerate()
        .map(|(i, b)| {
            let space = match b.access {
                Access::Uniform => "uniform",
                Access::StorageRead => "storage, read",
                Access::StorageReadWrite => "storage, read_write",
            };
            format!(
                "@group({group}) @binding({i}) var<{space}> {}: {};\n",
                b.name, b.wgsl_type
            )
        })
        .collect()
}

/// The bind-group layout of `bindings`.
pub fn bind_group_layout(
    device: &wgpu::Device,
    label: &str,
    bindings: &[Binding],
) -> wgpu::BindGroupLayout {
    let entries: Vec<_> = bindings
        .iter()
        .enumerate()
        .map(|(i, b)| wgpu::BindGroupLayoutEntry {
            binding: i as u32,
            visibility: b.stages,
            ty: wgpu::BindingType::Buffer {
                ty: match b.access {
                    Access::Uniform => wgpu::BufferBindingType::Uniform,
                    Access::StorageRead => wgpu::BufferBindingType::Storage { read_only: true },
                    Access::StorageReadWrite => {
                        wgpu::BufferBindingType::Storage { read_only: false }
                    }
                },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        })
        .collect();
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries: &entries,
    })
}

/// A bind group with `buffers[i]` whole at binding `i`: the buffers in the order of
/// the binding list `layout` was made from.
pub fn bind_group<const N: usize>(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    buffers: [&wgpu::Buffer; N],
) -> wgpu::BindGroup {
    let entries: Vec<_> = buffers
        .iter()
        .enumerate()
        .map(|(i, b)| wgpu::BindGroupEntry {
            binding: i as u32,
            resource: b.as_entire_binding(),
        })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout,
        entries: &entries,
    })
}
