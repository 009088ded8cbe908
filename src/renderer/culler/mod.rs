//! The one culler every view of a frame goes through: each display, each eye in
//! `multi-camera`, each far layer, the light. On the GPU it is compute passes over scene
//! data uploaded once: the rig cull's, once per frame, for every view it takes
//! ([`crate::cull::rig`]), and up to four per other view (after the frame's coarse
//! cull when it runs); on
//! the CPU one parallel pass over the spheres per frame for every view the frame frustum
//! holds, one for the light, and an upload per view. A view's pass takes the culler and
//! never asks which it is: this module is the only place that does (its diagnostics,
//! read back after a frame, in `diagnostics.rs`).

mod diagnostics;

pub use diagnostics::WallCulls;
mod occlusion;

use super::options::CullMode;
use super::plan::{CullView, FramePlan};
use super::recorder::{PassRecord, Recorder};
use crate::bins::BinRange;
use crate::buffers::Upload;
use crate::contexts::DisplayContext;
use crate::cull::CullOutput;
use crate::cull::cpu;
use crate::cull::gpu::{CoarseGroups, CullerFeatures, GpuCuller};
use crate::cull::gpu_buffers::{CullScene, OcclusionRoom};
use crate::cull::rig::RigSets;
use crate::cull::targets::CullTargets;
use crate::error::Result;
use crate::keep::marks::{TileDisplay, TileMarks};
use crate::occlusion::{Phase, cull_early};
use crate::records::{CullLayout, MoveEdit, PlaceEdit};
use crate::renderer::plan::KeptTiles;
use crate::scene::Scene;
use crate::shaders::SPAN;
use crate::shaders::{CullTests, Windows};
use std::sync::OnceLock;

pub struct Culler {
    kind: Kind,
    /// Instance slots of room: what every view's visible list holds.
    slots: u32,
    /// The rig cull's members, in order (none: it does not run).
    members: Vec<CullView>,
    /// The material bins' ranges of every view's draws (fixed: meshes do not change;
    /// a re-layout that would change them reallocates).
    bins: Vec<BinRange>,
}

enum Kind {
    /// Passes over scene data on the GPU; `coarse` is the coarse cull's groups 1, when it
    /// runs.
    Gpu {
        culler: GpuCuller,
        scene: Box<CullScene>,
        coarse: Option<CoarseGroups>,
        /// With the rig cull: its members' outputs, in member order, and its bind
        /// groups (made with the first member's view).
        rig: Vec<CullTargets>,
        rig_groups: OnceLock<Vec<wgpu::BindGroup>>,
        /// Keeping unchanged pixels: the pass that marks the changed tiles.
        marks: Option<TileMarks>,
    },
    /// The CPU culler over its own copy of the cull layout, and this frame's results;
    /// with occlusion, per display that culls by it its visibility words (the CPU's
    /// copy of what the GPU keeps in its occlusion buffer), and the pyramids it reads
    /// back between a frame's halves with the plan of the frame they serve.
    Cpu {
        layout: CullLayout,
        outputs: Vec<(CullView, CullOutput)>,
        visibility: Vec<Option<Vec<u32>>>,
        late: Option<Box<occlusion::LateReadback>>,
    },
}

/// What a culler is made for: the slots of room, the levels of detail, how many
/// displays the coarse cull lists blocks for (0: no coarse cull), and whether it times
/// the floor kernel ([`super::RendererOptions::cull_floor`]).
#[derive(Clone, Debug)]
pub struct CullShape {
    /// The views the rig cull culls together (GPU culling; empty: none): those of its
    /// first part (frustum and early phases), then its late members
    /// ([`CullView::Late`]).
    pub rig: Vec<CullView>,
    pub slots: u32,
    pub levels: u32,
    pub coarse_slots: u32,
    pub floor: bool,
    pub occlusion: OcclusionRoom,
    /// With occlusion, whether far layers test against their displays' pyramids.
    pub tested: bool,
    /// Display slots whose hidden areas the GPU cull reads (0: no cull drops by one).
    pub hidden_slots: u32,
    /// Whether views cull by a far split (the far layer).
    pub split: bool,
}

