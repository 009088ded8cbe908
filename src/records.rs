//! The storage-buffer records the GPU reads and writes (`#[repr(C)]` + bytemuck),
//! mirrored in `wgsl/shared/records.wgsl` (`records_match_wgsl` checks every offset),
//! and the serialization of uniforms (encase) into the bytes WGSL expects.

use bytemuck::{Pod, Zeroable};
use glam::Vec4;

use crate::bins::{BinKind, BinRange, Bins};
use crate::places::Places;
use crate::scene::{Instance, MAX_LODS, Mesh, Scene};

/// What the vertex shader reads per instance, indexed by instance id (80 bytes: WGSL
/// rounds the record to its rows' 16-byte alignment).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct InstanceRecord {
    /// Rows of the 3x4 affine `world_from_local`: `world = rows * vec4(local, 1)`.
    pub world_from_local: [[f32; 4]; 3],
    /// RGBA8 unorm, linear.
    pub color: u32,
    /// Index into the scene's meshes.
    pub mesh: u32,
    /// [`crate::scene::Animation::spin`]: radians per second about local +Y.
    pub spin: f32,
    /// [`crate::scene::Animation::bob`]: meters along world +Y.
    pub bob: f32,
    /// [`Instance::material`], or [`InstanceRecord::MESH_MATERIAL`]: the mesh's own.
    pub material: u32,
    /// The slot's generation ([`crate::live::Handle`]; 0 outside a live scene): the
    /// motion vectors' draw takes an instance whose previous record has another for a
    /// newcomer, with no previous transform of its own.
    pub generation: u32,
    /// Zeros (the record is 80 bytes).
    pub unused: [u32; 2],
}

impl InstanceRecord {
    /// No override: the instance draws with its mesh's material.
    pub const MESH_MATERIAL: u32 = u32::MAX;
}

/// The 32 bytes before a scatter's edits (`EditHeader` in `wgsl/shared/scatter.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Pod, Zeroable)]
pub struct EditHeader {
    /// Edits in the buffer.
    pub count: u32,
    /// 1 when the GPU culler's spheres, order and positions are bound (GPU culling).
    pub spheres_too: u32,
    /// Workgroups along x of the dispatch (its y spreads past the device's limit).
    pub groups_x: u32,
    /// With occlusion, the visibility words per display slot: a filled or vacated
    /// place's bit is cleared in each slot's (a newcomer starts as not drawn). Zero
    /// without occlusion.
    pub visibility_words: u32,
    /// With occlusion, the display slots that have visibility words; else zero.
    pub visibility_slots: u32,
    /// How a moved sphere is written (moves only): [`EditHeader::EXACT`] the edit's;
    /// for a two-frame submission's second frame, grown to hold both frames' spheres
    /// about the first frame's center, by the radius the CPU computed
    /// ([`EditHeader::GROWN_GIVEN`], edits from the CPU) or by one measured here
    /// ([`EditHeader::GROWN_MEASURED`], the pose pass's).
    pub grow: u32,
    /// Zeros (the header is 32 bytes).
    pub unused: [u32; 2],
}

impl EditHeader {
    /// Each moved sphere is the edit's.
    pub const EXACT: u32 = 0;
    /// Grown about the sphere's center to the edit's radius (the CPU's).
    pub const GROWN_GIVEN: u32 = 1;
    /// Grown about the sphere's center to hold the edit's sphere, measured on the GPU.
    pub const GROWN_MEASURED: u32 = 2;
}

/// Relative margin of a grown radius over its computed reach
/// ([`crate::renderer::grown`], `wgsl/scatter_moves.wgsl`): the distance between the
/// centers is rounded (a few ulps; this is 8), and the grown sphere must hold the second
/// frame's sphere whatever the rounding.
pub const GROWN_SLACK: f32 = 1e-6;

/// A moved instance as the moves scatter takes it (56 bytes): the slot
/// ([`Places::VACANT`]: void, its instance removed after an earlier sync staged it), the
/// new transform's rows and the world sphere's radius, computed on the CPU
/// ([`crate::scene::Scene::world_sphere`]).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct MoveEdit {
    /// The instance's slot.
    pub slot: u32,
    /// The new `world_from_local`'s rows.
    pub rows: [[f32; 4]; 3],
    /// The new world sphere's radius.
    pub radius: f32,
}

