//! A changing scene reaching the GPU: [`Renderer::sync`] uploads what a
//! [`LiveScene`] changed since the last sync, sparsely where it can.

use super::Renderer;
use super::checks::check_device;
use super::display::{self, PathInputs};
use super::frame::FramePasses;
use super::plan::FramePlan;
use super::second_frame::{self, SecondFrame};
use crate::error::{Error, Result};
use crate::live::{Changes, LiveScene, MoveEdit, PlaceEdit};
use crate::records::{CullLayout, RecordEdit};
use crate::scatter::{ScatterTargets, Scatters, record_edit};
use crate::scene::Scene;

/// What [`Renderer::sync`] did.
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

impl Renderer {
    /// Brings the GPU copy of `live` up to date with its changes since the last sync,
    /// paying for what changed: inserts and removes fill and vacate places of the cull
    /// order (8 bytes each), moved and inserted instances go up as scatter edits (56
    /// bytes each), recolored and inserted ones as records (76 bytes), all applied by
    /// one compute pass in the next `encode`; a mesh out of vacant places lays the cull
    /// order out again (O(instances), with room); a scene that outgrew its buffers, or
    /// gained meshes, is uploaded again with room to grow by half. Call it before
    /// `prepare`.
    pub fn sync(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        live: &mut LiveScene,
    ) -> Result<SyncStats> {
        let mut changes = live.take_changes();
        if let Some(second) = &mut self.second {
            second.take_deferred().apply_to(&mut changes);
        }
        if changes.lights {
            self.lighting.set(&live.lights())?;
            self.keeper.redraw_whole();
        }
        let joints = std::mem::take(&mut changes.joints);
        let driven = std::mem::take(&mut changes.driven);
        let stopped = changes
            .removed
            .iter()
            .chain(&driven)
            .copied()
            .collect::<Vec<_>>();
        let mut stats = self.sync_instances(device, queue, live, changes)?;
        // After a reallocation the pass was built from the live scene as it is.
        if let (Some(pose), false) = (&mut self.frame_passes.pose, stats.reallocated) {
            for slot in stopped {
                stats.bytes_uploaded += pose.stop(queue, slot);
            }
        }
        if let Some(skin) = &self.frame_passes.skin {
            for range in joints {
                stats.bytes_uploaded += skin.upload(queue, &live.scene().skins, range);
            }
        }
        Ok(stats)
    }

    /// [`Renderer::sync`] of the instances (and, reallocating, of everything).
    fn sync_instances(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        live: &mut LiveScene,
        changes: Changes,
    ) -> Result<SyncStats> {
        let (scene, places) = (live.scene(), live.places());
        let needed = (scene.instances.len() as u32).max(places.len());
        let occupied = |slot| live.occupied(slot);
        if changes.geometry || needed > self.slots || changes.restructured {
            self.keeper.reload(scene, occupied);
        } else {
            let moved = changes.moved.iter().map(|m| m.slot);
            let slots = (changes.removed.iter().chain(&changes.recolored).copied()).chain(moved);
            self.keeper.changed(scene, slots, occupied);
        }
        if let Some(second) = &mut self.second {
            second.moved(scene, &changes.moved);
        }
        if changes.geometry || needed > self.slots {
            return self.reallocate(device, live, needed);
        }
        if changes.restructured {
            let layout = CullLayout::with_places(scene, places);
            // A blended bin's range has an entry per place of its meshes.
            let culler = &self.shared.culler;
            if culler.bins() != layout.bin_ranges(self.options.lod_levels()) {
                return self.reallocate(device, live, needed);
            }
            return Ok(self.reload(queue, live, layout));
        }
        for &slot in &changes.removed {
            self.scatter.moves.void(slot);
        }
        let records = self.stage_records(device, live, &changes.recolored);
        let Changes { placed, moved, .. } = changes;
        let (mut stats, placed) = self.stage_places(device, placed);
        let (moved, moved_edits) = self.stage_moves(device, scene, moved);
        stats.moved = moved.moved;
        stats.bytes_uploaded += moved.bytes_uploaded + records;
        live.recycle(placed, moved_edits);
        Ok(stats)
    }

    /// Uploads everything again into new buffers with room for half as much more.
    fn reallocate(
        &mut self,
        device: &wgpu::Device,
        live: &LiveScene,
        needed: u32,
    ) -> Result<SyncStats> {
        let (scene, places) = (live.scene(), live.places());
        check_device(device, scene, &self.options)?;
        let room = needed + needed / 2;
        let plan = FramePlan::new(&self.rig, &self.options, self.coarse, 0.0)?;
        // The records with their slots' generations (a reused slot's went up).
        let records = live.instance_records();
        let inputs = PathInputs {
            scene,
            records: &records,
            rig: &self.rig,
            plan: &plan,
            frame: &self.frame,
            options: &self.options,
            slots: room,
            shadow_group: &self.shadow_map.bind_group,
        };
        let built = display::build(device, CullLayout::with_places(scene, places), &inputs)?;
        (self.shared, self.pyramids, self.displays) =
            (built.shared, built.pyramids, built.displays);
        self.slots = room;
        // The bindings may now need more windows.
        let windows = self.options.windows(device, room);
        self.scatter = Scatters::new(device, windows);
        if self.second.is_some() {
            self.second = Some(SecondFrame::new(device, windows, scene));
        }
        let made = (scene, &self.options);
        let bound = super::frame_bindings(&self.shared, &self.frame, windows);
        self.frame_passes = FramePasses::new(device, made, bound, |s| live.animates(s))?;
        let bytes = std::mem::size_of_val(&records[..]) as u64;
        Ok(SyncStats {
            bytes_uploaded: bytes,
            reloaded: true,
            reallocated: true,
            ..SyncStats::default()
        })
    }

