//! `profile`'s comparisons of a feature's rows against the rows without it that are
//! otherwise the same: two frames per submission, and keeping unchanged pixels.

use super::profile_report::Row;
use crate::keep::KeepUnchanged;

/// With two frames per submission: each such row's CPU per displayed frame against the
/// row of one frame per submission that is otherwise the same (same order of rows).
pub(super) fn print_frames(rows: &[Row]) {
    let key = |r: &Row| (r.rig.clone(), r.mode, r.cull, r.instances, r.occlusion);
    for r in rows.iter().filter(|r| r.frames_per_submit == 2) {
        let single = rows
            .iter()
            .find(|s| s.frames_per_submit == 1 && key(s) == key(r));
        let ratio = single.map(|s| r.cpu_ms_per_displayed_frame / s.cpu_ms_median.max(1e-9));
        println!(
            "{} {} {:?} {}: two frames per submission, CPU per displayed frame {:.3} ms{}",
            r.rig,
            r.mode.name(),
            r.cull,
            r.instances,
            r.cpu_ms_per_displayed_frame,
            ratio.map_or(String::new(), |x| format!(
                ", {x:.3} of one frame per submission"
            )),
        );
    }
}

/// With `--keep-unchanged on`: each such row's CPU and GPU per frame, fragments shaded
/// and triangles submitted against the row with it off that is otherwise the same, and
/// the tiles its kept frames redrew.
pub(super) fn print_keep(rows: &[Row]) {
    let key = |r: &Row| {
        let moving = r.moving_percent.to_bits();
        (
            r.rig.clone(),
            r.mode,
            r.cull,
            r.instances,
            r.frames_per_submit,
            moving,
        )
    };
    for r in rows
        .iter()
        .filter(|r| r.keep_unchanged == KeepUnchanged::On)
    {
        let Some(off) =
            (rows.iter()).find(|s| s.keep_unchanged == KeepUnchanged::Off && key(s) == key(r))
        else {
            continue;
        };
        let ratio = |a: Option<f64>, b: Option<f64>| match a.zip(b) {
            Some((a, b)) if b > 0.0 => format!("{:.3}", a / b),
            _ => "-".into(),
        };
        let count = |v: Option<u64>| v.map(|x| x as f64);
        println!(
            "{} {} {:?} {} {} % moving: unchanged pixels kept, {:.0} tiles redrawn (median), {} frames whole; CPU {:.3} of off, GPU {}, fragments {}, triangles {}",
            r.rig,
            r.mode.name(),
            r.cull,
            r.instances,
            r.moving_percent,
            r.tiles_changed_median,
            r.whole_redraws,
            r.cpu_ms_median / off.cpu_ms_median.max(1e-9),
            ratio(r.gpu_ms_median, off.gpu_ms_median),
            ratio(
                count(r.fragment_invocations),
                count(off.fragment_invocations)
            ),
            ratio(count(r.triangles_submitted), count(off.triangles_submitted)),
        );
    }
}
