//! Scenes, as data: meshes packed into one vertex and one index buffer, and instances of
//! them. Where scenes come from sits above this module: [`crate::gltf_import`],
//! [`crate::procedural`], and [`crate::scene_spec`] choosing between them by name.
//!
//! An instance's id is its index in [`Scene::instances`]. For glTF files the order is
//! defined in `gltf_import`; for procedural scenes it is generation order.

use bytemuck::{Pod, Zeroable};
use glam::{Affine3A, Mat4, Vec3, Vec4};

mod camera;
mod material;

pub use camera::{Camera, Projection};
pub use material::{AlphaMode, Encoding, Material, SecondUv, Shading, Texture};

/// One vertex as the draw pipeline reads it (`VertexInput` in `wgsl/shared/decode.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct Vertex {
    /// Local space, meters.
    pub position: [f32; 3],
    /// Local space, not necessarily unit length.
    pub normal: [f32; 3],
    /// Texture coordinates: the set the material's textures read, or the first of the
    /// two sets a material reads ([`Material::second_uv`] says which slots read
    /// `uv1`).
    pub uv: [f32; 2],
    /// Index into [`Scene::materials`]. Per vertex because glTF gives each primitive (our
    /// mesh) one material: the vertex stage then needs no extra load to find it.
    pub material: u32,
    /// Local tangent (xyz, along +u of `uv`) and handedness (w: the bitangent is
    /// `w * cross(normal, tangent)`), as signed normalized bytes: what normal maps need,
    /// in 4 bytes (8-bit normal maps resolve no finer than the byte's 1/127).
    pub tangent: [i8; 4],
    /// The second set of texture coordinates, for materials whose textures read two
    /// (glTF's `TEXCOORD_1` beside `TEXCOORD_0`, say); zero where none is read.
    pub uv1: [f32; 2],
}

impl Vertex {
    /// An untextured vertex of material 0, its tangent any unit vector across `normal`.
    pub fn new(position: Vec3, normal: Vec3) -> Vertex {
        let across = normal.normalize_or(Vec3::Y).any_orthonormal_vector();
        Vertex {
            position: position.into(),
            normal: normal.into(),
            uv: [0.0; 2],
            material: 0,
            tangent: pack_snorm8(across.extend(1.0)),
            uv1: [0.0; 2],
        }
    }

    /// The tangent as the vertex stage reads it (`Snorm8x4`).
    pub fn tangent(&self) -> Vec4 {
        Vec4::from_array(self.tangent.map(|c| (c as f32 / 127.0).max(-1.0)))
    }
}

/// `v` (each component in -1..=1) as signed normalized bytes, rounded to nearest.
pub fn pack_snorm8(v: Vec4) -> [i8; 4] {
    v.to_array()
        .map(|c| (c.clamp(-1.0, 1.0) * 127.0).round() as i8)
}

/// A mesh's slice of the shared buffers and its local bounding sphere.
///
/// Triangles are front-facing when counter-clockwise as seen after the instance's
/// transform, and back faces are culled. A surface seen from both sides lists its
/// triangles in both windings ([`both_windings`]); an instance whose transform mirrors
/// (negative determinant) needs a mesh with the winding reversed
/// ([`Scene::add_mirrored_mesh`]).
/// The glTF import does both (`doubleSided` materials, mirroring nodes).
#[derive(Clone, Debug, PartialEq)]
pub struct Mesh {
    /// As the file names it (or generated).
    pub name: String,
    /// First index in [`Scene::indices`].
    pub first_index: u32,
    /// Its indices (three per triangle).
    pub index_count: u32,
    /// Added to each index.
    pub base_vertex: i32,
    /// Local-space bounding sphere: center in xyz, radius in w.
    pub bounds: Vec4,
    /// Coarser levels of detail, finest first (the mesh itself is level 0), made with
    /// meshoptimizer when the mesh is added; shares the mesh's vertices.
    pub lods: Vec<Lod>,
}

