//! The cull order's places: per mesh a range of places, each holding one instance (its
//! slot) or vacant, so that inserts and removes change one place each instead of the
//! whole order.
//!
//! A scene is laid out tight (every mesh's instances in ascending slot, no vacant
//! place); a [`crate::live::LiveScene`] then gives an inserted instance its mesh's
//! lowest vacant place and leaves a removed one's place vacant. When a mesh has no
//! vacant place left the whole order is laid out again, ascending slots per mesh, each
//! mesh with room to grow ([`Places::with_room`]), which amortizes the O(instances)
//! rewrite over the inserts that filled the room. The visible ids of a draw come out
//! in place order (the README's cull contract).

use std::collections::BTreeSet;

use crate::scene::{Instance, Scene};

/// Where each instance sits in the cull order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Places {
    /// Per mesh: its first place and how many places it has.
    ranges: Vec<(u32, u32)>,
    /// The slot at each place ([`Places::VACANT`] where none).
    slot_at: Vec<u32>,
    /// The place of each slot ([`Places::VACANT`] for vacant slots).
    place_of: Vec<u32>,
    /// Per mesh: its vacant places, lowest first.
    vacant: Vec<BTreeSet<u32>>,
}

impl Places {
    /// A vacant place's slot, and a vacant slot's place.
    pub const VACANT: u32 = u32::MAX;

    /// `scene`'s instances in ascending slot per mesh, no vacant place.
    pub fn tight(scene: &Scene) -> Places {
        Places::laid_out(scene, |_| 0)
    }

    /// As [`Places::tight`], each mesh with room for half its instances more and at
    /// least a quarter of the scene's instances per mesh: a layout is only needed again
    /// after that many inserts into one mesh.
    pub fn with_room(scene: &Scene) -> Places {
        let meshes = scene.meshes.len().max(1) as u32;
        let floor = (scene.instances.len() as u32 / (4 * meshes)).max(64);
        Places::laid_out(scene, |count| (count / 2).max(floor))
    }

    fn laid_out(scene: &Scene, room: impl Fn(u32) -> u32) -> Places {
        let mut counts = vec![0u32; scene.meshes.len()];
        for inst in occupied(scene) {
            counts[inst.1 as usize] += 1;
        }
        let mut start = 0;
        let ranges: Vec<(u32, u32)> = counts
            .iter()
            .map(|&count| {
                let range = (start, count + room(count));
                start += range.1;
                range
            })
            .collect();
        let mut slot_at = vec![Places::VACANT; start as usize];
        let mut place_of = vec![Places::VACANT; scene.instances.len()];
        let mut next: Vec<u32> = ranges.iter().map(|r| r.0).collect();
        for (slot, mesh) in occupied(scene) {
            let place = &mut next[mesh as usize];
            slot_at[*place as usize] = slot;
            place_of[slot as usize] = *place;
            *place += 1;
        }
        let vacant = ranges
            .iter()
            .zip(&next)
            .map(|(&(start, len), &used)| (used..start + len).collect())
            .collect();
        Places {
            ranges,
            slot_at,
            place_of,
            vacant,
        }
    }

    /// Places in the order, vacant ones included: what culling runs over.
    pub fn len(&self) -> u32 {
        self.slot_at.len() as u32
    }

    /// Whether there are no places.
    pub fn is_empty(&self) -> bool {
        self.slot_at.is_empty()
    }

    /// Mesh `mesh`'s first place and number of places.
    pub fn range(&self, mesh: u32) -> (u32, u32) {
        self.ranges[mesh as usize]
    }

    /// The slot at each place ([`Places::VACANT`] where none).
    pub fn slots(&self) -> &[u32] {
        &self.slot_at
    }

    /// The place of each slot ([`Places::VACANT`] for vacant slots).
    pub fn of_slots(&self) -> &[u32] {
        &self.place_of
    }

    /// Puts `slot` (an instance of `mesh`) into its mesh's lowest vacant place and
    /// returns it; `None` when the mesh has none (lay the order out again).
    pub fn take(&mut self, slot: u32, mesh: u32) -> Option<u32> {
        let place = self.vacant.get_mut(mesh as usize)?.pop_first()?;
        self.slot_at[place as usize] = slot;
        if self.place_of.len() <= slot as usize {
            self.place_of.resize(slot as usize + 1, Places::VACANT);
        }
        self.place_of[slot as usize] = place;
        Some(place)
    }

    /// Empties `slot`'s place (an instance of `mesh` removed) and returns it.
    pub fn release(&mut self, slot: u32, mesh: u32) -> u32 {
        let place = std::mem::replace(&mut self.place_of[slot as usize], Places::VACANT);
        self.slot_at[place as usize] = Places::VACANT;
        self.vacant[mesh as usize].insert(place);
        place
    }
}

/// `scene`'s occupied slots and their meshes, in slot order.
fn occupied(scene: &Scene) -> impl Iterator<Item = (u32, u32)> + '_ {
    scene
        .instances
        .iter()
        .enumerate()
        .filter(|(_, i)| i.mesh != Instance::VACANT_MESH)
        .map(|(slot, i)| (slot as u32, i.mesh))
}
