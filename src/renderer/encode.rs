//! Recording a frame into the caller's encoder: the frame level's passes, then every
//! display's (whole, or in two halves around a submission where the CPU culler needs the
//! pyramids), and the headless conveniences that prepare, record and submit.

use super::display::occlusion::cull_late;
use super::frame::FramePasses;
use super::frame_stats::FrameStats;
use super::recorder::Recorder;
use super::{DisplayTarget, PassRecord, Renderer, TargetViews};
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
        (device, queue): (&wgpu::Device, &wgpu::Queue),
        encoder: &mut wgpu::CommandEncoder,
        targets: &[TargetViews],
        timer: Option<&mut GpuTimer>,
    ) -> Result<FrameStats> {
        self.check_targets(targets)?;
        let culled = cull_late((device, queue), &mut self.shared.culler, &self.displays)?;
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
            stats = stats + display.encode_early(encoder, (&self.shared, target), rec);
        }
        let pyramids = (self.pyramids).encode(encoder, (&self.shared.culler, targets), rec);
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
            stats = stats + display.encode_late(encoder, (&self.shared, target), rec);
        }
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
            self.shared.draw_scene.keep_previous(encoder);
        }
        // A kept frame's changed tiles: the spheres as last drawn, then as posed now.
        let marked = self.shared.culler.encode_marks(encoder, false);
        let (mut posing, mut cpu_staging) = self.encode_pose(encoder, rec, false);
        if pairs {
            self.shared.draw_scene.keep_previous(encoder);
            let (second, staging) = self.encode_pose(encoder, rec, true);
            (posing, cpu_staging) = (posing + second, cpu_staging + staging);
        }
        let marked = marked + self.shared.culler.encode_marks(encoder, true);
        if marked > 0 {
            rec.log(PassRecord::frame("keep_mark"));
        }
        let any = self.displays.first().and_then(|d| d.indirect());
        let coarse = match any {
            Some(d) => self
                .shared
                .culler
                .encode_frame(encoder, Some(d.view_cull()), rec),
            None => 0,
        };
        let (shadowed, draw_calls) = match &self.frame_passes.shadow {
            Some(shadow) => {
                let shared = (self.shared.drawing(), &self.shared.culler);
                shadow.encode(encoder, shared, &self.shadow_map, rec)
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
        let FramePasses {
            skin, morph, pose, ..
        } = &mut self.frame_passes;
        let posed = match (pose, second) {
            (Some(pose), false) => pose.encode(encoder, rec),
            (Some(pose), true) => pose.encode_next(encoder, rec),
            (None, _) => 0,
        };
        let morphed = match (morph, second) {
            (Some(morph), false) => morph.encode(encoder, rec),
            (Some(morph), true) => morph.encode_next(encoder, rec),
            (None, _) => 0,
        };
        let clustered = match second {
            false => self.lighting.encode(encoder, rec),
            true => 0,
        };
        let skinned = match (skin, second) {
            (Some(skin), false) => skin.encode(encoder, rec),
            (Some(skin), true) => skin.encode_next(encoder, rec),
            (None, _) => 0,
        };
        (self.shared.draw_scene).rewritten(scattered + posed > 0, skinned + morphed > 0);
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