/// A coarser level of a mesh: its triangles, and how far they stray from the mesh's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lod {
    /// First index in [`Scene::indices`].
    pub first_index: u32,
    /// Its indices.
    pub index_count: u32,
    /// meshoptimizer's error, as a fraction of the mesh's bounding radius.
    pub error: f32,
}

/// Levels of detail per mesh, the mesh itself included.
pub const MAX_LODS: usize = 4;

/// One placed copy of a mesh: what culling tests and a draw draws.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Instance {
    /// Local to world.
    pub world_from_local: Affine3A,
    /// Index into [`Scene::meshes`] ([`Instance::VACANT_MESH`] in a vacant slot).
    pub mesh: u32,
    /// Linear RGBA.
    pub color: Vec4,
    /// The instance's own material in place of its mesh's (an index into
    /// [`Scene::materials`]), or `None`. It must draw with the mesh's pipeline (the same
    /// [`crate::bins::Bin`]: alpha mode and shading), since draws are grouped by mesh;
    /// what may differ is the data (textures, cutoff, factors).
    pub material: Option<u32>,
    /// Motion the GPU evaluates from the frame context's time, with no CPU work per frame.
    pub animation: Animation,
}

impl Instance {
    /// The mesh id of a vacant slot of a [`crate::live::LiveScene`], which culling
    /// skips.
    pub const VACANT_MESH: u32 = u32::MAX;
}

/// Per-instance motion, evaluated in the vertex shader (`wgsl/shared/draw_common.wgsl`)
/// from the frame's time `t` in seconds: the mesh turns about its local +Y axis (through
/// the local origin) by `spin * t` radians, then is placed by `world_from_local`, then
/// lifted along world +Y by `bob * sin(pi * t)` meters (a two-second period). Culling
/// uses a sphere that holds every pose ([`Scene::world_sphere`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Animation {
    /// Radians per second about the local +Y axis.
    pub spin: f32,
    /// Amplitude in meters along world +Y.
    pub bob: f32,
}

impl Animation {
    /// A still instance.
    pub const NONE: Animation = Animation {
        spin: 0.0,
        bob: 0.0,
    };
}

/// What is drawn, as data: meshes in shared buffers, instances, materials, textures.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    /// Every mesh's vertices.
    pub vertices: Vec<Vertex>,
    /// Every mesh's indices, levels of detail included.
    pub indices: Vec<u32>,
    /// The meshes, by id.
    pub meshes: Vec<Mesh>,
    /// The instances, by id.
    pub instances: Vec<Instance>,
    /// May be empty: material 0 is then untextured.
    pub materials: Vec<Material>,
    /// Base color images, by index.
    pub textures: Vec<Texture>,
    /// Node animations and the instances they move (by the ids instances have here):
    /// posed once per frame ([`crate::pose`]); empty for a still scene.
    pub posing: crate::pose::Posing,
    /// Skinned instances, moved by posed nodes ([`crate::skin`]); empty without.
    pub skins: crate::skin::Skins,
    /// Morphed meshes, moved by their targets' weights ([`crate::morph`]); empty
    /// without.
    pub morphs: crate::morph::Morphs,
    /// Punctual lights ([`crate::lights`]), shaded through each display's clusters.
    pub lights: Vec<crate::lights::Light>,
    /// The file's cameras, in node order; empty for generated scenes.
    pub cameras: Vec<Camera>,
    /// Whether `lights` are in physical units (lux, candela), as a file's
    /// `KHR_lights_punctual` are: `--exposure auto` meters them
    /// ([`crate::exposure::metered_ev100`]). Generated lamps are in our units, lit for
    /// unit exposure.
    pub physical_lights: bool,
}

impl Scene {
    /// Poses the instances its node animations move at `time` seconds (what `render
    /// --time` draws; a live scene poses with [`crate::live::LiveScene::pose`]), and
    /// sets its morphs' weights to that time's (the renderer samples its own at each
    /// frame's time, in `prepare`).
    pub fn pose(&mut self, time: f32) {
        let posed = self.posed(time);
        self.place(posed);
        self.morphs.set_time(time);
    }

