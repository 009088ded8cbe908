//! `stereocull stress`: frames with a moving viewer, timed, with a progress bar.

use std::time::Instant;

use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;

mod report;

use super::edits::EditArgs;
use super::occlusion_report::{OcclusionReport, occlusion_report};
use super::render::{PassReport, far_near, pass_reports, passes_per_level};
use super::session::Session;
use super::{FRAME_SECONDS, SceneArgs};
use crate::error::Result;
use crate::profiling::{GpuTimer, percentile};
use crate::renderer::{CullMode, DispatchLevels, OcclusionBytes, StereoMode};

#[derive(Args)]
pub struct StressArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Submissions to draw (each shows `--frames-per-submit` frames).
    #[arg(long, default_value_t = 100)]
    pub frames: u32,
    #[arg(long, value_enum, default_value = "gpu")]
    pub cull: CullMode,
    #[arg(long, value_enum, default_value = "instanced")]
    pub mode: StereoMode,
    /// MSAA samples per pixel (1: none).
    #[arg(long, default_value_t = 1)]
    pub msaa: u32,
    #[command(flatten)]
    pub edits: EditArgs,
    /// Print per-frame and summary figures as one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
    /// Latch each frame's pose at the submit (GPU cull): the pose is sampled from the
    /// viewer's path again once the frame is recorded ([`crate::renderer::Renderer::latch`]),
    /// by a renderer made for it (`RendererOptions::late_latch`).
    #[arg(long)]
    pub latch: bool,
    /// Hold the head still (no walk): with `--keep-unchanged`, frames redraw only what
    /// the edits and animations change.
    #[arg(long)]
    pub still: bool,
}

#[derive(Serialize)]
struct FrameRecord {
    frame: u32,
    /// sync + prepare + encode + submit on the CPU.
    cpu_ms: f64,
    /// Of `cpu_ms`, syncing the frame's edits (0 without `--moving` / `--churn`).
    sync_ms: f64,
    /// Of `cpu_ms`, copying them into staging memory (in `encode`).
    staging_ms: f64,
    /// Making the frame's edits (the caller's work, not in `cpu_ms`).
    edit_ms: f64,
    /// Instances synced as scatter edits; whether the cull order was rewritten.
    moved: u32,
    reloaded: bool,
    /// Primitives reaching the clipper in the draw passes (pipeline statistics; `None`
    /// where the adapter has none).
    triangles_submitted: Option<u64>,
    /// Fragment-shader invocations in the frame (pipeline statistics; lavapipe counts
    /// them before its depth test), and the display draws' samples that passed it.
    fragment_invocations: Option<u64>,
    samples_passed: Option<u64>,
    /// Keeping unchanged pixels: the tiles and pixels redrawn (every view's where drawn
    /// whole), or why the frame was drawn whole.
    tiles_changed: u32,
    pixels_redrawn: u64,
    whole_redraw: Option<crate::keep::WholeRedraw>,
    /// Until the GPU finished the frame.
    frame_ms: f64,
    /// From sampling the pose the frame is drawn with to its submit.
    pose_age_ms: f64,
    /// The skinning pass's GPU milliseconds (timestamps; `None` without skins or them).
    skin_gpu_ms: Option<f64>,
    pose_gpu_ms: Option<f64>,
    visible: Vec<u32>,
    /// Sphere-against-frustum tests (GPU culling; see `Diagnostics::sphere_tests`).
    sphere_tests: Option<u64>,
    /// The passes recorded, with their level and vertex-shader invocations.
    passes: Vec<PassReport>,
    draw_calls: u32,
    dispatches: u32,
    /// The dispatches by level (frame, displays).
    dispatch_levels: DispatchLevels,
    bytes_uploaded: u64,
}

