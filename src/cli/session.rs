//! What every command that draws frames shares: the device, rig, scene and renderer
//! opened from the command line, and one frame at a time drawn and timed (with its
//! live edits, and with `--latch` its pose latched at the submit).

use std::time::Instant;

use super::SceneArgs;
use super::edits::{EditArgs, EditDriver, live_copy};
use crate::device::{Gpu, list_counts};
use crate::error::{Error, Result};
#[cfg(feature = "cluster")]
use crate::frame_input::FrameInput;
use crate::live::LiveScene;
use crate::profiling::GpuTimer;
use crate::renderer::{
    CullMode, DisplayTarget, FrameStats, PosingMode, Renderer, RendererOptions, StereoMode,
    SyncStats,
};
use crate::rig::Rig;
use crate::scene::Scene;

/// 4x MSAA (VR practice, and what lavapipe has) where the adapter renders the color
/// format at 4 samples and, in multiview, has multisampled two-layer targets; else 1.
pub fn default_msaa(gpu: &Gpu, mode: StereoMode, counts: &[u32]) -> u32 {
    let layered = mode != StereoMode::Multiview
        || gpu
            .device
            .features()
            .contains(wgpu::Features::MULTISAMPLE_ARRAY);
    if counts.contains(&4) && layered { 4 } else { 1 }
}

/// Everything a command needs to draw frames.
pub struct Session {
    pub gpu: Gpu,
    pub rig: Rig,
    pub scene: Scene,
    pub renderer: Renderer,
    pub targets: Vec<DisplayTarget>,
    /// With `--moving` or `--churn`: the live scene and what edits it each frame.
    pub live: Option<(LiveScene, EditDriver)>,
    /// Where frames record GPU timings and pipeline statistics, if asked and available.
    pub timer: Option<GpuTimer>,
    /// With two frames per submission: the second frame's pose (`None`: the first's).
    pub next_rig: Option<Rig>,
    frames: u32,
}

/// One frame's figures from [`Session::frame`].
pub struct FrameFigures {
    /// Recorded and uploaded by prepare + encode + submit (sync's bytes included).
    pub stats: FrameStats,
    /// posing + sync + prepare + encode + submit on the CPU: stereocull's cost.
    pub cpu_ms: f64,
    /// Applying the frame's edits to the live scene: the caller's work.
    pub edit_ms: f64,
    /// Of `cpu_ms`, the sync.
    pub sync_ms: f64,
    pub sync: SyncStats,
    /// From sampling the pose the frame is drawn with (the frame's start, or the
    /// latch's sample) to its submit call.
    pub pose_age_ms: f64,
}

impl Session {
    /// The scene as it stands: the live scene's after its edits, else the loaded one.
    pub fn current_scene(&self) -> &Scene {
        match &self.live {
            Some((live, _)) => live.scene(),
            None => &self.scene,
        }
    }

    /// Loads the rig and scene (posed at `time` seconds, or with `--animation off`
    /// stripped of its animations) and opens the device, then the renderer with `cull`,
    /// `mode`, `msaa` samples per pixel (checked against the adapter's counts; `None`:
    /// [`default_msaa`]) and, where every frame will be latched, `late_latch`. A scene
    /// with edits or animations is live: each [`Session::frame`] poses it at the
    /// frame's time.
    pub fn open(
        args: &SceneArgs,
        (cull, mode, msaa, late_latch): (CullMode, StereoMode, Option<u32>, bool),
        edits: &EditArgs,
        time: f32,
    ) -> Result<Session> {
        let mut scene = args.load_scene()?;
        let rig = args.load_rig(&scene)?;
        if !args.animation.on() {
            scene.posing.clips.clear();
            scene.morphs.stop();
        }
        scene.pose(time);
        let gpu = Gpu::headless()?;
        let mut options = RendererOptions {
            cull,
            mode,
            posing: args.posing.resolve(cull),
            late_latch,
            ..args.options()
        };
        let counts = gpu.sample_counts(options.color_format);
        let msaa = msaa.unwrap_or_else(|| default_msaa(&gpu, mode, &counts));
        options.sample_count = msaa;
        if !counts.contains(&msaa) {
            return Err(Error::Unsupported(format!(
                "--msaa {msaa}: this adapter renders {:?} at {} samples per pixel",
                options.color_format,
                list_counts(&counts)
            )));
        }
        let live = live_copy(&scene, edits, options.posing)?;
        let renderer = Renderer::new(&gpu.device, &scene, &rig, options)?;
        let targets = renderer.create_targets(&gpu.device);
        Ok(Session {
            gpu,
            rig,
            scene,
            renderer,
            targets,
            live,
            timer: None,
            next_rig: None,
            frames: 0,
        })
    }

    /// Applies this frame's edits (if live), syncs them, writes the contexts for `time`
    /// (seconds), records and submits one frame.
    pub fn frame(&mut self, time: f32) -> Result<FrameFigures> {
        self.frame_latched(time, None)
    }