    /// Moves each of `posed`'s instances to its transform.
    fn place(&mut self, posed: Vec<(u32, Affine3A)>) {
        for (instance, world) in posed {
            if let Some(instance) = self.instances.get_mut(instance as usize) {
                instance.world_from_local = world;
            }
        }
    }

    /// Whether it has animations that move something (otherwise every time poses alike).
    pub fn is_animated(&self) -> bool {
        let moved = !self.posing.instances.is_empty() || !self.skins.is_empty();
        !self.posing.clips.is_empty() && moved
    }

    /// Poses the node animations and skins at `time`: writes the skins' joint matrices
    /// and returns each posed instance (node and skinned) with its world transform.
    pub fn posed(&mut self, time: f32) -> Vec<(u32, Affine3A)> {
        let worlds = self.posing.node_worlds(time);
        crate::pose::place_lights(&self.posing.lights, &worlds, &mut self.lights);
        let nodes = self.posing.instance_transforms_in(&worlds);
        let mut posed: Vec<(u32, Affine3A)> =
            (self.posing.instances.iter().map(|i| i.instance).zip(nodes)).collect();
        posed.extend(self.skins.set_poses(&self.skins.poses(&worlds)));
        posed
    }

    /// Poses the skins alone by the nodes at rest (no clip applied), leaving every other
    /// instance where it was placed: what an imported skinned scene is drawn in until a
    /// frame poses it.
    pub fn pose_skins_at_rest(&mut self) {
        let poses = self.skins.poses(&self.posing.rest_worlds());
        let posed = self.skins.set_poses(&poses);
        self.place(posed);
    }

    /// Triangles of every instance at its finest level: what a frame could draw.
    pub fn triangles(&self) -> u64 {
        (self.instances.iter())
            .filter_map(|i| self.meshes.get(i.mesh as usize))
            .map(|m| (m.index_count / 3) as u64)
            .sum()
    }

    /// Removes instances whose transform, animation or world bounding sphere is not
    /// finite (NaN or infinite entries): culling cannot place them, and a NaN sphere would
    /// be culled differently by different hardware. Every other instance keeps its order; ids are
    /// renumbered. Returns how many were dropped.
    pub fn drop_non_finite_instances(&mut self) -> usize {
        let before = self.instances.len();
        let meshes = &self.meshes;
        let kept: Vec<bool> = (self.instances.iter())
            .map(|inst| {
                let finite = Mat4::from(inst.world_from_local).is_finite()
                    && inst.animation.spin.is_finite()
                    && inst.animation.bob.is_finite();
                finite && world_sphere_of(meshes, inst).is_finite()
            })
            .collect();
        let mut kept_flags = kept.iter();
        self.instances
            .retain(|_| *kept_flags.next().unwrap_or(&false));
        self.posing.keep_instances(&kept);
        self.skins.keep_instances(&kept);
        before - self.instances.len()
    }

    /// Appends a mesh and returns its id. The bounding sphere is centered on the
    /// vertices' box, which is tight enough for culling and cheap to compute.
    pub fn add_mesh(
        &mut self,
        name: impl Into<String>,
        vertices: &[Vertex],
        indices: &[u32],
    ) -> u32 {
        let bounds = bounding_sphere(vertices);
        let mut mesh = Mesh {
            name: name.into(),
            first_index: self.indices.len() as u32,
            index_count: indices.len() as u32,
            base_vertex: self.vertices.len() as i32,
            bounds,
            lods: Vec::new(),
        };
        self.vertices.extend_from_slice(vertices);
        self.indices.extend_from_slice(indices);
        for (level, error) in lod_chain(vertices, indices, bounds.w) {
            mesh.lods.push(Lod {
                first_index: self.indices.len() as u32,
                index_count: level.len() as u32,
                error,
            });
            self.indices.extend(level);
        }
        self.meshes.push(mesh);
        self.meshes.len() as u32 - 1
    }

