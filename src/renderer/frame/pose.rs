//! The frame's posing pass on the GPU ([`crate::pose_tables`], `wgsl/pose.wgsl`):
//! three dispatches (node locals, node worlds, targets) and the moves scatter of what
//! they wrote, in one compute pass before the skinning pass, from the frame context's
//! time. Built only with [`crate::renderer::Posing::Gpu`] and a scene that moves.

use super::skin::SkinPass;
use crate::buffers::init_buffer;
use crate::error::Result;
use crate::renderer::options::{PosingMode, RendererOptions};
use crate::renderer::recorder::Recorder;
use crate::scene::Scene;
use std::collections::HashMap;

use crate::places::Places;
use crate::pose_tables::{POSE_GROUP, PoseParamsRecord, PoseTables, PoseTargetRecord};
use crate::records::EditHeader;
use crate::scatter::{GpuMoves, ScatterTargets};
use crate::shaders::{
    POSE_BINDINGS, Windows, bind_group, bind_group_layout, dispatch_size, pipeline_layout,
    pose_source,
};

/// The pass's pipelines, tables and bindings.
pub struct PosePass {
    pipelines: [wgpu::ComputePipeline; 3],
    /// The frame's pose: one group for its three entry points (`POSE_BINDINGS`), and
    /// the scatter of its moves.
    first: PoseAt,
    /// A two-frame submission's second pose, `dt` ahead: the same tables, its own
    /// parameters and moves, which grow each sphere to hold both poses.
    second: Option<PoseAt>,
    dispatches: [(u32, u32); 3],
    /// Each posed slot's target (to void a removed instance's).
    targets_of: HashMap<u32, u32>,
    targets: wgpu::Buffer,
    gpu_bytes: u64,
}

/// One pose's bindings and the scatter of its moves.
struct PoseAt {
    bind_group: wgpu::BindGroup,
    moves: GpuMoves,
}

/// Where the pass writes: the skins' joint matrices and the scatter's targets; and,
/// for two frames per submission, the second frame's `dt`.
pub struct PoseOutputs<'a> {
    pub joint_matrices: &'a wgpu::Buffer,
    pub scatter: ScatterTargets<'a>,
    pub windows: Windows,
    pub second_ahead: Option<f32>,
}

