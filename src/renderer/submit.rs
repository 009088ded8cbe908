//! A frame's calls, in the order a caller makes them: [`Renderer::sync`] (and
//! [`Renderer::sync_next`]) stage a live scene's edits; [`Renderer::prepare`] (or
//! [`Renderer::prepare_pair`]) plans the frame ([`Renderer::plan`] shows the plan) and
//! writes it; [`Renderer::encode`] records it top-down (or [`Renderer::encode_early`]
//! and [`Renderer::encode_late`] around a submission, or [`Renderer::encode_culls`]
//! before the caller's own passes); [`Renderer::latch`] writes a later pose before the
//! submit; [`Renderer::submit_frame`] does it all headless.

use super::display::indirect::IndirectDisplay;
use super::display::{Display, Shared};
use super::frame::FrameScene;
use super::frame::edits::{Staging, SyncInto};
use super::frame_stats::FrameStats;
use super::plan::{FramePlan, PlanStorage};
use super::recorder::Recorder;
use super::uploads::Writes;
use super::{DisplayTarget, PassRecord, Renderer, SyncStats, TargetViews, frames, keeping};
use crate::error::{Error, Result};
use crate::live::LiveScene;
use crate::profiling::GpuTimer;
use crate::rig::Rig;

impl Renderer {
    /// Brings the GPU copy of `live` up to date with its changes since the last sync,
    /// paying for what changed: inserts and removes fill and vacate places of the cull
    /// order (8 bytes each), moved and inserted instances go up as scatter edits (56
    /// bytes each), recolored and inserted ones as records (76 bytes), all applied by
    /// one compute pass in the next `encode`; a mesh out of vacant places lays the cull
    /// order out again (O(instances), with room); a scene that outgrew its buffers, or
    /// gained meshes, is uploaded again with room to grow by half. Call it before
    /// `prepare`.
    pub fn sync(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        live: &mut LiveScene,
    ) -> Result<SyncStats> {
        let mut changes = self.frame.edits.take_changes(live);
        if changes.lights {
            self.frame.lighting_mut().set(&live.lights())?;
            self.keeper.redraw_whole();
        }
        let joints = std::mem::take(&mut changes.joints);
        let driven = std::mem::take(&mut changes.driven);
        let stopped: Vec<u32> = changes.removed.iter().chain(&driven).copied().collect();
        let into = SyncInto {
            culler: &mut self.shared.culler,
            draw_scene: &mut self.shared.draw_scene,
            keeper: &mut self.keeper,
            slots: self.slots,
            levels: self.options.lod_levels(),
        };
        let mut stats = match self.frame.edits.stage(device, queue, live, changes, into) {
            Staging::Staged(stats) => stats,
            Staging::Reallocate => {
                let needed = (live.scene().instances.len() as u32).max(live.places().len());
                self.reallocate(device, live, needed + needed / 2)?
            }
        };
        // After a reallocation the pass was built from the live scene as it is.
        if let (Some(pose), false) = (&mut self.frame.passes.pose, stats.reallocated) {
            for slot in stopped {
                stats.bytes_uploaded += pose.stop(queue, slot);
            }
        }
        if let Some(skin) = &self.frame.passes.skin {
            for range in joints {
                stats.bytes_uploaded += skin.upload(queue, &live.scene().skins, range);
            }
        }
        Ok(stats)
    }

