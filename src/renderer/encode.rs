//! Recording a frame into the caller's encoder: the frame level's passes, then every
//! display's (whole, or in two halves around a submission where the CPU culler needs the
//! pyramids), and the headless conveniences that prepare, record and submit.

use super::display::indirect::IndirectPath;
use super::frame_stats::FrameStats;
use super::recorder::Recorder;
use super::{DisplayTarget, PassRecord, Path, Renderer, TargetViews};
use crate::error::{Error, Result};
use crate::profiling::GpuTimer;
use crate::rig::Rig;

impl Renderer {
    /// Records every display into `targets[i]` for display `i`: its cull dispatches (GPU
    /// culling) and its passes. With a timer, each display is a scope named after it and
    /// each pass a scope within it, `cull` or `draw`. The edits of the last
    /// [`Renderer::sync`] are copied into place from staging memory that comes back for
    /// reuse when `encoder` is submitted: submit every encoder this records into.
    /// Culling on the CPU with occlusion a frame needs its pyramids on the CPU halfway:
    /// that is [`Error::Unsupported`] here; record it with [`Renderer::encode_early`] and
    /// [`Renderer::encode_late`].
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
        self.encode_part(encoder, targets, timer, Part::Whole)
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
        self.encode_part(encoder, targets, timer, Part::Early)
    }

    /// The second half of a frame, after the encoder of [`Renderer::encode_early`] was
    /// submitted: culling on the CPU with occlusion, waits for the GPU, reads every
    /// display's pyramids back and culls each display's late phase (and far layer)
    /// against them, then uploads those culls; then records each display's late phase.
    pub fn encode_late(
        &mut self,
        (device, queue): (&wgpu::Device, &wgpu::Queue),
        encoder: &mut wgpu::CommandEncoder,
        targets: &[TargetViews],
        timer: Option<&mut GpuTimer>,
    ) -> Result<FrameStats> {
        let culled = match &mut self.path {
            Path::Indirect(p) => p.cull_late(device, queue)?,
            Path::Classic(_) => FrameStats::default(),
        };
        Ok(culled + self.encode_part(encoder, targets, timer, Part::Rest)?)
    }

    /// Whether each frame reads its pyramids back halfway (CPU culling with occlusion):
    /// then record it with [`Renderer::encode_early`], submit, and
    /// [`Renderer::encode_late`].
    pub fn reads_back(&self) -> bool {
        self.path.core().culler.reads_back()
    }

    /// Records `part` of the frame into `encoder`.
    fn encode_part(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &[TargetViews],
        timer: Option<&mut GpuTimer>,
        part: Part,
    ) -> Result<FrameStats> {
        if targets.len() != self.shapes.len() {
            return Err(Error::TargetCount {
                targets: targets.len(),
                displays: self.shapes.len(),
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
        if let Some(p) = self.path.indirect() {
            p.check_depth(targets)?;
            (0..self.shapes.len()).try_for_each(|i| p.check_own_pipelines(i))?;
        }
        // The second half's log continues the first's.
        let log = match part {
            Part::Rest => std::mem::take(&mut self.passes),
            _ => Vec::new(),
        };
        let mut rec = Recorder::new(timer, log);
        let mut stats = match part {
            Part::Rest => FrameStats::default(),
            _ => self.encode_frame(encoder, &mut rec),
        };
        stats.dispatch_levels.frame = stats.dispatches;
        // A whole frame is its two halves: every display's early half, then every
        // display's rest, so that one set of dispatches culls every late phase between.
        let halves = match part {
            Part::Whole => &[Part::Early, Part::Rest][..],
            Part::Early => &[Part::Early],
            Part::Rest => &[Part::Rest],
        };
        for &half in halves {
            stats = stats + self.encode_half(encoder, targets, &mut rec, half);
        }
        self.passes = rec.finish(encoder, part != Part::Early);
        Ok(stats)
    }

    /// Records every display's `half` of the frame (`Early` or `Rest`); after the
    /// early halves, every display's pyramids and late culls.
    fn encode_half(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &[TargetViews],
        rec: &mut Recorder,
        half: Part,
    ) -> FrameStats {
        let mut stats = FrameStats::default();
        for (i, target) in targets.iter().enumerate() {
            // No scope (timestamps) for a display with no late half (the classic
            // modes' displays have none).
            let rest = matches!(&self.path, Path::Indirect(p) if p.has_late(i));
            if half == Part::Rest && !rest {
                continue;
            }
            rec.enter(encoder, &self.names[i]);
            let at = (i, target);
            let recorded = match (&self.path, half) {
                (Path::Indirect(p), Part::Rest) => p.encode_rest(encoder, at, rec),
                (Path::Indirect(p), _) => p.encode_early(encoder, at, rec),
                (Path::Classic(p), _) => p.encode_display(encoder, at, rec),
            };
            stats.draw_calls += recorded.draw_calls;
            stats.dispatches += recorded.dispatches;
            stats.dispatch_levels.display += recorded.dispatches;
            rec.leave(encoder);
        }
        if let (Path::Indirect(p), Part::Early) = (&self.path, half) {
            stats = stats + self.encode_late_culls(p, encoder, targets, rec);
        }
        stats
    }

    /// With occlusion, after every display's early half: every display's pyramids,
    /// then the late culls (the rig cull's late members in one set of dispatches, or
    /// each display's own). The pyramids and the rig's late culls count at the frame
    /// level: one set of dispatches serves every display.
    fn encode_late_culls(
        &self,
        p: &IndirectPath,
        encoder: &mut wgpu::CommandEncoder,
        targets: &[TargetViews],
        rec: &mut Recorder,
    ) -> FrameStats {
        let mut stats = FrameStats::default();
        let frame = p.encode_pyramids(encoder, targets, rec);
        for i in (0..targets.len()).filter(|&i| p.culls_late_apart(i)) {
            rec.enter(encoder, &self.names[i]);
            let own = p.encode_late_cull(encoder, i, rec);
            stats.dispatches += own;
            stats.dispatch_levels.display += own;
            rec.leave(encoder);
        }
        let frame = frame + p.encode_late_rig(encoder, rec);
        stats.dispatches += frame;
        stats.dispatch_levels.frame += frame;
        stats
    }

    /// The frame level's passes, before any display's: the pose's writes copied into
    /// place ([`super::uploads`]), with motion vectors the copy of the previous frame's
    /// records and vertices, the frame's pose (the scatter of moved instances, posing,
    /// morph targets, skinning), with two frames per submission the second frame's
    /// pose after a copy of the first's ([`super::second_frame`]), then the coarse
    /// cull and the shadow pass.
    pub(super) fn encode_frame(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder,
    ) -> FrameStats {
        self.uploads.record(encoder);
        let pairs = self.second.is_some();
        if !pairs {
            self.path.core_mut().draw_scene.keep_previous(encoder);
        }
        // A kept frame's changed tiles: the spheres as last drawn, then as posed now.
        let marked = self.path.core_mut().culler.encode_marks(encoder, false);
        let (mut posing, mut cpu_staging) = self.encode_pose(encoder, rec, false);
        if pairs {
            self.path.core_mut().draw_scene.keep_previous(encoder);
            let (second, staging) = self.encode_pose(encoder, rec, true);
            (posing, cpu_staging) = (posing + second, cpu_staging + staging);
        }
        let marked = marked + self.path.core_mut().culler.encode_marks(encoder, true);
        if marked > 0 {
            rec.log(PassRecord::frame("keep_mark"));
        }
        let coarse = match &self.path {
            Path::Indirect(p) => p.encode_frame(encoder, rec),
            Path::Classic(_) => 0,
        };
        let (shadowed, draw_calls) = match &self.shadow {
            Some(shadow) => {
                let core = self.path.core();
                shadow.encode(
                    encoder,
                    (core.drawing(), &core.culler),
                    &self.shadow_map,
                    rec,
                )
            }
            None => (0, 0),
        };
        FrameStats {
            dispatches: posing + marked + coarse + shadowed,
            draw_calls,
            cpu_staging,
            ..Default::default()
        }
    }

    /// A frame's pose: its edits scattered, its animations posed on the GPU, its morph
    /// targets and skins, the lights' clusters; for the `second` frame of a submission,
    /// its own edits, morph weights and joint matrices (the rest serves both frames).
    /// Returns the dispatches and the CPU time of staging the edits.
    fn encode_pose(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder,
        second: bool,
    ) -> (u32, std::time::Duration) {
        let (scattered, cpu_staging) = match (&mut self.second, second) {
            // The first frame's copy of the records (just made) gets its vacant
            // records first.
            (Some(frame), true) => {
                let (vacant, staging) = frame.first.encode(encoder);
                let (own, own_staging) = frame.scatter.encode(encoder);
                (vacant + own, staging + own_staging)
            }
            _ => self.scatter.encode(encoder),
        };
        if scattered > 0 {
            rec.log(PassRecord::frame("scatter"));
        }
        let posed = match (&self.pose, second) {
            (Some(pose), false) => pose.encode(encoder, rec),
            (Some(pose), true) => pose.encode_next(encoder, rec),
            (None, _) => 0,
        };
        let morphed = match (&self.morph, second) {
            (Some(morph), false) => morph.encode(encoder, rec),
            (Some(morph), true) => morph.encode_next(encoder, rec),
            (None, _) => 0,
        };
        let clustered = match second {
            false => self.lighting.encode(encoder, rec),
            true => 0,
        };
        let skinned = match (&mut self.skin, second) {
            (Some(skin), false) => skin.encode(encoder, rec),
            (Some(skin), true) => skin.encode_next(encoder, rec),
            (None, _) => 0,
        };
        (self.path.core_mut().draw_scene).rewritten(scattered + posed > 0, skinned + morphed > 0);
        let dispatches = scattered + posed + morphed + clustered + skinned;
        (dispatches, cpu_staging)
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
                early + self.encode_late((device, queue), &mut encoder, &views, timer)?
            }
            false => self.encode(&mut encoder, &views, timer)?,
        };
        if self.options.late_latch {
            self.latch(queue, rig)?;
        }
        queue.submit([encoder.finish()]);
        Ok(prepared + recorded)
    }
}

/// Which part of a frame an `encode` records.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Part {
    Whole,
    /// Up to each display's pyramids.
    Early,
    /// The rest.
    Rest,
}
