//! GPU culling: per display, four compute dispatches (`wgsl/cull.wgsl`,
//! `cull_scan.wgsl`, `cull_draws.wgsl`, `cull_compact.wgsl`) that write the visible
//! list, the draws and the draw count per the contract in [`super`], byte-identical to
//! [`super::cpu`]. Each sphere is read once per display whatever the levels of detail,
//! into one word per position; the prefix sums run as a tree (spans, groups of spans,
//! then one workgroup over the groups), never one workgroup over every block. With the
//! frame-level coarse cull ([`super::coarse`]), two dispatches per frame first
//! (`wgsl/cull_coarse.wgsl`) list each display's blocks, and each display's passes run
//! over its blocks' positions, dispatched indirectly from their count.

use crate::buffers::{init_buffer, init_buffer_with_room, storage_buffer};

use crate::cull::CullOutput;
use crate::cull::coarse::{BLOCK, CoarseCull};
use crate::records::{CullLayout, DrawArgs};
use crate::records::{storage_bytes, uniform_bytes};
use crate::shaders::{
    COARSE_BINDINGS, CULL_BINDINGS, CullPass, SPAN, WORKGROUP_SIZE, Windows, bind_group,
    bind_group_layout, compute_pipeline, dispatch_size, pipeline_layout,
};
use encase::ShaderType;
use glam::Vec4;

/// The uniform the cull passes read besides the display context (`CullParams` in
/// `wgsl/shared/records.wgsl`); encase lays it out as WGSL does.
#[derive(Clone, Copy, Debug, PartialEq, Eq, encase::ShaderType)]
pub struct CullParams {
    /// Places of the cull order (instances when laid out tight).
    pub instance_count: u32,
    /// Meshes in the scene: draws per level.
    pub mesh_count: u32,
    /// The device's limit of workgroups per dimension: the coarse pass splits the
    /// candidates' dispatch into x and y with it.
    pub max_groups: u32,
    /// Levels of detail in use: 1 (off) or [`crate::scene::MAX_LODS`].
    pub lod_levels: u32,
}

/// Bytes of the counts buffer: the draw count, then the visible total.
pub const COUNTS_BYTES: u64 = 8;

/// The cull pipelines and their shared bind-group layout.
pub struct GpuCuller {
    layout: wgpu::BindGroupLayout,
    /// How the spheres are bound.
    windows: Windows,
    /// The display passes over every instance, in dispatch order (the displays' without
    /// the coarse cull; the light's always).
    pipelines: Vec<wgpu::ComputePipeline>,
    coarse: Option<CoarsePipelines>,
    /// The floor kernel, when asked for (`profile`).
    floor: Option<wgpu::ComputePipeline>,
}

/// The coarse cull's pipelines.
struct CoarsePipelines {
    /// The display passes over the candidates.
    display: Vec<wgpu::ComputePipeline>,
    /// The frame passes, and their group 1's layout (their writes of the display
    /// passes' indirect dispatch).
    frame: Vec<wgpu::ComputePipeline>,
    args_layout: wgpu::BindGroupLayout,
}

/// Scene data the cull passes read, uploaded once, plus scratch shared by all displays
/// (displays cull one after another, so one scratch suffices).
pub struct CullScene {
    /// Places of the cull order the passes run over.
    pub instance_count: u32,
    groups: (u32, u32),
    max_groups: u32,
    /// Levels of detail culled into: the y of the scan dispatch.
    pub levels: u32,
    /// Groups of spans at most: the x of the scan dispatch.
    scan_groups: u32,
    params: wgpu::Buffer,
    spheres: wgpu::Buffer,
    order: wgpu::Buffer,
    positions: wgpu::Buffer,
    mesh_of: wgpu::Buffer,
    meshes: wgpu::Buffer,
    mesh_bounds: wgpu::Buffer,
    lods: wgpu::Buffer,
    entries: wgpu::Buffer,
    span_sums: wgpu::Buffer,
    /// The coarse cull's slots (displays; 0 without it) and its buffers per slot.
    coarse_slots: u32,
    block_marks: wgpu::Buffer,
    block_list: wgpu::Buffer,
    /// Each slot's listed positions (the coarse passes write it; read back for
    /// statistics).
    pub candidate_count: wgpu::Buffer,
    candidate_ranges: wgpu::Buffer,
    block_tests: wgpu::Buffer,
    /// The display passes' indirect dispatches, one per slot, written by the coarse
    /// passes.
    coarse_args: wgpu::Buffer,
}

