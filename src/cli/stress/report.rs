//! `stress`'s summary printed as text.

use super::Summary;

/// The summary, a line per figure group.
pub(super) fn print_summary(s: &Summary) {
    println!("adapter: {}", s.adapter);
    println!(
        "{} instances, {} frames, cull {:?}, coarse cull {}",
        s.instances,
        s.frames,
        s.cull,
        if s.coarse_cull { "on" } else { "off" }
    );
    println!(
        "cpu (sync+prepare+encode+submit): median {:.3} ms, p95 {:.3} ms; per displayed frame {:.3} ms ({} per submission)",
        s.cpu_ms_median, s.cpu_ms_p95, s.cpu_ms_per_displayed_frame_median, s.frames_per_submit
    );
    println!(
        "pose age at submit: median {:.3} ms ({})",
        s.pose_age_at_submit_ms_median,
        if s.latch {
            "latched"
        } else {
            "sampled before prepare"
        }
    );
    if s.moving_percent > 0.0 || s.churn_percent > 0.0 {
        println!(
            "edits ({} % moving, {} % churn): making them {:.3} ms, sync {:.3} ms, staging {:.3} ms (medians)",
            s.moving_percent,
            s.churn_percent,
            s.edit_ms_median,
            s.sync_ms_median,
            s.staging_ms_median
        );
    }
    println!(
        "frame (until GPU done):      median {:.2} ms, p95 {:.2} ms",
        s.frame_ms_median, s.frame_ms_p95
    );
    for (name, v) in s.displays.iter().zip(&s.visible_mean) {
        println!("  {name:>18}: {v:.0} visible on average");
    }
    if let (Some(first), Some(last)) = (s.memory.first(), s.memory.last()) {
        let show = |v: Option<u64>| v.map_or("n/a".to_string(), |v| v.to_string());
        println!(
            "memory after frame {} / {}: RSS {} / {} KiB, wgpu objects {} / {}, GPU allocations {} / {} bytes",
            first.frame,
            last.frame,
            show(first.rss_kib),
            show(last.rss_kib),
            show(first.wgpu_objects.map(|v| v as u64)),
            show(last.wgpu_objects.map(|v| v as u64)),
            show(first.gpu_allocated_bytes),
            show(last.gpu_allocated_bytes),
        );
    }
    let show = |v: Option<f64>| v.map_or("n/a".into(), |t| format!("{t:.0}"));
    println!(
        "per frame: {} draw calls, {} dispatches, {} bytes uploaded, {} triangles submitted, {} sphere tests; GPU memory {} bytes per instance",
        s.draw_calls_per_frame,
        s.dispatches_per_frame,
        s.bytes_uploaded_per_frame,
        show(s.triangles_submitted_median),
        show(s.sphere_tests_median),
        s.gpu_bytes_per_instance
    );
    if s.keep_unchanged != crate::keep::KeepUnchanged::Off {
        println!(
            "kept pixels ({:?}{}): median {} tiles and {} pixels redrawn, {} of {} frames drawn whole, {} fragment invocations (median)",
            s.keep_unchanged,
            if s.still { ", head still" } else { "" },
            s.tiles_changed_median,
            s.pixels_redrawn_median,
            s.whole_redraws,
            s.frames,
            show(s.fragment_invocations_median),
        );
    }
    if let Some(bytes) = &s.occlusion_bytes {
        println!(
            "occlusion: {} GPU bytes per display, {} for the shared pyramids",
            bytes.per_display, bytes.pyramids
        );
    }
    for r in s.occlusion.iter().flatten() {
        println!(
            "{}: last frame {} in the frustum, {} drawn early, {} late, {} occluded",
            r.display, r.frustum, r.early, r.late, r.occluded
        );
    }
}
