//! Scenes: meshes packed into one vertex and one index buffer, and instances of them.
//!
//! An instance's id is its index in [`Scene::instances`]. For glTF files the order is
//! defined in `gltf_import`; for procedural scenes it is generation order.

use std::path::Path;

use bytemuck::{Pod, Zeroable};
use glam::{Affine3A, Mat4, Quat, Vec3, Vec4};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;

use crate::error::{Error, Result};
use crate::shapes::{self, Shape};

/// One vertex as the draw pipeline reads it (`wgsl/draw.wgsl`, locations 0 and 1).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct Vertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
}

impl Vertex {
    pub fn new(position: Vec3, normal: Vec3) -> Vertex {
        Vertex {
            position: position.into(),
            normal: normal.into(),
        }
    }
}

/// A mesh's slice of the shared buffers and its local bounding sphere.
#[derive(Clone, Debug, PartialEq)]
pub struct Mesh {
    pub name: String,
    pub first_index: u32,
    pub index_count: u32,
    pub base_vertex: i32,
    /// Local-space bounding sphere: center in xyz, radius in w.
    pub bounds: Vec4,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Instance {
    pub world_from_local: Affine3A,
    pub mesh: u32,
    /// Linear RGBA.
    pub color: Vec4,
}

#[derive(Clone, Debug, Default)]
pub struct Scene {
    pub vertices: Vec<Vertex>,
    pub indices: Vec<u32>,
    pub meshes: Vec<Mesh>,
    pub instances: Vec<Instance>,
}

/// The scene spec naming the built-in room (`assets/room.glb`).
pub const DEFAULT_SCENE: &str = "default";
/// Meshes a `procedural:N` scene uses when no count is given.
pub const DEFAULT_PROCEDURAL_MESHES: u32 = 8;
/// Seed a `procedural:N` scene uses when none is given.
pub const DEFAULT_PROCEDURAL_SEED: u64 = 1;

impl Scene {
    /// `default` (the built-in room), `procedural:N[:MESHES[:SEED]]`, or a path to a
    /// `.gltf` / `.glb` file.
    /// An empty scene is an error: there would be nothing to cull or draw, and GPU
    /// buffers cannot be empty.
    pub fn load(spec: &str) -> Result<Scene> {
        let scene = match spec.strip_prefix("procedural:") {
            Some(rest) => {
                let (n, meshes, seed) = parse_procedural(spec, rest)?;
                Scene::procedural(n, meshes, seed)
            }
            None if spec == DEFAULT_SCENE => crate::gltf_import::import_bytes(
                crate::default_scene::ROOM_GLB,
                None,
                Path::new("assets/room.glb"),
            )?,
            None => crate::gltf_import::import(Path::new(spec))?,
        };
        let mut scene = scene;
        let dropped = scene.drop_non_finite_instances();
        if dropped > 0 {
            log::warn!("{spec}: dropped {dropped} instance(s) with non-finite transforms");
        }
        if scene.instances.is_empty() {
            return Err(Error::SceneSpec {
                spec: spec.into(),
                message: "the scene has no mesh instances to draw".into(),
            });
        }
        Ok(scene)
    }

    /// Removes instances whose transform or world bounding sphere is not finite (NaN or
    /// infinite entries): culling cannot place them, and a NaN sphere would be culled
    /// differently by different hardware. Every other instance keeps its order; ids are
    /// renumbered. Returns how many were dropped.
    pub fn drop_non_finite_instances(&mut self) -> usize {
        let before = self.instances.len();
        let meshes = &self.meshes;
        self.instances.retain(|inst| {
            let finite = Mat4::from(inst.world_from_local).is_finite();
            finite && world_sphere_of(meshes, inst).is_finite()
        });
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
        let mesh = Mesh {
            name: name.into(),
            first_index: self.indices.len() as u32,
            index_count: indices.len() as u32,
            base_vertex: self.vertices.len() as i32,
            bounds: bounding_sphere(vertices),
        };
        self.vertices.extend_from_slice(vertices);
        self.indices.extend_from_slice(indices);
        self.meshes.push(mesh);
        self.meshes.len() as u32 - 1
    }