/// One display's cull outputs: what its draw pass consumes.
pub struct CullTargets {
    /// The visible ids, per the cull contract.
    pub visible: wgpu::Buffer,
    /// The packed draws (meshes times levels entries), for the multi-draw.
    pub draws: wgpu::Buffer,
    /// [`COUNTS_BYTES`]: the draw count (what `multi_draw_indexed_indirect_count`
    /// reads), then the visible total (for statistics without reading `visible`).
    pub counts: wgpu::Buffer,
}

impl CullScene {
    /// Uploads `layout`, with room for `slots` instances (a live scene's capacity), for
    /// culling into `levels` levels of detail (1: LOD off), with room for the coarse
    /// cull's lists of `coarse_slots` displays (0: no coarse cull).
    pub fn new(
        device: &wgpu::Device,
        layout: &CullLayout,
        slots: u32,
        levels: u32,
        coarse_slots: u32,
    ) -> CullScene {
        let slots = slots
            .max(layout.positions.len() as u32)
            .max(layout.order.len() as u32);
        let max_groups = device.limits().max_compute_workgroups_per_dimension;
        let (params, groups) = cull_params(layout, (max_groups, levels));
        let room = |label: &str, contents: &[u8], per_slot: u64| {
            let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
            init_buffer_with_room(device, label, contents, per_slot * slots as u64, usage)
        };
        let scratch = wgpu::BufferUsages::STORAGE;
        // The display passes may run past the last instance to the end of its block.
        let positions = slots.next_multiple_of(BLOCK) as u64;
        let per_slot = |bytes: u64| bytes * coarse_slots as u64;
        let block_bytes = per_slot(4 * slots.div_ceil(BLOCK) as u64);
        let meshes = layout.meshes.len() as u64;
        let (spans, scan_groups) = span_shape(positions as u32);
        CullScene {
            instance_count: params.instance_count,
            groups,
            max_groups,
            levels,
            scan_groups,
            params: init_buffer(
                device,
                "stereocull.cull_params",
                &uniform_bytes(&params),
                wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            ),
            spheres: room(
                "stereocull.spheres",
                bytemuck::cast_slice(&layout.spheres),
                16,
            ),
            order: room("stereocull.order", bytemuck::cast_slice(&layout.order), 4),
            positions: room(
                "stereocull.positions",
                bytemuck::cast_slice(&layout.positions),
                4,
            ),
            mesh_of: room(
                "stereocull.mesh_of",
                bytemuck::cast_slice(&layout.mesh_of),
                4,
            ),
            meshes: room("stereocull.meshes", bytemuck::cast_slice(&layout.meshes), 0),
            mesh_bounds: room(
                "stereocull.mesh_bounds",
                bytemuck::cast_slice(&layout.mesh_bounds),
                0,
            ),
            lods: room("stereocull.lods", bytemuck::cast_slice(&layout.lods), 0),
            entries: storage_buffer(device, "stereocull.entries", 4 * positions, scratch),
            span_sums: storage_buffer(
                device,
                "stereocull.span_sums",
                4 * ((spans + scan_groups) * levels) as u64,
                scratch,
            ),
            coarse_slots,
            block_marks: storage_buffer(device, "stereocull.block_marks", block_bytes, scratch),
            block_list: storage_buffer(device, "stereocull.block_list", block_bytes, scratch),
            candidate_count: storage_buffer(
                device,
                "stereocull.candidate_count",
                per_slot(4),
                scratch | wgpu::BufferUsages::COPY_SRC,
            ),
            candidate_ranges: storage_buffer(
                device,
                "stereocull.candidate_ranges",
                per_slot(8 * meshes),
                scratch,
            ),
            block_tests: storage_buffer(
                device,
                "stereocull.block_tests",
                per_slot(CoarseCull::min_size().get()),
                scratch | wgpu::BufferUsages::COPY_DST,
            ),
            coarse_args: storage_buffer(
                device,
                "stereocull.coarse_args",
                per_slot(12),
                scratch | wgpu::BufferUsages::INDIRECT,
            ),
        }
    }

