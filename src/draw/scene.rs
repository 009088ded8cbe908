//! The scene as the draws read it on the GPU: geometry, instance records, materials
//! and, with motion vectors, the previous frame's records and vertices.

use super::Drawer;
use crate::buffers::{init_buffer, init_buffer_with_room, storage_buffer};
use crate::error::Result;
use crate::materials::GpuMaterials;
use crate::records::InstanceRecord;
use crate::scene::Scene;
use crate::shaders::{Bound, MOTION_BINDINGS, Windows, bind_group};

/// The scene's geometry, instance records and materials on the GPU, uploaded once, and
/// the frame's shadow map the draws sample.
pub struct DrawScene {
    /// Every mesh's vertices, one buffer.
    pub vertices: wgpu::Buffer,
    /// Every mesh's indices (and levels of detail), one buffer.
    pub indices: wgpu::Buffer,
    /// One [`InstanceRecord`] per slot, with room.
    pub instances: wgpu::Buffer,
    /// Textures and material records (group 1).
    pub materials: GpuMaterials,
    /// Group 2: the frame's shadow map (the renderer's).
    pub shadow_group: wgpu::BindGroup,
    /// With motion vectors: the previous frame's records and vertices.
    pub previous: Option<Previous>,
}

/// What the draw with motion vectors reads of the previous frame ([`crate::motion`]):
/// copies of the instance records and, where passes rewrite them each frame (skins,
/// morph targets), of the vertices, taken before the frame's scatter and posing.
pub struct Previous {
    /// The records as the previous frame drew them.
    pub instances: wgpu::Buffer,
    /// The vertices as the previous frame drew them; `None`: the scene's, which no
    /// pass rewrites.
    pub vertices: Option<wgpu::Buffer>,
    /// Group 3 of the draw pipelines with motion vectors.
    pub bind_group: wgpu::BindGroup,
    /// Whether the records, and the vertices, changed since they were last copied:
    /// a frame that rewrites neither needs no copy (the copies already hold what it
    /// draws), which spares a static scene a copy of every record per frame.
    stale: Stale,
}

/// What [`Previous`] must copy again before the next frame's passes.
#[derive(Clone, Copy, Debug)]
struct Stale {
    records: bool,
    vertices: bool,
}

impl DrawScene {
    /// Uploads `scene`, its instances as `records` (one per slot in use), with room for
    /// `slots` instance records. Fails when the scene's materials do not fit together
    /// or exceed the device.
    pub fn new(
        device: &wgpu::Device,
        drawer: &Drawer,
        (scene, records, shadow_group): (&Scene, &[InstanceRecord], &wgpu::BindGroup),
        slots: u32,
    ) -> Result<DrawScene> {
        let init =
            |label: &str, contents: &[u8], usage| init_buffer(device, label, contents, usage);
        let vertices = init(
            "stereocull.vertices",
            bytemuck::cast_slice(&scene.vertices),
            DrawScene::vertex_usage(scene),
        );
        let instances = init_buffer_with_room(
            device,
            "stereocull.instances",
            bytemuck::cast_slice(records),
            DrawScene::BYTES_PER_INSTANCE * slots as u64,
            // COPY_SRC: read back by diagnostics (`instance_records`), copied to
            // `Previous` with motion vectors or two frames per submission.
            wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_DST
                | wgpu::BufferUsages::COPY_SRC,
        );
        let rewritten = DrawScene::rewrites_vertices(scene);
        let previous = (drawer.earlier.as_ref()).map(|layout| {
            let copied = (&instances, rewritten.then_some(&vertices));
            Previous::new(device, (layout, &drawer.windows), copied)
        });
        Ok(DrawScene {
            materials: GpuMaterials::new(device, &drawer.materials_layout, scene)?,
            shadow_group: shadow_group.clone(),
            previous,
            vertices,
            indices: init(
                "stereocull.indices",
                bytemuck::cast_slice(&scene.indices),
                wgpu::BufferUsages::INDEX,
            ),
            instances,
        })
    }

    /// The vertex buffer's uses: drawn, read back, and written by the skinning and morph
    /// passes when the scene has skins or morph targets.
    fn vertex_usage(scene: &Scene) -> wgpu::BufferUsages {
        let skinned = match DrawScene::rewrites_vertices(scene) {
            true => wgpu::BufferUsages::STORAGE,
            false => wgpu::BufferUsages::empty(),
        };
        wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_SRC | skinned
    }

    /// Whether frame passes rewrite the vertices (skins, morph targets).
    fn rewrites_vertices(scene: &Scene) -> bool {
        !(scene.skins.is_empty() && scene.morphs.is_empty())
    }

    /// GPU bytes per instance slot for drawing: its record.
    pub const BYTES_PER_INSTANCE: u64 = size_of::<InstanceRecord>() as u64;

    /// With motion vectors, copies what the frame's passes are about to rewrite (the
    /// records, and the vertices where skins or morph targets rewrite them) into
    /// [`Previous`], where they changed since the last copy: record first in a frame,
    /// and submit what follows (a copy left unsubmitted is taken as done).
    pub fn keep_previous(&mut self, encoder: &mut wgpu::CommandEncoder) {
        let Some(previous) = &mut self.previous else {
            return;
        };
        if previous.stale.records {
            let size = self.instances.size();
            encoder.copy_buffer_to_buffer(&self.instances, 0, &previous.instances, 0, size);
        }
        if let (Some(vertices), true) = (&previous.vertices, previous.stale.vertices) {
            encoder.copy_buffer_to_buffer(&self.vertices, 0, vertices, 0, vertices.size());
        }
        previous.stale = Stale {
            records: false,
            vertices: false,
        };
    }

    /// Marks the records (a scatter, posing, a reload) and the vertices (skinning,
    /// morph targets) as rewritten since [`DrawScene::keep_previous`] last copied them.
    pub fn rewritten(&mut self, records: bool, vertices: bool) {
        if let Some(previous) = &mut self.previous {
            previous.stale.records |= records;
            previous.stale.vertices |= vertices;
        }
    }
}

impl Previous {
    /// Buffers the size of `instances` and, where passes rewrite them, of `vertices`,
    /// bound as group 3. Their contents come from the first encode's copy, before any
    /// pass reads them.
    fn new(
        device: &wgpu::Device,
        (layout, windows): (&wgpu::BindGroupLayout, &Windows),
        (instances, vertices): (&wgpu::Buffer, Option<&wgpu::Buffer>),
    ) -> Previous {
        let copy = wgpu::BufferUsages::COPY_DST;
        let like = |source: &wgpu::Buffer, label, usage| {
            storage_buffer(device, label, source.size(), usage | copy)
        };
        let instances = like(
            instances,
            "stereocull.previous_instances",
            wgpu::BufferUsages::STORAGE,
        );
        let vertices = vertices.map(|v| {
            like(
                v,
                "stereocull.previous_vertices",
                wgpu::BufferUsages::VERTEX,
            )
        });
        let bind_group = bind_group(
            device,
            "stereocull.motion",
            layout,
            &MOTION_BINDINGS,
            windows,
            [instances.bound()],
        );
        Previous {
            instances,
            vertices,
            bind_group,
            stale: Stale {
                records: true,
                vertices: true,
            },
        }
    }
}
