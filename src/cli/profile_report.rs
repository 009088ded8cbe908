//! `profile`'s outputs: one row per configuration, the table it prints and
//! `profile.csv` (the chart draws the same rows).

use serde::Serialize;
use wgpu_profiler::GpuTimerQueryResult;

use super::occlusion_report::OcclusionReport;
use super::render::PassReport;
use crate::error::{Error, Result};
use crate::renderer::StereoMode;
use crate::renderer::{CullMode, DispatchLevels, FarSplit};

/// One configuration's figures: the CSV columns first, then the details.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    pub mode: StereoMode,
    pub cull: CullMode,
    pub rig: String,
    pub instances: u32,
    /// prepare + encode + submit.
    pub cpu_ms_median: f64,
    /// Frames each submission draws (2: dt multiview).
    pub frames_per_submit: u32,
    /// `cpu_ms_median` over the frames each submission shows.
    pub cpu_ms_per_displayed_frame: f64,
    /// Keeping unchanged pixels (`--keep-unchanged`).
    pub keep_unchanged: crate::keep::KeepUnchanged,
    /// Of the timed frames, the median tiles a kept frame redrew (0 for a frame drawn
    /// whole), and the frames drawn whole.
    pub tiles_changed_median: f64,
    pub whole_redraws: u32,
    pub cpu_ms_p95: f64,
    /// Sum of the timed passes; `None` without timestamp queries.
    pub gpu_ms_median: Option<f64>,
    pub gpu_ms_p95: Option<f64>,
    pub draw_calls: u32,
    pub dispatches: u32,
    /// The dispatches by level (frame, displays).
    pub dispatches_per_level: DispatchLevels,
    pub bytes_uploaded: u64,
    pub adapter: String,
    pub cull_ms_median: f64,
    pub upload_ms_median: f64,
    pub encode_ms_median: f64,
    /// Of `encode_ms_median`, copying the edits into staging memory.
    pub staging_ms_median: f64,
    /// Instances the last frame synced as moves (inserted ones too).
    pub moved: u32,
    /// A plain copy of the frame's edit bytes from one warm buffer into another (with
    /// edits).
    pub copy_ms_median: Option<f64>,
    /// With moves and a 0 % row of the same configuration: what they cost.
    pub edits: Option<EditCost>,
    pub submit_ms_median: f64,
    pub gpu_cull_ms_median: Option<f64>,
    pub gpu_draw_ms_median: Option<f64>,
    /// Whether some display culled by occlusion.
    pub occlusion: bool,
    /// Where animations were posed (as configured; a still scene has nothing to pose).
    pub posing: crate::renderer::PosingMode,
    /// With occlusion: the depth pyramids' GPU time, and the late phase's (its cull and
    /// its draw pass), per frame.
    pub gpu_pyramid_ms_median: Option<f64>,
    pub gpu_late_ms_median: Option<f64>,
    /// Per display, what occlusion did in the last frame.
    pub occlusion_displays: Vec<Option<OcclusionReport>>,
    /// With occlusion and a row of the same configuration without it in the run.
    pub occlusion_over_off: Option<OcclusionRatios>,
    /// Pipeline statistics of the draw passes (last frame); `None` where unavailable.
    pub vertex_invocations: Option<u64>,
    pub clipper_primitives: Option<u64>,
    /// Fragment-shader invocations of the draw passes (last frame): pixels shaded.
    pub fragment_invocations: Option<u64>,
    /// Samples of the display draws that passed the depth test (last frame; occlusion
    /// queries): what a GPU testing depth before shading shades. `None` untimed.
    pub samples_passed: Option<u64>,
    /// Pixels of every display's views together (target memory scales with it).
    pub target_pixels: u64,
    pub indirect_validation: bool,
    pub moving_percent: f64,
    pub churn_percent: f64,
    /// Percent of the meshes made blended glass (`--glass`).
    pub glass_percent: f64,
    /// Of `cpu_ms_median`'s frames, the median sync of the frame's edits.
    pub sync_ms_median: f64,
    /// Primitives reaching the clipper in the draw passes (last frame).
    pub triangles_submitted: Option<u64>,
    /// Whether the frames ran the coarse cull.
    pub coarse_cull: bool,
    /// Sphere-against-frustum tests of the last frame (GPU culling).
    pub sphere_tests: Option<u64>,
    pub shadows: bool,
    pub far_layer: bool,
    /// Foveated displays' inset cull.
    pub inset_cull: bool,
    /// GPU culling: the rig cull (`--rig-cull`).
    pub rig_cull: bool,
    /// The last frame's far/near split per display (with the far layer).
    pub far_near: Vec<Option<FarSplit>>,
    /// The last frame's shadow passes (1 with shadows, whatever the rig).
    pub shadow_passes: usize,
    /// The floor kernel's median GPU ms (one read of every sphere, one flag written per
    /// instance: the least a cull could do), timed in the same frames (GPU culling).
    pub floor_ms_median: Option<f64>,
    /// The floor kernel by the wall clock, submitted alone and waited for (median over
    /// `--frames` submissions): what it costs where timestamps mislead (lavapipe).
    pub wall_floor_ms_median: Option<f64>,
    /// The frame's whole cull by the wall clock, submitted alone (median over
    /// `--frames` submissions): the rig cull's dispatches and every view's that culls
    /// apart (all of them, per display, without the rig cull).
    pub rig_cull_wall_ms: Option<f64>,
    /// Per display, its median GPU cull ms and that over `floor_ms_median`.
    pub cull_over_floor: Vec<CullOverFloor>,
    /// The last frame's passes, with level and vertex-shader invocations.
    pub passes: Vec<PassReport>,
    /// The last timed frame's GPU scopes, for `--trace`.
    #[serde(skip)]
    pub trace: Vec<GpuTimerQueryResult>,
}

