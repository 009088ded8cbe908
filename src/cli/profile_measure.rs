//! One configuration of `stereocull profile` measured: its renderer made, warm-up and timed frames run (with their edits), and the
//! frames' samples reduced to a report [`Row`] (CPU phases, GPU passes, pipeline
//! statistics, the cull against its floor).

use std::time::Instant;

use indicatif::ProgressBar;

use super::FRAME_SECONDS;
use super::edits::{EditArgs, live_copy};
use super::occlusion_report::occlusion_report;
use super::profile_args::ProfileArgs;
use super::profile_report::{CullOverFloor, Row};
use super::render::{PassReport, pass_reports};
use crate::device::Gpu;
use crate::error::Result;
use crate::profiling::{GpuTimer, percentile};
use crate::renderer::{
    CoarseMode, CullMode, DispatchLevels, OcclusionMode, PosingMode, Renderer, RendererOptions,
    StereoMode, SyncStats, WallCulls,
};
use crate::rig::Rig;
use crate::scene::Scene;
use wgpu_profiler::GpuTimerQueryResult;

/// One measured configuration.
pub(super) struct Config<'a> {
    pub(super) spec: &'a str,
    pub(super) rig: &'a Rig,
    pub(super) mode: StereoMode,
    pub(super) cull: CullMode,
    pub(super) coarse: CoarseMode,
    pub(super) rig_cull: bool,
    pub(super) far: bool,
    pub(super) inset: bool,
    pub(super) occlusion: OcclusionMode,
    pub(super) posing: PosingMode,
    pub(super) edits: EditArgs,
    /// Percent of the meshes glazed ([`crate::procedural::glaze`]): the scene's.
    pub(super) glass: f64,
    /// Frames per submission.
    pub(super) frames: u32,
    /// Keeping unchanged pixels.
    pub(super) keep: crate::keep::KeepUnchanged,
}

