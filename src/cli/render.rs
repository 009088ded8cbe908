//! `stereocull render`: one frame of every display to PNG, with stats.json.

use std::path::PathBuf;
use std::time::Instant;

use clap::Parser;
use serde::Serialize;

use super::edits::{EditArgs, EditDriver, live_copy};
use super::occlusion_report::occlusion_report;
use super::{SceneArgs, write_json};
use crate::device::{Gpu, list_counts};
use crate::error::{Error, Result};
use crate::foveated_composite::{CompositeParams, FoveatedComposite, composite_cpu};
use crate::live::LiveScene;
use crate::profiling::{FrameQueries, GpuTimer};
use crate::readback::read_rgba8;
use crate::renderer::{
    CullMode, DisplayTarget, FrameStats, Level, PosingMode, Renderer, RendererOptions, StereoMode,
    SyncStats,
};
use crate::rig::Rig;
use crate::scene::Scene;

#[derive(Parser)]
pub struct RenderArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Output directory for `<display>.png` and `stats.json`.
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    #[arg(long, value_enum, default_value = "gpu")]
    pub cull: CullMode,
    #[arg(long, value_enum, default_value = "instanced")]
    pub mode: StereoMode,
    /// The frame's time in seconds (animated instances are drawn at it).
    #[arg(long, default_value_t = 0.0)]
    pub time: f32,
    /// MSAA samples per pixel (1: none); `stereocull info` lists the adapter's counts.
    /// Default: 4 where the adapter has it for this mode, else 1.
    #[arg(long)]
    pub msaa: Option<u32>,
    /// Also write each display's depth as an XR compositor's depth layer takes it:
    /// `<display>-depth.f32` (little-endian f32, rows from the top, multiview's layers
    /// side by side; under MSAA each pixel's nearest sample) and its contract (each
    /// view's rectangle or layer, planes, depth range) in `stats.json`.
    #[arg(long)]
    pub compositor_depth: bool,
}

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
    /// `mode` and `msaa` samples per pixel (checked against the adapter's counts; `None`:
    /// [`default_msaa`]). A scene with edits or animations is live: each
    /// [`Session::frame`] poses it at the frame's time.
    pub fn open(
        args: &SceneArgs,
        (cull, mode, msaa): (CullMode, StereoMode, Option<u32>),
        edits: &EditArgs,
        time: f32,
    ) -> Result<Session> {
        let rig = args.load_rig()?;
        let mut scene = args.load_scene()?;
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
        let ms = |since: Instant| since.elapsed().as_secs_f64() * 1e3;
        let (mut edit_ms, mut sync_ms, mut sync) = (0.0, 0.0, SyncStats::default());
        let start = Instant::now();
        if let Some((live, driver)) = &mut self.live {
            // Posing is stereocull's frame-context work: counted in cpu_ms.
            if self.renderer.options().posing == PosingMode::Cpu {
                live.pose(time)?;
            }
            let edits = Instant::now();
            driver.apply(live, self.frames)?;
            edit_ms = ms(edits);
            let sync_start = Instant::now();
            sync = self
                .renderer
                .sync(&self.gpu.device, &self.gpu.queue, live)?;
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
        let mut stats = self.renderer.prepare(queue, &self.rig, time)?;
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

/// One pass of a frame as the reports list it ([`Renderer::passes`]).
#[derive(Clone, Debug, Serialize)]
pub struct PassReport {
    pub level: Level,
    pub name: &'static str,
    pub display: Option<String>,
    pub eye: Option<u32>,
    /// Vertex-shader invocations (pipeline statistics, where the adapter has them; draw
    /// and shadow passes).
    pub vertex_invocations: Option<u64>,
}

/// The last frame's passes in recording order, with the displays named and each
/// counted pass's vertex-shader invocations from `queries`.
pub fn pass_reports(
    renderer: &Renderer,
    rig: &Rig,
    queries: Option<&FrameQueries>,
) -> Vec<PassReport> {
    renderer
        .passes()
        .iter()
        .map(|p| PassReport {
            level: p.level,
            name: p.name,
            display: p.display.map(|d| rig.displays[d as usize].name.clone()),
            eye: p.eye,
            vertex_invocations: p
                .statistics
                .zip(queries)
                .and_then(|(i, q)| q.vertex_invocations_per_query.get(i as usize).copied()),
        })
        .collect()
}

/// The last frame's far/near split, per display with a far layer, named.
pub fn far_near(session: &Session) -> Result<Vec<serde_json::Value>> {
    let device = (&session.gpu.device, &session.gpu.queue);
    let splits = session
        .renderer
        .diagnostics(device.0, device.1)
        .far_split()?;
    Ok(session
        .rig
        .displays
        .iter()
        .zip(splits)
        .filter_map(|(d, s)| s.map(|s| serde_json::json!({ "display": d.name, "split": s })))
        .collect())
}

/// How many passes of each level `passes` holds: (frame, display, eye).
pub fn passes_per_level(passes: &[PassReport]) -> serde_json::Value {
    let count = |level| passes.iter().filter(|p| p.level == level).count();
    serde_json::json!({
        "frame": count(Level::Frame),
        "display": count(Level::Display),
        "eye": count(Level::Eye),
    })
}

#[derive(Serialize)]
struct DisplayStats {
    name: String,
    views: u32,
    image: String,
    width: u32,
    height: u32,
    visible: u32,
    /// Each view's `[x, y, width, height]` in the display's target.
    viewports: Vec<[u32; 4]>,
    /// Pixels of all views together: what the frame shades (per sample).
    pixels: u64,
    /// Foveated displays: the target as drawn (`<name>-views.png`); `image` is then the
    /// composite of each eye's inset over its outer view.
    #[serde(skip_serializing_if = "Option::is_none")]
    views_image: Option<String>,
    /// Foveated displays: whether the gaze was moved to keep an inset inside its view.
    #[serde(skip_serializing_if = "Option::is_none")]
    gaze_clamped: Option<bool>,
    /// With `--compositor-depth`: the depth file and its contract.
    #[serde(skip_serializing_if = "Option::is_none")]
    depth: Option<DepthStats>,
}

#[derive(Serialize)]
struct DepthStats {
    file: String,
    /// Of the file: the layers side by side.
    width: u32,
    height: u32,
    #[serde(flatten)]
    layer: crate::compositor::DepthLayer,
}

/// Display `index`'s compositor depth written to `<name>-depth.f32` under `out`.
fn write_depth(session: &Session, index: usize, out: &std::path::Path) -> Result<DepthStats> {
    let (device, queue) = (&session.gpu.device, &session.gpu.queue);
    let depth = &session.targets[index].depth;
    let (width, values) = crate::compositor::read_layer(device, queue, depth)?;
    let path = out.join(format!("{}-depth.f32", session.rig.displays[index].name));
    let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    std::fs::write(&path, bytes).map_err(|e| Error::io(&path, e))?;
    Ok(DepthStats {
        file: path.display().to_string(),
        width,
        height: depth.height(),
        layer: session.renderer.depth_layer(&session.rig, index)?,
    })
}

/// Display `index`'s image as drawn and, for a foveated display, its composite (each
/// eye's inset over its outer view, by the GPU composite).
fn display_images(
    session: &Session,
    index: usize,
) -> Result<(image::RgbaImage, Option<image::RgbaImage>)> {
    let (device, queue) = (&session.gpu.device, &session.gpu.queue);
    let target = &session.targets[index];
    let drawn = read_rgba8(device, queue, &target.color)?;
    let layout = session
        .renderer
        .layout(index)
        .unwrap_or(session.rig.displays[index].layout());
    let Some(params) = CompositeParams::of_display(&session.rig, index, &layout)? else {
        return Ok((drawn, None));
    };
    // Multiview's layers are no 2D texture the GPU composite could read: the CPU twin
    // composites them as read back, side by side.
    if target.color.depth_or_array_layers() > 1 {
        let composite = composite_cpu(&drawn, &params);
        return Ok((drawn, Some(composite)));
    }
    let format = target.color.format();
    let output = FoveatedComposite::create_output(device, &params, format);
    let mut encoder = device.create_command_encoder(&Default::default());
    let source = target.color.create_view(&Default::default());
    let view = output.create_view(&Default::default());
    FoveatedComposite::new(device, format).encode(device, &mut encoder, &source, &params, &view);
    queue.submit([encoder.finish()]);
    Ok((drawn, Some(read_rgba8(device, queue, &output)?)))
}

/// The frame's figures, with the fragments it shaded (pipeline statistics, where the
/// adapter counts them) and the pixels the visibility masks kept from being shaded.
fn frame_json(
    stats: &FrameStats,
    queries: Option<&crate::profiling::FrameQueries>,
    masked_pixels: u64,
) -> serde_json::Value {
    let mut frame = serde_json::json!(stats);
    frame["fragment_invocations"] = serde_json::json!(queries.and_then(|q| q.fragment_invocations));
    frame["masked_pixels"] = serde_json::json!(masked_pixels);
    frame
}

fn save(image: &image::RgbaImage, path: &std::path::Path) -> Result<()> {
    image.save(path).map_err(|source| Error::Image {
        path: path.to_path_buf(),
        source,
    })
}

pub fn render(args: &RenderArgs) -> Result<()> {
    let edits = EditArgs::default();
    let how = (args.cull, args.mode, args.msaa);
    let mut session = Session::open(&args.scene, how, &edits, args.time)?;
    // Room for every display's draw passes (one per eye, or two with occlusion, at
    // most) and the shadow pass.
    let counted = 3 * session.rig.displays.len() as u32 + 1;
    // Occlusion's early phase draws what the display drew last frame: a first frame
    // draws everything late (no depth yet to hide behind), the second draws that early
    // and finds what it hides. Two frames before this one prime it, as in a running
    // application.
    let primed = session.renderer.occlusion_bytes().is_some();
    for _ in 0..2 * u32::from(primed) {
        session.frame(args.time)?;
        session.gpu.wait()?;
    }
    session.timer = GpuTimer::new(&session.gpu.device, &session.gpu.queue, counted);
    let FrameFigures { stats, cpu_ms, .. } = session.frame(args.time)?;
    let start = Instant::now();
    session.gpu.wait()?;
    let gpu_wait_ms = start.elapsed().as_secs_f64() * 1e3;
    let queries = match session.timer.as_mut() {
        Some(t) => Some(t.read(&session.gpu.device, &session.gpu.queue)?),
        None => None,
    };
    let passes = pass_reports(&session.renderer, &session.rig, queries.as_ref());
    let far_near = far_near(&session)?;
    let occlusion = occlusion_report(
        &session.gpu,
        &session.renderer,
        (&session.rig, args.time),
        session.current_scene(),
    )?;
    std::fs::create_dir_all(&args.out).map_err(|e| Error::io(&args.out, e))?;
    let visible = session
        .renderer
        .diagnostics(&session.gpu.device, &session.gpu.queue)
        .visible_counts()?;
    let candidates = session
        .renderer
        .diagnostics(&session.gpu.device, &session.gpu.queue)
        .candidates()?;
    let resolved = session.rig.resolve()?;
    let mut displays = Vec::new();
    for (index, (display, visible)) in session.rig.displays.iter().zip(visible).enumerate() {
        let path = args.out.join(format!("{}.png", display.name));
        let (drawn, composite) = display_images(&session, index)?;
        let views_path = composite
            .as_ref()
            .map(|_| args.out.join(format!("{}-views.png", display.name)));
        if let Some(views_path) = &views_path {
            save(&drawn, views_path)?;
        }
        let image = composite.unwrap_or(drawn);
        save(&image, &path)?;
        let gaze_clamped = (display.views() == 4).then(|| resolved.displays[index].gaze_clamped);
        if gaze_clamped == Some(true) {
            eprintln!(
                "{}: the gaze would put an inset outside its eye's view; the inset was moved inside",
                display.name
            );
        }
        let layout = display.layout();
        println!(
            "{:>18}: {} views, {}x{}, {visible} visible -> {}",
            display.name,
            display.views(),
            image.width(),
            image.height(),
            path.display()
        );
        displays.push(DisplayStats {
            name: display.name.clone(),
            views: display.views(),
            image: path.display().to_string(),
            width: image.width(),
            height: image.height(),
            visible,
            viewports: layout.viewports().to_vec(),
            pixels: layout.pixels(),
            views_image: views_path.map(|p| p.display().to_string()),
            gaze_clamped,
            depth: match args.compositor_depth {
                true => Some(write_depth(&session, index, &args.out)?),
                false => None,
            },
        });
    }
    println!(
        "{} instances, {} with cull {:?}, {}x MSAA: {} draw calls, {} dispatches, {} bytes uploaded, CPU {cpu_ms:.2} ms, GPU wait {gpu_wait_ms:.1} ms",
        session.scene.instances.len(),
        args.mode.name(),
        args.cull,
        session.renderer.options().sample_count,
        stats.draw_calls,
        stats.dispatches,
        stats.bytes_uploaded
    );
    for r in occlusion.iter().flatten() {
        println!(
            "{:>18}: occlusion: {} in the frustum, {} drawn early, {} late, {} occluded",
            r.display, r.frustum, r.early, r.late, r.occluded
        );
    }
    let out = args.out.join("stats.json");
    write_json(
        &out,
        &serde_json::json!({
            "adapter": session.gpu.adapter_line(),
            "scene": args.scene.scene,
            "rig": args.scene.rig,
            "cull": args.cull,
            "mode": args.mode,
            "msaa": session.renderer.options().sample_count,
            "instances": session.scene.instances.len(),
            "gpu_bytes_per_instance": session.renderer.gpu_bytes_per_instance(),
            "frame": frame_json(&stats, queries.as_ref(), session.renderer.masked_pixels()),
            "coarse_cull": session.renderer.coarse_cull(),
            "coarse_candidates": candidates,
            "shadows": session.renderer.options().shadows,
            "far_layer": session.renderer.options().far_layer,
            "far_near": far_near,
            "occlusion": occlusion,
            "occlusion_primed_by_two_frames": primed,
            "occlusion_bytes": session.renderer.occlusion_bytes(),
            "passes_per_level": passes_per_level(&passes),
            "passes": passes,
            "cpu_encode_submit_ms": cpu_ms,
            "gpu_wait_ms": gpu_wait_ms,
            "displays": displays,
        }),
    )
}