/// A moving configuration's CPU against the same configuration at 0 % moving in the
/// same run, per moved instance and beside a plain copy of the same bytes.
#[derive(Clone, Debug, Serialize)]
pub struct EditCost {
    /// `cpu_ms_median` minus the static row's, per moved instance.
    pub extra_ns_per_move: f64,
    /// The phases that do the edits' work (sync and the staging copy; the rest records
    /// one dispatch and its copy commands whatever the moves), per moved instance:
    /// measured directly, so free of the noise in a difference of two frames' totals.
    pub sync_staging_ns_per_move: f64,
    /// `copy_ms_median` per moved instance.
    pub copy_ns_per_move: f64,
    /// `extra_ns_per_move` and `sync_staging_ns_per_move` over `copy_ns_per_move`.
    pub over_copy: f64,
    pub sync_staging_over_copy: f64,
    /// Where the extra goes: each phase's median minus the static row's, ms.
    pub sync_ms: f64,
    pub prepare_ms: f64,
    pub staging_ms: f64,
    /// `encode` without the staging copy.
    pub encode_ms: f64,
    pub submit_ms: f64,
}

/// A configuration with occlusion over the same without it, in the same run.
#[derive(Clone, Debug, Serialize)]
pub struct OcclusionRatios {
    pub triangles_submitted: Option<f64>,
    pub vertex_invocations: Option<f64>,
    pub cpu_ms: f64,
    pub gpu_ms: Option<f64>,
}

/// Fills [`Row::occlusion_over_off`] of every row with occlusion from the row of the
/// same configuration without it, where the run has one (`--occlusion on,off`).
pub fn price_occlusion(rows: &mut [Row]) {
    let key = |r: &Row| {
        let (a, b) = (r.moving_percent.to_bits(), r.churn_percent.to_bits());
        let flags = (r.coarse_cull, r.far_layer, r.inset_cull, r.rig_cull);
        let apart = (r.keep_unchanged, r.frames_per_submit);
        let glass = r.glass_percent.to_bits();
        (
            r.mode,
            r.cull,
            r.rig.clone(),
            r.instances,
            flags,
            apart,
            a,
            b,
            glass,
        )
    };
    let ratio = |a: Option<u64>, b: Option<u64>| Some(a? as f64 / b?.max(1) as f64);
    let priced: Vec<_> = (rows.iter())
        .map(|r| {
            let off = rows.iter().find(|b| !b.occlusion && key(b) == key(r))?;
            r.occlusion.then(|| OcclusionRatios {
                triangles_submitted: ratio(r.triangles_submitted, off.triangles_submitted),
                vertex_invocations: ratio(r.vertex_invocations, off.vertex_invocations),
                cpu_ms: r.cpu_ms_median / off.cpu_ms_median,
                gpu_ms: r.gpu_ms_median.zip(off.gpu_ms_median).map(|(a, b)| a / b),
            })
        })
        .collect();
    for (r, p) in rows.iter_mut().zip(priced) {
        r.occlusion_over_off = p;
    }
}