    /// [`Session::frame`]; with `latch`, the frame's pose is sampled again once the
    /// frame is recorded (`latch` moves the rig's viewer) and latched before the submit
    /// ([`Renderer::latch`]).
    pub fn frame_latched(
        &mut self,
        time: f32,
        latch: Option<&dyn Fn(&mut Rig)>,
    ) -> Result<FrameFigures> {
        let frame = self.frames;
        let edit = |live: &mut LiveScene, driver: &mut EditDriver, _: &mut Rig| {
            driver.apply(live, frame).map(drop)
        };
        self.frame_edited(time, latch, edit)
    }

    #[cfg(feature = "cluster")]
    /// A frame as a cluster's head sent it: `input`'s edits made on the live scene, its
    /// pose and gaze on the rig (no driver of this session's own), then drawn at its
    /// time.
    pub fn frame_from(&mut self, input: &FrameInput) -> Result<FrameFigures> {
        if self.live.is_none() {
            if !input.edits.is_empty() {
                return Err(Error::Unsupported(
                    "a frame input with edits for a scene opened without --moving or --churn"
                        .into(),
                ));
            }
            input.apply_pose(&mut self.rig)?;
        }
        let edit = |live: &mut LiveScene, _: &mut EditDriver, rig: &mut Rig| input.apply(live, rig);
        self.frame_edited(input.time, None, edit)
    }

    /// One frame whose edits `edit` makes (on a live scene; none without one).
    fn frame_edited(
        &mut self,
        time: f32,
        latch: Option<&dyn Fn(&mut Rig)>,
        edit: impl FnOnce(&mut LiveScene, &mut EditDriver, &mut Rig) -> Result<()>,
    ) -> Result<FrameFigures> {
        let ms = |since: Instant| since.elapsed().as_secs_f64() * 1e3;
        let (mut edit_ms, mut sync_ms, mut sync) = (0.0, 0.0, SyncStats::default());
        let start = Instant::now();
        if let Some((live, driver)) = &mut self.live {
            // Posing is stereocull's frame-context work: counted in cpu_ms.
            if self.renderer.options().posing == PosingMode::Cpu {
                live.pose(time)?;
            }
            let edits = Instant::now();
            edit(live, driver, &mut self.rig)?;
            edit_ms = ms(edits);
            let sync_start = Instant::now();
            let (device, queue) = (&self.gpu.device, &self.gpu.queue);
            sync = self.renderer.sync(device, queue, live)?;
            let options = self.renderer.options();
            // The second frame of a submission is posed at its own time, after the
            // first frame's sync took the first's.
            if options.frames_per_submit == 2 && options.posing == PosingMode::Cpu {
                live.pose(time + options.dt)?;
                let next = self.renderer.sync_next(device, queue, live)?;
                sync.bytes_uploaded += next.bytes_uploaded;
                sync.moved += next.moved;
            }
            sync_ms = ms(sync_start);
        }
        self.frames += 1;
        let (mut stats, pose_age_ms) = self.submit(time, start, latch)?;
        stats.bytes_uploaded += sync.bytes_uploaded;
        Ok(FrameFigures {
            stats,
            cpu_ms: ms(start) - edit_ms,
            edit_ms,
            sync_ms,
            sync,
            pose_age_ms,
        })
    }

    /// Prepares, records and submits the frame at the rig's pose, sampled at `sampled`;
    /// with `latch`, samples the pose again once the frame is recorded (`latch` moves
    /// the rig's viewer) and latches it. Returns the frame's figures and the pose's age
    /// at the submit in milliseconds. (Culling on the CPU with occlusion the frame is
    /// submitted in two halves: its age then runs to the end of the second.)
    fn submit(
        &mut self,
        time: f32,
        mut sampled: Instant,
        latch: Option<&dyn Fn(&mut Rig)>,
    ) -> Result<(FrameStats, f64)> {
        let (device, queue) = (&self.gpu.device, &self.gpu.queue);
        if self.renderer.reads_back() {
            let timer = self.timer.as_mut();
            let stats = (self.renderer).submit_frame_timed(
                device,
                queue,
                &self.rig,
                time,
                &self.targets,
                timer,
            )?;
            return Ok((stats, sampled.elapsed().as_secs_f64() * 1e3));
        }
        let options = self.renderer.options();
        let mut stats = match options.frames_per_submit {
            2 => {
                let next = (
                    self.next_rig.as_ref().unwrap_or(&self.rig),
                    time + options.dt,
                );
                (self.renderer).prepare_pair(queue, (&self.rig, time), next)?
            }
            _ => self.renderer.prepare(queue, &self.rig, time)?,
        };
        let mut encoder = device.create_command_encoder(&Default::default());
        let views: Vec<_> = self.targets.iter().map(DisplayTarget::views).collect();
        stats = stats + (self.renderer).encode(&mut encoder, &views, self.timer.as_mut())?;
        if let Some(latch) = latch {
            sampled = Instant::now();
            latch(&mut self.rig);
            stats.bytes_uploaded += self.renderer.latch(queue, &self.rig)?.bytes_uploaded;
        }
        let age = sampled.elapsed().as_secs_f64() * 1e3;
        queue.submit([encoder.finish()]);
        Ok((stats, age))
    }
}