    /// Writes this frame's block tests, one per coarse slot (display, in order): the
    /// display frustums' planes grown for rounding ([`CoarseCull::around`]). Returns the
    /// bytes written; nothing without the coarse cull.
    pub fn write_block_tests(&self, queue: &wgpu::Queue, planes: &[[Vec4; 6]]) -> u64 {
        if self.coarse_slots == 0 {
            return 0;
        }
        let tests: Vec<CoarseCull> = planes.iter().map(|p| CoarseCull::around(*p)).collect();
        let bytes = storage_bytes(&tests);
        queue.write_buffer(&self.block_tests, 0, &bytes);
        bytes.len() as u64
    }

    /// Writes a new `layout` (instances inserted or removed) into the buffers, which must
    /// have room for it (same meshes, no more slots than made for); returns the bytes.
    pub fn reload(&mut self, queue: &wgpu::Queue, layout: &CullLayout) -> u64 {
        let (params, groups) = cull_params(layout, (self.max_groups, self.levels));
        (self.instance_count, self.groups) = (params.instance_count, groups);
        let writes: [(&wgpu::Buffer, &[u8]); 6] = [
            (&self.params, &uniform_bytes(&params)),
            (&self.spheres, bytemuck::cast_slice(&layout.spheres)),
            (&self.order, bytemuck::cast_slice(&layout.order)),
            (&self.positions, bytemuck::cast_slice(&layout.positions)),
            (&self.mesh_of, bytemuck::cast_slice(&layout.mesh_of)),
            (&self.meshes, bytemuck::cast_slice(&layout.meshes)),
        ];
        writes
            .iter()
            .map(|(buffer, bytes)| {
                queue.write_buffer(buffer, 0, bytes);
                bytes.len() as u64
            })
            .sum()
    }

    /// Where the scatter passes write (the spheres in cull order, each slot's
    /// position, each position's slot) and what they read (each mesh's local bounds).
    pub fn scatter_targets(&self) -> [&wgpu::Buffer; 4] {
        [
            &self.spheres,
            &self.positions,
            &self.order,
            &self.mesh_bounds,
        ]
    }

    /// Bytes on the GPU per instance for culling (spheres, order, positions, mesh, the
    /// entry), whatever the levels of detail (their span sums add 4 bytes per level per
    /// [`SPAN`] instances).
    pub const BYTES_PER_INSTANCE: u64 = 16 + 4 + 4 + 4 + 4;
}

impl CullTargets {
    /// Sized for every instance visible and `draws` draws (meshes times levels).
    pub fn new(device: &wgpu::Device, instance_count: u32, draws: u32) -> CullTargets {
        let out = wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST;
        let indirect = out | wgpu::BufferUsages::INDIRECT;
        CullTargets {
            visible: storage_buffer(device, "stereocull.visible", 4 * instance_count as u64, out),
            draws: storage_buffer(
                device,
                "stereocull.draws",
                (size_of::<DrawArgs>() as u32 * draws) as u64,
                indirect,
            ),
            counts: storage_buffer(device, "stereocull.counts", COUNTS_BYTES, indirect),
        }
    }