    /// The second frame's own changes in a submission of two frames
    /// ([`super::RendererOptions::frames_per_submit`] 2): after [`Renderer::sync`] took
    /// the first frame's, the caller poses `live` at the second frame's time (with
    /// [`LiveScene::pose`]) and moves or recolors instances for it alone; this takes
    /// those changes, which the second frame draws and the first does not (see
    /// [`super::frames`]). Call it before `prepare_pair`.
    ///
    /// Inserts join the cull order both frames share, hidden from the first frame's
    /// views; removes wait for the next sync (the first frame still draws them), hidden
    /// from the second frame's. New meshes, inserts that lay the cull order out again or
    /// pass the renderer's room, an insert into a place a remove emptied, and light
    /// changes belong to both frames: they are [`Error::Unsupported`] here and leave
    /// `live`'s changes untaken. So is a renderer of one frame per submission.
    pub fn sync_next(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        live: &mut LiveScene,
    ) -> Result<SyncStats> {
        let into = SyncInto {
            culler: &mut self.shared.culler,
            draw_scene: &mut self.shared.draw_scene,
            keeper: &mut self.keeper,
            slots: self.slots,
            levels: self.options.lod_levels(),
        };
        let (mut stats, joints) = self.frame.edits.stage_next(device, live, into)?;
        if let Some(skin) = &mut self.frame.passes.skin {
            for range in joints {
                stats.bytes_uploaded += skin.upload_next(queue, &live.scene().skins, range);
            }
        }
        Ok(stats)
    }

    /// What the frame at `time` for `rig`'s pose will do ([`FramePlan`]): what
    /// [`Renderer::prepare`] writes, for inspection.
    pub fn plan(&self, rig: &Rig, time: f32) -> Result<FramePlan> {
        self.plan_in(rig, time, PlanStorage::default())
    }

    fn plan_in(&self, rig: &Rig, time: f32, storage: PlanStorage) -> Result<FramePlan> {
        self.check_shapes(rig)?;
        let mut plan = FramePlan::new_in(rig, &self.options, self.coarse, time, storage)?;
        self.frame.expose(&mut plan.frame, &self.options);
        Ok(plan.with_far_sizes(self.displays.iter().map(Display::far_size)))
    }

    /// [`Renderer::plan`] in the last written plan's vectors.
    fn plan_again(&mut self, rig: &Rig, time: f32) -> Result<FramePlan> {
        let storage = std::mem::take(&mut self.spare);
        self.plan_in(rig, time, storage)
    }

    /// What a submission of two frames ([`super::RendererOptions::frames_per_submit`]
    /// 2) will do: `now`'s rig at its time, then `next`'s at its own
    /// ([`FramePlan::pair`]). Both rigs must have the renderer's displays.
    pub fn plan_pair(&self, now: (&Rig, f32), next: (&Rig, f32)) -> Result<FramePlan> {
        self.check_shapes(now.0)?;
        self.check_shapes(next.0)?;
        let mut plan = FramePlan::pair(now, next, &self.options, self.coarse)?;
        self.frame.expose(&mut plan.frame, &self.options);
        Ok(plan.with_far_sizes(self.displays.iter().map(Display::far_size)))
    }

    fn check_shapes(&self, rig: &Rig) -> Result<()> {
        let frames = self.options.frames_per_submit;
        let same = rig.displays.len() == self.displays.len()
            && (rig.displays.iter().zip(&self.displays)).all(|(d, display)| {
                let s = display.shape();
                let same_layout = || frames::layout(d, s.layered, frames) == s.layout;
                d.views() * frames == s.views() && (d.views() < 4 || same_layout())
            });
        match same {
            true => Ok(()),
            false => Err(Error::rig(
                "prepare",
                "the rig's displays differ from the renderer's (in number or views, or a foveated display's layout: it has a gaze or none for the renderer's life)",
            )),
        }
    }

    /// Writes this frame's contexts (and, culling on the CPU, the cull results), all
    /// from one plan of `rig`, which must have the displays the renderer was made with;
    /// only poses may change. `time` (seconds on the caller's clock) goes into the frame
    /// context, from which the GPU animates instances.
    ///
    /// A renderer made for two frames per submission draws the second at the same pose,
    /// `RendererOptions::dt` later: [`Renderer::prepare_pair`] takes its own pose.
    pub fn prepare(&mut self, queue: &wgpu::Queue, rig: &Rig, time: f32) -> Result<FrameStats> {
        let plan = self.plan_again(rig, time)?;
        let next = time + self.options.dt;
        self.prepare_plan(queue, plan, rig, [time, next])
    }

