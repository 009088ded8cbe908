//! What a live scene's edits changed since the last sync ([`Changes`]): the lists
//! `Renderer::sync` uploads from.

use super::{MoveEdit, PlaceEdit};

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