/// The rows [`price_occlusion`] priced, one line each.
pub fn print_occlusion(rows: &[Row]) {
    let show = |v: Option<f64>| v.map_or("n/a".into(), |x| format!("{x:.3}"));
    for r in rows {
        let Some(o) = &r.occlusion_over_off else {
            continue;
        };
        println!(
            "occlusion on/off {} {} {}: triangles {}, vertex invocations {}, CPU {:.3}, GPU {} (pyramids {} ms, late phase {} ms)",
            r.rig,
            r.mode.name(),
            r.instances,
            show(o.triangles_submitted),
            show(o.vertex_invocations),
            o.cpu_ms,
            show(o.gpu_ms),
            show(r.gpu_pyramid_ms_median),
            show(r.gpu_late_ms_median),
        );
    }
}

/// Per row with glass (`--glass 0,1,10`) and a row of the same configuration without:
/// the GPU cull's time (where the blended bins' sort runs, a pass of its own) against
/// that row's.
pub fn print_glass(rows: &[Row]) {
    for r in rows.iter().filter(|r| r.glass_percent > 0.0) {
        let plain = rows.iter().find(|b| {
            b.glass_percent == 0.0
                && (b.mode, b.cull, &b.rig, b.instances, b.occlusion)
                    == (r.mode, r.cull, &r.rig, r.instances, r.occlusion)
        });
        let (Some(plain), Some(cull)) = (plain, r.gpu_cull_ms_median) else {
            continue;
        };
        let ratio = plain.gpu_cull_ms_median.map(|p| cull / p.max(1e-9));
        println!(
            "glass {} % {} {} {}: GPU cull {cull:.3} ms (with the blended sort), {} x the cull without glass; CPU {:.3} x",
            r.glass_percent,
            r.rig,
            r.mode.name(),
            r.instances,
            ratio.map_or("n/a".into(), |x| format!("{x:.2}")),
            r.cpu_ms_median / plain.cpu_ms_median.max(1e-9),
        );
    }
}

/// Fills [`Row::edits`] of every row with moves from the row of the same configuration
/// without them, where the run has one (`--moving 0,1,10`).
pub fn price_edits(rows: &mut [Row]) {
    let same = |a: &Row, b: &Row| {
        (
            a.mode,
            a.cull,
            &a.rig,
            a.instances,
            a.coarse_cull,
            a.far_layer,
            a.inset_cull,
            a.rig_cull,
            a.churn_percent,
            a.occlusion,
            a.glass_percent,
            (a.keep_unchanged, a.frames_per_submit),
        ) == (
            b.mode,
            b.cull,
            &b.rig,
            b.instances,
            b.coarse_cull,
            b.far_layer,
            b.inset_cull,
            b.rig_cull,
            b.churn_percent,
            b.occlusion,
            b.glass_percent,
            (b.keep_unchanged, b.frames_per_submit),
        )
    };
    let costs: Vec<Option<EditCost>> = rows
        .iter()
        .map(|r| {
            let base = rows
                .iter()
                .find(|b| b.moving_percent == 0.0 && same(b, r))?;
            let copy = r.copy_ms_median.filter(|_| r.moved > 0)?;
            let per_move = |ms: f64| ms * 1e6 / r.moved as f64;
            let extra = per_move(r.cpu_ms_median - base.cpu_ms_median);
            let prepare = |x: &Row| x.cull_ms_median + x.upload_ms_median;
            let staging = r.staging_ms_median - base.staging_ms_median;
            let own = per_move(r.sync_ms_median + r.staging_ms_median);
            Some(EditCost {
                extra_ns_per_move: extra,
                sync_staging_ns_per_move: own,
                copy_ns_per_move: per_move(copy),
                over_copy: extra / per_move(copy),
                sync_staging_over_copy: own / per_move(copy),
                sync_ms: r.sync_ms_median - base.sync_ms_median,
                prepare_ms: prepare(r) - prepare(base),
                staging_ms: staging,
                encode_ms: r.encode_ms_median - base.encode_ms_median - staging,
                submit_ms: r.submit_ms_median - base.submit_ms_median,
            })
        })
        .collect();
    for (r, c) in rows.iter_mut().zip(costs) {
        r.edits = c;
    }
}