pub(super) fn measure(
    gpu: &Gpu,
    scene: &Scene,
    &Config {
        spec,
        rig,
        mode,
        cull,
        coarse,
        rig_cull,
        far,
        inset,
        occlusion,
        posing,
        edits,
        glass,
        frames,
        keep,
    }: &Config,
    args: &ProfileArgs,
    mut timer: Option<&mut GpuTimer>,
    bar: &ProgressBar,
) -> Result<Row> {
    let options = RendererOptions {
        cull,
        mode,
        sample_count: args.msaa,
        lod: args.lod.on(),
        coarse_cull: coarse,
        rig_cull,
        shadows: args.shadows.on(),
        far_layer: far,
        far_threshold_px: args.far_threshold,
        inset_cull: inset,
        visibility_mask: args.visibility_mask.on(),
        motion_vectors: args.motion_vectors.on(),
        cull_floor: timer.is_some() && cull == CullMode::Gpu && !mode.per_instance(),
        occlusion,
        posing,
        frames_per_submit: frames,
        dt: args.dt,
        keep_unchanged: keep,
        ..Default::default()
    };
    let mut renderer = Renderer::new(&gpu.device, scene, rig, options)?;
    let targets = renderer.create_targets(&gpu.device);
    let views: Vec<_> = targets.iter().map(|t| t.views()).collect();
    let mut samples = Samples::default();
    let mut copy = PlainCopy::default();
    let mut live = live_copy(scene, &edits, posing)?;
    for frame in 0..args.warmup + args.frames {
        // The edits themselves are the caller's work: made before the clock starts.
        if let Some((live, driver)) = &mut live {
            driver.apply(live, frame)?;
        }
        let start = Instant::now();
        let time = frame as f32 * FRAME_SECONDS;
        let synced = match &mut live {
            Some((live, _)) => {
                if posing == PosingMode::Cpu {
                    live.pose(time)?;
                }
                let mut synced = renderer.sync(&gpu.device, &gpu.queue, live)?;
                // A pair's second frame posed at its own time, in a sync of its own.
                if posing == PosingMode::Cpu && frames == 2 {
                    live.pose(time + args.dt)?;
                    let next = renderer.sync_next(&gpu.device, &gpu.queue, live)?;
                    synced.bytes_uploaded += next.bytes_uploaded;
                }
                synced
            }
            None => SyncStats::default(),
        };
        let sync_end = Instant::now();
        copy.bytes = synced.bytes_uploaded as usize;
        let prepared = renderer.prepare(&gpu.queue, rig, time)?;
        let encode_start = Instant::now();
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        // CPU culling with occlusion: the stall for the pyramids counts as encoding.
        let recorded = match renderer.reads_back() {
            true => {
                let early = renderer.encode_early(&mut encoder, &views, timer.as_deref_mut())?;
                gpu.queue.submit([encoder.finish()]);
                encoder = gpu.device.create_command_encoder(&Default::default());
                let (device, queue) = (&gpu.device, &gpu.queue);
                let late =
                    renderer.encode_late(device, queue, &mut encoder, &views, timer.as_deref_mut());
                early + late?
            }
            false => renderer.encode(&mut encoder, &views, timer.as_deref_mut())?,
        };
        let submit_start = Instant::now();
        gpu.queue.submit([encoder.finish()]);
        let end = Instant::now();
        gpu.wait()?;
        // The plain copy of the last frame's edit bytes (the same count every frame),
        // after the frame: timed in the frame's place, it would leave the frame caches
        // a megabyte colder than the static row's.
        let copied = copy.time();
        let queries = match timer.as_deref_mut() {
            Some(t) => Some(t.read(&gpu.device, &gpu.queue)?),
            None => None,
        };
        bar.inc(1);
        if frame < args.warmup {
            continue;
        }
        let ms = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e3;
        samples.cpu.push(ms(start, end));
        samples.sync.push(ms(start, sync_end));
        // Culling on the CPU with occlusion, the late culls run in the encode.
        let culled = prepared.cpu_cull + recorded.cpu_cull;
        samples.cull.push(culled.as_secs_f64() * 1e3);
        samples.upload.push(prepared.cpu_upload.as_secs_f64() * 1e3);
        samples.encode.push(ms(encode_start, submit_start));
        samples
            .staging
            .push(recorded.cpu_staging.as_secs_f64() * 1e3);
        samples.copy.extend(copied);
        samples.moved = synced.moved;
        let (tiles, _) = super::redrawn(&renderer, gpu, &prepared)?;
        samples.tiles.push(f64::from(tiles));
        samples.whole += u32::from(prepared.whole_redraw.is_some());
        samples.submit.push(ms(submit_start, end));
        samples.passes = pass_reports(&renderer, rig, queries.as_ref());
        if let Some(q) = queries {
            let of = |label| {
                q.passes
                    .iter()
                    .filter(|(l, _)| *l == label)
                    .map(|(_, v)| v)
                    .sum::<f64>()
            };
            samples.gpu_cull.push(of("cull") + of("rig_cull"));
            samples.gpu_draw.push(of("draw"));
            samples.gpu_pyramid.push(of("pyramid"));
            let late = of("late_cull") + of("rig_late_cull") + of("late_draw");
            samples.gpu_late.push(late);
            // The floor kernel is the yardstick, not part of the frame.
            samples
                .gpu
                .push(q.passes.iter().map(|(_, v)| v).sum::<f64>() - of("cull_floor"));
            samples.statistics = q.vertex_invocations.zip(q.clipper_primitives);
            samples.fragments = q.fragment_invocations;
            samples.passed = q.samples_passed;
            samples.triangles = q.triangles_submitted;
        }
        if let Some(t) = timer.as_deref() {
            samples.floors.push(cull_and_floor(t.last_frame(), rig));
        }
        samples.levels = recorded.dispatch_levels;
        samples.last = (
            recorded.draw_calls,
            recorded.dispatches,
            prepared.bytes_uploaded + synced.bytes_uploaded,
        );
    }
    let sphere_tests = renderer
        .diagnostics(&gpu.device, &gpu.queue)
        .sphere_tests()?;
    let far_near = renderer.diagnostics(&gpu.device, &gpu.queue).far_split()?;
    let last_time = (args.warmup + args.frames).saturating_sub(1) as f32 * FRAME_SECONDS;
    let scene_now = live.as_ref().map_or(scene, |(l, _)| l.scene());
    let occlusion_displays = occlusion_report(gpu, &renderer, (rig, last_time), scene_now)?;
    let occludes = occlusion_displays.iter().any(Option::is_some);
    let med = |v: &[f64]| percentile(v, 0.5);
    let wall = renderer
        .diagnostics(&gpu.device, &gpu.queue)
        .cull_against_floor(args.frames)?;
    let over_floor = floor_ratios(&samples.floors, rig, wall.as_ref());
    let gpu_med = |v: &[f64]| (!v.is_empty()).then(|| percentile(v, 0.5));
    Ok(Row {
        mode,
        cull,
        rig: spec.to_string(),
        instances: scene.instances.len() as u32,
        cpu_ms_median: med(&samples.cpu),
        frames_per_submit: frames,
        keep_unchanged: keep,
        tiles_changed_median: med(&samples.tiles),
        whole_redraws: samples.whole,
        cpu_ms_per_displayed_frame: med(&samples.cpu) / f64::from(frames),
        cpu_ms_p95: percentile(&samples.cpu, 0.95),
        gpu_ms_median: gpu_med(&samples.gpu),
        gpu_ms_p95: (!samples.gpu.is_empty()).then(|| percentile(&samples.gpu, 0.95)),
        draw_calls: samples.last.0,
        dispatches: samples.last.1,
        dispatches_per_level: samples.levels,
        bytes_uploaded: samples.last.2,
        adapter: gpu.adapter_line(),
        cull_ms_median: med(&samples.cull),
        upload_ms_median: med(&samples.upload),
        encode_ms_median: med(&samples.encode),
        staging_ms_median: med(&samples.staging),
        moved: samples.moved,
        copy_ms_median: gpu_med(&samples.copy),
        edits: None,
        submit_ms_median: med(&samples.submit),
        gpu_cull_ms_median: gpu_med(&samples.gpu_cull),
        gpu_draw_ms_median: gpu_med(&samples.gpu_draw),
        posing,
        occlusion: occludes,
        gpu_pyramid_ms_median: gpu_med(&samples.gpu_pyramid).filter(|_| occludes),
        gpu_late_ms_median: gpu_med(&samples.gpu_late).filter(|_| occludes),
        occlusion_displays,
        occlusion_over_off: None,
        vertex_invocations: samples.statistics.map(|s| s.0),
        clipper_primitives: samples.statistics.map(|s| s.1),
        fragment_invocations: samples.fragments,
        samples_passed: samples.passed,
        target_pixels: rig.displays.iter().map(|d| d.layout().pixels()).sum(),
        indirect_validation: gpu.indirect_validation(),
        moving_percent: edits.moving,
        glass_percent: glass,
        churn_percent: edits.churn,
        sync_ms_median: med(&samples.sync),
        triangles_submitted: samples.triangles,
        coarse_cull: renderer.coarse_cull(),
        sphere_tests,
        shadows: args.shadows.on(),
        far_layer: far,
        inset_cull: inset,
        rig_cull,
        far_near,
        shadow_passes: samples.passes.iter().filter(|p| p.name == "shadow").count(),
        floor_ms_median: over_floor.as_ref().map(|f| f.0),
        wall_floor_ms_median: wall.as_ref().map(|w| w.floor_ms),
        rig_cull_wall_ms: wall.as_ref().map(|w| w.rig_ms),
        cull_over_floor: over_floor.map_or(Vec::new(), |f| f.1),
        passes: samples.passes,
        trace: timer.map(|t| t.last_frame().to_vec()).unwrap_or_default(),
    })
}