    /// Writes the whole scene into the existing buffers: records, cull order, spheres.
    fn reload(&mut self, queue: &wgpu::Queue, live: &LiveScene, layout: CullLayout) -> SyncStats {
        self.scatter.reset();
        if let Some(second) = &mut self.second {
            second.reload(live.scene());
        }
        let records = live.instance_records();
        let core = &mut self.shared;
        queue.write_buffer(
            &core.draw_scene.instances,
            0,
            bytemuck::cast_slice(&records),
        );
        core.draw_scene.rewritten(true, false);
        let layout_bytes = core.culler.reload(queue, layout);
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
    ) -> (SyncStats, Vec<PlaceEdit>) {
        if placed.is_empty() {
            return (SyncStats::default(), placed);
        }
        let count = placed.len() as u32;
        self.shared.culler.place(&placed);
        let targets = self.shared.scatter_targets();
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
    ) -> (SyncStats, Vec<MoveEdit>) {
        if moved.is_empty() {
            return (SyncStats::default(), moved);
        }
        let count = moved.len() as u32;
        self.shared.culler.moved(scene, &moved);
        let targets = self.shared.scatter_targets();
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
    fn stage_records(&mut self, device: &wgpu::Device, live: &LiveScene, recolored: &[u32]) -> u64 {
        if recolored.is_empty() {
            return 0;
        }
        let records: Vec<RecordEdit> = recolored
            .iter()
            .map(|&slot| record_edit(live, slot))
            .collect();
        let targets = self.shared.scatter_targets();
        self.scatter.records.stage(device, records, targets).0
    }
}

impl Renderer {
    /// The second frame's own changes in a submission of two frames
    /// ([`super::RendererOptions::frames_per_submit`] 2): after [`Renderer::sync`] took
    /// the first frame's, the caller poses `live` at the second frame's time (with
    /// [`LiveScene::pose`]) and moves or recolors instances for it alone; this takes
    /// those changes, which the second frame draws and the first does not (see
    /// [`super::second_frame`]). Call it before `prepare_pair`.
    ///
    /// Inserts join the cull order both frames share, hidden from the first frame's
    /// views; removes wait for the next sync (the first frame still draws them), hidden
    /// from the second frame's. New meshes, inserts that lay the cull order out again or
    /// pass the renderer's room, an insert into a place a remove emptied, and light
    /// changes belong to both frames: they are [`Error::Unsupported`] here and leave
    /// `live`'s changes untaken. So is a renderer of one frame per submission.
    pub fn sync_next(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        live: &mut LiveScene,
    ) -> Result<SyncStats> {
        let why = match &self.second {
            None => Some("it takes a renderer of two frames per submission"),
            Some(_) => second_frame::unjoined(live.pending_changes()),
        };
        let (Some(second), None) = (&mut self.second, why) else {
            let why = why.unwrap_or_default();
            return Err(Error::Unsupported(format!(
                "the second frame's sync: {why}"
            )));
        };
        if live.slot_count() > self.slots {
            return Err(Error::Unsupported(
                "the second frame's sync: an insert past the renderer's room uploads everything again, for both frames: make it before the first frame's sync".into(),
            ));
        }
        let changes = live.take_changes();
        let (filled, born) = second.split(changes.placed, &changes.removed);
        let mut moved = changes.moved;
        let culler = &mut self.shared.culler;
        culler.place(&filled);
        culler.grown(&second.grow(live.scene(), &mut moved, &born));
        let staged = second_frame::Staged {
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
        let core = &self.shared;
        let copy = ScatterTargets {
            instances: &(core.draw_scene.previous.as_ref())
                .expect("pairs keep the first frame's records")
                .instances,
            spheres: None,
            visibility: (0, 0),
        };
        let targets = (self.shared.scatter_targets(), copy);
        let (bytes, spare) = second.stage(device, live, staged, targets);
        stats.bytes_uploaded += bytes;
        if let Some(skin) = &mut self.frame_passes.skin {
            for range in changes.joints {
                stats.bytes_uploaded += skin.upload_next(queue, &live.scene().skins, range);
            }
        }
        live.recycle(Vec::new(), spare);
        Ok(stats)
    }
}