impl CullShape {
    /// The optional tests the GPU cull's pipelines hold: those a frame can use.
    fn tests(&self) -> CullTests {
        CullTests {
            hidden: self.hidden_slots > 0,
            tiles: self.occlusion.tiles.0 > 0,
            early: self.occlusion.displays > 0,
            split: self.split,
        }
    }
}

/// One view's cull outputs (per the cull contract) and, on the GPU, its bindings.
pub struct CullPass {
    pub view: CullView,
    /// Which part of a two-phase cull it is (the frustum alone without occlusion).
    phase: Phase,
    pub targets: CullTargets,
    bind_group: Option<wgpu::BindGroup>,
    /// Its index among the rig cull's members, if it is one (the rig's dispatches cull
    /// it in its phase).
    member: Option<u32>,
}

impl Culler {
    /// The culler `mode` asks for, over `layout`.
    pub fn new(
        device: &wgpu::Device,
        mode: CullMode,
        layout: CullLayout,
        shape: CullShape,
        windows: Windows,
    ) -> Culler {
        let bins = layout.bin_ranges(shape.levels);
        let members = match mode {
            CullMode::Gpu => shape.rig.clone(),
            CullMode::Cpu => Vec::new(),
        };
        let late = members.iter().filter(|m| matches!(m, CullView::Late(_)));
        let late = late.count() as u32;
        let sets = RigSets {
            first: members.len() as u32 - late,
            late,
        };
        let kind = match mode {
            CullMode::Cpu => Kind::Cpu {
                layout,
                outputs: Vec::new(),
                visibility: Vec::new(),
                late: None,
            },
            CullMode::Gpu => {
                let features = CullerFeatures {
                    coarse: shape.coarse_slots > 0,
                    floor: shape.floor,
                    occlusion: shape.occlusion.displays > 0,
                    tested: shape.tested,
                    blend: layout.bins.first_blend_bin() != u32::MAX,
                    rig: sets,
                    tests: shape.tests(),
                    levels: shape.levels,
                };
                let culler = GpuCuller::new(device, features, windows);
                let room = (
                    shape.coarse_slots,
                    shape.occlusion,
                    sets,
                    shape.hidden_slots,
                );
                let scene = CullScene::new(device, &layout, (shape.slots, shape.levels), room);
                let scene = Box::new(scene);
                let coarse = culler.coarse_bind_groups(device, &scene);
                let draws = bins.iter().map(|r| r.capacity).sum();
                let rig = match sets.members() {
                    0 => Vec::new(),
                    n => CullTargets::bank(device, shape.slots, draws, n),
                };
                let marks = (shape.occlusion.tiles.0 > 0).then(|| {
                    let room = (shape.slots, shape.occlusion.tiles.0);
                    TileMarks::new(device, &scene, room, windows)
                });
                Kind::Gpu {
                    culler,
                    scene,
                    coarse,
                    rig,
                    rig_groups: OnceLock::new(),
                    marks,
                }
            }
        };
        Culler {
            kind,
            slots: shape.slots,
            members,
            bins,
        }
    }

    /// Draw entries of every view's outputs: the bins' ranges together.
    pub fn draws(&self) -> u32 {
        self.bins.iter().map(|r| r.capacity).sum()
    }

    /// The material bins' ranges of every view's draws.
    pub fn bins(&self) -> &[BinRange] {
        &self.bins
    }

