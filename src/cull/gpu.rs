//! GPU culling: per display, three compute dispatches (`wgsl/cull.wgsl`,
//! `cull_draws.wgsl`, `cull_compact.wgsl`) that write the visible list, the draws and
//! the draw count per the contract in [`super`], byte-identical to [`super::cpu`]. Each
//! sphere is read once per display whatever the levels of detail, into one word per
//! position; the prefix sums run as a tree (a span per invocation, its workgroup's
//! spans, then one workgroup over the workgroups' totals), never one workgroup over
//! every span. With the frame-level coarse cull ([`super::coarse`]), three dispatches
//! per frame first (`wgsl/cull_coarse.wgsl`) list each display's blocks, and each
//! display's passes run over its blocks' positions, dispatched indirectly from their
//! count. The buffers they read and write are [`super::gpu_buffers`]'s.

use crate::cull::gpu_buffers::CullScene;
use crate::cull::rig::{MAX_RIG_VIEWS, RigCull, RigSets};
use crate::cull::targets::CullTargets;
use crate::shaders::Bound;
use crate::shaders::Phase;
use crate::shaders::{
    CANDIDATE_BINDINGS, COARSE_BINDINGS, CULL_BINDINGS, CullKey, CullPass, CullTests, Windows,
    bind_group, bind_group_layout, compute_pipeline, pipeline_layout, subgroup_tier,
};
use encase::ShaderType;

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
    /// With occlusion: the cull pass's early and late (and tested) phases, over everything and (with
    /// the coarse cull) over candidates.
    phases: Vec<((bool, Phase), wgpu::ComputePipeline)>,
    /// With blended bins: the blend pass over everything and (with the coarse cull)
    /// over candidates.
    blend: Vec<(bool, wgpu::ComputePipeline)>,
    /// With the rig cull: its passes in dispatch order (the blend pass last, with
    /// blended bins).
    rig: Vec<wgpu::ComputePipeline>,
    /// With occlusion, the rig's cull pass for its late members.
    rig_late: Option<wgpu::ComputePipeline>,
    /// The optional tests its cull passes hold.
    tests: CullTests,
}

/// What a [`GpuCuller`] is built for besides the display passes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CullerFeatures {
    /// The frame's coarse cull.
    pub coarse: bool,
    /// The floor kernel (`profile`).
    pub floor: bool,
    /// Two-phase occlusion culling.
    pub occlusion: bool,
    /// With occlusion, the far layers' cull tested against their displays' pyramids.
    pub tested: bool,
    /// Blended material bins: the blend pass after the display passes.
    pub blend: bool,
    /// The rig cull's members ([`crate::cull::rig`]; none: it does not run): its
    /// passes, and the floor kernel as the rig's.
    pub rig: RigSets,
    /// The optional tests the cull passes hold: those a frame of the renderer can use.
    pub tests: CullTests,
    /// Levels of detail in use (1, or [`crate::scene::MAX_LODS`] with LOD on).
    pub levels: u32,
}

/// The coarse cull's pipelines.
struct CoarsePipelines {
    /// The display passes over the candidates.
    display: Vec<wgpu::ComputePipeline>,
    /// The frame passes, and their group 1's layout (what they write: the lists, the
    /// marks, the display passes' indirect dispatches; and the block tests).
    frame: Vec<wgpu::ComputePipeline>,
    args_layout: wgpu::BindGroupLayout,
    /// The display passes' group 1 over the candidates: the lists, read only.
    candidates_layout: wgpu::BindGroupLayout,
}

/// The coarse cull's bind groups: the frame passes' group 1 and the display passes'
/// over the candidates.
pub struct CoarseGroups {
    /// The frame passes' ([`COARSE_BINDINGS`]).
    pub args: wgpu::BindGroup,
    /// The display passes' over candidates ([`CANDIDATE_BINDINGS`]).
    pub candidates: wgpu::BindGroup,
}

