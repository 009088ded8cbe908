//! Unchanged pixels kept: the multiview talk's "only pixels with moving objects change".
//! When the viewer's pose, the rig and the time's effect on the scene leave most of a
//! frame as the last one drew it, a display redraws only the [`crate::cull::tiles::TILE`]-pixel tiles
//! that something changed: a moved, inserted, removed, re-materialed or animated
//! instance marks the tiles its bounds cover before and after, in each eye; the cull
//! keeps only instances that touch a marked tile; the draw pass keeps last frame's
//! color and depth, clears the marked tiles and redraws them. Everything else stays as
//! it was, so the frame is the one a full redraw makes.
//!
//! Whatever can change pixels away from the object, or every pixel, redraws the frame
//! whole, and [`WholeRedraw`] says why.
//!
//! The technique's room, pass by pass:
//! - here, [`Keeper`]: what changed since the last frame, or why it redraws whole;
//! - [`marks`]: the changed tiles marked on the GPU (`wgsl/keep_mark.wgsl`);
//! - [`crate::cull::tiles::TileMask`]: their CPU twin, and the cull's tile test, which
//!   the cull reads (it sits with the cull's other tests, so the cull names nothing here);
//! - [`clear`]: the changed tiles listed and cleared in the draw pass
//!   (`wgsl/keep_list.wgsl`, `wgsl/keep_tiles.wgsl`);
//! - `renderer/keeping.rs`: a frame plan's tiles, and the options that never keep.

pub mod clear;
pub mod marks;

use glam::Vec4;

use crate::rig::Rig;
use crate::scene::Scene;

/// Whether frames keep unchanged pixels (`--keep-unchanged`). A kept frame draws over
/// what the last frame left in its targets: pass the same targets every frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum KeepUnchanged {
    /// Never: every frame is drawn whole.
    #[default]
    Off,
    /// Wherever the frame allows; a renderer whose options or scene never allow it
    /// is refused ([`crate::renderer::Renderer::new`]).
    On,
    /// Wherever the frame allows; otherwise whole, with the reason in the frame's stats.
    Auto,
}

/// Why a frame was drawn whole.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum WholeRedraw {
    /// `--keep-unchanged off`.
    Off,
    /// No earlier frame to keep.
    FirstFrame,
    /// The viewer's pose or the rig changed: every pixel moves.
    Pose,
    /// The head just stopped: instances changed while it moved, untracked (tracking
    /// costs every moving frame), so their bounds are taken again at the next sync.
    Settling,
    /// The scene was laid out again or grew, a light changed (it lights every pixel
    /// it reaches), or morph weights were set by hand.
    Scene,
    /// With shadows, an instance changed: its shadow falls away from it.
    Shadows,
    /// A blended instance is drawn over the pixels it covers, kept or not; redrawn over
    /// kept pixels it would blend twice, and its sort order follows the viewer.
    Blended,
    /// A mode, option or content the tiles do not serve, as said.
    Unsupported(&'static str),
}

/// A slot whose tiles a kept frame redraws: its instance's world sphere as last drawn
/// and now (`None`: no instance; zero where the GPU marks the tiles: see
/// [`Keeper::new`]'s `measures`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Change {
    /// The instance's slot.
    pub slot: u32,
    /// Its sphere as last drawn.
    pub before: Option<Vec4>,
    /// Its sphere now.
    pub after: Option<Vec4>,
}

impl Change {
    /// The spheres that mark its tiles.
    pub fn spheres(&self) -> impl Iterator<Item = Vec4> {
        self.before.into_iter().chain(self.after)
    }
}

