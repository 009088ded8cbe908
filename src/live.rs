//! A scene that changes between frames: instances inserted, moved, recolored, given
//! materials of their own and removed
//! through stable [`Handle`]s, and meshes added, with the changes since the last
//! [`crate::renderer::Renderer::sync`] kept so that only they cross the bus.
//!
//! An instance lives in a slot, and its slot is its instance id everywhere (the cull
//! contract's visible ids, `Surface.instance`). A removed instance's slot is vacant until
//! an insert reuses it, lowest vacant slot first; the slot's generation then moves on,
//! so handles to the removed instance stay invalid. In the cull order an instance has a
//! place among its mesh's ([`Places`]): an insert takes its mesh's lowest vacant place
//! and a remove leaves one, each a two-word edit; only a mesh out of vacant places lays
//! the whole order out again, with room.
//!
//! ```no_run
//! # fn demo(device: &wgpu::Device, queue: &wgpu::Queue) -> stereocull::Result<()> {
//! use glam::{Affine3A, Vec3, Vec4};
//! use stereocull::live::LiveScene;
//! use stereocull::renderer::{Renderer, RendererOptions};
//! use stereocull::{rig::Rig, scene_spec};
//!
//! let scene = scene_spec::load("procedural:10000")?;
//! let rig = Rig::preset("hmd")?;
//! let mut renderer = Renderer::new(device, &scene, &rig, RendererOptions::default())?;
//! let mut live = LiveScene::new(scene); // its instances keep their ids as slots
//! let handles = live.handles();
//! let spawned = live.insert(*live.get(handles[0])?)?;
//! for frame in 0..90 {
//!     let t = frame as f32 / 90.0;
//!     live.set_transform(handles[7], Affine3A::from_translation(Vec3::new(t, 1.5, -2.0)))?;
//!     live.set_color(spawned, Vec4::new(t, 0.2, 0.2, 1.0))?;
//!     let synced = renderer.sync(device, queue, &mut live)?; // 56 bytes per move
//!     renderer.prepare(queue, &rig, t)?;
//!     // ... encode and submit as in the renderer's example
//! #   let _ = synced;
//! }
//! live.remove(spawned)?; // `spawned` is now an Error::BadHandle
//! # Ok(()) }
//! ```

use glam::{Affine3A, Mat4, Vec4};

use crate::bins::check_override;
use crate::error::{Error, Result};
use crate::places::Places;
use crate::records::{InstanceRecord, instance_record};
use crate::scene::{Instance, Scene, Vertex};

/// A stable reference to one inserted instance.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub struct Handle {
    slot: u32,
    generation: u32,
}

impl Handle {
    /// The instance id: its slot.
    pub fn slot(self) -> u32 {
        self.slot
    }
}

pub use crate::records::{MoveEdit, PlaceEdit};

/// A [`Scene`] whose instances sit in slots. Vacant slots hold an instance of mesh
/// [`LiveScene::VACANT`], which culling skips.
#[derive(Clone, Debug)]
pub struct LiveScene {
    scene: Scene,
    generations: Vec<u32>,
    /// Vacant slots, lowest first.
    vacant: std::collections::BTreeSet<u32>,
    /// Per slot: the change set (`epoch`) it was last moved in, and its edit's index in
    /// `changes.moved` then; epochs make forgetting a change set free.
    moved_at: Vec<(u32, u32)>,
    /// Per slot: the change set it was last listed in `changes.recolored` in.
    recolored: Vec<u32>,
    /// Per place: the change set it was last changed in, and its edit's index in
    /// `changes.placed` then.
    placed_at: Vec<(u32, u32)>,
    /// The current change set; starts at 1, so that 0 means never.
    epoch: u32,
    changes: Changes,
    places: Places,
    /// Skinned slots whose joints the engine supplies.
    driven: std::collections::BTreeSet<u32>,
    /// Per light of `scene.lights` (its slot): its generation, and whether it is lit.
    light_slots: Vec<(u32, bool)>,
}

impl LiveScene {
    /// The mesh id of a vacant slot.
    pub const VACANT: u32 = Instance::VACANT_MESH;

    /// What a vacant slot holds.
    pub const VACANT_INSTANCE: Instance = Instance {
        world_from_local: Affine3A::IDENTITY,
        mesh: LiveScene::VACANT,
        color: Vec4::ZERO,
        material: None,
        animation: crate::scene::Animation::NONE,
    };

