//! A live scene's edits reaching the GPU ([`crate::renderer::Renderer::sync`]): what
//! changed since the last sync is staged here, sparsely where it can, and scattered
//! into place by the frame's first pass; with two frames per submission, the second
//! frame's own edits beside the first's ([`crate::renderer::frames`]).

use crate::draw::DrawScene;
use crate::error::{Error, Result};
use crate::keep::Keeper;
use crate::live::{Changes, LiveScene, MoveEdit, PlaceEdit};
use crate::records::{CullLayout, RecordEdit};
use crate::renderer::culler::Culler;
use crate::renderer::frames::{self, SecondFrame, Staged};
use crate::renderer::recorder::{PassRecord, Recorder};
use crate::scatter::{ScatterTargets, Scatters, record_edit};
use crate::scene::Scene;
use crate::shaders::Windows;

/// What [`crate::renderer::Renderer::sync`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct SyncStats {
    /// Bytes staged for upload (places, edits, records).
    pub bytes_uploaded: u64,
    /// Instances whose transform went up sparsely (one scatter edit each; inserted
    /// instances too).
    pub moved: u32,
    /// Places of the cull order filled or vacated (inserts and removes, one scatter
    /// edit each).
    pub placed: u32,
    /// The cull order was written again (a mesh ran out of vacant places):
    /// O(instances), amortized over the inserts that filled the room.
    pub reloaded: bool,
    /// The scene outgrew the buffers (or gained meshes): everything was uploaded again,
    /// with room to grow by half.
    pub reallocated: bool,
}

/// The edits staged for the next frame's scatter pass, and with two frames per
/// submission the second frame's own.
pub struct Edits {
    scatter: Scatters,
    second: Option<SecondFrame>,
}

/// What a sync writes besides the staged edits: the culler (its places and spheres),
/// the scene as drawn (its records, reloaded), what the keeper compares, and the room
/// the buffers have.
pub struct SyncInto<'a> {
    pub culler: &'a mut Culler,
    pub draw_scene: &'a mut DrawScene,
    pub keeper: &'a mut Keeper,
    /// Instance slots the buffers have room for.
    pub slots: u32,
    /// Levels of detail: a restructured scene whose bins' ranges no longer match
    /// reallocates.
    pub levels: u32,
}

/// What [`Edits::stage`] did: staged the changes, or found that the buffers must be
/// made again (the scene outgrew them, gained meshes, or changed its bins).
pub enum Staging {
    Staged(SyncStats),
    Reallocate,
}

impl Edits {
    /// Empty staging in `windows`; with `pairs` (two frames per submission) room for
    /// the second frame's own edits of `scene`.
    pub fn new(device: &wgpu::Device, windows: Windows, scene: &Scene, pairs: bool) -> Edits {
        Edits {
            scatter: Scatters::new(device, windows),
            second: pairs.then(|| SecondFrame::new(device, windows, scene)),
        }
    }

    /// Whether the frames come in pairs (two frames per submission).
    pub fn pairs(&self) -> bool {
        self.second.is_some()
    }

    /// `live`'s changes since the last sync, with what the last submission's second
    /// frame deferred to it.
    pub fn take_changes(&mut self, live: &mut LiveScene) -> Changes {
        let mut changes = live.take_changes();
        if let Some(second) = &mut self.second {
            second.take_deferred().apply_to(&mut changes);
        }
        changes
    }