    /// Writes a CPU cull's `out` into these buffers; returns the bytes written.
    pub fn upload(&self, queue: &wgpu::Queue, out: &CullOutput) -> u64 {
        let counts = [out.draw_count, out.visible.len() as u32];
        let writes: [(&wgpu::Buffer, &[u8]); 3] = [
            (&self.visible, bytemuck::cast_slice(&out.visible)),
            (&self.draws, bytemuck::cast_slice(&out.draws)),
            (&self.counts, bytemuck::cast_slice(&counts)),
        ];
        writes
            .iter()
            .filter(|(_, bytes)| !bytes.is_empty())
            .map(|(buffer, bytes)| {
                queue.write_buffer(buffer, 0, bytes);
                bytes.len() as u64
            })
            .sum()
    }
}

/// Spans and groups of spans (the scan's x) over `positions` cull positions, as
/// `span_count` and `group_count` in `wgsl/shared/cull_math.wgsl` count them.
fn span_shape(positions: u32) -> (u32, u32) {
    let spans = positions.div_ceil(SPAN);
    (spans, spans.div_ceil(WORKGROUP_SIZE))
}

fn cull_params(layout: &CullLayout, (max_groups, levels): (u32, u32)) -> (CullParams, (u32, u32)) {
    let n = layout.spheres.len() as u32;
    let groups = dispatch_size(n.div_ceil(WORKGROUP_SIZE), max_groups);
    let params = CullParams {
        instance_count: n,
        mesh_count: layout.meshes.len() as u32,
        max_groups,
        lod_levels: levels,
    };
    (params, groups)
}