impl PosePass {
    /// The pass for `tables`, reading the frame context `frame`.
    pub fn new(
        device: &wgpu::Device,
        tables: &PoseTables,
        frame: &wgpu::Buffer,
        outputs: PoseOutputs,
    ) -> PosePass {
        let storage = |label: &str, bytes: &[u8], write: bool| {
            let usage = wgpu::BufferUsages::STORAGE
                | if write {
                    wgpu::BufferUsages::COPY_DST
                } else {
                    wgpu::BufferUsages::empty()
                };
            init_buffer(device, label, bytes, usage)
        };
        use bytemuck::cast_slice as cast;
        let nodes = storage("stereocull.pose_nodes", cast(&tables.nodes), false);
        let channels = storage("stereocull.pose_channels", cast(&tables.channels), false);
        let times = storage("stereocull.pose_times", cast(&tables.times), false);
        let values = storage("stereocull.pose_values", cast(&tables.values), false);
        let targets = storage("stereocull.pose_targets", cast(&tables.targets), true);
        let joints = storage("stereocull.pose_joints", cast(&tables.joints), false);
        let rows = vec![0u8; tables.nodes.len() * 48];
        let locals = storage("stereocull.pose_locals", &rows, false);
        let worlds = storage("stereocull.pose_worlds", &rows, false);
        let max = device.limits().max_compute_workgroups_per_dimension;
        let (node_count, target_count) = (tables.nodes.len() as u32, tables.targets.len() as u32);
        let node_groups = dispatch_size(node_count.div_ceil(POSE_GROUP), max);
        let target_groups = dispatch_size(target_count.div_ceil(POSE_GROUP), max);
        let params = PoseParamsRecord {
            node_row: node_groups.0 * POSE_GROUP,
            target_row: target_groups.0 * POSE_GROUP,
            nodes: node_count,
            targets: target_count,
            ahead: 0.0,
        };
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("stereocull.pose"),
            source: wgpu::ShaderSource::Wgsl(pose_source().into()),
        });
        let (label, whole) = ("stereocull.pose", &Windows::WHOLE);
        let layout = bind_group_layout(device, label, &POSE_BINDINGS, whole);
        let at = |ahead: f32, grow: u32| {
            let params = init_buffer(
                device,
                "stereocull.pose_params",
                bytemuck::bytes_of(&PoseParamsRecord { ahead, ..params }),
                wgpu::BufferUsages::UNIFORM,
            );
            let moves = GpuMoves::new(
                device,
                (outputs.windows, grow),
                target_count,
                outputs.scatter,
            );
            let all = [
                frame,
                &nodes,
                &channels,
                &times,
                &values,
                &locals,
                &worlds,
                &targets,
                &joints,
                outputs.joint_matrices,
                moves.edits(),
                &params,
            ];
            let bind_group = bind_group(device, label, &layout, &POSE_BINDINGS, whole, all);
            PoseAt { bind_group, moves }
        };
        let first = at(0.0, EditHeader::EXACT);
        let second = (outputs.second_ahead).map(|dt| at(dt, EditHeader::GROWN_MEASURED));
        let pipeline_layout = pipeline_layout(device, label, &layout);
        let pipelines = ["locals_main", "worlds_main", "targets_main"].map(|entry| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(label),
                layout: Some(&pipeline_layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        });
        PosePass {
            pipelines,
            first,
            second,
            dispatches: [node_groups, node_groups, target_groups],
            targets_of: (tables.targets.iter().enumerate())
                .filter(|(_, t)| t.slot != Places::VACANT)
                .map(|(k, t)| (t.slot, k as u32))
                .collect(),
            targets,
            gpu_bytes: tables.gpu_bytes(),
        }
    }

    /// Stops posing the instance in `slot` (removed, or posed by the engine now): its
    /// target's slot goes void (4 bytes); returns the bytes written.
    pub fn stop(&mut self, queue: &wgpu::Queue, slot: u32) -> u64 {
        let Some(k) = self.targets_of.remove(&slot) else {
            return 0;
        };
        let offset = k as u64 * size_of::<PoseTargetRecord>() as u64;
        let void = Places::VACANT.to_le_bytes();
        queue.write_buffer(&self.targets, offset, &void);
        void.len() as u64
    }

    /// Records the frame's posing, logged as the frame pass `pose`; returns its
    /// dispatches.
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder, rec: &mut Recorder) -> u32 {
        self.encode_at(&self.first, encoder, rec)
    }

    /// Records a two-frame submission's second pose, `dt` ahead (none for a pass made
    /// without one); returns its dispatches.
    pub fn encode_next(&self, encoder: &mut wgpu::CommandEncoder, rec: &mut Recorder) -> u32 {
        match &self.second {
            Some(second) => self.encode_at(second, encoder, rec),
            None => 0,
        }
    }

    fn encode_at(
        &self,
        at: &PoseAt,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder,
    ) -> u32 {
        let (mut pass, open) = rec.frame_pass(encoder, "pose");
        for k in 0..3 {
            pass.set_pipeline(&self.pipelines[k]);
            pass.set_bind_group(0, &at.bind_group, &[]);
            let (x, y) = self.dispatches[k];
            pass.dispatch_workgroups(x, y, 1);
        }
        at.moves.encode(&mut pass);
        rec.close_frame_pass(encoder, pass, open);
        4
    }

    /// GPU bytes of its tables and scratch.
    pub fn gpu_bytes(&self) -> u64 {
        self.gpu_bytes
    }
}

/// What the pose pass binds: the frame context, the skins' joint matrices, and where
/// its moves go (the path's scatter targets).
pub struct GpuParts<'a> {
    pub frame: &'a wgpu::Buffer,
    pub skin: Option<&'a SkinPass>,
    pub windows: Windows,
    pub scatter: ScatterTargets<'a>,
}

/// The pose pass, with [`PosingMode::Gpu`] and a scene that moves; `posed(slot)`: whether
/// it still poses the instance in `slot`.
pub fn build(
    device: &wgpu::Device,
    scene: &Scene,
    options: &RendererOptions,
    gpu: GpuParts,
    posed: impl Fn(u32) -> bool,
) -> Result<Option<PosePass>> {
    if options.posing != PosingMode::Gpu {
        return Ok(None);
    }
    let Some(tables) = PoseTables::new(scene, posed)? else {
        return Ok(None);
    };
    // Node animations alone have no joint matrices: the targets pass writes none.
    let stand_in;
    let joint_matrices = match gpu.skin {
        Some(skin) => skin.joint_matrices(),
        None => {
            let usage = wgpu::BufferUsages::STORAGE;
            stand_in = crate::buffers::storage_buffer(device, "stereocull.no_joints", 0, usage);
            &stand_in
        }
    };
    let outputs = PoseOutputs {
        joint_matrices,
        scatter: gpu.scatter,
        windows: gpu.windows,
        second_ahead: (options.frames_per_submit == 2).then_some(options.dt),
    };
    Ok(Some(PosePass::new(device, &tables, gpu.frame, outputs)))
}