    /// Takes `scene` with its instances in slots `0..n` (their ids so far); the handles
    /// of those instances are [`LiveScene::handles`].
    pub fn new(scene: Scene) -> LiveScene {
        let n = scene.instances.len();
        let places = Places::tight(&scene);
        LiveScene {
            generations: vec![0; n],
            vacant: Default::default(),
            moved_at: vec![(0, 0); n],
            recolored: vec![0; n],
            placed_at: vec![(0, 0); places.len() as usize],
            epoch: 1,
            changes: Changes::default(),
            places,
            light_slots: vec![(0, true); scene.lights.len()],
            scene,
            driven: Default::default(),
        }
    }

    /// Where each instance sits in the cull order (what the renderer lays out).
    pub fn places(&self) -> &Places {
        &self.places
    }

    /// The scene as the renderer uploads it: every slot, vacant ones included.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// Handles of the instances in their slots, in slot order.
    pub fn handles(&self) -> Vec<Handle> {
        (0..self.slot_count())
            .filter(|&s| self.occupied(s))
            .map(|slot| Handle {
                slot,
                generation: self.generations[slot as usize],
            })
            .collect()
    }

    /// Whether the scene's animations still pose the instance in `slot`: it is the one
    /// placed there by [`LiveScene::new`] (not removed) and, if skinned, the engine has
    /// not supplied its joints.
    pub fn animates(&self, slot: u32) -> bool {
        let original = Handle {
            slot,
            generation: 0,
        };
        self.check(original).is_ok() && !self.driven.contains(&slot)
    }

    /// The record the GPU holds for `slot`: its instance's, with the slot's generation
    /// (an insert into a reused slot is a newcomer to the motion vectors' draw).
    pub fn instance_record(&self, slot: u32) -> InstanceRecord {
        InstanceRecord {
            generation: self.generations[slot as usize],
            ..instance_record(&self.scene.instances[slot as usize])
        }
    }

    /// Every slot's record, in slot order ([`LiveScene::instance_record`]).
    pub fn instance_records(&self) -> Vec<InstanceRecord> {
        (0..self.slot_count())
            .map(|s| self.instance_record(s))
            .collect()
    }

    /// Slots issued so far, occupied or vacant.
    pub fn slot_count(&self) -> u32 {
        self.scene.instances.len() as u32
    }

    /// Whether `slot` holds an instance.
    pub fn occupied(&self, slot: u32) -> bool {
        self.scene
            .instances
            .get(slot as usize)
            .is_some_and(|i| i.mesh != LiveScene::VACANT)
    }

    /// Instances present (slots minus vacant ones).
    pub fn len(&self) -> usize {
        self.scene.instances.len() - self.vacant.len()
    }

    /// Whether the scene holds no instance.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The instance behind `handle`.
    pub fn get(&self, handle: Handle) -> Result<&Instance> {
        self.check(handle)?;
        Ok(&self.scene.instances[handle.slot as usize])
    }

    /// Inserts `instance` into the lowest vacant slot (or a new one) and returns its
    /// handle. Its mesh must exist and its transform and animation be finite.
    pub fn insert(&mut self, instance: Instance) -> Result<Handle> {
        if instance.mesh as usize >= self.scene.meshes.len() {
            return Err(Error::InvalidScene(format!(
                "insert: mesh {} of {}",
                instance.mesh,
                self.scene.meshes.len()
            )));
        }
        check_finite(&instance.world_from_local)?;
        if !(instance.animation.spin.is_finite() && instance.animation.bob.is_finite()) {
            return Err(Error::NonFinite("the animation".into()));
        }
        check_override(&self.scene, &instance)?;
        let slot = match self.vacant.pop_first() {
            Some(slot) => {
                self.scene.instances[slot as usize] = instance;
                slot
            }
            None => {
                self.scene.instances.push(instance);
                self.generations.push(0);
                self.moved_at.push((0, 0));
                self.recolored.push(0);
                self.slot_count() - 1
            }
        };
        match self.places.take(slot, instance.mesh) {
            Some(place) => {
                self.stage_place(PlaceEdit { place, slot });
                self.stage_move(slot);
                self.stage_record(slot);
            }
            None => self.lay_out(),
        }
        Ok(Handle {
            slot,
            generation: self.generations[slot as usize],
        })
    }

    /// Moves an instance: only its transform and sphere are uploaded at the next sync.
    /// The edit is made here, while the instance is in cache, not at the sync.
    pub fn set_transform(&mut self, handle: Handle, world_from_local: Affine3A) -> Result<()> {
        self.check(handle)?;
        check_finite(&world_from_local)?;
        self.scene.instances[handle.slot as usize].world_from_local = world_from_local;
        self.stage_move(handle.slot);
        Ok(())
    }