/// What a renderer tracks between frames to keep their unchanged pixels.
pub struct Keeper {
    mode: KeepUnchanged,
    /// Why no frame may keep pixels, whatever changes.
    never: Option<&'static str>,
    /// The rig and time the last frame was drawn at.
    last: Option<(Rig, f32)>,
    /// The last frame's pose was replaced after it was planned ([`Keeper::forget`]).
    forgotten: bool,
    /// Each slot's world sphere as last drawn (`None`: vacant). Measured only where the
    /// CPU marks the tiles (`measures`: culling on the CPU); where the GPU marks them
    /// from its own spheres, only whether a slot is occupied counts, and the sphere is
    /// held as zero (measuring it took a third of a change's bookkeeping, caches cold:
    /// docs/performance.md).
    spheres: Vec<Option<Vec4>>,
    measures: bool,
    /// What the time moves.
    by_time: ByTime,
    /// Per slot, whether its pixels change with the time ([`ByTime::moves`]), and those
    /// slots in order; rebuilt from the flags when one changes (rarely: moves
    /// keep an instance's animation).
    animates: Vec<bool>,
    animated: Vec<u32>,
    animated_stale: bool,
    /// The slots that changed since the last frame, each once, with its sphere as last
    /// drawn and now; `pending[slot]`: its index in `changed` plus one (0: unchanged).
    changed: Vec<Change>,
    pending: Vec<u32>,
    /// A change since the last frame that redraws whole.
    forced: Option<WholeRedraw>,
    /// The head moves: changes are not tracked ([`WholeRedraw::Settling`]); `missed`:
    /// some came; `rebuild`: the next sync takes every bound again.
    paused: bool,
    missed: bool,
    rebuild: bool,
    /// Per mesh, whether its instances are blended.
    blended_meshes: Vec<bool>,
    /// Whether an instance drawn since the last reload is blended.
    blended: bool,
    shadows: bool,
}

impl Keeper {
    /// The keeper of a renderer made for `scene`, whose frames `never` keep pixels for
    /// that reason where given; `measures`: whether the CPU marks the tiles (culling on
    /// the CPU), which needs each changed instance's world sphere.
    pub fn new(
        scene: &Scene,
        mode: KeepUnchanged,
        never: Option<&'static str>,
        shadows: bool,
        measures: bool,
    ) -> Keeper {
        let mut keeper = Keeper {
            mode,
            never,
            last: None,
            forgotten: false,
            spheres: Vec::new(),
            measures,
            by_time: ByTime {
                posed: Vec::new(),
                morphed: Vec::new(),
            },
            animates: Vec::new(),
            animated: Vec::new(),
            animated_stale: false,
            changed: Vec::new(),
            pending: Vec::new(),
            forced: None,
            paused: false,
            missed: false,
            rebuild: false,
            blended_meshes: Vec::new(),
            blended: false,
            shadows,
        };
        keeper.reload(scene, |_| true);
        keeper
    }

    /// Takes `scene` whole (made, laid out again, reallocated): the next frame is drawn
    /// whole. `occupied(slot)`: whether the slot holds an instance.
    pub fn reload(&mut self, scene: &Scene, occupied: impl Fn(u32) -> bool) {
        self.reload_for(scene, occupied, WholeRedraw::Scene);
    }

    fn reload_for(&mut self, scene: &Scene, occupied: impl Fn(u32) -> bool, why: WholeRedraw) {
        if !self.tracks() {
            return;
        }
        (self.paused, self.missed, self.rebuild) = (false, false, false);
        let slots = 0..scene.instances.len() as u32;
        self.spheres = (slots.clone())
            .map(|s| occupied(s).then(|| self.sphere(scene, s)))
            .collect();
        self.by_time = ByTime::of(scene);
        let by_time = &self.by_time;
        self.animates = slots
            .map(|s| occupied(s) && by_time.moves(scene, s))
            .collect();
        self.animated_stale = true;
        let bins = crate::bins::Bins::of(scene);
        let first = bins.first_blend_bin();
        self.blended_meshes = bins.of_mesh.iter().map(|&b| b >= first).collect();
        self.blended =
            (0..scene.instances.len() as u32).any(|s| occupied(s) && self.is_blended(scene, s));
        self.forced = Some(why);
    }