    /// Stages `changes` of `live` for the next frame: inserts and removes fill and
    /// vacate places of the cull order, moved and inserted instances go up as scatter
    /// edits, recolored and inserted ones as records; a mesh out of vacant places lays
    /// the cull order out again.
    pub fn stage(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        live: &mut LiveScene,
        changes: Changes,
        into: SyncInto,
    ) -> Staging {
        let (scene, places) = (live.scene(), live.places());
        let needed = (scene.instances.len() as u32).max(places.len());
        let occupied = |slot| live.occupied(slot);
        if changes.geometry || needed > into.slots || changes.restructured {
            into.keeper.reload(scene, occupied);
        } else {
            let moved = changes.moved.iter().map(|m| m.slot);
            let slots = (changes.removed.iter().chain(&changes.recolored).copied()).chain(moved);
            into.keeper.changed(scene, slots, occupied);
        }
        if let Some(second) = &mut self.second {
            second.moved(scene, &changes.moved);
        }
        if changes.geometry || needed > into.slots {
            return Staging::Reallocate;
        }
        if changes.restructured {
            let layout = CullLayout::with_places(scene, places);
            // A blended bin's range has an entry per place of its meshes.
            if into.culler.bins() != layout.bin_ranges(into.levels) {
                return Staging::Reallocate;
            }
            return Staging::Staged(self.reload(queue, live, layout, into));
        }
        for &slot in &changes.removed {
            self.scatter.moves.void(slot);
        }
        let targets = scatter_targets(into.culler, into.draw_scene);
        let records = self.stage_records(device, live, &changes.recolored, targets);
        let Changes { placed, moved, .. } = changes;
        let (mut stats, placed) = self.stage_places(device, placed, into.culler, into.draw_scene);
        let (moved, moved_edits) =
            self.stage_moves(device, scene, moved, into.culler, into.draw_scene);
        stats.moved = moved.moved;
        stats.bytes_uploaded += moved.bytes_uploaded + records;
        live.recycle(placed, moved_edits);
        Staging::Staged(stats)
    }

    /// Writes the whole scene into the existing buffers: records, cull order, spheres.
    fn reload(
        &mut self,
        queue: &wgpu::Queue,
        live: &LiveScene,
        layout: CullLayout,
        into: SyncInto,
    ) -> SyncStats {
        self.scatter.reset();
        if let Some(second) = &mut self.second {
            second.reload(live.scene());
        }
        let records = live.instance_records();
        let instances = &into.draw_scene.instances;
        queue.write_buffer(instances, 0, bytemuck::cast_slice(&records));
        into.draw_scene.rewritten(true, false);
        let layout_bytes = into.culler.reload(queue, layout);
        SyncStats {
            bytes_uploaded: std::mem::size_of_val(&records[..]) as u64 + layout_bytes,
            reloaded: true,
            ..SyncStats::default()
        }
    }

    /// Stages the places filled and vacated for the scatter pass (the GPU culler's), or
    /// has the CPU culler take them; returns a cleared list for the live scene to fill
    /// next.
    fn stage_places(
        &mut self,
        device: &wgpu::Device,
        placed: Vec<PlaceEdit>,
        culler: &mut Culler,
        draw_scene: &DrawScene,
    ) -> (SyncStats, Vec<PlaceEdit>) {
        if placed.is_empty() {
            return (SyncStats::default(), placed);
        }
        let count = placed.len() as u32;
        culler.place(&placed);
        let targets = scatter_targets(culler, draw_scene);
        let (bytes, spare) = self.scatter.stage_places(device, placed, targets);
        let stats = SyncStats {
            bytes_uploaded: bytes,
            placed: count,
            ..SyncStats::default()
        };
        (stats, spare)
    }

    /// Stages the moved instances' edits; a CPU culler's layout takes their new spheres.
    /// Returns a cleared list for the live scene to fill next.
    fn stage_moves(
        &mut self,
        device: &wgpu::Device,
        scene: &Scene,
        moved: Vec<MoveEdit>,
        culler: &mut Culler,
        draw_scene: &DrawScene,
    ) -> (SyncStats, Vec<MoveEdit>) {
        if moved.is_empty() {
            return (SyncStats::default(), moved);
        }
        let count = moved.len() as u32;
        culler.moved(scene, &moved);
        let targets = scatter_targets(culler, draw_scene);
        let (bytes, spare) = self.scatter.moves.stage(device, moved, targets);
        let stats = SyncStats {
            bytes_uploaded: bytes,
            moved: count,
            ..SyncStats::default()
        };
        (stats, spare)
    }