    /// Poses the scene's node animations at `time` seconds ([`crate::pose`], once per
    /// frame): every instance they move that is still in the scene (in its slot since
    /// [`LiveScene::new`]) moves as by [`LiveScene::set_transform`], so only the posed
    /// instances' edits cross the bus. Returns how many moved.
    pub fn pose(&mut self, time: f32) -> Result<u32> {
        let posed = self.scene.posed(time);
        self.changes.lights |= !self.scene.posing.lights.is_empty();
        let all = self.scene.skins.joint_matrices.len() as u32;
        if all > 0 {
            self.changes.joints.clear();
            self.changes.joints.push(0..all);
        }
        let mut moved = 0;
        for (slot, world) in posed {
            let handle = Handle {
                slot,
                generation: 0,
            };
            if self.check(handle).is_ok() {
                self.set_transform(handle, world)?;
                moved += 1;
            }
        }
        Ok(moved)
    }

    /// Poses the skinned instance behind `handle` with joint transforms the engine
    /// supplies (`joint_worlds`: each joint's world transform, in the skin's joint
    /// order): its culling sphere follows them, and only its joint matrices and its
    /// transform go up at the next sync. An error for an instance without a skin, the
    /// wrong joint count, or transforms that are not finite.
    pub fn set_joints(&mut self, handle: Handle, joint_worlds: &[Affine3A]) -> Result<()> {
        self.check(handle)?;
        let skins = &self.scene.skins;
        let Some(s) = skins.of_instance(handle.slot) else {
            return Err(Error::InvalidScene(format!(
                "set_joints: instance {} has no skin",
                handle.slot
            )));
        };
        let skin = &skins.skins[s];
        if joint_worlds.len() != skin.joints.len() {
            return Err(Error::InvalidScene(format!(
                "set_joints: {} joint transforms for a skin of {}",
                joint_worlds.len(),
                skin.joints.len()
            )));
        }
        joint_worlds.iter().try_for_each(check_finite)?;
        let pose = skin.pose_joints(joint_worlds);
        let range = self.scene.skins.set_pose(s, &pose);
        self.changes.joints.push(range);
        if self.driven.insert(handle.slot) {
            self.changes.driven.push(handle.slot);
        }
        self.set_transform(handle, pose.world_from_local)
    }

    /// Lists `slot`'s edit (transform and sphere) in this change set, once.
    fn stage_move(&mut self, slot: u32) {
        let edit = make_edit(&self.scene, slot);
        match self.moved_at[slot as usize] {
            (epoch, at) if epoch == self.epoch => self.changes.moved[at as usize] = edit,
            _ => {
                self.moved_at[slot as usize] = (self.epoch, self.changes.moved.len() as u32);
                self.changes.moved.push(edit);
            }
        }
    }

    /// Lists a place's new state in this change set, once (its last).
    fn stage_place(&mut self, edit: PlaceEdit) {
        let place = edit.place as usize;
        match self.placed_at[place] {
            (epoch, at) if epoch == self.epoch => self.changes.placed[at as usize] = edit,
            _ => {
                self.placed_at[place] = (self.epoch, self.changes.placed.len() as u32);
                self.changes.placed.push(edit);
            }
        }
    }

    /// Lays the cull order out again, every mesh with room; the next sync uploads it.
    fn lay_out(&mut self) {
        self.places = Places::with_room(&self.scene);
        self.placed_at = vec![(0, 0); self.places.len() as usize];
        self.changes.placed.clear();
        self.changes.restructured = true;
    }

    /// Lists `slot`'s record (color, animation) for a rewrite in this change set, once.
    fn stage_record(&mut self, slot: u32) {
        if std::mem::replace(&mut self.recolored[slot as usize], self.epoch) != self.epoch {
            self.changes.recolored.push(slot);
        }
    }

    /// Recolors the instance behind `handle` (linear RGBA): a record edit at the next sync.
    pub fn set_color(&mut self, handle: Handle, color: Vec4) -> Result<()> {
        self.check(handle)?;
        if !color.is_finite() {
            return Err(Error::NonFinite("the color".into()));
        }
        self.scene.instances[handle.slot as usize].color = color;
        self.stage_record(handle.slot);
        Ok(())
    }