#[derive(Serialize)]
struct Summary {
    adapter: String,
    instances: usize,
    displays: Vec<String>,
    cull: CullMode,
    /// Whether frames ran the frame-level coarse cull.
    coarse_cull: bool,
    /// Submissions, each of `frames_per_submit` displayed frames.
    frames: u32,
    frames_per_submit: u32,
    cpu_ms_median: f64,
    /// `cpu_ms_median` over the frames each submission shows.
    cpu_ms_per_displayed_frame_median: f64,
    cpu_ms_p95: f64,
    sync_ms_median: f64,
    staging_ms_median: f64,
    edit_ms_median: f64,
    moving_percent: f64,
    churn_percent: f64,
    frame_ms_median: f64,
    frame_ms_p95: f64,
    /// Whether each frame's pose was latched at its submit (`--latch`), and the median
    /// time from sampling the pose a frame is drawn with to its submit.
    latch: bool,
    pose_age_at_submit_ms_median: f64,
    visible_mean: Vec<f64>,
    /// Median over the frames of the sphere tests (GPU culling).
    sphere_tests_median: Option<f64>,
    /// Whether frames draw the shadow map, and the last frame's passes per level.
    shadows: bool,
    passes_per_level: serde_json::Value,
    /// With the far layer: the last frame's far distance and far/near split per display.
    far_near: Vec<serde_json::Value>,
    draw_calls_per_frame: u32,
    dispatches_per_frame: u32,
    /// The last frame's dispatches by level (frame, displays).
    dispatches_per_level: DispatchLevels,
    bytes_uploaded_per_frame: u64,
    /// Median over the frames of the triangles submitted (pipeline statistics).
    triangles_submitted_median: Option<f64>,
    /// Median over the frames of the fragment-shader invocations and of the samples
    /// that passed the depth test.
    fragment_invocations_median: Option<f64>,
    samples_passed_median: Option<f64>,
    /// Keeping unchanged pixels (`--keep-unchanged`, `--still`): the median tiles and
    /// pixels redrawn, and the frames drawn whole.
    keep_unchanged: crate::keep::KeepUnchanged,
    still: bool,
    tiles_changed_median: f64,
    pixels_redrawn_median: f64,
    whole_redraws: usize,
    gpu_bytes_per_instance: u64,
    /// Vertices the skinning pass poses per frame (once for every display and eye), and
    /// the GPU bytes each takes in the pass's rest buffer (its posed copy is the scene's
    /// vertex); the joint matrices take `bytes_per_joint` each.
    skinned_vertices_per_frame: u32,
    skinning_bytes: serde_json::Value,
    /// Median over the frames of the skinning pass's GPU time.
    skin_gpu_ms_median: Option<f64>,
    /// Where animations were posed (`--posing`), the pose pass's GPU time (posing on
    /// the GPU), and the GPU bytes of its tables and per-node scratch.
    posing: crate::renderer::PosingMode,
    pose_gpu_ms_median: Option<f64>,
    posing_bytes: u64,
    /// GPU bytes occlusion adds per display and once (`None` without it).
    occlusion_bytes: Option<OcclusionBytes>,
    /// Per display, what occlusion did in the last frame.
    occlusion: Vec<Option<OcclusionReport>>,
    /// Memory after the first frame, after every tenth of the run, and after the last:
    /// in a soak run, growth after warm-up means a leak.
    memory: Vec<MemorySample>,
}

#[derive(Serialize)]
struct MemorySample {
    /// Frames completed.
    frame: u32,
    /// Resident memory of this process (Linux; with a software driver it holds GPU
    /// memory too).
    rss_kib: Option<u64>,
    /// Live wgpu buffers, textures, views, bind groups, query sets and command buffers.
    wgpu_objects: Option<usize>,
    /// Bytes wgpu's allocator holds on the device, where the backend reports it.
    gpu_allocated_bytes: Option<u64>,
}

impl MemorySample {
    fn take(session: &Session, frame: u32) -> MemorySample {
        MemorySample {
            frame,
            rss_kib: resident_kib(),
            wgpu_objects: session.gpu.live_resources(),
            gpu_allocated_bytes: session
                .gpu
                .device
                .generate_allocator_report()
                .map(|r| r.total_allocated_bytes),
        }
    }
}