    /// The instances in `slots` changed (moved, inserted, removed, re-materialed):
    /// their tiles before and after change. `occupied(slot)`: whether the slot holds
    /// an instance now.
    pub fn changed(
        &mut self,
        scene: &Scene,
        slots: impl IntoIterator<Item = u32>,
        occupied: impl Fn(u32) -> bool,
    ) {
        if !self.tracks() {
            return;
        }
        if self.rebuild {
            return self.reload_for(scene, occupied, WholeRedraw::Settling);
        }
        if self.paused {
            self.missed = true;
            return;
        }
        for slot in slots {
            let s = slot as usize;
            if s >= scene.instances.len() {
                continue;
            }
            if s >= self.spheres.len() {
                self.spheres.resize(s + 1, None);
                self.animates.resize(s + 1, false);
            }
            let now = occupied(slot).then(|| self.sphere(scene, slot));
            self.change(slot, self.spheres[s], now);
            self.spheres[s] = now;
            self.blended |= now.is_some() && self.is_blended(scene, slot);
            let animated = now.is_some() && self.by_time.moves(scene, slot);
            if self.animates[s] != animated {
                self.animates[s] = animated;
                self.animated_stale = true;
            }
            if self.shadows {
                self.forced.get_or_insert(WholeRedraw::Shadows);
            }
        }
    }

    /// Slot `slot` goes from `before` to `after` this frame (after any earlier change
    /// this frame: its first `before` stays).
    fn change(&mut self, slot: u32, before: Option<Vec4>, after: Option<Vec4>) {
        let s = slot as usize;
        if s >= self.pending.len() {
            self.pending.resize(s + 1, 0);
        }
        match self.pending[s] {
            0 => {
                self.changed.push(Change {
                    slot,
                    before,
                    after,
                });
                self.pending[s] = self.changed.len() as u32;
            }
            at => self.changed[at as usize - 1].after = after,
        }
    }

    /// The world sphere of the instance in `slot`, where the CPU marks the tiles.
    fn sphere(&self, scene: &Scene, slot: u32) -> Vec4 {
        match self.measures {
            true => scene.world_sphere(&scene.instances[slot as usize]),
            false => Vec4::ZERO,
        }
    }

    fn set_pending(&mut self, changes: &[Change], value: u32) {
        for c in changes {
            self.pending[c.slot as usize] = value;
        }
    }

    /// The lights changed (they light pixels far from any changed instance), or morph
    /// weights were set by hand (every instance of the mesh moves): the next frame is
    /// drawn whole.
    pub fn redraw_whole(&mut self) {
        self.forced.get_or_insert(WholeRedraw::Scene);
    }

    /// The frame at `rig`'s pose and `time`: either the slots whose tiles it redraws,
    /// or why it redraws whole. Either way it becomes the last frame.
    pub fn frame(&mut self, rig: &Rig, time: f32) -> Result<Vec<Change>, WholeRedraw> {
        let changed = std::mem::take(&mut self.changed);
        self.set_pending(&changed, 0);
        let forced = self.forced.take();
        let forgotten = std::mem::take(&mut self.forgotten);
        let last = (self.last.replace((rig.clone(), time))).filter(|_| !forgotten);
        if self.mode == KeepUnchanged::Off {
            return Err(WholeRedraw::Off);
        }
        if let Some(why) = self.never {
            return Err(WholeRedraw::Unsupported(why));
        }
        let Some((last_rig, last_time)) = last else {
            return Err(WholeRedraw::FirstFrame);
        };
        if last_rig != *rig {
            self.paused = true;
            return Err(WholeRedraw::Pose);
        }
        if self.paused {
            match self.missed || self.rebuild {
                true => {
                    self.rebuild = true;
                    return Err(WholeRedraw::Settling);
                }
                false => self.paused = false,
            }
        }
        if let Some(why) = forced {
            return Err(why);
        }
        if self.blended {
            return Err(WholeRedraw::Blended);
        }
        let mut changes = changed;
        if time != last_time {
            if self.animated_stale {
                let flags = self.animates.iter().enumerate();
                self.animated = flags.filter(|(_, a)| **a).map(|(s, _)| s as u32).collect();
                self.animated_stale = false;
            }
            if self.shadows && !self.animated.is_empty() {
                return Err(WholeRedraw::Shadows);
            }
            // A changed slot's before and after already hold its animation's reach.
            self.set_pending(&changes, 1);
            let (pending, spheres) = (&self.pending, &self.spheres);
            let unchanged = (self.animated.iter())
                .filter(|&&s| pending.get(s as usize).is_none_or(|&p| p == 0));
            let animated = unchanged.filter_map(|&slot| {
                let x = spheres[slot as usize]?;
                Some(Change {
                    slot,
                    before: Some(x),
                    after: Some(x),
                })
            });
            let animated: Vec<Change> = animated.collect();
            self.set_pending(&changes, 0);
            changes.extend(animated);
        }
        Ok(changes)
    }