/// A rewritten instance record as the records scatter takes it (76 bytes): the slot,
/// then [`InstanceRecord`]'s members (flat: WGSL would align a nested record to 16).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct RecordEdit {
    /// The instance's slot.
    pub slot: u32,
    /// [`InstanceRecord::world_from_local`].
    pub rows: [[f32; 4]; 3],
    /// [`InstanceRecord::color`].
    pub color: u32,
    /// [`InstanceRecord::mesh`].
    pub mesh: u32,
    /// [`InstanceRecord::spin`].
    pub spin: f32,
    /// [`InstanceRecord::bob`].
    pub bob: f32,
    /// [`InstanceRecord::material`].
    pub material: u32,
    /// [`InstanceRecord::generation`].
    pub generation: u32,
}

/// A place of the cull order and the slot now there ([`Places::VACANT`]: none), as the
/// places scatter takes it (8 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Pod, Zeroable)]
pub struct PlaceEdit {
    /// The place in the cull order.
    pub place: u32,
    /// The slot now there, or [`Places::VACANT`].
    pub slot: u32,
}

impl RecordEdit {
    /// The edit writing `record` into `slot`.
    pub fn new(slot: u32, record: InstanceRecord) -> RecordEdit {
        RecordEdit {
            slot,
            rows: record.world_from_local,
            color: record.color,
            mesh: record.mesh,
            spin: record.spin,
            bob: record.bob,
            material: record.material,
            generation: record.generation,
        }
    }
}

/// A mesh's index range, and its range in the cull order (written once at upload).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Pod, Zeroable)]
pub struct MeshRecord {
    /// First index of the mesh in the index buffer.
    pub first_index: u32,
    /// Its indices.
    pub index_count: u32,
    /// Added to each index.
    pub base_vertex: i32,
    /// First position of this mesh's instances in [`CullLayout::order`].
    pub cull_start: u32,
    /// How many places of the cull order this mesh has.
    pub cull_count: u32,
    /// Its material's bin ([`crate::bins::Bins::of_mesh`]): the range of the draws
    /// its draws go to.
    pub bin: u32,
}

/// One level of detail of a mesh as culling reads it: [`MAX_LODS`] per mesh, level 0
/// the mesh itself; levels a mesh lacks have an infinite error and are never chosen.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct LodRecord {
    /// First index of this level in the index buffer.
    pub first_index: u32,
    /// Its indices.
    pub index_count: u32,
    /// The level's error relative to the mesh's bounding radius, squared: an instance
    /// with world sphere radius `r` at distance `d` from the viewer takes the level when
    /// `d * d > error_sq * lod_scale * r * r` (`lod_scale` from the frame context).
    pub error_sq: f32,
}

/// One indexed indirect draw, as `multi_draw_indexed_indirect(_count)` reads it.
/// The draws pass (`wgsl/cull_draws.wgsl`) writes every field each frame, and so does
/// `cull::cpu`; entries from `draw_count` to the mesh count are all zero.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct DrawArgs {
    /// The mesh's, copied.
    pub index_count: u32,
    /// `views * visible instances of this mesh`: doubled for stereo so that
    /// `instance_index >> 1` is the slot in the visible list and `& 1` the eye.
    pub instance_count: u32,
    /// The mesh's, copied.
    pub first_index: u32,
    /// The mesh's, copied.
    pub base_vertex: i32,
    /// `views * offset of this mesh's first visible instance in the visible list`.
    pub first_instance: u32,
}

/// The scene as culling sees it: instances grouped by mesh, each in its place
/// ([`Places`]: ascending id within a mesh when laid out, vacant places where removed
/// instances were and inserted ones will go).
/// With this order one prefix sum over visibility flags gives every visible instance its
/// slot, already grouped by draw and in place order: the contract falls out of the
/// storage order.
#[derive(Clone, Debug, PartialEq)]
pub struct CullLayout {
    /// World bounding spheres (center, radius) in cull order: what the GPU reads
    /// ([`CullLayout::VACANT_SPHERE`] at vacant places).
    pub spheres: Vec<Vec4>,
    /// The same spheres as columns (x, y, z, -radius), for the CPU culler: its plane
    /// tests vectorize over columns. CPU memory only.
    pub columns: [Vec<f32>; 4],
    /// Instance id at each cull position ([`CullLayout::VACANT`] at vacant places).
    pub order: Vec<u32>,
    /// Cull position of each instance id ([`CullLayout::VACANT`] for vacant slots):
    /// where a moved instance's sphere goes.
    pub positions: Vec<u32>,
    /// Mesh of each cull position: which levels of detail it has.
    pub mesh_of: Vec<u32>,
    /// Per mesh: its index range, its range of the cull order and its bin.
    pub meshes: Vec<MeshRecord>,
    /// The material bins the meshes' draws are grouped by.
    pub bins: Bins,
    /// [`MAX_LODS`] per mesh.
    pub lods: Vec<LodRecord>,
    /// Each mesh's local bounding sphere (center, radius): the moves scatter makes a
    /// moved instance's world center from it.
    pub mesh_bounds: Vec<Vec4>,
}