pub fn stress(args: &StressArgs) -> Result<()> {
    let msaa = Some(args.msaa);
    let how = (args.cull, args.mode, msaa, args.latch);
    let mut session = Session::open(&args.scene, how, &args.edits, 0.0)?;
    // Room for every display's draw passes (one per eye, or two with occlusion, at
    // most) and the shadow pass.
    let counted = 3 * session.rig.displays.len() as u32 + 1;
    session.timer = GpuTimer::new(&session.gpu.device, &session.gpu.queue, counted);
    let bar = if args.json {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(args.frames as u64)
    };
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} frames {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let base = session.rig.viewer;
    let mut records = Vec::new();
    let mut memory = Vec::new();
    let every = (args.frames / 10).max(1);
    // With two frames per submission, each submission shows frames 2k and 2k + 1 of
    // the path, `dt` apart.
    let (per_submit, dt) = {
        let o = session.renderer.options();
        (o.frames_per_submit, o.dt)
    };
    let period = if per_submit == 2 { dt } else { FRAME_SECONDS };
    let shown = (args.frames * per_submit).max(1) as f32;
    // Look around and sway, so that culling sees a different view every frame.
    let walk = |rig: &mut crate::rig::Rig, shown_frame: u32| {
        if args.still {
            return;
        }
        let phase = shown_frame as f32 / shown * std::f32::consts::TAU;
        rig.viewer.yaw_deg = base.yaw_deg + 40.0 * phase.sin();
        rig.viewer.position[0] = base.position[0] + 0.3 * (2.0 * phase).sin();
    };
    for frame in 0..args.frames {
        let first = frame * per_submit;
        let sway = |rig: &mut crate::rig::Rig| walk(rig, first);
        sway(&mut session.rig);
        if per_submit == 2 {
            let mut next = session.rig.clone();
            walk(&mut next, first + 1);
            session.next_rig = Some(next);
        }
        let start = Instant::now();
        let latch = args.latch.then_some(&sway as &dyn Fn(&mut crate::rig::Rig));
        let figures = session.frame_latched(first as f32 * period, latch)?;
        let (stats, cpu_ms) = (figures.stats, figures.cpu_ms);
        session.gpu.wait()?;
        let frame_ms = start.elapsed().as_secs_f64() * 1e3;
        let queries = match session.timer.as_mut() {
            Some(t) => Some(t.read(&session.gpu.device, &session.gpu.queue)?),
            None => None,
        };
        let triangles_submitted = queries.as_ref().and_then(|q| q.triangles_submitted);
        let pass_ms = |name: &str| {
            (queries.as_ref())
                .and_then(|q| q.passes.iter().find(|(label, _)| label == name))
                .map(|(_, ms)| *ms)
        };
        let (skin_gpu_ms, pose_gpu_ms) = (pass_ms("skin"), pass_ms("pose"));
        let passes = pass_reports(&session.renderer, &session.rig, queries.as_ref());
        let visible = session
            .renderer
            .diagnostics(&session.gpu.device, &session.gpu.queue)
            .visible_counts()?;
        let sphere_tests = session
            .renderer
            .diagnostics(&session.gpu.device, &session.gpu.queue)
            .sphere_tests()?;
        let (tiles_changed, pixels_redrawn) =
            super::redrawn(&session.renderer, &session.gpu, &stats)?;
        let record = FrameRecord {
            frame,
            cpu_ms,
            sync_ms: figures.sync_ms,
            staging_ms: stats.cpu_staging.as_secs_f64() * 1e3,
            edit_ms: figures.edit_ms,
            moved: figures.sync.moved,
            reloaded: figures.sync.reloaded,
            triangles_submitted,
            fragment_invocations: queries.as_ref().and_then(|q| q.fragment_invocations),
            samples_passed: queries.as_ref().and_then(|q| q.samples_passed),
            tiles_changed,
            pixels_redrawn,
            whole_redraw: stats.whole_redraw,
            frame_ms,
            pose_age_ms: figures.pose_age_ms,
            skin_gpu_ms,
            pose_gpu_ms,
            visible,
            sphere_tests,
            passes,
            draw_calls: stats.draw_calls,
            dispatches: stats.dispatches,
            dispatch_levels: stats.dispatch_levels,
            bytes_uploaded: stats.bytes_uploaded,
        };
        bar.set_message(format!("cpu {cpu_ms:.3} ms, frame {frame_ms:.1} ms"));
        if !args.json {
            let line = format!(
                "frame {frame:>5}: cpu {cpu_ms:8.3} ms  frame {frame_ms:9.2} ms  visible {:?}",
                record.visible
            );
            // A bar drawn on no terminal drops its println: print plainly then.
            if bar.is_hidden() {
                println!("{line}");
            } else {
                bar.println(line);
            }
        }
        bar.inc(1);
        records.push(record);
        let done = frame + 1;
        if done == 1 || done % every == 0 || done == args.frames {
            memory.push(MemorySample::take(&session, done));
        }
    }
    bar.finish_and_clear();
    memory.dedup_by_key(|m| m.frame);
    let far_near = far_near(&session)?;
    let last_time = (args.frames.saturating_sub(1) * per_submit) as f32 * period;
    let occlusion = occlusion_report(
        &session.gpu,
        &session.renderer,
        (&session.rig, last_time),
        session.current_scene(),
    )?;
    let mut summary = summarize(&session, args, &records, far_near, memory);
    summary.occlusion = occlusion;
    if args.json {
        let all = serde_json::json!({ "frames": records, "summary": summary });
        println!("{all}");
    } else {
        report::print_summary(&summary);
    }
    Ok(())
}