    /// `view`'s cull outputs (room for every slot and draw: a rig member's range of
    /// the rig's) and its bindings to the frame's and the view's contexts.
    pub fn view(
        &self,
        device: &wgpu::Device,
        view: CullView,
        phase: Phase,
        contexts: [&wgpu::Buffer; 2],
    ) -> CullPass {
        let member = (self.members.iter().position(|m| *m == view))
            .filter(|_| matches!(phase, Phase::Frustum | Phase::Early | Phase::Late));
        let (targets, bind_group) = match &self.kind {
            Kind::Gpu {
                culler,
                scene,
                rig,
                rig_groups,
                ..
            } => {
                let targets = match member {
                    Some(m) => rig[m].clone(),
                    None => CullTargets::new(device, self.slots, self.draws()),
                };
                if member.is_some() {
                    rig_groups
                        .get_or_init(|| culler.rig_bind_groups(device, scene, contexts, &targets));
                }
                let group = culler.bind_group(device, scene, contexts, &targets);
                (targets, Some(group))
            }
            Kind::Cpu { .. } => (CullTargets::new(device, self.slots, self.draws()), None),
        };
        CullPass {
            view,
            phase,
            targets,
            bind_group,
            member: member.map(|m| m as u32),
        }
    }

    /// This frame's culls as `plan` lists them: on the CPU, all of them (and the
    /// light's); on the GPU, the coarse cull's block tests, one per display, and the
    /// displays' hidden areas and changed tiles. Returns the bytes written.
    pub fn prepare(&mut self, queue: &impl Upload, plan: &FramePlan) -> u64 {
        match &mut self.kind {
            Kind::Gpu { scene, marks, .. } => {
                let planes: Vec<_> = plan.resolved.displays.iter().map(|d| d.planes).collect();
                let marked = match marks {
                    Some(marks) => write_marks(queue, marks, plan),
                    None => 0,
                };
                scene.write_block_tests(queue, &planes)
                    + scene.write_hidden(queue, plan.displays.iter().map(|d| d.hidden.as_deref()))
                    + marked
            }
            Kind::Cpu {
                layout,
                outputs,
                visibility,
                ..
            } => {
                // A display that culls by occlusion culls its early phase below instead.
                let occludes = |view: CullView| match view {
                    CullView::Display(i) => visibility.get(i).is_some_and(Option::is_some),
                    _ => false,
                };
                let culls = plan.culls();
                let plain: Vec<_> = culls.iter().filter(|c| !occludes(c.view)).collect();
                let jobs: Vec<_> = plain.iter().map(|c| c.job.clone()).collect();
                let culled = cpu::cull_frame(layout, &jobs, &plan.cull);
                *outputs = plain.iter().map(|c| c.view).zip(culled).collect();
                // Outside the coarse cull: one more pass for the light and the insets.
                let insets = plan.inset_culls();
                let apart: Vec<_> = plan.light_cull.iter().chain(&insets).collect();
                if !apart.is_empty() {
                    let jobs: Vec<_> = apart.iter().map(|c| c.job.clone()).collect();
                    let out = cpu::cull_many_lod(layout, &jobs, &plan.cull.lod);
                    outputs.extend(apart.iter().map(|c| c.view).zip(out));
                }
                // With occlusion a display's first cull is its early phase.
                for (i, words) in visibility.iter().enumerate() {
                    let (Some(words), Some(job)) = (words, plan.job(CullView::Display(i))) else {
                        continue;
                    };
                    let early = cull_early(layout, &job, &plan.cull.lod, words);
                    set_output(outputs, CullView::Display(i), early);
                }
                0
            }
        }
    }

    /// This frame's result for `view` in CPU memory: the CPU culler's (`None` on the GPU,
    /// whose results stay in its buffers, or for a view the plan does not cull).
    pub fn output(&self, view: CullView) -> Option<&CullOutput> {
        match &self.kind {
            Kind::Cpu { outputs, .. } => outputs.iter().find(|(v, _)| *v == view).map(|(_, o)| o),
            Kind::Gpu { .. } => None,
        }
    }

    /// Writes `view`'s CPU result into its outputs (nothing on the GPU, whose passes
    /// write them); returns the bytes written.
    pub fn upload(&self, queue: &wgpu::Queue, view: &CullPass) -> u64 {
        self.output(view.view)
            .map_or(0, |out| view.targets.upload(queue, out))
    }

