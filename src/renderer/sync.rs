//! A changing scene reaching the GPU: [`Renderer::sync`] uploads what a
//! [`LiveScene`] changed since the last sync, sparsely where it can.

use super::{Path, Renderer, check_device};
use crate::cull::gpu::CullScene;
use crate::error::Result;
use crate::live::{Changes, LiveScene, MoveEdit, PlaceEdit};
use crate::places::Places;
use crate::records::{CullLayout, InstanceRecord, instance_records};
use crate::scatter::{RecordEdit, ScatterTargets, Scatters, record_edit};
use crate::scene::Scene;

/// What edits change in the culling: the GPU culler's buffers, or the CPU culler's layout.
pub(super) enum CullState<'a> {
    Gpu(&'a mut CullScene),
    Cpu(&'a mut CullLayout),
}

/// What [`Renderer::sync`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct SyncStats {
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

impl Path {
    /// The instance records and the culling state: what edits change.
    fn edit_targets(&mut self) -> (&wgpu::Buffer, CullState<'_>) {
        match self {
            Path::Indirect(p) => p.edit_targets(),
            Path::Classic(p) => (&p.draw_scene.instances, CullState::Cpu(&mut p.layout)),
        }
    }
}

impl Renderer {
    /// Brings the GPU copy of `live` up to date with its changes since the last sync,
    /// paying for what changed: inserts and removes fill and vacate places of the cull
    /// order (8 bytes each), moved and inserted instances go up as scatter edits (56
    /// bytes each), recolored and inserted ones as records (68 bytes), all applied by
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
        let changes = live.take_changes();
        let (scene, places) = (live.scene(), live.places());
        let needed = (scene.instances.len() as u32).max(places.len());
        if changes.geometry || needed > self.slots {
            return self.reallocate(device, (scene, places), needed);
        }
        if changes.restructured {
            return Ok(self.reload(queue, scene, places));
        }
        for &slot in &changes.removed {
            self.scatter.moves.void(slot);
        }
        let records = self.stage_records(device, scene, &changes.recolored);
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
        (scene, places): (&Scene, &Places),
        needed: u32,
    ) -> Result<SyncStats> {
        check_device(device, scene, &self.options)?;
        let room = needed + needed / 2;
        let at = (&self.rig, &self.frame);
        self.path = Path::new(device, (scene, places), at, (&self.options, room))?;
        self.slots = room;
        // The bindings may now need more windows.
        self.scatter = Scatters::new(device, self.options.windows(device, room));
        let bytes = (scene.instances.len() * size_of::<InstanceRecord>()) as u64;
        Ok(SyncStats {
            bytes_uploaded: bytes,
            reloaded: true,
            reallocated: true,
            ..SyncStats::default()
        })
    }

    /// Writes the whole scene into the existing buffers: records, cull order, spheres.
    fn reload(&mut self, queue: &wgpu::Queue, scene: &Scene, places: &Places) -> SyncStats {
        self.scatter.reset();
        let records = instance_records(scene);
        let (instances, culling) = self.path.edit_targets();
        queue.write_buffer(instances, 0, bytemuck::cast_slice(&records));
        let layout = CullLayout::with_places(scene, places);
        let layout_bytes = match culling {
            CullState::Gpu(cull) => cull.reload(queue, &layout),
            CullState::Cpu(cpu) => {
                *cpu = layout;
                0
            }
        };
        SyncStats {
            bytes_uploaded: std::mem::size_of_val(&records[..]) as u64 + layout_bytes,
            reloaded: true,
            ..SyncStats::default()
        }
    }

    /// Stages the places filled and vacated (GPU culling), or applies them to the CPU
    /// culler's layout; returns a cleared list for the live scene to fill next.
    fn stage_places(
        &mut self,
        device: &wgpu::Device,
        placed: Vec<PlaceEdit>,
    ) -> (SyncStats, Vec<PlaceEdit>) {
        if placed.is_empty() {
            return (SyncStats::default(), placed);
        }
        let count = placed.len() as u32;
        let (instances, culling) = self.path.edit_targets();
        let (bytes, spare) = match culling {
            CullState::Gpu(cull) => {
                let targets = ScatterTargets {
                    instances,
                    spheres: Some(cull.scatter_targets()),
                };
                self.scatter.places.stage(device, placed, targets)
            }
            CullState::Cpu(layout) => {
                for &[place, slot] in &placed {
                    layout.set_place((place, slot, CullLayout::VACANT_SPHERE));
                }
                let mut spare = placed;
                spare.clear();
                (0, spare)
            }
        };
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
        let (instances, mut culling) = self.path.edit_targets();
        if let CullState::Cpu(layout) = &mut culling {
            for edit in &moved {
                let slot = edit[0] as usize;
                let sphere = scene.world_sphere(&scene.instances[slot]);
                layout.set_sphere(layout.positions[slot], sphere);
            }
        }
        let targets = ScatterTargets {
            instances,
            spheres: scatter_spheres(&culling),
        };
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
    fn stage_records(&mut self, device: &wgpu::Device, scene: &Scene, recolored: &[u32]) -> u64 {
        if recolored.is_empty() {
            return 0;
        }
        let records: Vec<RecordEdit> = recolored
            .iter()
            .map(|&slot| record_edit(scene, slot))
            .collect();
        let (instances, culling) = self.path.edit_targets();
        let targets = ScatterTargets {
            instances,
            spheres: scatter_spheres(&culling),
        };
        self.scatter.records.stage(device, records, targets).0
    }
}

/// The GPU culler's spheres, cull positions and order, which edits update (`None`
/// culling on the CPU).
fn scatter_spheres<'a>(culling: &'a CullState<'_>) -> Option<[&'a wgpu::Buffer; 4]> {
    match culling {
        CullState::Gpu(cull) => Some(cull.scatter_targets()),
        CullState::Cpu(_) => None,
    }
}