    /// [`Renderer::prepare`] for a submission of two frames
    /// ([`super::RendererOptions::frames_per_submit`] 2): `now`'s rig and time, then the
    /// next frame's, whose pose the caller's tracker predicts. The frames are drawn
    /// into each display's target side by side (the first frame's views, then the
    /// second's: [`Renderer::layout`]), each to be shown on its own vsync.
    pub fn prepare_pair(
        &mut self,
        queue: &wgpu::Queue,
        now: (&Rig, f32),
        next: (&Rig, f32),
    ) -> Result<FrameStats> {
        let plan = self.plan_pair(now, next)?;
        self.prepare_plan(queue, plan, now.0, [now.1, next.1])
    }

    fn prepare_plan(
        &mut self,
        queue: &wgpu::Queue,
        mut plan: FramePlan,
        rig: &Rig,
        times: [f32; 2],
    ) -> Result<FrameStats> {
        let [time, next_time] = times;
        if self.options.motion_vectors {
            self.motion_from = self.motion_last.take();
        }
        let (tiles_changed, whole_redraw) = match self.keeper.frame(rig, time) {
            Ok(changes) => {
                let on_gpu = self.options.cull == super::CullMode::Gpu;
                (keeping::keep(&mut plan, &changes, on_gpu), None)
            }
            Err(why) => (0, Some(why)),
        };
        self.keeps = whole_redraw.is_none();
        let mut stats = self.write_plan(queue, plan, true)?;
        stats.tiles_changed = tiles_changed;
        stats.whole_redraw = whole_redraw;
        if let Some(morph) = &mut self.frame.passes.morph {
            stats.bytes_uploaded += morph.prepare(queue, time);
            if self.frame.edits.pairs() {
                stats.bytes_uploaded += morph.prepare_next(queue, next_time);
            }
        }
        // Texels go up with the first frame: `new` has no queue.
        stats.bytes_uploaded += self.shared.draw_scene.materials.upload(queue);
        self.prepared = Some(time);
        Ok(stats)
    }

    /// Late latching: after [`Renderer::encode`] and before the submit, the frame's
    /// pose replaced by `rig`'s (sampled as late as the caller can), at the time the
    /// frame was prepared for. Every pass the frame recorded reads the pose from the
    /// contexts and cull inputs that `prepare` writes (never from the recorded commands),
    /// so this plans the frame again from `rig` and writes them again: the frame is the
    /// one planned and drawn at `rig`, whatever the distance from the planned pose
    /// (the levels of detail, the coarse cull's blocks, the far split, the foveated
    /// insets, the lights' clusters and the shadow's fit are all chosen on the GPU from
    /// what is written here, or written here). `rig` must have the renderer's displays,
    /// as for `prepare`.
    ///
    /// Culling on the CPU cannot latch: its cull ran in `prepare`, from the planned
    /// pose, and the frame's draws hold its results; that is [`Error::Unsupported`], as
    /// is a latch before any `prepare`.
    pub fn latch(&mut self, queue: &wgpu::Queue, rig: &Rig) -> Result<FrameStats> {
        if let Some(why) = super::checks::why_no_latch(&self.options) {
            return Err(Error::Unsupported(why.into()));
        }
        let Some(time) = self.prepared else {
            return Err(Error::Unsupported(
                "latch comes after prepare and encode, before the submit".into(),
            ));
        };
        if self.keeps {
            return Err(Error::Unsupported(
                "this frame keeps the last frame's pixels, which a new pose would move: latch frames with keep_unchanged off".into(),
            ));
        }
        self.uploads.check_latch()?;
        // The frame is drawn at `rig`, not at the pose the keeper compares the next with.
        self.keeper.forget();
        let plan = self.plan_again(rig, time)?;
        self.write_plan(queue, plan, false)
    }

