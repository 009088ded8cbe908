//! A changing scene reaching the GPU: [`Renderer::sync`] uploads what a
//! [`LiveScene`] changed since the last sync, sparsely where it can.

use super::{Path, Renderer, check_device};
use crate::cull::gpu::CullScene;
use crate::error::Result;
use crate::live::{Edit, LiveScene, edit_sphere};
use crate::records::{CullLayout, InstanceRecord, instance_records};
use crate::scatter::{ScatterTargets, Scatters, record_edit};
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
    /// Instances whose transform went up sparsely (one scatter edit each).
    pub moved: u32,
    /// The cull order was written again (instances inserted or removed): O(instances).
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
    /// paying for what changed: moved instances go up as scatter edits (68 bytes each,
    /// applied by one dispatch in the next `encode`); inserts and removes rewrite the cull
    /// order and records (O(instances)); a scene that outgrew its buffers, or gained
    /// meshes, is uploaded again with room to grow by half. Call it before `prepare`.
    pub fn sync(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        live: &mut LiveScene,
    ) -> Result<SyncStats> {
        let changes = live.take_changes();
        let scene = live.scene();
        let slots = scene.instances.len() as u32;
        if changes.geometry || slots > self.slots {
            check_device(device, scene, &self.options)?;
            let room = slots + slots / 2;
            self.path = Path::new(
                device,
                scene,
                (&self.rig, &self.frame),
                (&self.options, room),
            )?;
            self.slots = room;
            // The bindings may now need more windows.
            self.scatter = Scatters::new(device, self.options.windows(device, room));
            let bytes = (scene.instances.len() * size_of::<InstanceRecord>()) as u64;
            return Ok(SyncStats {
                bytes_uploaded: bytes,
                reloaded: true,
                reallocated: true,
                ..SyncStats::default()
            });
        }
        if changes.restructured {
            return Ok(self.reload(queue, scene));
        }
        let mut stats = self.stage_moves(device, queue, scene, &changes.moved);
        if !changes.recolored.is_empty() {
            let records: Vec<Edit> = changes
                .recolored
                .iter()
                .map(|&slot| record_edit(scene, slot))
                .collect();
            let (instances, culling) = self.path.edit_targets();
            let targets = ScatterTargets {
                instances,
                spheres: scatter_spheres(&culling),
            };
            let scatter = &mut self.scatter.records;
            stats.bytes_uploaded += scatter.stage(device, queue, (scene, &records), targets);
        }
        Ok(stats)
    }

    /// Writes the whole scene into the existing buffers: records, cull order, spheres.
    fn reload(&mut self, queue: &wgpu::Queue, scene: &Scene) -> SyncStats {
        self.scatter.reset();
        let records = instance_records(scene);
        let (instances, culling) = self.path.edit_targets();
        queue.write_buffer(instances, 0, bytemuck::cast_slice(&records));
        let layout = CullLayout::new(scene);
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

    /// Stages the moved instances' edits; a CPU culler's layout takes their new spheres.
    fn stage_moves(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &Scene,
        moved: &[Edit],
    ) -> SyncStats {
        if moved.is_empty() {
            return SyncStats::default();
        }
        let (instances, culling) = self.path.edit_targets();
        let targets = ScatterTargets {
            instances,
            spheres: scatter_spheres(&culling),
        };
        let bytes = self
            .scatter
            .moves
            .stage(device, queue, (scene, moved), targets);
        if let CullState::Cpu(layout) = culling {
            for edit in moved {
                let at = layout.positions[edit[0] as usize];
                layout.set_sphere(at, edit_sphere(edit));
            }
        }
        SyncStats {
            bytes_uploaded: bytes,
            moved: moved.len() as u32,
            ..SyncStats::default()
        }
    }
}

/// The GPU culler's spheres and cull positions, which moves update (`None` culling on
/// the CPU).
fn scatter_spheres<'a>(culling: &'a CullState<'_>) -> Option<[&'a wgpu::Buffer; 2]> {
    match culling {
        CullState::Gpu(cull) => Some(cull.scatter_targets()),
        CullState::Cpu(_) => None,
    }
}
