//! GPU culling: per display, three compute dispatches (`wgsl/cull.wgsl`,
//! `cull_draws.wgsl`, `cull_compact.wgsl`) that write the visible list, the draws and the
//! draw count per the contract in [`super`], byte-identical to [`super::cpu`].

use wgpu::util::DeviceExt;

use crate::records::{CullLayout, DrawArgs};
use crate::shaders::{CullPass, WORKGROUP_SIZE};

/// The uniform the cull passes read besides the display context (`CullParams` in WGSL).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct CullParams {
    pub instance_count: u32,
    pub mesh_count: u32,
    pub groups_x: u32,
    /// Pads the uniform to 16 bytes.
    pub reserved: u32,
}

/// Bytes of the count buffer: the draw count, then the visible total.
pub const COUNT_BYTES: u64 = 8;

/// The cull pipelines and their shared bind-group layout.
pub struct GpuCuller {
    layout: wgpu::BindGroupLayout,
    pipelines: Vec<wgpu::ComputePipeline>,
}

/// Scene data the cull passes read, uploaded once, plus scratch shared by all displays
/// (displays cull one after another, so one scratch suffices).
pub struct CullScene {
    pub instance_count: u32,
    pub mesh_count: u32,
    groups: (u32, u32),
    params: wgpu::Buffer,
    spheres: wgpu::Buffer,
    order: wgpu::Buffer,
    meshes: wgpu::Buffer,
    local_prefix: wgpu::Buffer,
    block_sums: wgpu::Buffer,
}

/// One display's cull outputs: what its draw pass consumes.
pub struct CullTargets {
    pub visible: wgpu::Buffer,
    pub draws: wgpu::Buffer,
    /// [`COUNT_BYTES`]: draw count, visible total.
    pub count: wgpu::Buffer,
}

impl CullScene {
    pub fn new(device: &wgpu::Device, layout: &CullLayout) -> CullScene {
        let n = layout.spheres.len() as u32;
        let groups = dispatch_size(
            n.div_ceil(WORKGROUP_SIZE),
            device.limits().max_compute_workgroups_per_dimension,
        );
        let params = CullParams {
            instance_count: n,
            mesh_count: layout.meshes.len() as u32,
            groups_x: groups.0,
            reserved: 0,
        };
        let init = |label: &str, contents: &[u8], usage| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            })
        };
        let storage = wgpu::BufferUsages::STORAGE;
        CullScene {
            instance_count: n,
            mesh_count: params.mesh_count,
            groups,
            params: init(
                "stereocull.cull_params",
                bytemuck::bytes_of(&params),
                wgpu::BufferUsages::UNIFORM,
            ),
            spheres: init(
                "stereocull.spheres",
                bytemuck::cast_slice(&layout.spheres),
                storage,
            ),
            order: init(
                "stereocull.order",
                bytemuck::cast_slice(&layout.order),
                storage,
            ),
            meshes: init(
                "stereocull.meshes",
                bytemuck::cast_slice(&layout.meshes),
                storage,
            ),
            local_prefix: storage_buffer(device, "stereocull.local_prefix", 4 * n as u64, storage),
            block_sums: storage_buffer(
                device,
                "stereocull.block_sums",
                4 * (groups.0 * groups.1) as u64,
                storage,
            ),
        }
    }

    /// Bytes on the GPU per instance for culling (spheres, order, scratch).
    pub const BYTES_PER_INSTANCE: u64 = 16 + 4 + 4;
}

impl CullTargets {
    /// Sized for every instance visible and every mesh drawn.
    pub fn new(device: &wgpu::Device, instance_count: u32, mesh_count: u32) -> CullTargets {
        let out = wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST;
        let indirect = out | wgpu::BufferUsages::INDIRECT;
        CullTargets {
            visible: storage_buffer(device, "stereocull.visible", 4 * instance_count as u64, out),
            draws: storage_buffer(
                device,
                "stereocull.draws",
                (size_of::<DrawArgs>() as u32 * mesh_count) as u64,
                indirect,
            ),
            count: storage_buffer(device, "stereocull.draw_count", COUNT_BYTES, indirect),
        }
    }
}

fn storage_buffer(
    device: &wgpu::Device,
    label: &str,
    size: u64,
    usage: wgpu::BufferUsages,
) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(4),
        usage,
        mapped_at_creation: false,
    })
}

/// Splits `groups` workgroups into x * y with x within the per-dimension limit.
fn dispatch_size(groups: u32, max_per_dimension: u32) -> (u32, u32) {
    let x = groups.clamp(1, max_per_dimension);
    (x, groups.div_ceil(x).max(1))
}

impl GpuCuller {
    pub fn new(device: &wgpu::Device) -> GpuCuller {
        let entry = |binding, ty| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty,
            count: None,
        };
        let uniform = wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        };
        let storage = |read_only| wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("stereocull.cull"),
            entries: &[
                entry(0, uniform),
                entry(1, uniform),
                entry(2, storage(true)),
                entry(3, storage(true)),
                entry(4, storage(true)),
                entry(5, storage(false)),
                entry(6, storage(false)),
                entry(7, storage(false)),
                entry(8, storage(false)),
                entry(9, storage(false)),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("stereocull.cull"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipelines = CullPass::ALL
            .iter()
            .map(|pass| {
                let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some(pass.label()),
                    source: wgpu::ShaderSource::Wgsl(pass.source().into()),
                });
                device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(pass.label()),
                    layout: Some(&pipeline_layout),
                    module: &module,
                    entry_point: Some(pass.entry_point()),
                    compilation_options: Default::default(),
                    cache: None,
                })
            })
            .collect();
        GpuCuller { layout, pipelines }
    }

    /// The bind group for one display: shared scene data plus its own outputs.
    pub fn bind_group(
        &self,
        device: &wgpu::Device,
        scene: &CullScene,
        display_context: &wgpu::Buffer,
        targets: &CullTargets,
    ) -> wgpu::BindGroup {
        let buffers = [
            display_context,
            &scene.params,
            &scene.spheres,
            &scene.order,
            &scene.meshes,
            &scene.local_prefix,
            &scene.block_sums,
            &targets.visible,
            &targets.draws,
            &targets.count,
        ];
        let entries: Vec<_> = buffers
            .iter()
            .enumerate()
            .map(|(i, b)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource: b.as_entire_binding(),
            })
            .collect();
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("stereocull.cull"),
            layout: &self.layout,
            entries: &entries,
        })
    }

    /// Records the three dispatches for one display: a fixed count, whatever the
    /// number of instances.
    pub fn encode(
        &self,
        pass: &mut wgpu::ComputePass,
        scene: &CullScene,
        bind_group: &wgpu::BindGroup,
    ) {
        pass.set_bind_group(0, bind_group, &[]);
        let (x, y) = scene.groups;
        for (pipeline, kind) in self.pipelines.iter().zip(CullPass::ALL) {
            pass.set_pipeline(pipeline);
            match kind {
                CullPass::Draws => pass.dispatch_workgroups(1, 1, 1),
                CullPass::Cull | CullPass::Compact => pass.dispatch_workgroups(x, y, 1),
            }
        }
    }

    pub const DISPATCHES_PER_DISPLAY: u32 = CullPass::ALL.len() as u32;
}