    /// Gives the instance behind `handle` a material of its own in place of its mesh's
    /// (`None`: its mesh's again), a record edit at the next sync. The material must
    /// draw with the mesh's pipeline (the same bin, [`check_override`]): an override
    /// changes the data a fragment reads (textures, cutoff, factors), not the draw.
    pub fn set_material(&mut self, handle: Handle, material: Option<u32>) -> Result<()> {
        self.check(handle)?;
        let slot = handle.slot as usize;
        let instance = Instance {
            material,
            ..self.scene.instances[slot]
        };
        check_override(&self.scene, &instance)?;
        self.scene.instances[slot] = instance;
        self.stage_record(handle.slot);
        Ok(())
    }

    /// Removes an instance and returns it; its slot becomes vacant.
    pub fn remove(&mut self, handle: Handle) -> Result<Instance> {
        self.check(handle)?;
        let slot = handle.slot as usize;
        let removed =
            std::mem::replace(&mut self.scene.instances[slot], LiveScene::VACANT_INSTANCE);
        self.generations[slot] = self.generations[slot].wrapping_add(1);
        self.vacant.insert(handle.slot);
        let place = self.places.release(handle.slot, removed.mesh);
        self.stage_place(PlaceEdit {
            place,
            slot: Places::VACANT,
        });
        // A move staged earlier in this change set goes: the slot has no instance.
        if let (epoch, at) = std::mem::take(&mut self.moved_at[slot])
            && epoch == self.epoch
        {
            self.changes.moved.swap_remove(at as usize);
            if let Some(shifted) = self.changes.moved.get(at as usize) {
                self.moved_at[shifted.slot as usize] = (epoch, at);
            }
        }
        self.changes.removed.push(handle.slot);
        Ok(removed)
    }

    /// Appends a mesh (see [`Scene::add_mesh`]) and returns its id.
    pub fn add_mesh(
        &mut self,
        name: impl Into<String>,
        vertices: &[Vertex],
        indices: &[u32],
    ) -> u32 {
        self.changes.geometry = true;
        let mesh = self.scene.add_mesh(name, vertices, indices);
        // The cull order gets the new mesh's range (empty, with room), so that a sync
        // before any instance of it lays the scene out whole.
        self.lay_out();
        mesh
    }

    /// The changes the next [`LiveScene::take_changes`] takes, left in place.
    pub fn pending_changes(&self) -> &Changes {
        &self.changes
    }

    /// The changes since the last call, which forgets them.
    pub fn take_changes(&mut self) -> Changes {
        self.epoch = self.epoch.wrapping_add(1);
        if self.epoch == 0 {
            // After 2^32 change sets the stamps start over.
            self.moved_at.fill((0, 0));
            self.recolored.fill(0);
            self.placed_at.fill((0, 0));
            self.epoch = 1;
        }
        std::mem::take(&mut self.changes)
    }

    /// Gives the next change set emptied lists with the capacity a sync is done with,
    /// so that a frame's edits land in memory already touched, not fresh pages.
    pub(crate) fn recycle(&mut self, placed: Vec<PlaceEdit>, moved: Vec<MoveEdit>) {
        if self.changes.placed.is_empty() && placed.capacity() > self.changes.placed.capacity() {
            self.changes.placed = placed;
        }
        if self.changes.moved.is_empty() && moved.capacity() > self.changes.moved.capacity() {
            self.changes.moved = moved;
        }
    }

    fn check(&self, handle: Handle) -> Result<()> {
        let slot = handle.slot as usize;
        match self.generations.get(slot) {
            None => Err(Error::BadHandle(format!(
                "slot {} was never issued ({} slots)",
                handle.slot,
                self.generations.len()
            ))),
            Some(&g) if g != handle.generation || !self.occupied(handle.slot) => Err(
                Error::BadHandle(format!("the instance in slot {} was removed", handle.slot)),
            ),
            Some(_) => Ok(()),
        }
    }
}

/// The edit of `slot`: its transform's rows and its world sphere's radius, as the
/// scatter pass reads them.
pub fn make_edit(scene: &Scene, slot: u32) -> MoveEdit {
    let instance = &scene.instances[slot as usize];
    MoveEdit {
        slot,
        rows: crate::scene::affine_rows(&instance.world_from_local),
        radius: scene.world_sphere(instance).w,
    }
}

fn check_finite(t: &Affine3A) -> Result<()> {
    match Mat4::from(*t).is_finite() {
        true => Ok(()),
        false => Err(Error::NonFinite("the transform".into())),
    }
}

