//! A two-frame submission's second frame posed apart from the first
//! ([`super::RendererOptions::frames_per_submit`] 2): node animations, skins and morph
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

use glam::Vec4;

use crate::live::{Changes, MoveEdit};
use crate::records::GROWN_SLACK;
use crate::scatter::Scatters;
use crate::scene::Scene;
use crate::shaders::Windows;

/// What a renderer of two frames per submission keeps for its second frame.
pub(super) struct SecondFrame {
    /// The second frame's moves (grown) and records, dispatched between the frames.
    pub(super) scatter: Scatters,
    /// Each slot's culling sphere as the culls hold it: the first frame's, about
    /// whose center a second frame's move grows it.
    spheres: Vec<Vec4>,
}

impl SecondFrame {
    /// For `scene` as uploaded, its records bound in `windows`.
    pub(super) fn new(device: &wgpu::Device, windows: Windows, scene: &Scene) -> SecondFrame {
        let mut second = SecondFrame {
            scatter: Scatters::second_frame(device, windows),
            spheres: Vec::new(),
        };
        second.reload(scene);
        second
    }

    /// Takes every slot's sphere from `scene` (uploaded whole again; a vacant slot's
    /// sphere is never read).
    pub(super) fn reload(&mut self, scene: &Scene) {
        self.spheres = (scene.instances.iter())
            .map(|i| scene.world_sphere(i))
            .collect();
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
    /// the first's center; returns each slot's grown sphere (for the CPU culler).
    pub(super) fn grow(&mut self, scene: &Scene, moved: &mut [MoveEdit]) -> Vec<(u32, Vec4)> {
        (moved.iter_mut())
            .map(|edit| {
                let slot = edit.slot as usize;
                let second = scene.world_sphere(&scene.instances[slot]);
                let sphere = grown(self.spheres[slot], second);
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
    Some(match changes {
        c if !c.placed.is_empty() || !c.removed.is_empty() || c.restructured || c.geometry => {
            "inserts and removes change the cull order both frames share: make them before the first frame's sync"
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