impl CullLayout {
    /// A vacant place's slot and a vacant slot's position.
    pub const VACANT: u32 = Places::VACANT;

    /// Each material bin's range of a draws buffer with `levels` levels of detail per
    /// mesh, bins in order, packed from entry 0: a bin's meshes times the levels, or
    /// for a blended bin the places of its meshes (a draw per visible instance).
    pub fn bin_ranges(&self, levels: u32) -> Vec<BinRange> {
        let mut first = 0;
        (self.bins.kinds.iter().enumerate())
            .map(|(b, &kind)| {
                let members = self.meshes.iter().filter(|m| m.bin == b as u32);
                let capacity = match kind.alpha {
                    BinKind::Blend => members.map(|m| m.cull_count).sum(),
                    _ => members.count() as u32 * levels,
                };
                let range = BinRange {
                    kind,
                    first,
                    capacity,
                };
                first += capacity;
                range
            })
            .collect()
    }

    /// A vacant place's sphere: its radius of minus infinity fails every plane test
    /// (GPU and CPU alike) and adds nothing to a coarse block's bounds.
    pub const VACANT_SPHERE: Vec4 = Vec4::new(0.0, 0.0, 0.0, f32::NEG_INFINITY);

    /// `scene` laid out tight ([`Places::tight`]).
    pub fn new(scene: &Scene) -> CullLayout {
        CullLayout::with_places(scene, &Places::tight(scene))
    }

    /// `scene` with its instances at `places`: O(places + meshes).
    pub fn with_places(scene: &Scene, places: &Places) -> CullLayout {
        let order = places.slots().to_vec();
        let spheres: Vec<Vec4> = order
            .iter()
            .map(|&slot| match slot {
                Places::VACANT => CullLayout::VACANT_SPHERE,
                _ => scene.world_sphere(&scene.instances[slot as usize]),
            })
            .collect();
        let mut positions = places.of_slots().to_vec();
        positions.resize(scene.instances.len(), CullLayout::VACANT);
        let mut mesh_of = Vec::with_capacity(order.len());
        let bins = Bins::of(scene);
        let meshes = scene
            .meshes
            .iter()
            .enumerate()
            .map(|(m, mesh)| {
                let (cull_start, cull_count) = places.range(m as u32);
                mesh_of.resize(mesh_of.len() + cull_count as usize, m as u32);
                MeshRecord {
                    first_index: mesh.first_index,
                    index_count: mesh.index_count,
                    base_vertex: mesh.base_vertex,
                    cull_start,
                    cull_count,
                    bin: bins.of_mesh[m],
                }
            })
            .collect();
        let column = |f: fn(&Vec4) -> f32| spheres.iter().map(f).collect();
        CullLayout {
            columns: [
                column(|s| s.x),
                column(|s| s.y),
                column(|s| s.z),
                column(|s| -s.w),
            ],
            spheres,
            order,
            positions,
            mesh_of,
            meshes,
            bins,
            lods: scene.meshes.iter().flat_map(lod_records).collect(),
            mesh_bounds: scene.meshes.iter().map(|m| m.bounds).collect(),
        }
    }

    /// Replaces the sphere at cull position `at` (an instance moved).
    pub fn set_sphere(&mut self, at: u32, sphere: Vec4) {
        let at = at as usize;
        self.spheres[at] = sphere;
        let [x, y, z, minus_r] = &mut self.columns;
        (x[at], y[at], z[at], minus_r[at]) = (sphere.x, sphere.y, sphere.z, -sphere.w);
    }