    /// Writes a rig member's record for this frame from `context`, the context it culls
    /// by (nothing for another view); returns the bytes written.
    pub fn write_member(
        &self,
        queue: &impl Upload,
        view: &CullPass,
        context: &DisplayContext,
    ) -> u64 {
        match (&self.kind, view.member) {
            (Kind::Gpu { scene, .. }, Some(m)) => {
                let early = view.phase == Phase::Early;
                let record = context.rig_view(view.targets.member_at(), early);
                // The late phase tests its pyramids with its eyes, a kept frame its tiles.
                let tiles = context.hidden & crate::cull::tiles::CULL_TILES != 0;
                let late = (view.phase == Phase::Late || tiles).then(|| context.rig_occlusion());
                scene.write_rig_member(queue, m, (&record, late.as_ref()))
            }
            _ => 0,
        }
    }

    /// Records the frame's coarse cull (GPU culling with it on), timed as `coarse_cull`
    /// inside a `frame` scope, the floor kernel when asked for, timed as `cull_floor`,
    /// and the rig cull, timed as `rig_cull`; `any` is any display's view (the coarse
    /// passes read none of its bindings; without the rig cull the floor writes its
    /// scratch, which its cull overwrites). Returns the dispatches.
    pub fn encode_frame(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        any: Option<&CullPass>,
        rec: &mut Recorder,
    ) -> u32 {
        let Kind::Gpu {
            culler,
            scene,
            coarse,
            rig_groups,
            ..
        } = &self.kind
        else {
            return 0;
        };
        let display = any.and_then(|v| v.bind_group.as_ref());
        let rig = rig_groups.get().map_or(&[][..], Vec::as_slice);
        let coarse = coarse.as_ref().map(|g| &g.args).zip(display);
        if coarse.is_none() && !culler.has_floor() && rig.is_empty() {
            return 0;
        }
        rec.enter(encoder, "frame");
        let mut dispatches = 0;
        if let Some((args, display)) = coarse {
            let (mut pass, open) = rec.compute_pass(encoder, PassRecord::frame("coarse_cull"));
            dispatches += culler.encode_frame(&mut pass, scene, [display, args]);
            rec.close_compute(encoder, pass, open);
        }
        if culler.has_floor() {
            let (mut pass, open) = rec.compute_pass(encoder, PassRecord::frame("cull_floor"));
            dispatches += match rig.is_empty() {
                true => culler.encode_floor(&mut pass, scene, display),
                false => culler.encode_floor(&mut pass, scene, rig),
            };
            rec.close_compute(encoder, pass, open);
        }
        if !rig.is_empty() {
            let (mut pass, open) = rec.compute_pass(encoder, PassRecord::frame("rig_cull"));
            dispatches += culler.encode_rig(&mut pass, scene, (rig, false));
            rec.close_compute(encoder, pass, open);
        }
        rec.leave(encoder);
        dispatches
    }

    /// Records the rig cull's late members (GPU culling with occlusion and the rig
    /// cull), timed as `rig_late_cull` inside a `frame` scope: after every display's
    /// early draw and pyramids. Returns the dispatches.
    pub fn encode_late_rig(&self, encoder: &mut wgpu::CommandEncoder, rec: &mut Recorder) -> u32 {
        let Kind::Gpu {
            culler,
            scene,
            rig_groups,
            ..
        } = &self.kind
        else {
            return 0;
        };
        let rig = rig_groups.get().map_or(&[][..], Vec::as_slice);
        if scene.rig_sets().late == 0 || rig.is_empty() {
            return 0;
        }
        let (mut pass, open) = rec.frame_pass(encoder, "rig_late_cull");
        let dispatches = culler.encode_rig(&mut pass, scene, (rig, true));
        rec.close_frame_pass(encoder, pass, open);
        dispatches
    }

    /// Whether [`Culler::encode`] records passes for `view` in its own phase: culling
    /// on the GPU, where the rig cull does not take it.
    pub fn records(&self, view: &CullPass) -> bool {
        matches!(self.kind, Kind::Gpu { .. }) && view.bind_group.is_some() && view.member.is_none()
    }

