//! Writing a frame's inputs: its plan from the rig's pose and the time, written by
//! `prepare` before the frame is recorded, and written again by `latch` from a later
//! pose before it is submitted.

use super::Renderer;
use super::display::{Display, Shared};
use super::frame_stats::FrameStats;
use super::frames;
use super::keeping;
use super::plan::{FramePlan, PlanStorage};
use super::uploads::Writes;
use crate::buffers::Upload;
use crate::error::{Error, Result};
use crate::rig::Rig;

impl Renderer {
    /// What the frame at `time` for `rig`'s pose will do ([`FramePlan`]): what
    /// [`Renderer::prepare`] writes, for inspection.
    pub fn plan(&self, rig: &Rig, time: f32) -> Result<FramePlan> {
        self.plan_in(rig, time, PlanStorage::default())
    }

    fn plan_in(&self, rig: &Rig, time: f32, storage: PlanStorage) -> Result<FramePlan> {
        self.check_shapes(rig)?;
        let plan = FramePlan::new_in(rig, &self.options, self.coarse, time, storage)?;
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
        let plan = FramePlan::pair(now, next, &self.options, self.coarse)?;
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
        self.prepare_plan(queue, plan, (rig, time), next)
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
        self.prepare_plan(queue, plan, now, next.1)
    }

    fn prepare_plan(
        &mut self,
        queue: &wgpu::Queue,
        mut plan: FramePlan,
        (rig, time): (&Rig, f32),
        next_time: f32,
    ) -> Result<FrameStats> {
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
        if let Some(morph) = &mut self.frame_passes.morph {
            stats.bytes_uploaded += morph.prepare(queue, time);
            if self.second.is_some() {
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
        let frame_bytes = to.pose.write_uniform(&self.frame, 0, &plan.frame);
        let light_bytes = self.lighting.prepare(to.pose, &plan);
        let light = plan.light_cull.as_ref().map(|_| plan.light);
        let mut stats = write_displays(to, &plan, (&mut self.shared, &mut self.displays));
        if let (Some(shadow), Some(light)) = (&self.frame_passes.shadow, light) {
            let start = std::time::Instant::now();
            let (size, culler) = (self.shadow_map.size, &self.shared.culler);
            stats.bytes_uploaded += shadow.prepare(to, &light, size, culler);
            stats.cpu_upload += start.elapsed();
        }
        self.uploads.send(queue, fresh)?;
        stats.bytes_uploaded += frame_bytes + light_bytes;
        // Culling on the CPU with occlusion, the frame's late culls keep the plan.
        let spent = self.shared.culler.keep_for_late(plan);
        self.spare = spent.map(FramePlan::into_storage).unwrap_or_default();
        Ok(stats)
    }
}

/// Writes the culler's results for `plan` (culling on the CPU, its culls), then each
/// display's contexts and cull inputs.
fn write_displays(
    to: Writes,
    plan: &FramePlan,
    (shared, displays): (&mut Shared, &mut [Display]),
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
