//! Two frames per submission: the multiview talk's "dt multiview", a view at another
//! time as well as another eye. Each display draws its eyes at the frame's time `t`
//! and at `t + dt` as one set of views (left and right now, then left and right next)
//! side by side in one target: one cull keeps what any of them may see, and one
//! multi-draw draws every visible object once per view, `instance_index % views` the
//! view. Each view's context says how far ahead its frame lies
//! ([`crate::contexts::EyeContext::time_ahead`]), so the draw animates each view's
//! instances at its own frame's time.
//!
//! What cannot join, and why, is `checks.rs`'s to say (`check_frames`).
//!
//! ## The second frame posed apart
//!
//! A submission's second frame is posed apart from the first: node animations, skins and morph
//! targets posed at `t + dt`, and edits the caller makes for the second frame alone.
//!
//! The caller syncs the first frame's pose and edits as usual
//! ([`super::Renderer::sync`]), then poses and edits the live scene for the second
//! frame and hands those changes to [`super::Renderer::sync_next`]. The frame's encode then runs, in order:
//! 1. the first frame's scatter, morph and skinning passes;
//! 2. a copy of the records and of the vertices those passes wrote
//!    ([`crate::draw::DrawScene::keep_previous`]), which the first frame's views read
//!    (`wgsl/draw_first_pose.wgsl`);
//! 3. the second frame's scatter (its moves and records), its morph weights and joint
//!    matrices copied into place, and its morph and skinning passes, which the second
//!    frame's views read.
//!
//! One cull serves both frames, so a sphere the second frame moves grows to hold the
//! first frame's sphere as well: it keeps its first-frame center and takes the
//! smallest radius about it that holds the second ([`grown`]). The CPU computes that
//! radius, as it computes every radius (`src/scatter.rs` says why), and writes it into
//! its own culler too: the GPU and CPU culls stay byte-identical. The next submission's
//! first frame writes the exact spheres of what it moves again; an instance only the
//! second frame moved keeps its grown sphere until it moves again (conservative).

use crate::contexts::DisplayContext;
use crate::error::{Error, Result};
use crate::live::{Changes, LiveScene, MoveEdit, PlaceEdit};
use crate::places::Places;
use crate::records::{GROWN_SLACK, InstanceRecord, RecordEdit};
use crate::rig::{Display, ResolvedRig, ViewLayout, VisibilityMask};
use crate::scatter::{ScatterTargets, Scatters, record_edit};
use crate::scene::{Instance, Scene};
use crate::shaders::Windows;
use bytemuck::Zeroable;
use glam::Vec4;
use std::collections::HashSet;
/// Where display `d`'s views lie in its target for `frames` frames per submission:
/// one frame's layout ([`Display::layout_in`]), or the second frame's views after the
/// first's, at the same sizes.
pub fn layout(d: &Display, layered: bool, frames: u32) -> ViewLayout {
    let one = d.layout_in(layered);
    if frames == 1 {
        return one;
    }
    let sizes: Vec<(u32, u32)> = (one.viewports().iter())
        .map(|&[_, _, w, h]| (w, h))
        .collect();
    ViewLayout::side_by_side(&sizes.repeat(frames as usize))
}

/// A display of `views` views' visibility mask as its views are masked: its outer
/// views' triangles (a foveated display's insets lie inside them), once per frame of
/// a submission (each frame's eyes are masked alike).
pub fn masked(mask: &VisibilityMask, views: u32, frames: u32) -> VisibilityMask {
    let outer = mask.views.len().min(views.min(2) as usize);
    VisibilityMask {
        views: (0..frames)
            .flat_map(|_| mask.views[..outer].iter().cloned())
            .collect(),
    }
}

/// The two frames' views as one resolved rig ([`ResolvedRig::followed_by`]).
pub(super) fn pair(now: &ResolvedRig, next: &ResolvedRig) -> Result<ResolvedRig> {
    now.followed_by(next).ok_or_else(|| {
        Error::rig(
            "frames",
            "no one display frustum holds a display's eyes at both frames' poses (they turn 180 degrees or more apart)",
        )
    })
}