    /// Records `view`'s cull on the GPU (over its display's blocks with the coarse
    /// cull), its pass timed and logged as `what`; nothing on the CPU (`upload` wrote
    /// it) or for a rig member (the frame's rig cull culled it). Returns the
    /// dispatches.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        view: &CullPass,
        phase: Phase,
        rec: &mut Recorder,
        what: PassRecord,
    ) -> u32 {
        let (
            Kind::Gpu {
                culler,
                scene,
                coarse,
                ..
            },
            Some(group),
        ) = (&self.kind, &view.bind_group)
        else {
            return 0;
        };
        // A rig member in its own phase was culled by the frame's rig cull.
        if view.member.is_some() && phase == view.phase {
            return 0;
        }
        let slot = over_candidates(coarse.as_ref(), view);
        let (mut pass, open) = rec.compute_pass(encoder, what);
        culler.encode(&mut pass, scene, group, (slot, phase));
        rec.close_compute(encoder, pass, open);
        culler.dispatches_per_display()
    }

    /// GPU bytes per instance the culler keeps besides the views' outputs.
    pub fn bytes_per_instance(mode: CullMode) -> u64 {
        match mode {
            CullMode::Gpu => CullScene::BYTES_PER_INSTANCE,
            CullMode::Cpu => 0,
        }
    }

    // What `Renderer::sync` changes in the culler: a new layout, the
    // places filled and vacated, the moved instances' spheres (the CPU culler's own copy;
    // the GPU's are scattered), and what the scatter passes write into on the GPU.
    /// Takes a new `layout` (instances inserted or removed, same room); returns the
    /// bytes written.
    pub fn reload(&mut self, queue: &wgpu::Queue, layout: CullLayout) -> u64 {
        match &mut self.kind {
            Kind::Gpu { scene, .. } => scene.reload(queue, &layout),
            Kind::Cpu {
                layout: own,
                visibility,
                ..
            } => {
                // Laid out afresh, no place holds what it held: every instance starts
                // as not drawn last frame, as the GPU's reload clears its words.
                let words = layout.spheres.len().div_ceil(SPAN as usize);
                for w in visibility.iter_mut().flatten() {
                    *w = vec![0; words];
                }
                *own = layout;
                0
            }
        }
    }

    /// Each slot's world sphere on the GPU (`None` culling on the CPU).
    pub fn read_spheres(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        slots: u32,
    ) -> Result<Option<Vec<[f32; 4]>>> {
        match &self.kind {
            Kind::Gpu { scene, .. } => scene.read_spheres(device, queue, slots).map(Some),
            Kind::Cpu { .. } => Ok(None),
        }
    }

    /// The GPU culler's spheres, cull positions, order, mesh bounds and occlusion
    /// words, which the scatter passes write edits into, and the visibility words' shape
    /// (words per display slot, slots); `None` for the CPU culler, which takes edits
    /// into its layout ([`Culler::place`], [`Culler::moved`]).
    pub fn scatter_targets(&self) -> (Option<[&wgpu::Buffer; 5]>, (u32, u32)) {
        match &self.kind {
            Kind::Gpu { scene, .. } => (Some(scene.scatter_targets()), scene.visibility_shape()),
            Kind::Cpu { .. } => (None, (0, 0)),
        }
    }

    /// The places filled and vacated, into the CPU culler's layout (the GPU's are
    /// scattered). Whoever now holds a place was not drawn last frame: its bit goes in
    /// every display's words, as `wgsl/scatter_places.wgsl` clears the GPU's.
    pub fn place(&mut self, placed: &[PlaceEdit]) {
        if let Kind::Cpu {
            layout, visibility, ..
        } = &mut self.kind
        {
            for edit in placed {
                layout.set_place((edit.place, edit.slot, CullLayout::VACANT_SPHERE));
                let (word, bit) = ((edit.place / SPAN) as usize, edit.place % SPAN);
                for words in visibility.iter_mut().flatten() {
                    words[word] &= !(1 << bit);
                }
            }
        }
    }

    /// The moved instances' new spheres, into the CPU culler's layout (the GPU's are
    /// scattered).
    pub fn moved(&mut self, scene: &Scene, moved: &[MoveEdit]) {
        if let Kind::Cpu { layout, .. } = &mut self.kind {
            for edit in moved {
                let slot = edit.slot as usize;
                let sphere = scene.world_sphere(&scene.instances[slot]);
                layout.set_sphere(layout.positions[slot], sphere);
            }
        }
    }

    /// A second frame's moved spheres, grown to hold both frames' poses, into the CPU
    /// culler's layout, as the moves scatter writes the GPU's in its grow mode.
    pub fn grown(&mut self, grown: &[(u32, glam::Vec4)]) {
        if let Kind::Cpu { layout, .. } = &mut self.kind {
            for &(slot, sphere) in grown {
                layout.set_sphere(layout.positions[slot as usize], sphere);
            }
        }
    }

    // A kept frame's changed tiles marked on the GPU ([`crate::keep::marks`]): the
    // culler arms its marking pass with the plan's listed slots, records its two phases
    // around the frame's pose, and tells the draw pass where the marked words lie.
    /// Records the marking pass's phase before the frame's scatter and pose (`after`
    /// false: every kept display's tiles cleared, the spheres as last drawn marked) or
    /// after them. Returns the dispatches (0 unless the frame keeps on the GPU).
    pub fn encode_marks(&mut self, encoder: &mut wgpu::CommandEncoder, after: bool) -> u32 {
        match &mut self.kind {
            Kind::Gpu {
                marks: Some(marks), ..
            } => match after {
                false => marks.encode_before(encoder),
                true => marks.encode_after(encoder),
            },
            _ => 0,
        }
    }

    /// Display slot `slot`'s `words` words of marked tiles: the buffer, the offset and
    /// the bytes (`None` where the GPU marks none).
    pub fn marked_words(&self, slot: u32, words: u32) -> Option<(&wgpu::Buffer, u64, u64)> {
        match &self.kind {
            Kind::Gpu {
                marks: Some(marks), ..
            } => Some(marks.words_of(slot, words)),
            _ => None,
        }
    }
}