    /// Plans the frame from `rig` at `time` and writes what its passes read of the
    /// pose: the frame context, the lights' views, each display's contexts and cull
    /// inputs, the shadow's light.
    /// With motion vectors the contexts are measured from the previous frame, and this
    /// plan is the next frame's previous. The pose's writes go up as one
    /// ([`super::uploads`]): placed anew when `fresh` (a prepare), else where the
    /// recorded frame copies them from (a latch).
    fn write_plan(
        &mut self,
        queue: &wgpu::Queue,
        mut plan: FramePlan,
        fresh: bool,
    ) -> Result<FrameStats> {
        if self.options.motion_vectors {
            if let Some(previous) = &self.motion_from {
                plan.measure_from(previous);
            }
            self.motion_last = Some(plan.as_previous());
        }
        self.uploads.begin(fresh);
        let to = Writes {
            pose: &self.uploads,
            queue,
        };
        let frame_bytes = self.frame.write(to, &plan);
        let mut stats = write_displays(to, &plan, &mut self.shared, &mut self.displays);
        let start = std::time::Instant::now();
        stats.bytes_uploaded += self.frame.write_shadow(to, &plan, &self.shared.culler);
        stats.cpu_upload += start.elapsed();
        self.uploads.send(queue, fresh)?;
        stats.bytes_uploaded += frame_bytes;
        // Culling on the CPU with occlusion, the frame's late culls keep the plan.
        let spent = self.shared.culler.keep_for_late(plan);
        self.spare = spent.map(FramePlan::into_storage).unwrap_or_default();
        Ok(stats)
    }

    /// Records every display into `targets[i]` for display `i`: its cull dispatches (GPU
    /// culling) and its passes. With a timer, each display is a scope named after it and
    /// each pass a scope within it, `cull` or `draw`. The edits of the last
    /// [`Renderer::sync`] are copied into place from staging memory that comes back for
    /// reuse when `encoder` is submitted: submit every encoder this records into.
    /// Culling on the CPU with occlusion a frame needs its pyramids on the CPU halfway:
    /// that is [`Error::Unsupported`] here; record it with [`Renderer::encode_early`] and
    /// [`Renderer::encode_late`].
    ///
    /// A frame, top-down: the frame level's passes; each display's cull and draw (with
    /// occlusion, its early phase); every display's pyramids; the late culls (the rig's
    /// in one set of dispatches, or each display's own); each display's late phase.
    pub fn encode(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &[TargetViews],
        timer: Option<&mut GpuTimer>,
    ) -> Result<FrameStats> {
        if self.reads_back() {
            return Err(Error::Unsupported(
                "occlusion with CPU culling needs each display's pyramids on the CPU between the frame's two halves: record them with encode_early and encode_late, submitting in between (or use submit_frame)".into(),
            ));
        }
        self.check_targets(targets)?;
        let mut rec = Recorder::new(timer, Vec::new());
        let early = self.record_early(encoder, targets, &mut rec);
        let late = self.record_late(encoder, targets, &mut rec);
        self.passes = rec.finish(encoder, true);
        Ok(early + late)
    }

    /// The first half of a frame: the frame's passes and each display's cull, draw and,
    /// with occlusion, its pyramids (culling on the GPU, its late cull too). Submit
    /// `encoder`, then record the rest with [`Renderer::encode_late`]. Any renderer can
    /// record its frames so; culling on the CPU with occlusion it must.
    pub fn encode_early(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &[TargetViews],
        timer: Option<&mut GpuTimer>,
    ) -> Result<FrameStats> {
        self.check_targets(targets)?;
        let mut rec = Recorder::new(timer, Vec::new());
        let early = self.record_early(encoder, targets, &mut rec);
        self.passes = rec.finish(encoder, false);
        Ok(early)
    }