    /// The instance's world bounding sphere: the local center transformed, the radius
    /// scaled by the largest axis scale (conservative under non-uniform scale), grown by
    /// [`crate::frustum::ROUNDING_SLACK`] of its magnitude so rounding never culls it.
    pub fn world_sphere(&self, instance: &Instance) -> Vec4 {
        world_sphere_of(&self.meshes, instance)
    }

    /// `n` instances of `mesh_count` built-in meshes scattered in a ball around the
    /// origin (where every preset's viewer stands), at real scale: objects of 0.1 m to
    /// 1.5 m, spread so that density stays near a few per cubic meter at any `n`.
    pub fn procedural(n: u32, mesh_count: u32, seed: u64) -> Scene {
        let mut scene = Scene::default();
        for k in 0..mesh_count.max(1) {
            let Shape { vertices, indices } = shapes::family(k);
            scene.add_mesh(format!("shape{k}"), &vertices, &indices);
        }
        let mut rng = Pcg64Mcg::seed_from_u64(seed);
        let radius = 4.0 + (n as f32).cbrt() * 0.8;
        let center = Vec3::new(0.0, 1.5, 0.0);
        scene.instances = (0..n)
            .map(|_| {
                let offset = random_in_shell(&mut rng, 1.0, radius);
                let rotation = Quat::from_euler(
                    glam::EulerRot::YXZ,
                    rng.random_range(0.0..std::f32::consts::TAU),
                    rng.random_range(-0.5..0.5),
                    0.0,
                );
                let scale = rng.random_range(0.25..1.5);
                Instance {
                    world_from_local: Affine3A::from_scale_rotation_translation(
                        Vec3::splat(scale),
                        rotation,
                        center + offset,
                    ),
                    mesh: rng.random_range(0..scene.meshes.len() as u32),
                    color: Vec4::new(rng.random(), rng.random(), rng.random(), 1.0),
                }
            })
            .collect();
        scene
    }
}

fn world_sphere_of(meshes: &[Mesh], instance: &Instance) -> Vec4 {
    let local = meshes[instance.mesh as usize].bounds;
    let m = instance.world_from_local.matrix3;
    let scale_sq = m
        .x_axis
        .length_squared()
        .max(m.y_axis.length_squared())
        .max(m.z_axis.length_squared());
    let center = instance.world_from_local.transform_point3(local.truncate());
    let radius = local.w * scale_sq.sqrt();
    let slack = crate::frustum::ROUNDING_SLACK * (center.abs().element_sum() + radius);
    center.extend(radius + slack)
}

fn random_in_shell(rng: &mut Pcg64Mcg, inner: f32, outer: f32) -> Vec3 {
    loop {
        let p = Vec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        ) * outer;
        let d = p.length();
        if (inner..=outer).contains(&d) {
            return p;
        }
    }
}

fn bounding_sphere(vertices: &[Vertex]) -> Vec4 {
    let positions = || vertices.iter().map(|v| Vec3::from(v.position));
    let min = positions().fold(Vec3::splat(f32::MAX), Vec3::min);
    let max = positions().fold(Vec3::splat(f32::MIN), Vec3::max);
    if vertices.is_empty() {
        return Vec4::ZERO;
    }
    let center = 0.5 * (min + max);
    let radius = positions().map(|p| p.distance(center)).fold(0.0, f32::max);
    // Rounding in the distance can leave the farthest vertex a hair outside.
    center.extend(radius * (1.0 + 1e-6))
}

fn parse_procedural(spec: &str, rest: &str) -> Result<(u32, u32, u64)> {
    let fail = |message: &str| Error::SceneSpec {
        spec: spec.into(),
        message: format!("{message}; expected procedural:N[:MESHES[:SEED]]"),
    };
    let mut parts = rest.split(':');
    let n = parts
        .next()
        .and_then(|s| s.parse().ok())
        .ok_or_else(|| fail("N is not a count"))?;
    let meshes = match parts.next() {
        Some(s) => s
            .parse()
            .ok()
            .filter(|&m: &u32| m > 0)
            .ok_or_else(|| fail("MESHES is not a positive count"))?,
        None => DEFAULT_PROCEDURAL_MESHES,
    };
    let seed = match parts.next() {
        Some(s) => s.parse().map_err(|_| fail("SEED is not an integer"))?,
        None => DEFAULT_PROCEDURAL_SEED,
    };
    if parts.next().is_some() {
        return Err(fail("too many fields"));
    }
    Ok((n, meshes, seed))
}
