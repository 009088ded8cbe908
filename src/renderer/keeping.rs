//! Keeping unchanged pixels ([`crate::keep`]) in a renderer: which renderers never can,
//! and a kept frame's changed tiles, one mask per display, set into its plan.

use std::sync::Arc;

use glam::UVec2;

use super::options::{OcclusionMode, PosingMode, RendererOptions, StereoMode};
use super::plan::{CullView, FramePlan, KeptTiles};
use crate::contexts::DisplayContext;
use crate::cull::tiles::{self, CULL_TILES, TileEye, TileMask};
use crate::frustum::sphere_in_planes;
use crate::keep::Change;
use crate::keep::marks::{MARK_AFTER, MARK_BEFORE};
use crate::scene::Scene;

/// Why no frame of a renderer made with `options` for `scene`, whose displays have
/// `views` views each, may keep pixels; `None` where frames may.
pub fn never(
    scene: &Scene,
    mut views: impl Iterator<Item = u32>,
    options: &RendererOptions,
) -> Option<&'static str> {
    Some(match options {
        o if o.mode != StereoMode::Instanced => {
            "the tiles serve the instanced mode's one draw pass per display"
        }
        o if o.frames_per_submit != 1 => "two frames per submission draw two times' pixels",
        o if o.far_layer => "the far layer is composited over every pixel",
        o if o.motion_vectors => "kept pixels would keep last frame's motion",
        o if o.occlusion == OcclusionMode::On => {
            "occlusion's phases need every instance tested each frame"
        }
        _ if views.any(|v| v > 2) => {
            "a foveated display's insets are composited over its outer views"
        }
        o if o.posing == PosingMode::Gpu && !scene.posing.lights.is_empty() => {
            "lights posed on the GPU light every pixel they reach: pose on the CPU"
        }
        _ => return None,
    })
}

/// Display `context`'s view size and eyes, side by side in its target.
fn eyes(context: &DisplayContext) -> (UVec2, Vec<TileEye>) {
    let size = context.resolution.as_uvec2();
    let eyes = (0..context.views.min(2))
        .map(|e| TileEye {
            view_from_world: context.eye[e as usize].view_from_world,
            clip_from_view: context.eye[e as usize].clip_from_view,
            x: e * size.x,
        })
        .collect();
    (size, eyes)
}

/// Tiles per display in `plan`.
pub fn tiles(plan: &FramePlan) -> Vec<u32> {
    (plan.displays.iter().map(|d| &d.context))
        .map(|c| {
            let g = tiles::grid(c.resolution.as_uvec2(), c.views.min(2));
            g.x * g.y
        })
        .collect()
}

/// Keeps `plan`'s frame: each display's tiles that `changes` (the changed instances'
/// bounds, before and after) cover, marked here (`on_gpu` false: returns the tiles
/// changed) or listed for the GPU's marking pass (returns 0: the count is the GPU's,
/// read back by the diagnostics). Either way set into each display's plan, cull and
/// context.
pub fn keep(plan: &mut FramePlan, changes: &[Change], on_gpu: bool) -> u32 {
    if on_gpu {
        plan.marks = changes.iter().map(mark_entry).collect();
    }
    let mut changed = 0;
    for display in &mut plan.displays {
        display.context.hidden |= CULL_TILES;
        if on_gpu {
            display.tiles = Some(KeptTiles::Gpu);
            continue;
        }
        let context = &display.context;
        let (size, eyes) = eyes(context);
        let mut mask = TileMask::new(eyes, size);
        // What the display frustum does not hold no eye of the display sees.
        let spheres = changes.iter().flat_map(Change::spheres);
        for s in spheres.filter(|&s| sphere_in_planes(&context.planes, s)) {
            mask.mark(s);
        }
        changed += mask.count();
        let mask = Arc::new(mask);
        for cull in (display.culls.iter_mut()).filter(|c| matches!(c.view, CullView::Display(_))) {
            cull.job.tiles = Some(mask.clone());
        }
        display.tiles = Some(KeptTiles::Cpu(mask));
    }
    changed
}

/// `change`'s entry in the marking pass's list: its slot, and the phases that mark it.
fn mark_entry(change: &Change) -> u32 {
    let before = if change.before.is_some() {
        MARK_BEFORE
    } else {
        0
    };
    let after = if change.after.is_some() {
        MARK_AFTER
    } else {
        0
    };
    change.slot | before | after
}