    /// The second half of a frame, after the encoder of [`Renderer::encode_early`] was
    /// submitted: culling on the CPU with occlusion, waits for the GPU, reads every
    /// display's pyramids back and culls each display's late phase (and far layer)
    /// against them, then uploads those culls; then records each display's late phase.
    pub fn encode_late(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        targets: &[TargetViews],
        timer: Option<&mut GpuTimer>,
    ) -> Result<FrameStats> {
        self.check_targets(targets)?;
        let views: Vec<_> = (self.displays.iter().map(Display::indirect))
            .map(|d| match d {
                Some(d) => (d.late().map(|l| l.cull_pass()), d.far_cull_pass()),
                None => (None, None),
            })
            .collect();
        let culled = self.shared.culler.cull_late(device, queue, &views)?;
        // The second half's log continues the first's.
        let mut rec = Recorder::new(timer, std::mem::take(&mut self.passes));
        let late = self.record_late(encoder, targets, &mut rec);
        self.passes = rec.finish(encoder, true);
        Ok(culled + late)
    }

    /// Whether each frame reads its pyramids back halfway (CPU culling with occlusion):
    /// then record it with [`Renderer::encode_early`], submit, and
    /// [`Renderer::encode_late`].
    pub fn reads_back(&self) -> bool {
        self.shared.culler.reads_back()
    }

    /// Whether `targets` fit the displays: one each, with a motion attachment where
    /// the renderer draws motion, depth an occluding display's pyramids can read, and
    /// the caller's own pipelines for every own bin.
    fn check_targets(&self, targets: &[TargetViews]) -> Result<()> {
        if targets.len() != self.displays.len() {
            return Err(Error::TargetCount {
                targets: targets.len(),
                displays: self.displays.len(),
            });
        }
        let motion = self.options.motion_vectors;
        if let Some(i) = targets.iter().position(|t| t.motion.is_some() != motion) {
            return Err(Error::Unsupported(format!(
                "display {i}'s target {} a motion attachment and the renderer was made {} motion vectors",
                if motion { "lacks" } else { "has" },
                if motion { "with" } else { "without" },
            )));
        }
        for (display, target) in self.displays.iter().zip(targets) {
            if let Some(d) = display.indirect() {
                d.check_depth(target)?;
                d.check_own_pipelines(&self.shared.culler)?;
            }
        }
        Ok(())
    }

    /// The frame up to the late phases: the frame level's passes, each display's
    /// first half, then with occlusion every display's pyramids and the late culls.
    fn record_early(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &[TargetViews],
        rec: &mut Recorder,
    ) -> FrameStats {
        let mut stats = self.encode_frame(encoder, rec);
        stats.dispatch_levels.frame = stats.dispatches;
        for (display, target) in self.displays.iter().zip(targets) {
            stats = stats + display.encode_early(encoder, &self.shared, target, rec);
        }
        let pyramids = (self.pyramids).encode(encoder, &self.shared.culler, targets, rec);
        for display in &self.displays {
            stats = stats + display.encode_late_cull(encoder, &self.shared, rec);
        }
        // The pyramids and the rig's late culls serve every display at once.
        let rig_late = self.shared.culler.encode_late_rig(encoder, rec);
        stats + FrameStats::frame_level(pyramids + rig_late)
    }

    /// Each display's late phase (with occlusion; nothing without).
    fn record_late(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &[TargetViews],
        rec: &mut Recorder,
    ) -> FrameStats {
        let mut stats = FrameStats::default();
        for (display, target) in self.displays.iter().zip(targets) {
            stats = stats + display.encode_late(encoder, &self.shared, target, rec);
        }
        stats
    }

    /// The frame level's passes, before any display's: the pose's writes copied into
    /// place ([`super::uploads`]), then the frame level's ([`super::frame::FrameLevel::encode`]).
    fn encode_frame(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder,
    ) -> FrameStats {
        self.uploads.record(encoder);
        let any_view = (self.displays.first())
            .and_then(Display::indirect)
            .map(IndirectDisplay::cull_pass);
        let scene = FrameScene {
            draw_scene: &mut self.shared.draw_scene,
            culler: &mut self.shared.culler,
            drawer: &self.shared.drawer,
            any_view,
        };
        self.frame.encode(encoder, scene, rec)
    }