impl GpuCuller {
    /// The display passes, and with `coarse` the frame passes and the display passes
    /// over their candidates too; with `floor` the floor kernel.
    pub fn new(
        device: &wgpu::Device,
        (coarse, floor): (bool, bool),
        windows: Windows,
    ) -> GpuCuller {
        let layout = bind_group_layout(device, "stereocull.cull", &CULL_BINDINGS, &windows);
        let build = |passes: &[CullPass], candidates: bool, with: &wgpu::PipelineLayout| {
            let build_one = |pass: &CullPass| {
                let source = pass.source(candidates, &windows);
                let label = pass.label(candidates);
                compute_pipeline(device, &label, with, source, pass.entry_point())
            };
            passes.iter().map(build_one).collect()
        };
        let display_layout = pipeline_layout(device, "stereocull.cull", &layout);
        let pipelines = build(&CullPass::DISPLAY, false, &display_layout);
        let coarse = coarse.then(|| {
            let whole = &Windows::WHOLE;
            let args_layout =
                bind_group_layout(device, "stereocull.coarse", &COARSE_BINDINGS, whole);
            let both = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("stereocull.coarse"),
                bind_group_layouts: &[Some(&layout), Some(&args_layout)],
                immediate_size: 0,
            });
            CoarsePipelines {
                display: build(&CullPass::DISPLAY, true, &display_layout),
                frame: build(&CullPass::FRAME, false, &both),
                args_layout,
            }
        });
        let floor = floor.then(|| build(&[CullPass::Floor], false, &display_layout).remove(0));
        GpuCuller {
            layout,
            windows,
            pipelines,
            coarse,
            floor,
        }
    }

    /// The bind group for one display: the frame context, shared scene data, and the
    /// display's context and outputs.
    pub fn bind_group(
        &self,
        device: &wgpu::Device,
        scene: &CullScene,
        [frame_context, display_context]: [&wgpu::Buffer; 2],
        targets: &CullTargets,
    ) -> wgpu::BindGroup {
        // In CULL_BINDINGS order.
        let buffers = [
            frame_context,
            display_context,
            &scene.params,
            &scene.order,
            &scene.meshes,
            &scene.lods,
            &scene.mesh_of,
            &scene.entries,
            &scene.span_sums,
            &targets.visible,
            &targets.draws,
            &targets.counts,
            &scene.block_marks,
            &scene.block_list,
            &scene.candidate_count,
            &scene.candidate_ranges,
            &scene.block_tests,
            &scene.spheres,
        ];
        let (label, layout) = ("stereocull.cull", &self.layout);
        bind_group(
            device,
            label,
            layout,
            &CULL_BINDINGS,
            &self.windows,
            buffers,
        )
    }

    /// Group 1 of the frame passes (with the coarse cull).
    pub fn coarse_bind_group(
        &self,
        device: &wgpu::Device,
        scene: &CullScene,
    ) -> Option<wgpu::BindGroup> {
        let coarse = self.coarse.as_ref()?;
        Some(bind_group(
            device,
            "stereocull.coarse",
            &coarse.args_layout,
            &COARSE_BINDINGS,
            &Windows::WHOLE,
            [&scene.coarse_args],
        ))
    }

    /// Records the frame's coarse cull (nothing without it): `bind_groups` are any
    /// display's group 0 (the frame passes read none of its display's bindings) and
    /// [`GpuCuller::coarse_bind_group`]. Returns the dispatches.
    pub fn encode_frame(
        &self,
        pass: &mut wgpu::ComputePass,
        scene: &CullScene,
        [display, args]: [&wgpu::BindGroup; 2],
    ) -> u32 {
        let Some(CoarsePipelines {
            frame: pipelines, ..
        }) = &self.coarse
        else {
            return 0;
        };
        pass.set_bind_group(0, display, &[]);
        pass.set_bind_group(1, args, &[]);
        let (x, y) = scene.groups;
        for (pipeline, kind) in pipelines.iter().zip(CullPass::FRAME) {
            pass.set_pipeline(pipeline);
            match kind {
                CullPass::CoarseLists => pass.dispatch_workgroups(scene.coarse_slots, 1, 1),
                _ => pass.dispatch_workgroups(x, y, 1),
            }
        }
        pipelines.len() as u32
    }

    /// Records the four dispatches for one display: a fixed count, whatever the
    /// number of instances; with the coarse cull's `slot` they run over that slot's
    /// listed blocks, dispatched as the coarse passes sized them (the scan's groups
    /// past the listed ones return at once).
    pub fn encode(
        &self,
        pass: &mut wgpu::ComputePass,
        scene: &CullScene,
        bind_group: &wgpu::BindGroup,
        slot: Option<u32>,
    ) {
        pass.set_bind_group(0, bind_group, &[]);
        let (x, y) = scene.groups;
        let (pipelines, slot) = match (&self.coarse, slot) {
            (Some(c), Some(slot)) => (&c.display, Some(slot)),
            _ => (&self.pipelines, None),
        };
        for (pipeline, kind) in pipelines.iter().zip(CullPass::DISPLAY) {
            pass.set_pipeline(pipeline);
            match (kind, slot) {
                (CullPass::Draws, _) => pass.dispatch_workgroups(1, 1, 1),
                (CullPass::Scan, _) => pass.dispatch_workgroups(scene.scan_groups, scene.levels, 1),
                (_, Some(s)) => {
                    pass.dispatch_workgroups_indirect(&scene.coarse_args, 12 * s as u64)
                }
                (_, None) => pass.dispatch_workgroups(x, y, 1),
            }
        }
    }

    /// Whether the floor kernel was built.
    pub fn has_floor(&self) -> bool {
        self.floor.is_some()
    }

    /// Records the floor kernel over every instance with `bind_group` (any display's;
    /// it writes that display's scratch). Returns whether it was built.
    pub fn encode_floor(
        &self,
        pass: &mut wgpu::ComputePass,
        scene: &CullScene,
        bind_group: &wgpu::BindGroup,
    ) -> bool {
        let Some(floor) = &self.floor else {
            return false;
        };
        pass.set_bind_group(0, bind_group, &[]);
        pass.set_pipeline(floor);
        let (x, y) = scene.groups;
        pass.dispatch_workgroups(x, y, 1);
        true
    }

    /// Compute dispatches per display: cull, scan, draws, compact.
    pub const DISPATCHES_PER_DISPLAY: u32 = CullPass::DISPLAY.len() as u32;
}