    /// Stages the rewritten records (recolored and inserted instances); returns the
    /// bytes.
    fn stage_records(
        &mut self,
        device: &wgpu::Device,
        live: &LiveScene,
        recolored: &[u32],
        targets: ScatterTargets,
    ) -> u64 {
        if recolored.is_empty() {
            return 0;
        }
        let records: Vec<RecordEdit> = recolored
            .iter()
            .map(|&slot| record_edit(live, slot))
            .collect();
        self.scatter.records.stage(device, records, targets).0
    }

    /// Stages the second frame's own changes of `live` (see
    /// [`crate::renderer::Renderer::sync_next`]); returns what it staged and the
    /// changes' joint ranges, for the skinning pass's second frame.
    pub fn stage_next(
        &mut self,
        device: &wgpu::Device,
        live: &mut LiveScene,
        into: SyncInto,
    ) -> Result<(SyncStats, Vec<std::ops::Range<u32>>)> {
        let why = match &self.second {
            None => Some("it takes a renderer of two frames per submission"),
            Some(_) => frames::unjoined(live.pending_changes()),
        };
        let (Some(second), None) = (&mut self.second, why) else {
            let why = why.unwrap_or_default();
            return Err(Error::Unsupported(format!(
                "the second frame's sync: {why}"
            )));
        };
        if live.slot_count() > into.slots {
            return Err(Error::Unsupported(
                "the second frame's sync: an insert past the renderer's room uploads everything again, for both frames: make it before the first frame's sync".into(),
            ));
        }
        let changes = live.take_changes();
        let (filled, born) = second.split(changes.placed, &changes.removed);
        let mut moved = changes.moved;
        into.culler.place(&filled);
        into.culler
            .grown(&second.grow(live.scene(), &mut moved, &born));
        let staged = Staged {
            filled,
            moved,
            recolored: changes.recolored,
            removed: changes.removed,
        };
        let mut stats = SyncStats {
            moved: staged.moved.len() as u32,
            placed: staged.filled.len() as u32,
            ..SyncStats::default()
        };
        let copy = ScatterTargets {
            instances: &(into.draw_scene.previous.as_ref())
                .expect("pairs keep the first frame's records")
                .instances,
            spheres: None,
            visibility: (0, 0),
        };
        let targets = scatter_targets(into.culler, into.draw_scene);
        let (bytes, spare) = second.stage(device, live, staged, targets, copy);
        stats.bytes_uploaded += bytes;
        live.recycle(Vec::new(), spare);
        Ok((stats, changes.joints))
    }

    /// The frame's scatter of the staged edits (for the `second` frame of a
    /// submission, the copy's vacant records first, then its own). Returns the
    /// dispatches and the CPU time of staging.
    pub fn encode(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder,
        second: bool,
    ) -> (u32, std::time::Duration) {
        let (scattered, staging) = match (&mut self.second, second) {
            // The first frame's copy of the records (just made) gets its vacant
            // records first.
            (Some(frame), true) => {
                let (vacant, staging) = frame.first.encode(encoder);
                let (own, own_staging) = frame.scatter.encode(encoder);
                (vacant + own, staging + own_staging)
            }
            _ => self.scatter.encode(encoder),
        };
        if scattered > 0 {
            rec.log(PassRecord::frame("scatter"));
        }
        (scattered, staging)
    }
}

/// Where the scatter passes (and the pose pass) write edits: the scene's records, and
/// the culler's spheres and visibility.
pub fn scatter_targets<'a>(culler: &'a Culler, draw_scene: &'a DrawScene) -> ScatterTargets<'a> {
    let (spheres, visibility) = culler.scatter_targets();
    ScatterTargets {
        instances: &draw_scene.instances,
        spheres,
        visibility,
    }
}