/// Marks the second frame's views of display `d` (those past its own views) as
/// `ahead` seconds after the frame context's time; with one frame per submission,
/// every view's context keeps 0.
pub(super) fn time_views(context: &mut DisplayContext, d: &Display, ahead: f32) {
    let own = d.views() as usize;
    if context.views as usize > own {
        for eye in &mut context.eye[own..] {
            eye.time_ahead = ahead;
        }
    }
}

/// What a renderer of two frames per submission keeps for its second frame.
pub(super) struct SecondFrame {
    /// The second frame's places filled, moves (grown) and records, dispatched between
    /// the frames.
    pub(super) scatter: Scatters,
    /// Vacant records for the slots the second frame fills, written into the first
    /// frame's copy of the records after the copy: the first frame's views skip them.
    pub(super) first: Scatters,
    /// Each slot's culling sphere as the culls hold it: the first frame's, about
    /// whose center a second frame's move grows it.
    spheres: Vec<Vec4>,
    /// What the second frame removed, which the first still draws: the next sync's.
    deferred: Deferred,
}

/// Places the second frame vacated and the slots it removed: the one cull order keeps
/// them for the first frame (the second's views skip their vacant records), and the
/// next [`super::Renderer::sync`] applies them.
#[derive(Default)]
pub(super) struct Deferred {
    pub(super) placed: Vec<PlaceEdit>,
    pub(super) removed: Vec<u32>,
}

impl Deferred {
    /// Puts these before `changes` (the next sync's); a place `changes` fills again
    /// keeps only the fill (one edit per place and dispatch).
    pub(super) fn apply_to(self, changes: &mut Changes) {
        let filled: HashSet<u32> = changes.placed.iter().map(|e| e.place).collect();
        let mut placed: Vec<_> = (self.placed.into_iter())
            .filter(|e| !filled.contains(&e.place))
            .collect();
        placed.append(&mut changes.placed);
        changes.placed = placed;
        changes.removed.extend(self.removed);
    }
}

/// The second frame's changes the GPU takes, as [`SecondFrame::stage`] stages them.
pub(super) struct Staged {
    pub(super) filled: Vec<PlaceEdit>,
    pub(super) moved: Vec<MoveEdit>,
    pub(super) recolored: Vec<u32>,
    pub(super) removed: Vec<u32>,
}

impl SecondFrame {
    /// For `scene` as uploaded, its records bound in `windows`.
    pub(super) fn new(device: &wgpu::Device, windows: Windows, scene: &Scene) -> SecondFrame {
        let mut second = SecondFrame {
            scatter: Scatters::second_frame(device, windows),
            first: Scatters::new(device, windows),
            spheres: Vec::new(),
            deferred: Deferred::default(),
        };
        second.reload(scene);
        second
    }

    /// Takes every slot's sphere from `scene` (uploaded whole again, so nothing is
    /// deferred; a vacant slot's sphere is never read).
    pub(super) fn reload(&mut self, scene: &Scene) {
        let sphere = |i: &Instance| match i.mesh {
            Instance::VACANT_MESH => Vec4::ZERO,
            _ => scene.world_sphere(i),
        };
        self.spheres = scene.instances.iter().map(sphere).collect();
        self.deferred = Deferred::default();
    }

    /// What the last submission's second frame removed, for this sync to apply.
    pub(super) fn take_deferred(&mut self) -> Deferred {
        std::mem::take(&mut self.deferred)
    }

    /// Splits the second frame's place edits: the vacated places and the removed
    /// slots wait for the next sync; returns the filled places and their slots.
    pub(super) fn split(
        &mut self,
        placed: Vec<PlaceEdit>,
        removed: &[u32],
    ) -> (Vec<PlaceEdit>, HashSet<u32>) {
        let (vacated, filled): (Vec<_>, Vec<_>) =
            placed.into_iter().partition(|e| e.slot == Places::VACANT);
        self.deferred.placed.extend(vacated);
        self.deferred.removed.extend(removed);
        let born = filled.iter().map(|e| e.slot).collect();
        (filled, born)
    }