    /// Applies a place edit: `slot` (or [`CullLayout::VACANT`]) with `sphere` at `place`.
    pub fn set_place(&mut self, (place, slot, sphere): (u32, u32, Vec4)) {
        self.order[place as usize] = slot;
        if slot != CullLayout::VACANT {
            if self.positions.len() <= slot as usize {
                self.positions.resize(slot as usize + 1, CullLayout::VACANT);
            }
            self.positions[slot as usize] = place;
        }
        self.set_sphere(place, sphere);
    }
}

fn lod_records(mesh: &Mesh) -> [LodRecord; MAX_LODS] {
    std::array::from_fn(|level| match level {
        0 => LodRecord {
            first_index: mesh.first_index,
            index_count: mesh.index_count,
            error_sq: 0.0,
        },
        _ => match mesh.lods.get(level - 1) {
            Some(l) => LodRecord {
                first_index: l.first_index,
                index_count: l.index_count,
                error_sq: l.error * l.error,
            },
            None => LodRecord {
                first_index: mesh.first_index,
                index_count: mesh.index_count,
                error_sq: f32::INFINITY,
            },
        },
    })
}

/// The level of detail of a sphere seen from `viewer`: how many of its mesh's coarser
/// levels pass `d * d > error_sq * lod_scale * r * r` (errors ascend with the level).
/// `wgsl/shared/cull_math.wgsl`'s `lod_level` does the same operations in the same order.
pub fn lod_level(sphere: Vec4, viewer: glam::Vec3, lods: &[LodRecord], lod_scale: f32) -> u32 {
    let (dx, dy, dz) = (
        sphere.x - viewer.x,
        sphere.y - viewer.y,
        sphere.z - viewer.z,
    );
    let d2 = dx * dx + dy * dy + dz * dz;
    let r2 = sphere.w * sphere.w;
    let mut level = 0;
    for lod in &lods[1..] {
        if d2 > lod.error_sq * lod_scale * r2 {
            level += 1;
        }
    }
    level
}

/// Every instance's record, in slot order (generation 0: see
/// [`crate::live::LiveScene::instance_records`]).
pub fn instance_records(scene: &Scene) -> Vec<InstanceRecord> {
    scene.instances.iter().map(instance_record).collect()
}

/// The record the GPU reads for `inst` (generation 0).
pub fn instance_record(inst: &Instance) -> InstanceRecord {
    InstanceRecord {
        world_from_local: crate::scene::affine_rows(&inst.world_from_local),
        color: pack_unorm4x8(inst.color),
        mesh: inst.mesh,
        spin: inst.animation.spin,
        bob: inst.animation.bob,
        material: inst.material.unwrap_or(InstanceRecord::MESH_MATERIAL),
        generation: 0,
        unused: [0; 2],
    }
}

/// Same rounding as WGSL's `pack4x8unorm`.
pub fn pack_unorm4x8(c: Vec4) -> u32 {
    let b = (c.clamp(Vec4::ZERO, Vec4::ONE) * 255.0).round();
    (b.x as u32) | (b.y as u32) << 8 | (b.z as u32) << 16 | (b.w as u32) << 24
}

/// Serializes a uniform (a context, the cull parameters) into the bytes the WGSL
/// struct expects.
pub fn uniform_bytes<T: encase::ShaderType + encase::internal::WriteInto>(value: &T) -> Vec<u8> {
    let mut bytes = Vec::new();
    uniform_bytes_into(value, &mut bytes);
    bytes
}

/// [`uniform_bytes`] into `bytes` (cleared first), whose allocation a caller that lays
/// out many uniforms keeps.
pub fn uniform_bytes_into<T>(value: &T, bytes: &mut Vec<u8>)
where
    T: encase::ShaderType + encase::internal::WriteInto,
{
    bytes.clear();
    encase::UniformBuffer::new(bytes)
        .write(value)
        .expect("writing into a growable Vec cannot fail");
}

/// Serializes storage records (a runtime-sized array) into the bytes the WGSL array
/// expects.
pub fn storage_bytes<T>(values: &[T]) -> Vec<u8>
where
    T: encase::ShaderType + encase::ShaderSize + encase::internal::WriteInto,
{
    let mut buffer = encase::StorageBuffer::new(Vec::new());
    buffer
        .write(values)
        .expect("writing into a growable Vec cannot fail");
    buffer.into_inner()
}