/// One display's GPU cull against the floor kernel of the same frames.
#[derive(Clone, Debug, Serialize)]
pub struct CullOverFloor {
    pub display: String,
    pub cull_ms: f64,
    pub ratio: f64,
    /// The display's cull alone by the wall clock, and that over the floor's.
    pub wall_cull_ms: Option<f64>,
    pub wall_ratio: Option<f64>,
}

impl Row {
    /// `gpu` or `cpu`, as the table, the CSV and the trace spell the cull.
    pub fn cull_name(&self) -> String {
        format!("{:?}", self.cull).to_lowercase()
    }

    /// The largest display's cull over the floor: the CSV's `cull_over_floor`.
    pub fn worst_cull_over_floor(&self) -> Option<f64> {
        self.cull_over_floor
            .iter()
            .map(|c| c.ratio)
            .reduce(f64::max)
    }

    /// The same by the wall clock: the CSV's `cull_over_floor_wall`.
    pub fn worst_wall_cull_over_floor(&self) -> Option<f64> {
        self.cull_over_floor
            .iter()
            .filter_map(|c| c.wall_ratio)
            .reduce(f64::max)
    }
}

fn opt(v: Option<f64>) -> String {
    v.map_or("n/a".into(), |x| format!("{x:.3}"))
}

pub(super) fn print_table(rows: &[Row]) {
    if let Some(r) = rows.first() {
        let validation = if r.indirect_validation { "on" } else { "off" };
        println!(
            "adapter: {}; wgpu indirect validation: {validation}",
            r.adapter
        );
    }
    println!(
        "{:>14} {:>13} {:>4} {:>9} {:>6} | {:>9} {:>9} | {:>9} {:>9} | {:>8} {:>8} {:>8} {:>8} | {:>9} {:>5} {:>10} | {:>11} {:>11} | {:>7} {:>7}",
        "rig",
        "mode",
        "cull",
        "instances",
        "moving",
        "cpu med",
        "cpu p95",
        "gpu med",
        "gpu p95",
        "cull",
        "upload",
        "encode",
        "submit",
        "draws",
        "disp",
        "uploaded",
        "vs invoc",
        "clip prims",
        "c/floor",
        "wall"
    );
    for r in rows {
        let rig = std::path::Path::new(&r.rig)
            .file_stem()
            .map_or(r.rig.clone(), |s| s.to_string_lossy().into());
        let rig = if r.inset_cull {
            format!("{rig}+inset")
        } else {
            rig
        };
        let rig = match (r.rig_cull, r.cull) {
            (false, CullMode::Gpu) => format!("{rig}/apart"),
            _ => rig,
        };
        println!(
            "{:>14} {:>13} {:>4} {:>9} {:>6} | {:>9.3} {:>9.3} | {:>9} {:>9} | {:>8.3} {:>8.3} {:>8.3} {:>8.3} | {:>9} {:>5} {:>10} | {:>11} {:>11} | {:>7} {:>7}",
            rig,
            r.mode.name(),
            r.cull_name(),
            r.instances,
            format!("{}%", r.moving_percent),
            r.cpu_ms_median,
            r.cpu_ms_p95,
            opt(r.gpu_ms_median),
            opt(r.gpu_ms_p95),
            r.cull_ms_median,
            r.upload_ms_median,
            r.encode_ms_median,
            r.submit_ms_median,
            r.draw_calls,
            r.dispatches,
            r.bytes_uploaded,
            count(r.vertex_invocations),
            count(r.clipper_primitives),
            opt(r.worst_cull_over_floor()),
            opt(r.worst_wall_cull_over_floor())
        );
    }
    print_edit_costs(rows);
}