// What a live scene's edits changed since the last sync ([`Changes`]): the lists
// `Renderer::sync` uploads from.
/// What changed since the last sync.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Changes {
    /// Places filled or vacated (each place once, its last state; in first-change
    /// order). Applied before the moves: an inserted instance's sphere goes up as its
    /// move, to its new place.
    pub placed: Vec<PlaceEdit>,
    /// Edits of the instances whose transform changed or that were inserted (each slot
    /// once, its last move; none for slots removed since).
    pub moved: Vec<MoveEdit>,
    /// Slots whose record changed otherwise (color, material, an insert), each once.
    pub recolored: Vec<u32>,
    /// Slots removed: a move staged by an earlier sync is void.
    pub removed: Vec<u32>,
    /// A mesh ran out of vacant places and the cull order was laid out again
    /// ([`LiveScene::places`](super::LiveScene::places)): the whole order goes up.
    pub restructured: bool,
    /// Meshes were added: geometry grows.
    pub geometry: bool,
    /// Ranges of the skins' joint matrices that changed ([`LiveScene::pose`](super::LiveScene::pose): all of
    /// them; [`LiveScene::set_joints`](super::LiveScene::set_joints): one skin's): they go up.
    pub joints: Vec<std::ops::Range<u32>>,
    /// Skinned slots the engine began to pose itself ([`LiveScene::set_joints`](super::LiveScene::set_joints)): GPU
    /// posing stops posing them.
    pub driven: Vec<u32>,
    /// A punctual light was inserted, changed, removed or posed: the lights go up
    /// whole (at most [`crate::lights::MAX_LIGHTS`] records).
    pub lights: bool,
}

impl Changes {
    /// Whether nothing changed.
    pub fn is_empty(&self) -> bool {
        *self == Changes::default()
    }
}

// A live scene's punctual lights by handle: each in a slot of `Scene::lights` with a
// generation, lit or removed; a change sends the lit ones up whole at the next sync.
/// A stable reference to one punctual light of a [`LiveScene`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct LightHandle {
    slot: u32,
    generation: u32,
}

impl LiveScene {
    /// The handles of the lights the scene started with, in order.
    pub fn light_handles(&self) -> Vec<LightHandle> {
        (self.light_slots.iter().enumerate())
            .filter(|(_, (_, lit))| *lit)
            .map(|(slot, &(generation, _))| LightHandle {
                slot: slot as u32,
                generation,
            })
            .collect()
    }

    /// The lights lit now, as the renderer shades them.
    pub fn lights(&self) -> Vec<crate::lights::Light> {
        (self.scene.lights.iter().zip(&self.light_slots))
            .filter(|(_, (_, lit))| *lit)
            .map(|(l, _)| *l)
            .collect()
    }

    /// Adds `light` (checked: [`crate::lights::Light::check`]) in a new slot; an error
    /// past [`crate::lights::MAX_LIGHTS`] lit lights.
    pub fn insert_light(&mut self, light: crate::lights::Light) -> Result<LightHandle> {
        light.check().map_err(Error::InvalidScene)?;
        let lit = self.light_slots.iter().filter(|(_, lit)| *lit).count();
        if lit >= crate::lights::MAX_LIGHTS {
            return Err(Error::InvalidScene(format!(
                "a light past the budget of {} (lights::MAX_LIGHTS)",
                crate::lights::MAX_LIGHTS
            )));
        }
        self.scene.lights.push(light);
        self.light_slots.push((0, true));
        self.changes.lights = true;
        Ok(LightHandle {
            slot: self.light_slots.len() as u32 - 1,
            generation: 0,
        })
    }

    /// Replaces the light behind `handle` (moved, recolored, re-aimed).
    pub fn set_light(&mut self, handle: LightHandle, light: crate::lights::Light) -> Result<()> {
        self.check_light(handle)?;
        light.check().map_err(Error::InvalidScene)?;
        self.scene.lights[handle.slot as usize] = light;
        self.changes.lights = true;
        Ok(())
    }

    /// Turns the light behind `handle` off for good; `handle` is then an error.
    pub fn remove_light(&mut self, handle: LightHandle) -> Result<crate::lights::Light> {
        self.check_light(handle)?;
        let slot = &mut self.light_slots[handle.slot as usize];
        *slot = (slot.0.wrapping_add(1), false);
        self.changes.lights = true;
        Ok(self.scene.lights[handle.slot as usize])
    }

    fn check_light(&self, handle: LightHandle) -> Result<()> {
        match self.light_slots.get(handle.slot as usize) {
            Some(&(generation, true)) if generation == handle.generation => Ok(()),
            _ => Err(Error::BadHandle(format!(
                "light {handle:?} was removed or never given"
            ))),
        }
    }
}