/// With the coarse cull, `view`'s slot and the candidates group its passes read (a view
/// that takes no blocks runs over everything).
fn over_candidates<'a>(
    coarse: Option<&'a CoarseGroups>,
    view: &CullPass,
) -> Option<(u32, &'a wgpu::BindGroup)> {
    Some((view.view.coarse_slot()?, &coarse?.candidates))
}

/// Sets (or adds) `view`'s output.
fn set_output(outputs: &mut Vec<(CullView, CullOutput)>, view: CullView, out: CullOutput) {
    match outputs.iter_mut().find(|(v, _)| *v == view) {
        Some((_, o)) => *o = out,
        None => outputs.push((view, out)),
    }
}

impl CullPass {
    /// Which part of a two-phase cull the view is.
    pub fn phase(&self) -> Phase {
        self.phase
    }
}

/// Arms `marks` for `plan`'s frame where it keeps with the tiles marked on the GPU:
/// its listed slots, over its kept displays. Returns the bytes written.
fn write_marks(queue: &impl Upload, marks: &mut TileMarks, plan: &FramePlan) -> u64 {
    let kept = (plan.displays.iter()).filter(|d| matches!(d.tiles, Some(KeptTiles::Gpu)));
    let displays: Vec<TileDisplay> = kept
        .map(|d| &d.context)
        .map(|c| TileDisplay {
            eyes: c.rig_occlusion(),
            planes: c.planes,
            base: marks.base(c.cull_slot),
        })
        .collect();
    match displays.is_empty() {
        true => 0,
        false => marks.write(queue, &plan.marks, &displays),
    }
}