/// Per moving row with a static twin: the extra CPU per moved instance, where it goes,
/// and the plain copy of the same bytes.
fn print_edit_costs(rows: &[Row]) {
    for r in rows {
        let Some(e) = &r.edits else { continue };
        println!(
            "edits {} {} {} {} {}%: {} moves, {} bytes; per move: plain copy {:.2} ns, sync + staging {:.2} ns ({:.2}x), frame over static {:+.1} ns ({:.1}x); ms over static: sync {:+.3}, prepare {:+.3}, staging {:+.3}, rest of encode {:+.3}, submit {:+.3}",
            r.rig,
            r.mode.name(),
            r.cull_name(),
            r.instances,
            r.moving_percent,
            r.moved,
            r.bytes_uploaded,
            e.copy_ns_per_move,
            e.sync_staging_ns_per_move,
            e.sync_staging_over_copy,
            e.extra_ns_per_move,
            e.over_copy,
            e.sync_ms,
            e.prepare_ms,
            e.staging_ms,
            e.encode_ms,
            e.submit_ms
        );
    }
}

fn count(v: Option<u64>) -> String {
    v.map_or("n/a".into(), |x| x.to_string())
}

pub(super) fn write_csv(path: &std::path::Path, rows: &[Row]) -> Result<()> {
    let mut text = String::from(
        "mode,cull,rig,instances,cpu_ms_median,cpu_ms_p95,gpu_ms_median,gpu_ms_p95,draw_calls,dispatches,bytes_uploaded,adapter,moving_percent,churn_percent,sync_ms_median,triangles_submitted,coarse_cull,sphere_tests,shadows,shadow_passes,floor_ms_median,cull_over_floor,cull_over_floor_wall,moved,staging_ms_median,copy_ms_median,sync_staging_ns_per_move,extra_ns_per_move,fragment_invocations,target_pixels\n",
    );
    let field = |v: Option<f64>| v.map_or(String::new(), |x| format!("{x:.4}"));
    for r in rows {
        text += &format!(
            "{},{},{},{},{:.4},{:.4},{},{},{},{},{},\"{}\",{},{},{:.4},{},{},{},{},{},{},{},{},{},{:.4},{},{},{},{},{}\n",
            r.mode.name(),
            r.cull_name(),
            r.rig,
            r.instances,
            r.cpu_ms_median,
            r.cpu_ms_p95,
            field(r.gpu_ms_median),
            field(r.gpu_ms_p95),
            r.draw_calls,
            r.dispatches,
            r.bytes_uploaded,
            r.adapter.replace('"', "'"),
            r.moving_percent,
            r.churn_percent,
            r.sync_ms_median,
            r.triangles_submitted
                .map_or(String::new(), |t| t.to_string()),
            r.coarse_cull,
            r.sphere_tests.map_or(String::new(), |t| t.to_string()),
            r.shadows,
            r.shadow_passes,
            field(r.floor_ms_median),
            field(r.worst_cull_over_floor()),
            field(r.worst_wall_cull_over_floor()),
            r.moved,
            r.staging_ms_median,
            field(r.copy_ms_median),
            field(r.edits.as_ref().map(|e| e.sync_staging_ns_per_move)),
            field(r.edits.as_ref().map(|e| e.extra_ns_per_move)),
            r.fragment_invocations
                .map_or(String::new(), |t| t.to_string()),
            r.target_pixels
        );
    }
    std::fs::write(path, text).map_err(|e| Error::io(path, e))
}