#[derive(Default)]
struct Samples {
    fragments: Option<u64>,
    passed: Option<u64>,
    cpu: Vec<f64>,
    sync: Vec<f64>,
    triangles: Option<u64>,
    cull: Vec<f64>,
    upload: Vec<f64>,
    encode: Vec<f64>,
    staging: Vec<f64>,
    /// A plain copy of each frame's edit bytes ([`PlainCopy`]).
    copy: Vec<f64>,
    /// Instances the last frame synced as moves.
    moved: u32,
    /// Per frame, the tiles kept frames redrew (0 drawn whole), and the frames drawn
    /// whole under keeping.
    tiles: Vec<f64>,
    whole: u32,
    submit: Vec<f64>,
    gpu: Vec<f64>,
    gpu_cull: Vec<f64>,
    gpu_draw: Vec<f64>,
    gpu_pyramid: Vec<f64>,
    gpu_late: Vec<f64>,
    /// The last frame's dispatches by level.
    levels: DispatchLevels,
    /// Draw calls, dispatches and bytes uploaded of the last frame (the same every frame).
    last: (u32, u32, u64),
    /// Vertex-shader invocations and clipped primitives of the last frame.
    statistics: Option<(u64, u64)>,
    passes: Vec<PassReport>,
    /// Per frame, each display's GPU cull ms (or the rig's) and the floor kernel's
    /// (when it ran).
    floors: Vec<FrameCulls>,
}