    /// Whether changes are tracked: frames may keep pixels.
    fn tracks(&self) -> bool {
        self.mode != KeepUnchanged::Off && self.never.is_none()
    }

    fn is_blended(&self, scene: &Scene, slot: u32) -> bool {
        let mesh = scene.instances[slot as usize].mesh as usize;
        self.blended_meshes.get(mesh).copied().unwrap_or(false)
    }

    /// Forgets the last frame: the next one is drawn whole (its pose was replaced after
    /// it was planned, or it was not drawn).
    pub fn forget(&mut self) {
        // A flag, not a drop: a latch forgets on the submit's path, and freeing the
        // rig's copy there cost a tenth of the latch; the next frame frees it.
        self.forgotten = true;
    }
}

/// What the time alone moves in a scene: per slot, whether the scene's own animations
/// pose it (its node's clips or its skin; the slots as loaded), and per mesh whether
/// its morph's weights play.
struct ByTime {
    posed: Vec<bool>,
    morphed: Vec<bool>,
}

impl ByTime {
    fn of(scene: &Scene) -> ByTime {
        let mut posed = vec![false; scene.instances.len()];
        let skins = scene.skins.skins.iter().map(|s| s.instance);
        for slot in scene
            .posing
            .instances
            .iter()
            .map(|n| n.instance)
            .chain(skins)
        {
            if let Some(p) = posed.get_mut(slot as usize) {
                *p = true;
            }
        }
        let mut morphed = vec![false; scene.meshes.len()];
        let played = scene
            .morphs
            .morphs
            .iter()
            .filter(|m| !m.channels.is_empty());
        for m in played {
            morphed[m.mesh as usize] = true;
        }
        ByTime { posed, morphed }
    }

    /// Whether the instance in `slot` changes with the time: it spins or bobs, is
    /// posed, or draws a playing morph.
    fn moves(&self, scene: &Scene, slot: u32) -> bool {
        let instance = &scene.instances[slot as usize];
        let a = instance.animation;
        a.spin != 0.0
            || a.bob != 0.0
            || self.posed.get(slot as usize).copied().unwrap_or(false)
            || self
                .morphed
                .get(instance.mesh as usize)
                .copied()
                .unwrap_or(false)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A forgotten frame (its pose latched after it was planned) is no last frame to
    /// keep from: the next frame at the same pose, which would keep, is drawn whole.
    #[test]
    fn a_forgotten_frame_is_not_kept_from() {
        let scene = crate::procedural::scene(40, 3, 7);
        let rig = Rig::preset("hmd").expect("the hmd preset");
        let mut keeper = Keeper::new(&scene, KeepUnchanged::On, None, false, true);
        assert_eq!(keeper.frame(&rig, 0.0).err(), Some(WholeRedraw::FirstFrame));
        assert!(keeper.frame(&rig, 0.0).is_ok(), "an unchanged frame keeps");
        keeper.forget();
        assert_eq!(keeper.frame(&rig, 0.0).err(), Some(WholeRedraw::FirstFrame));
        assert!(
            keeper.frame(&rig, 0.0).is_ok(),
            "the frame after it keeps again"
        );
    }
}