impl GpuCuller {
    /// The display passes, and with `coarse` the frame passes and the display passes
    /// over their candidates too; with `floor` the floor kernel.
    pub fn new(device: &wgpu::Device, features: CullerFeatures, windows: Windows) -> GpuCuller {
        let CullerFeatures {
            coarse,
            floor,
            occlusion,
            tested,
            blend,
            rig: sets,
            tests,
            levels,
        } = features;
        let rig = sets.members() > 0;
        // The rig's first part and its late members each fill sets of their own.
        let fields = |members: u32| members.min(MAX_RIG_VIEWS as u32) * levels;
        let key = |over_candidates: bool| CullKey {
            over_candidates,
            phase: Phase::Frustum,
            tests,
            rig_fields: fields(sets.first),
        };
        let layout = bind_group_layout(device, "stereocull.cull", &CULL_BINDINGS, &windows);
        let build = |passes: &[CullPass], candidates: bool, with: &wgpu::PipelineLayout| {
            let build_one = |pass: &CullPass| {
                let source = pass.source(key(candidates), &windows);
                let label = pass.label(candidates);
                compute_pipeline(device, &label, with, source, pass.entry_point())
            };
            passes.iter().map(build_one).collect()
        };
        let display_layout = pipeline_layout(device, "stereocull.cull", &layout);
        let subgroups = subgroup_tier(device);
        let display = CullPass::DISPLAY.map(|p| match p {
            CullPass::Cull if subgroups => CullPass::CullSubgroups,
            p => p,
        });
        let pipelines = build(&display, false, &display_layout);
        let whole = &Windows::WHOLE;
        let with_group_1 = |label: &str, second: &wgpu::BindGroupLayout| {
            device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(label),
                bind_group_layouts: &[Some(&layout), Some(second)],
                immediate_size: 0,
            })
        };
        let candidates_layout = coarse.then(|| {
            let label = "stereocull.candidates";
            bind_group_layout(device, label, &CANDIDATE_BINDINGS, whole)
        });
        let over_candidates = candidates_layout
            .as_ref()
            .map(|l| with_group_1("stereocull.candidates", l));
        // The display passes' layout over everything or (`true`) over candidates.
        let layout_over = |candidates: bool| match (candidates, &over_candidates) {
            (true, Some(l)) => l,
            _ => &display_layout,
        };
        let coarse = candidates_layout.map(|candidates_layout| {
            let args_layout =
                bind_group_layout(device, "stereocull.coarse", &COARSE_BINDINGS, whole);
            let both = with_group_1("stereocull.coarse", &args_layout);
            CoarsePipelines {
                display: build(&display, true, layout_over(true)),
                frame: build(&CullPass::FRAME, false, &both),
                args_layout,
                candidates_layout,
            }
        });
        let floor_pass = if rig {
            CullPass::RigFloor
        } else {
            CullPass::Floor
        };
        let floor = floor.then(|| build(&[floor_pass], false, &display_layout).remove(0));
        let rig_passes = CullPass::RIG
            .into_iter()
            .chain(blend.then_some(CullPass::RigBlend));
        // With occlusion the late members' cull: the rig's cull pass in the late phase
        // (the other rig passes read no phase).
        let rig_late = (rig && occlusion).then(|| {
            let pass = CullPass::RigCull;
            let late = CullKey {
                rig_fields: fields(sets.late),
                ..key(false).in_phase(Phase::Late)
            };
            let source = pass.source(late, &windows);
            let label = Phase::Late.label(&pass.label(false));
            compute_pipeline(device, &label, &display_layout, source, pass.entry_point())
        });
        let rig = match rig {
            true => build(&rig_passes.collect::<Vec<_>>(), false, &display_layout),
            false => Vec::new(),
        };
        let cull = display[0];
        let phased = |candidates: bool, phase: Phase| {
            let source = cull.source(key(candidates).in_phase(phase), &windows);
            let label = phase.label(&cull.label(candidates));
            let with = layout_over(candidates);
            let pipeline = compute_pipeline(device, &label, with, source, cull.entry_point());
            ((candidates, phase), pipeline)
        };
        let over = [Some(false), features.coarse.then_some(true)];
        let phases = (over.into_iter().flatten())
            .flat_map(|c| [Phase::Early, Phase::Late, Phase::Tested].map(|p| (c, p)))
            .filter(|(_, p)| occlusion && (tested || *p != Phase::Tested))
            .map(|(c, p)| phased(c, p))
            .collect();
        let blend = (over.into_iter().flatten())
            .filter(|_| blend)
            .map(|c| {
                let pass = CullPass::Blend;
                let (label, source) = (pass.label(c), pass.source(key(c), &windows));
                let entry = pass.entry_point();
                (
                    c,
                    compute_pipeline(device, &label, layout_over(c), source, entry),
                )
            })
            .collect();
        GpuCuller {
            layout,
            windows,
            pipelines,
            coarse,
            floor,
            phases,
            blend,
            rig,
            rig_late,
            tests,
        }
    }

    /// The optional tests its cull passes hold.
    pub fn tests(&self) -> CullTests {
        self.tests
    }

    /// The bind group for one display: the frame context, shared scene data, and the
    /// display's context and outputs (its ranges of them).
    pub fn bind_group(
        &self,
        device: &wgpu::Device,
        scene: &CullScene,
        contexts: [&wgpu::Buffer; 2],
        targets: &CullTargets,
    ) -> wgpu::BindGroup {
        self.group(device, scene, (contexts, 0), targets.bindings())
    }

    /// The bind groups of the rig cull, one per group of members: `contexts` are the
    /// frame's and any view's (the rig passes read no view's context), `targets` any
    /// member's (the rig passes bind the buffers the members share, whole).
    pub fn rig_bind_groups(
        &self,
        device: &wgpu::Device,
        scene: &CullScene,
        contexts: [&wgpu::Buffer; 2],
        targets: &CullTargets,
    ) -> Vec<wgpu::BindGroup> {
        let whole = [&targets.visible, &targets.draws, &targets.counts];
        (0..scene.rig_sets.groups())
            .map(|g| self.group(device, scene, (contexts, g), whole.map(|b| b.bound())))
            .collect()
    }

    /// Group 0 with the rig's group `rig_group` of members and `targets`.
    fn group<'a>(
        &self,
        device: &wgpu::Device,
        scene: &'a CullScene,
        ([frame_context, display_context], rig_group): ([&'a wgpu::Buffer; 2], u32),
        [visible, draws, counts]: [wgpu::BufferBinding<'a>; 3],
    ) -> wgpu::BindGroup {
        let rig = wgpu::BufferBinding {
            buffer: &scene.rig,
            offset: rig_group as u64 * scene.rig_stride,
            size: Some(RigCull::min_size()),
        };
        // In CULL_BINDINGS order.
        let buffers = [
            frame_context.bound(),
            display_context.bound(),
            scene.params.bound(),
            rig,
            scene.order.bound(),
            scene.meshes.bound(),
            scene.lods.bound(),
            scene.mesh_of.bound(),
            scene.entries.bound(),
            scene.span_sums.bound(),
            visible,
            draws,
            counts,
            scene.occlusion.bound(),
            scene.hidden.bound(),
            scene.spheres.bound(),
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

    /// Group 1 of the frame passes and of the display passes over candidates (with the
    /// coarse cull).
    pub fn coarse_bind_groups(
        &self,
        device: &wgpu::Device,
        scene: &CullScene,
    ) -> Option<CoarseGroups> {
        let coarse = self.coarse.as_ref()?;
        let lists = [
            &scene.block_list,
            &scene.candidate_count,
            &scene.candidate_ranges,
        ];
        let [list, count, ranges] = lists;
        // In COARSE_BINDINGS order.
        let writes = [
            &scene.coarse_args,
            &scene.block_marks,
            list,
            count,
            ranges,
            &scene.block_tests,
        ];
        let whole = &Windows::WHOLE;
        Some(CoarseGroups {
            args: bind_group(
                device,
                "stereocull.coarse",
                &coarse.args_layout,
                &COARSE_BINDINGS,
                whole,
                writes,
            ),
            candidates: bind_group(
                device,
                "stereocull.candidates",
                &coarse.candidates_layout,
                &CANDIDATE_BINDINGS,
                whole,
                lists,
            ),
        })
    }

    /// Records the frame's coarse cull (nothing without it): `bind_groups` are any
    /// display's group 0 (the frame passes read none of its display's bindings) and
    /// [`CoarseGroups::args`]. Returns the dispatches.
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
        let (blocks, slots) = (scene.groups.blocks, scene.coarse_slots);
        for (pipeline, kind) in pipelines.iter().zip(CullPass::FRAME) {
            pass.set_pipeline(pipeline);
            match kind {
                CullPass::CoarseLists => pass.dispatch_workgroups(slots, 1, 1),
                CullPass::CoarsePlace => pass.dispatch_workgroups(blocks, slots, 1),
                _ => pass.dispatch_workgroups(blocks, 1, 1),
            }
        }
        pipelines.len() as u32
    }

    /// Records the three dispatches for one display: a fixed count, whatever the
    /// number of instances; with the coarse cull's `slot` (and its candidates group,
    /// [`CoarseGroups::candidates`]) they run over that slot's listed blocks,
    /// dispatched as the coarse passes sized them. The cull pass runs in occlusion
    /// `phase` (built with occlusion, else the frustum alone).
    pub fn encode(
        &self,
        pass: &mut wgpu::ComputePass,
        scene: &CullScene,
        bind_group: &wgpu::BindGroup,
        (slot, phase): (Option<(u32, &wgpu::BindGroup)>, Phase),
    ) {
        pass.set_bind_group(0, bind_group, &[]);
        let (pipelines, slot) = match (&self.coarse, slot) {
            (Some(c), Some((slot, candidates))) => {
                pass.set_bind_group(1, candidates, &[]);
                (&c.display, Some(slot))
            }
            _ => (&self.pipelines, None),
        };
        let candidates = slot.is_some();
        let phased = (self.phases.iter())
            .find(|(key, _)| *key == (candidates, phase))
            .map(|(_, p)| p);
        for (pipeline, kind) in pipelines.iter().zip(CullPass::DISPLAY) {
            match (kind, phased) {
                (CullPass::Cull, Some(p)) => pass.set_pipeline(p),
                _ => pass.set_pipeline(pipeline),
            }
            // The subgroup tier stands where CullPass::Cull does, on the same grid.
            let (grid, args) = match kind {
                CullPass::Draws => {
                    pass.dispatch_workgroups(1, 1, 1);
                    continue;
                }
                CullPass::Cull => (scene.groups.spans, 0),
                _ => (scene.groups.positions, 12),
            };
            match slot {
                Some(s) => {
                    pass.dispatch_workgroups_indirect(&scene.coarse_args, 24 * s as u64 + args)
                }
                None => pass.dispatch_workgroups(grid.0, grid.1, 1),
            }
        }
        if let Some((_, blend)) = self.blend.iter().find(|(c, _)| *c == candidates) {
            pass.set_pipeline(blend);
            pass.dispatch_workgroups(1, 1, 1);
        }
    }

    /// Records the rig cull's first part (`late` false: its frustum and early members)
    /// or its late members: one set of dispatches per group of them (`groups`, every
    /// group's, [`GpuCuller::rig_bind_groups`]). Returns the dispatches.
    pub fn encode_rig(
        &self,
        pass: &mut wgpu::ComputePass,
        scene: &CullScene,
        (groups, late): (&[wgpu::BindGroup], bool),
    ) -> u32 {
        let sets = scene.rig_sets;
        let part = match late {
            false => 0..sets.first_groups(),
            true => sets.first_groups()..sets.groups(),
        };
        let mut dispatches = 0;
        for g in part {
            pass.set_bind_group(0, &groups[g as usize], &[]);
            let rig_passes = [
                CullPass::RigCull,
                CullPass::RigDraws,
                CullPass::RigCompact,
                CullPass::RigBlend,
            ];
            for (pipeline, kind) in self.rig.iter().zip(rig_passes) {
                match (kind, &self.rig_late) {
                    (CullPass::RigCull, Some(phased)) if late => pass.set_pipeline(phased),
                    _ => pass.set_pipeline(pipeline),
                }
                let (x, y) = match kind {
                    CullPass::RigCull | CullPass::RigCompact => scene.groups.spans,
                    _ => (1, sets.members_in(g)),
                };
                pass.dispatch_workgroups(x, y, 1);
                dispatches += 1;
            }
        }
        dispatches
    }

    /// Whether the rig cull's pipelines were built.
    pub fn has_rig(&self) -> bool {
        !self.rig.is_empty()
    }

    /// Dispatches per display: the three passes, and the blend pass with blended bins.
    pub fn dispatches_per_display(&self) -> u32 {
        Self::DISPATCHES_PER_DISPLAY + u32::from(!self.blend.is_empty())
    }

    /// Whether the floor kernel was built.
    pub fn has_floor(&self) -> bool {
        self.floor.is_some()
    }

    /// Records the floor kernel over every instance with each of `bind_groups` (any
    /// display's, whose scratch it writes; with the rig cull, the rig's groups, every
    /// member's). Returns the dispatches.
    pub fn encode_floor<'a>(
        &self,
        pass: &mut wgpu::ComputePass,
        scene: &CullScene,
        bind_groups: impl IntoIterator<Item = &'a wgpu::BindGroup>,
    ) -> u32 {
        let Some(floor) = &self.floor else {
            return 0;
        };
        pass.set_pipeline(floor);
        let mut dispatches = 0;
        for group in bind_groups {
            pass.set_bind_group(0, group, &[]);
            // The rig's floor walks spans, as the rig's cull does.
            let (x, y) = match self.has_rig() {
                true => scene.groups.spans,
                false => scene.groups.positions,
            };
            pass.dispatch_workgroups(x, y, 1);
            dispatches += 1;
        }
        dispatches
    }

    /// Compute dispatches per display: cull, draws, compact.
    pub const DISPATCHES_PER_DISPLAY: u32 = CullPass::DISPLAY.len() as u32;
}