    /// Appends a twin of mesh `id` with its triangles' winding reversed, sharing its
    /// vertices, and returns its id: the mesh for instances whose transform mirrors.
    pub fn add_mirrored_mesh(&mut self, id: u32) -> u32 {
        let mesh = self.meshes[id as usize].clone();
        let mut reversed = |first: u32, count: u32| {
            let (first, count) = (first as usize, count as usize);
            let indices = reversed_winding(&self.indices[first..first + count]);
            let at = self.indices.len() as u32;
            self.indices.extend(indices);
            at
        };
        let twin = Mesh {
            name: format!("{} (mirrored)", mesh.name),
            first_index: reversed(mesh.first_index, mesh.index_count),
            lods: mesh
                .lods
                .iter()
                .map(|l| Lod {
                    first_index: reversed(l.first_index, l.index_count),
                    ..*l
                })
                .collect(),
            ..mesh
        };
        self.meshes.push(twin);
        self.meshes.len() as u32 - 1
    }

    /// The scene's bounds as one sphere (center, radius) that holds every instance's
    /// world sphere ([`Scene::world_sphere`]) as placed now; `None` without instances.
    pub fn bounds(&self) -> Option<Vec4> {
        enclosing_sphere(self.instances.iter().map(|i| self.world_sphere(i)))
    }

    /// The instance's world bounding sphere: the local center transformed, the radius
    /// scaled by the largest axis scale (conservative under non-uniform scale), grown to
    /// hold every pose of its [`Animation`] (a spinning mesh's points stay within twice
    /// the local center's distance from the spin axis of where they start; a bob within
    /// its amplitude), and by [`crate::frustum::ROUNDING_SLACK`] of its magnitude so
    /// rounding never culls it.
    pub fn world_sphere(&self, instance: &Instance) -> Vec4 {
        world_sphere_of(&self.meshes, instance)
    }
}

/// The scene's bounds as one sphere (center, radius) holding every instance's world
/// sphere: centered on the box around them, as wide as the farthest one reaches.
/// `None` for a scene without instances.
fn enclosing_sphere(spheres: impl Iterator<Item = Vec4> + Clone) -> Option<Vec4> {
    let (lo, hi) = spheres.clone().fold(None, |acc: Option<(Vec3, Vec3)>, s| {
        let (c, r) = (s.truncate(), s.w);
        Some(match acc {
            None => (c - r, c + r),
            Some((lo, hi)) => (lo.min(c - r), hi.max(c + r)),
        })
    })?;
    let center = (lo + hi) * 0.5;
    let radius = spheres
        .map(|s| center.distance(s.truncate()) + s.w)
        .fold(0.0, f32::max);
    Some(center.extend(radius))
}

fn world_sphere_of(meshes: &[Mesh], instance: &Instance) -> Vec4 {
    let local = meshes[instance.mesh as usize].bounds;
    let m = instance.world_from_local.matrix3;
    let scale_sq = m
        .x_axis
        .length_squared()
        .max(m.y_axis.length_squared())
        .max(m.z_axis.length_squared());
    let center = transform_center(&instance.world_from_local, local.truncate());
    let animation = instance.animation;
    let orbit = if animation.spin == 0.0 {
        0.0
    } else {
        2.0 * local.x.hypot(local.z)
    };
    let radius = (local.w + orbit) * scale_sq.sqrt() + animation.bob.abs();
    let slack = crate::frustum::ROUNDING_SLACK * (center.abs().element_sum() + radius);
    center.extend(radius + slack)
}

/// The rows of the 3x4 affine `m` (`world = rows * vec4(local, 1)`), as instance
/// records, move edits and the pose pass's tables hold a transform.
pub fn affine_rows(m: &Affine3A) -> [[f32; 4]; 3] {
    let (x, y, z, t) = (
        m.matrix3.x_axis,
        m.matrix3.y_axis,
        m.matrix3.z_axis,
        m.translation,
    );
    [
        [x.x, y.x, z.x, t.x],
        [x.y, y.y, z.y, t.y],
        [x.z, y.z, z.z, t.z],
    ]
}

