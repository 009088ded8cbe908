//! What occlusion culling did in a frame, for `render`'s stats.json, `stress --json`
//! and `profile.json`.

use serde::Serialize;

use crate::cull::cpu;
use crate::device::Gpu;
use crate::error::Result;
use crate::occlusion::occluded_in_eye;
use crate::records::CullLayout;
use crate::renderer::{CullView, Renderer};
use crate::rig::Rig;
use crate::scene::Scene;

/// One display's occlusion in the last frame.
#[derive(Clone, Debug, Serialize)]
pub struct OcclusionReport {
    pub display: String,
    /// Instances the display frustum keeps (the CPU reference cull of the frame's plan).
    pub frustum: u32,
    /// Drawn early (drawn last frame) and late (not hidden by the early depth).
    pub early: u32,
    pub late: u32,
    /// Kept by the frustum, drawn in neither phase.
    pub occluded: u32,
    /// For a stereo display: instances the either-eye rule keeps that a test of the
    /// left eye alone, or of the right eye alone, would drop (what naive stereo
    /// occlusion would get wrong).
    pub one_eye_drops: Option<[u32; 2]>,
    /// With the far layer: the far instances its frustum keeps, and of those how many
    /// the display's pyramids hide (not drawn into the far layer).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub far_frustum: Option<u32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub far_occluded: Option<u32>,
}

/// Per display of `rig`, what occlusion did in `renderer`'s last frame (at `time`,
/// of `scene` as it stood); `None` for a display without it.
pub fn occlusion_report(
    gpu: &Gpu,
    renderer: &Renderer,
    (rig, time): (&Rig, f32),
    scene: &Scene,
) -> Result<Vec<Option<OcclusionReport>>> {
    let diagnostics = renderer.diagnostics(&gpu.device, &gpu.queue);
    let counts = diagnostics.occlusion_counts()?;
    if counts.iter().all(Option::is_none) {
        return Ok(counts.iter().map(|_| None).collect());
    }
    let plan = renderer.plan(rig, time)?;
    let layout = CullLayout::new(scene);
    let culled = cpu::cull_frame(&layout, &plan.jobs(), &plan.cull);
    let culls = plan.culls();
    let kept_by = |view: CullView| {
        let at = culls.iter().position(|c| c.view == view);
        at.map(|k| &culled[k])
    };
    let frustum = |i: usize| kept_by(CullView::Display(i));
    let mut reports = Vec::new();
    for (i, count) in counts.iter().enumerate() {
        let (Some(count), Some(kept)) = (count, frustum(i)) else {
            reports.push(None);
            continue;
        };
        let drops = match (diagnostics.visibility(i)?, diagnostics.pyramid(i)?) {
            (Some((shape, _)), Some(pyramid)) => {
                let display = &plan.displays[i].context;
                let hidden = |id: u32, e: u32| {
                    let s = layout.spheres[layout.positions[id as usize] as usize];
                    let eye = &display.eye[e as usize];
                    occluded_in_eye(s, eye, (&pyramid, shape), (e, display.occlusion_margin_px))
                };
                let drops = |e: u32| {
                    let other = 1 - e;
                    let dropped = kept
                        .visible
                        .iter()
                        .filter(|&&id| hidden(id, e) && !hidden(id, other));
                    dropped.count() as u32
                };
                (shape.eyes == 2).then(|| [drops(0), drops(1)])
            }
            _ => None,
        };
        let frustum = kept.visible.len() as u32;
        let far_frustum = kept_by(CullView::Far(i)).map(|f| f.visible.len() as u32);
        let far_drawn = diagnostics.far_cull(i)?.map(|f| f.visible.len() as u32);
        reports.push(Some(OcclusionReport {
            display: rig.displays[i].name.clone(),
            frustum,
            early: count.early,
            late: count.late,
            occluded: frustum.saturating_sub(count.early + count.late),
            one_eye_drops: drops,
            far_frustum,
            far_occluded: far_frustum.zip(far_drawn).map(|(f, d)| f.saturating_sub(d)),
        }));
    }
    Ok(reports)
}