fn summarize(
    session: &Session,
    args: &StressArgs,
    records: &[FrameRecord],
    far_near: Vec<serde_json::Value>,
    memory: Vec<MemorySample>,
) -> Summary {
    let of = |f: fn(&FrameRecord) -> f64| records.iter().map(f).collect::<Vec<f64>>();
    let cpu = of(|r| r.cpu_ms);
    let cpu_ms_median = percentile(&cpu, 0.5);
    let frame: Vec<f64> = records.iter().map(|r| r.frame_ms).collect();
    let displays = session.rig.displays.len();
    let per_submit = session.renderer.options().frames_per_submit;
    let n = records.len().max(1) as f64;
    let last = records.last();
    Summary {
        adapter: session.gpu.adapter_line(),
        instances: session.scene.instances.len(),
        displays: session
            .rig
            .displays
            .iter()
            .map(|d| d.name.clone())
            .collect(),
        cull: args.cull,
        coarse_cull: session.renderer.coarse_cull(),
        frames: args.frames,
        frames_per_submit: per_submit,
        cpu_ms_median,
        cpu_ms_per_displayed_frame_median: cpu_ms_median / per_submit as f64,
        cpu_ms_p95: percentile(&cpu, 0.95),
        sync_ms_median: percentile(&of(|r| r.sync_ms), 0.5),
        staging_ms_median: percentile(&of(|r| r.staging_ms), 0.5),
        edit_ms_median: percentile(&of(|r| r.edit_ms), 0.5),
        moving_percent: args.edits.moving,
        churn_percent: args.edits.churn,
        frame_ms_median: percentile(&frame, 0.5),
        frame_ms_p95: percentile(&frame, 0.95),
        latch: args.latch,
        pose_age_at_submit_ms_median: percentile(&of(|r| r.pose_age_ms), 0.5),
        visible_mean: (0..displays)
            .map(|d| records.iter().map(|r| r.visible[d] as f64).sum::<f64>() / n)
            .collect(),
        draw_calls_per_frame: last.map_or(0, |r| r.draw_calls),
        dispatches_per_frame: last.map_or(0, |r| r.dispatches),
        dispatches_per_level: last.map_or(DispatchLevels::default(), |r| r.dispatch_levels),
        bytes_uploaded_per_frame: last.map_or(0, |r| r.bytes_uploaded),
        triangles_submitted_median: median_of(records, |r| r.triangles_submitted),
        fragment_invocations_median: median_of(records, |r| r.fragment_invocations),
        samples_passed_median: median_of(records, |r| r.samples_passed),
        keep_unchanged: session.renderer.options().keep_unchanged,
        still: args.still,
        tiles_changed_median: percentile(&of(|r| r.tiles_changed as f64), 0.5),
        pixels_redrawn_median: percentile(&of(|r| r.pixels_redrawn as f64), 0.5),
        whole_redraws: records.iter().filter(|r| r.whole_redraw.is_some()).count(),
        sphere_tests_median: median_of(records, |r| r.sphere_tests),
        shadows: session.renderer.options().shadows,
        passes_per_level: passes_per_level(last.map_or(&[], |r| &r.passes[..])),
        far_near,
        gpu_bytes_per_instance: session.renderer.gpu_bytes_per_instance(),
        skinned_vertices_per_frame: session.renderer.skinned_vertices(),
        skin_gpu_ms_median: {
            let v: Vec<f64> = records.iter().filter_map(|r| r.skin_gpu_ms).collect();
            (!v.is_empty()).then(|| percentile(&v, 0.5))
        },
        posing: session.renderer.options().posing,
        pose_gpu_ms_median: {
            let v: Vec<f64> = records.iter().filter_map(|r| r.pose_gpu_ms).collect();
            (!v.is_empty()).then(|| percentile(&v, 0.5))
        },
        posing_bytes: session.renderer.posing_bytes(),
        skinning_bytes: serde_json::json!({
            "per_skinned_vertex": size_of::<crate::skin::SkinVertex>(),
            "per_joint": size_of::<crate::skin::JointMatrix>(),
        }),
        occlusion_bytes: session.renderer.occlusion_bytes(),
        occlusion: Vec::new(),
        memory,
    }
}

/// The median of a figure frames may lack; `None` when every frame lacks it.
fn median_of(records: &[FrameRecord], f: fn(&FrameRecord) -> Option<u64>) -> Option<f64> {
    let v: Vec<f64> = records.iter().filter_map(f).map(|t| t as f64).collect();
    (!v.is_empty()).then(|| percentile(&v, 0.5))
}

/// VmRSS from /proc/self/status; `None` where there is no such file.
fn resident_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmRSS:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}