    /// The passes the last `encode` (or `encode_culls`) recorded, in order, each with its
    /// level (frame, display, eye): the shadow pass appears once per frame, whatever
    /// the displays.
    pub fn passes(&self) -> &[PassRecord] {
        &self.passes
    }

    /// Headless convenience: [`Renderer::prepare`], [`Renderer::encode`] into a new encoder
    /// (with `late_latch`, [`Renderer::latch`] at `rig`) and submit, rendering into
    /// `targets` (from [`Renderer::create_targets`]).
    pub fn submit_frame(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        rig: &Rig,
        time: f32,
        targets: &[DisplayTarget],
    ) -> Result<FrameStats> {
        self.submit_frame_timed(device, queue, rig, time, targets, None)
    }

    /// [`Renderer::submit_frame`] with GPU timing and pipeline statistics recorded into
    /// `timer` (read it after the frame completes).
    pub fn submit_frame_timed(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        rig: &Rig,
        time: f32,
        targets: &[DisplayTarget],
        timer: Option<&mut GpuTimer>,
    ) -> Result<FrameStats> {
        let prepared = self.prepare(queue, rig, time)?;
        let mut encoder = device.create_command_encoder(&Default::default());
        let views: Vec<_> = targets.iter().map(DisplayTarget::views).collect();
        let recorded = match self.reads_back() {
            true => {
                let mut timer = timer;
                let early = self.encode_early(&mut encoder, &views, timer.as_deref_mut())?;
                queue.submit([encoder.finish()]);
                encoder = device.create_command_encoder(&Default::default());
                early + self.encode_late(device, queue, &mut encoder, &views, timer)?
            }
            false => self.encode(&mut encoder, &views, timer)?,
        };
        if self.options.late_latch {
            self.latch(queue, rig)?;
        }
        queue.submit([encoder.finish()]);
        Ok(prepared + recorded)
    }
    /// For drawing into the caller's own render passes: records this frame's culls
    /// (GPU culling: each display's dispatches, timed as `cull` inside a scope per
    /// display; CPU culling: nothing, `prepare` uploaded them). Then, in passes the
    /// caller begins, [`Renderer::draw_display`] for each display. Occlusion's two
    /// phases need the renderer's own passes (a draw, the depth's pyramids, another
    /// draw): here each display is culled by its frustum alone. Culling on the CPU with
    /// occlusion, `prepare` uploaded the early phases, so that is
    /// [`Error::Unsupported`].
    pub fn encode_culls(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        timer: Option<&mut GpuTimer>,
    ) -> Result<FrameStats> {
        if self.reads_back() {
            return Err(Error::Unsupported(
                "occlusion with CPU culling draws in the renderer's own passes (encode_early, encode_late): make the renderer with occlusion off to draw in passes of your own".into(),
            ));
        }
        let mut rec = Recorder::new(timer, Vec::new());
        let mut stats = self.encode_frame(encoder, &mut rec);
        stats.dispatch_levels.frame = stats.dispatches;
        for display in &self.displays {
            stats = stats + display.encode_cull(encoder, &self.shared, &mut rec);
        }
        self.passes = rec.finish(encoder, true);
        Ok(stats)
    }
}

/// Writes the culler's results for `plan` (culling on the CPU, its culls), then each
/// display's contexts and cull inputs.
fn write_displays(
    to: Writes,
    plan: &FramePlan,
    shared: &mut Shared,
    displays: &mut [Display],
) -> FrameStats {
    let mut stats = FrameStats::default();
    let start = std::time::Instant::now();
    stats.bytes_uploaded += shared.culler.prepare(to.pose, plan);
    stats.cpu_cull = start.elapsed();
    let start = std::time::Instant::now();
    for (display, planned) in displays.iter_mut().zip(&plan.displays) {
        stats.bytes_uploaded += display.prepare(to, planned, shared);
    }
    stats.cpu_upload = start.elapsed();
    stats
}