/// `m` applied to point `p`, row by row, each `x * p.x + y * p.y + z * p.z + t` summed
/// left to right without fma: the CPU twin of the moves scatter's center
/// (`wgsl/scatter_moves.wgsl`), so that both make the same world sphere.
pub fn transform_center(m: &Affine3A, p: Vec3) -> Vec3 {
    let (x, y, z, t) = (
        m.matrix3.x_axis,
        m.matrix3.y_axis,
        m.matrix3.z_axis,
        m.translation,
    );
    Vec3::from_array(std::array::from_fn(|i| {
        x[i] * p.x + y[i] * p.y + z[i] * p.z + t[i]
    }))
}

fn reversed_winding(indices: &[u32]) -> Vec<u32> {
    indices
        .chunks_exact(3)
        .flat_map(|t| [t[0], t[2], t[1]])
        .collect()
}

/// The triangles of `indices` in both windings: a surface drawn from either side.
pub fn both_windings(indices: &[u32]) -> Vec<u32> {
    let mut both = indices.to_vec();
    both.extend(reversed_winding(indices));
    both
}

/// The largest error a level may have, as a fraction of the mesh's bounding radius.
const MAX_LOD_ERROR: f32 = 0.25;

/// Up to [`MAX_LODS`] - 1 coarser index lists of a mesh, each about a quarter of the
/// one before, with their errors relative to `radius`; stops where meshoptimizer can no
/// longer halve the triangles within [`MAX_LOD_ERROR`]. Vertices are welded by position
/// first, so that UV and normal seams do not read as borders that must stay. A surface
/// listed in both windings ([`both_windings`]) is simplified one side at a time: welded,
/// its two sides close every open edge, so its borders would collapse freely (an open
/// tube fell to four triangles).
fn lod_chain(vertices: &[Vertex], indices: &[u32], radius: f32) -> Vec<(Vec<u32>, f32)> {
    let (front, back) = indices.split_at(indices.len() / 2);
    let two_sided = !indices.is_empty() && reversed_winding(front) == back;
    let side = if two_sided { front } else { indices };
    let chain = one_sided_lod_chain(vertices, side, radius);
    if !two_sided {
        return chain;
    }
    chain
        .into_iter()
        .map(|(level, error)| (both_windings(&level), error))
        .collect()
}

fn one_sided_lod_chain(vertices: &[Vertex], indices: &[u32], radius: f32) -> Vec<(Vec<u32>, f32)> {
    let Ok(adapter) =
        meshopt::VertexDataAdapter::new(bytemuck::cast_slice(vertices), size_of::<Vertex>(), 0)
    else {
        return Vec::new();
    };
    let weld = meshopt::generate_position_remap(&adapter);
    let welded: Vec<u32> = indices.iter().map(|&i| weld[i as usize]).collect();
    let mut chain: Vec<(Vec<u32>, f32)> = Vec::new();
    let mut previous = indices.len();
    while chain.len() + 1 < MAX_LODS && previous >= 4 * 3 * 8 {
        let target = (previous / 4).next_multiple_of(3);
        let mut error = 0.0;
        let options = meshopt::SimplifyOptions::ErrorAbsolute;
        let cap = MAX_LOD_ERROR * radius;
        let level = meshopt::simplify(&welded, &adapter, target, cap, options, Some(&mut error));
        if level.is_empty() || 2 * level.len() > previous {
            break;
        }
        previous = level.len();
        chain.push((level, error / radius.max(f32::MIN_POSITIVE)));
    }
    chain
}

fn bounding_sphere(vertices: &[Vertex]) -> Vec4 {
    sphere_around(|| vertices.iter().map(|v| Vec3::from(v.position))).unwrap_or(Vec4::ZERO)
}

/// The sphere (xyz center, w radius) around the points `points()` yields, centered on
/// their box, which is tight enough for culling and cheap; `None` for no points.
pub fn sphere_around<I: Iterator<Item = Vec3>>(points: impl Fn() -> I) -> Option<Vec4> {
    let first = points().next()?;
    let (min, max) = points().fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p)));
    let center = 0.5 * (min + max);
    let radius = points().map(|p| p.distance(center)).fold(0.0, f32::max);
    // Rounding in the distance can leave the farthest point a hair outside.
    Some(center.extend(radius * (1.0 + 1e-6)))
}