/// One frame's GPU cull ms per display (the `cull` pass in the display's scope), or with
/// the rig cull the rig's alone (`rig_cull` in the frame scope), and the floor kernel's
/// (`cull_floor` in the frame scope), from the timer's scopes.
fn cull_and_floor(scopes: &[GpuTimerQueryResult], rig: &Rig) -> FrameCulls {
    let ms = |scope: &str, pass: &str| {
        let outer = scopes.iter().find(|s| s.label == scope)?;
        let inner = outer.nested_queries.iter().find(|s| s.label == pass)?;
        inner.time.as_ref().map(|t| (t.end - t.start) * 1e3)
    };
    let rig_cull = ms("frame", "rig_cull");
    let culls = match rig_cull {
        Some(rig_cull) => vec![rig_cull],
        None => (rig.displays.iter())
            .map(|d| ms(&d.name, "cull").unwrap_or(0.0))
            .collect(),
    };
    FrameCulls {
        culls,
        floor: ms("frame", "cull_floor"),
        rig: rig_cull.is_some(),
    }
}

/// One frame's GPU culls: per display, or the rig's alone (`rig`), and the floor's.
struct FrameCulls {
    culls: Vec<f64>,
    floor: Option<f64>,
    rig: bool,
}

/// The floor kernel's median ms and, per display (with the rig cull, for the rig as
/// one, named `rig`), its median GPU cull over that floor (medians over the frames;
/// `None` where the floor did not run), beside the same by the wall clock (`wall`).
fn floor_ratios(
    frames: &[FrameCulls],
    rig: &Rig,
    wall: Option<&WallCulls>,
) -> Option<(f64, Vec<CullOverFloor>)> {
    let floors: Vec<f64> = frames.iter().filter_map(|f| f.floor).collect();
    if floors.is_empty() {
        return None;
    }
    let floor = percentile(&floors, 0.5);
    let rig_culled = frames.iter().any(|f| f.rig);
    let names: Vec<String> = match rig_culled {
        true => vec!["rig".to_string()],
        false => rig.displays.iter().map(|d| d.name.clone()).collect(),
    };
    let displays = names.into_iter().enumerate().map(|(d, display)| {
        let culls: Vec<f64> = frames
            .iter()
            .filter_map(|f| f.culls.get(d).copied())
            .collect();
        let cull_ms = percentile(&culls, 0.5);
        let wall_cull_ms = match rig_culled {
            true => wall.map(|w| w.rig_ms),
            false => wall.and_then(|w| w.views_ms.get(d).copied()),
        };
        CullOverFloor {
            display,
            cull_ms,
            ratio: cull_ms / floor,
            wall_cull_ms,
            wall_ratio: wall.zip(wall_cull_ms).map(|(w, c)| c / w.floor_ms),
        }
    });
    Some((floor, displays.collect()))
}

/// The yardstick of an edit's CPU cost: the same bytes copied, in the same run on the
/// same host once per frame (after it, so that its megabyte of traffic does not cool
/// the frame's caches), from memory just written (as the caller just wrote its edits)
/// into memory last touched a frame ago (as the staging belt's chunk was): what the
/// edits' trip to the GPU cannot beat on the CPU.
#[derive(Default)]
struct PlainCopy {
    /// The bytes to copy: the last sync's.
    bytes: usize,
    from: Vec<u8>,
    to: Vec<u8>,
}

impl PlainCopy {
    /// Milliseconds to copy `bytes` bytes (`None` before any).
    fn time(&mut self) -> Option<f64> {
        let n = self.bytes;
        if n == 0 {
            return None;
        }
        if self.from.len() < n {
            (self.from, self.to) = (vec![0; n], vec![0; n]);
        }
        // Patterned, not zero: nothing may take a shortcut over zero pages.
        for (i, b) in self.from[..n].iter_mut().enumerate() {
            *b = (i * 31 + 7) as u8;
        }
        let start = Instant::now();
        self.to[..n].copy_from_slice(std::hint::black_box(&self.from[..n]));
        std::hint::black_box(&self.to);
        Some(start.elapsed().as_secs_f64() * 1e3)
    }
}