    /// Stages the second frame's changes: places filled, moves, records (a removed
    /// instance's is vacant: the second frame's views skip it), and vacant records for
    /// the filled slots in the first frame's copy (`copy`). Returns the bytes and a
    /// cleared list of moves.
    pub(super) fn stage(
        &mut self,
        device: &wgpu::Device,
        live: &LiveScene,
        staged: Staged,
        targets: ScatterTargets,
        copy: ScatterTargets,
    ) -> (u64, Vec<MoveEdit>) {
        let Staged {
            filled,
            moved,
            recolored,
            removed,
        } = staged;
        let vacant = InstanceRecord {
            mesh: Instance::VACANT_MESH,
            ..InstanceRecord::zeroed()
        };
        let unborn: Vec<_> = (filled.iter())
            .map(|e| RecordEdit::new(e.slot, vacant))
            .collect();
        let records: Vec<_> = (recolored.iter().chain(&removed))
            .map(|&slot| record_edit(live, slot))
            .collect();
        let mut bytes = 0;
        let mut spare = Vec::new();
        if !filled.is_empty() {
            bytes += self.scatter.stage_places(device, filled, targets).0;
            bytes += self.first.records.stage(device, unborn, copy).0;
        }
        if !moved.is_empty() {
            let staged;
            (staged, spare) = self.scatter.moves.stage(device, moved, targets);
            bytes += staged;
        }
        if !records.is_empty() {
            bytes += self.scatter.records.stage(device, records, targets).0;
        }
        (bytes, spare)
    }

    /// The first frame's moved (and inserted) instances: their exact spheres.
    pub(super) fn moved(&mut self, scene: &Scene, moved: &[MoveEdit]) {
        for edit in moved {
            let slot = edit.slot as usize;
            if slot >= self.spheres.len() {
                self.spheres.resize(slot + 1, Vec4::ZERO);
            }
            self.spheres[slot] = scene.world_sphere(&scene.instances[slot]);
        }
    }

    /// The second frame's moves, each radius grown to hold both frames' spheres about
    /// the first's center (exact for the slots it filled, `born`: the first frame
    /// does not draw them); returns each slot's sphere (for the CPU culler).
    pub(super) fn grow(
        &mut self,
        scene: &Scene,
        moved: &mut [MoveEdit],
        born: &HashSet<u32>,
    ) -> Vec<(u32, Vec4)> {
        (moved.iter_mut())
            .map(|edit| {
                let slot = edit.slot as usize;
                if slot >= self.spheres.len() {
                    self.spheres.resize(slot + 1, Vec4::ZERO);
                }
                let second = scene.world_sphere(&scene.instances[slot]);
                let sphere = match born.contains(&edit.slot) {
                    true => second,
                    false => grown(self.spheres[slot], second),
                };
                edit.radius = sphere.w;
                self.spheres[slot] = sphere;
                (edit.slot, sphere)
            })
            .collect()
    }
}

/// The sphere about `first`'s center that holds `first` and `second`.
pub fn grown(first: Vec4, second: Vec4) -> Vec4 {
    let reach = first.truncate().distance(second.truncate()) + second.w;
    first
        .truncate()
        .extend(first.w.max(reach * (1.0 + GROWN_SLACK)))
}

/// Why changes cannot be the second frame's alone: what the two frames share.
pub(super) fn unjoined(changes: &Changes) -> Option<&'static str> {
    let vacated = (changes.placed.iter()).filter(|e| e.slot == Places::VACANT);
    Some(match changes {
        c if c.restructured || c.geometry => {
            "new meshes, or inserts past a mesh's room, lay the cull order both frames share out again: make them before the first frame's sync"
        }
        // Each remove vacates its place; a place filled again holds no vacancy.
        c if vacated.count() != c.removed.len() => {
            "an insert filled a place a remove emptied, which the first frame still draws: make one of them before the first frame's sync"
        }
        c if c.lights => {
            "one set of lights lights both frames: change (or pose) the lights before the first frame's sync"
        }
        c if !c.driven.is_empty() => {
            "a skin the engine begins to pose itself changes what the pose pass poses for both frames: set its joints before the first frame's sync"
        }
        _ => return None,
    })
}
