//! glTF 2.0 / GLB import into a [`Scene`].
//!
//! Instance ids: the default scene's nodes (the first scene when none is the default)
//! are visited depth-first, children in order; within a node, its mesh's primitives in
//! order; within a primitive, the `EXT_mesh_gpu_instancing` copies in order. One mesh
//! record per glTF primitive, shared by every node that uses that mesh.

use std::collections::{HashMap, HashSet};
use std::path::Path;

use attributes::check_accessor;
use glam::{Affine3A, Mat4, Quat, Vec3, Vec4};
use gltf::accessor::{DataType, Dimensions};
use gltf::buffer::Data;
use gltf::{Document, Semantic};

use crate::error::{Error, Result};
use crate::pose::NodeInstance;
use crate::scene::{Animation, Instance, Scene, Vertex, both_windings};

mod animations;
mod attributes;
mod buffers;
mod cameras;
pub mod extensions;
mod lights;
mod materials;
mod morphs;
mod preconditions;
mod skins;

use materials::check_images;

const INSTANCING: &str = "EXT_mesh_gpu_instancing";

/// The scene of the glTF or GLB file at `path`: its default scene's nodes, meshes,
/// instances, materials and textures; malformed input is an error naming it.
pub fn import(path: &Path) -> Result<Scene> {
    let bytes = std::fs::read(path).map_err(|e| Error::Scene {
        path: path.into(),
        message: e.to_string(),
    })?;
    import_bytes(&bytes, path.parent(), path)
}

/// The extensions the glTF or GLB file at `path` names, and whether the importer reads
/// each (what `info --scene` lists).
pub fn extension_uses(path: &Path) -> Result<Vec<extensions::ExtensionUse>> {
    let fail = |message: String| Error::Scene {
        path: path.into(),
        message,
    };
    let bytes = std::fs::read(path).map_err(|e| fail(e.to_string()))?;
    let raw = gltf::Gltf::from_slice_without_validation(&bytes)
        .map_err(|e| fail(format!("not valid glTF: {e}")))?;
    Ok(extensions::uses(raw.document.as_json()))
}

/// Imports glTF or GLB bytes; external buffers resolve against `base`, and errors
/// name `origin`.
pub fn import_bytes(bytes: &[u8], base: Option<&Path>, origin: &Path) -> Result<Scene> {
    let fail = |message: String| Error::Scene {
        path: origin.into(),
        message,
    };
    let gltf = parse(bytes).map_err(|e| fail(format!("not valid glTF: {e}")))?;
    let buffers = buffers::load(&gltf.document, base, gltf.blob.clone())
        .map_err(|e| fail(format!("buffer: {e}")))?;
    let unread: Vec<_> = (extensions::uses(gltf.document.as_json()).into_iter())
        .filter(|e| !e.read)
        .map(|e| e.name)
        .collect();
    if !unread.is_empty() {
        log::warn!(
            "{}: uses extensions stereocull does not read (drawn without them): {}",
            origin.display(),
            unread.join(", ")
        );
    }
    check_images(&gltf.document, base).map_err(&fail)?;
    let mut importer = Importer {
        document: &gltf.document,
        buffers: &buffers,
        scene: Scene::default(),
        primitive_mesh: HashMap::new(),
        visited: HashSet::new(),
        mirrored: HashMap::new(),
        materials: HashMap::new(),
        textures: HashMap::new(),
        base,
        skipped: 0,
        animated: (animations::targets(&gltf.document).into_iter())
            .chain(skins::joints(&gltf.document))
            .collect(),
        pose_nodes: HashMap::new(),
        pending_skins: Vec::new(),
        pending_morphs: Vec::new(),
    };
    let root = gltf
        .document
        .default_scene()
        .or_else(|| gltf.document.scenes().next())
        .ok_or_else(|| fail("the file has no scene".into()))?;
    for node in root.nodes() {
        importer.visit(node).map_err(&fail)?;
    }
    importer.read_clips().map_err(&fail)?;
    let morphed_skins = importer.finish_morphs();
    importer.resolve_skins(&morphed_skins).map_err(&fail)?;
    if importer.skipped > 0 {
        log::warn!(
            "{}: skipped {} non-triangle primitive instance(s)",
            origin.display(),
            importer.skipped
        );
    }
    Ok(importer.scene)
}

/// `gltf::Gltf::from_slice`, with the inputs that make gltf 1.4 panic turned into errors
/// (found by the `gltf_import` fuzz target; regressions in
/// `fuzz/regressions/gltf_import/`): a GLB header length shorter than the header (an
/// unchecked subtraction), a POSITION accessor index out of range (its validator
/// indexes that accessor unchecked), and what the crate's accessors unwrap unvalidated
/// ([`preconditions`]).
fn parse(bytes: &[u8]) -> Step<gltf::Gltf> {
    const GLB_HEADER: u32 = 12;
    if let Some(length) = bytes.strip_prefix(b"glTF").and_then(|b| b.get(4..8)) {
        let length = u32::from_le_bytes([length[0], length[1], length[2], length[3]]);
        if length < GLB_HEADER {
            return Err(format!(
                "GLB header: length {length} is shorter than the header"
            ));
        }
    }
    let raw = gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| e.to_string())?;
    let mut json = raw.document.into_json();
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let position = primitive
                .attributes
                .get(&gltf::json::validation::Checked::Valid(Semantic::Positions));
            if let Some(index) = position.filter(|i| i.value() >= json.accessors.len()) {
                return Err(format!(
                    "meshes[{m}].primitives[{p}].attributes.POSITION: accessor {} does not exist",
                    index.value()
                ));
            }
        }
    }
    preconditions::check(&json)?;
    extensions::check_required(&mut json)?;
    let document = gltf::Document::from_json(json).map_err(|e| e.to_string())?;
    Ok(gltf::Gltf {
        document,
        blob: raw.blob,
    })
}

struct Importer<'a> {
    document: &'a Document,
    buffers: &'a [Data],
    scene: Scene,
    /// (glTF mesh, primitive) -> our mesh id, so shared meshes share one record.
    primitive_mesh: HashMap<(usize, usize), Option<u32>>,
    /// Nodes already placed: glTF nodes form trees, and a node met twice (a cycle, or
    /// two parents) would otherwise recurse forever or multiply instances.
    visited: HashSet<usize>,
    /// Mesh id -> its reversed-winding twin, for nodes that mirror.
    mirrored: HashMap<u32, u32>,
    /// glTF material (None: the default material) -> our material id.
    materials: HashMap<Option<usize>, u32>,
    /// (glTF image, how it is read) -> our texture id.
    textures: HashMap<(usize, crate::scene::Encoding), u32>,
    /// Where external images resolve.
    base: Option<&'a Path>,
    skipped: usize,
    /// The nodes an animation channel targets, and the skins' joints: posed nodes.
    animated: HashSet<usize>,
    /// glTF node -> its index in `scene.posing.nodes`, for the animated nodes (and
    /// joints) and their descendants.
    pose_nodes: HashMap<usize, u32>,
    /// Skinned instances whose joints are resolved once every node is placed.
    pending_skins: Vec<skins::PendingSkin>,
    /// Morphs whose bounds grow once their animations are read.
    pending_morphs: Vec<morphs::PendingMorph>,
}

type Step<T> = std::result::Result<T, String>;

impl Importer<'_> {
    /// Places `root` and its descendants, depth first in child order (the documented
    /// instance-id order), with an explicit stack: a file may nest nodes deeper than the
    /// thread's stack would allow recursion.
    fn visit(&mut self, root: gltf::Node) -> Step<()> {
        let mut stack = vec![(root, Affine3A::IDENTITY, None)];
        while let Some((node, parent, parent_pose)) = stack.pop() {
            if !self.visited.insert(node.index()) {
                return Err(format!(
                    "nodes[{}] is reached twice (a cycle, or two parents); glTF nodes form trees",
                    node.index()
                ));
            }
            let local = Mat4::from_cols_array_2d(&node.transform().matrix());
            let world = parent * Affine3A::from_mat4(local);
            let pose = self.pose_node(&node, parent, parent_pose);
            self.place_light(&node, world, pose)?;
            self.place_camera(&node, world)?;
            self.place(&node, world, pose)?;
            let children: Vec<_> = node.children().collect();
            stack.extend(children.into_iter().rev().map(|c| (c, world, pose)));
        }
        Ok(())
    }

    fn place(&mut self, node: &gltf::Node, world: Affine3A, pose: Option<u32>) -> Step<()> {
        if let Some(skin) = node.skin() {
            return self.place_skinned(node, skin);
        }
        let Some(mesh) = node.mesh() else {
            return Ok(());
        };
        let copies = self.instancing_copies(node)?;
        for primitive in mesh.primitives() {
            let id = match primitive.morph_targets().len() {
                0 => self.mesh_id(&mesh, &primitive)?,
                _ => self.morphed_mesh_id(node, &mesh, &primitive)?,
            };
            let Some(id) = id else {
                self.skipped += copies.len();
                continue;
            };
            let color = Vec4::from(
                primitive
                    .material()
                    .pbr_metallic_roughness()
                    .base_color_factor(),
            );
            for copy in &copies {
                let world_from_local = world * *copy;
                let mirrored = world_from_local.matrix3.determinant() < 0.0;
                let mesh = match mirrored {
                    false => id,
                    true => self.mirrored_mesh_id(id, &primitive),
                };
                if let Some(node) = pose {
                    self.scene.posing.instances.push(NodeInstance {
                        instance: self.scene.instances.len() as u32,
                        node,
                        node_from_local: *copy,
                    });
                }
                self.scene.instances.push(Instance {
                    world_from_local,
                    mesh,
                    color,
                    material: None,
                    animation: Animation::NONE,
                });
            }
        }
        Ok(())
    }

    /// The node's `EXT_mesh_gpu_instancing` transforms, or one identity copy.
    fn instancing_copies(&self, node: &gltf::Node) -> Step<Vec<Affine3A>> {
        let Some(ext) = node.extension_value(INSTANCING) else {
            return Ok(vec![Affine3A::IDENTITY]);
        };
        let where_ = || format!("node {} {INSTANCING}", node.index());
        let attribute = |name: &str| {
            ext.get("attributes")
                .and_then(|a| a.get(name))
                .and_then(|v| v.as_u64())
        };
        let t: Option<Vec<[f32; 3]>> = attribute("TRANSLATION")
            .map(|i| self.read_floats(i, &where_))
            .transpose()?;
        let r: Option<Vec<[f32; 4]>> = attribute("ROTATION")
            .map(|i| self.read_floats(i, &where_))
            .transpose()?;
        let s: Option<Vec<[f32; 3]>> = attribute("SCALE")
            .map(|i| self.read_floats(i, &where_))
            .transpose()?;
        let lens = [
            t.as_ref().map(Vec::len),
            r.as_ref().map(Vec::len),
            s.as_ref().map(Vec::len),
        ];
        let count = lens.iter().flatten().copied().max().unwrap_or(0);
        if lens.iter().flatten().any(|&l| l != count) {
            return Err(format!("{}: attributes differ in count", where_()));
        }
        Ok((0..count)
            .map(|i| {
                Affine3A::from_scale_rotation_translation(
                    s.as_ref().map_or(Vec3::ONE, |v| Vec3::from(v[i])),
                    r.as_ref()
                        .map_or(Quat::IDENTITY, |v| Quat::from_array(v[i])),
                    t.as_ref().map_or(Vec3::ZERO, |v| Vec3::from(v[i])),
                )
            })
            .collect())
    }

    /// Our mesh id for a primitive, created on first use; `None` for primitives that are
    /// not triangle lists (skipped with a warning).
    fn mesh_id(&mut self, mesh: &gltf::Mesh, primitive: &gltf::Primitive) -> Step<Option<u32>> {
        let key = (mesh.index(), primitive.index());
        if let Some(&id) = self.primitive_mesh.get(&key) {
            return Ok(id);
        }
        let id = if primitive.mode() == gltf::mesh::Mode::Triangles {
            let (vertices, indices) = self.triangles(primitive, key)?;
            let name = format!("{}#{}", mesh.name().unwrap_or("mesh"), primitive.index());
            Some(self.scene.add_mesh(name, &vertices, &indices))
        } else {
            None
        };
        self.primitive_mesh.insert(key, id);
        Ok(id)
    }

    /// A morphed primitive's mesh: the node's own (its copies share it), with its morph;
    /// `None` for primitives that are not triangle lists.
    fn morphed_mesh_id(
        &mut self,
        node: &gltf::Node,
        mesh: &gltf::Mesh,
        primitive: &gltf::Primitive,
    ) -> Step<Option<u32>> {
        if primitive.mode() != gltf::mesh::Mode::Triangles {
            return Ok(None);
        }
        let (id, vertices) = self.own_mesh(node, mesh, primitive)?;
        let base = self.scene.meshes[id as usize].base_vertex as u32;
        let destinations = base..base + vertices.len() as u32;
        self.add_morph((node, primitive), (&vertices, destinations), (id, false))?;
        Ok(Some(id))
    }

    /// A triangle primitive as a mesh of `node`'s own (skinned or morphed: the passes
    /// write its vertices), with the vertices it was read as.
    fn own_mesh(
        &mut self,
        node: &gltf::Node,
        mesh: &gltf::Mesh,
        primitive: &gltf::Primitive,
    ) -> Step<(u32, Vec<Vertex>)> {
        let key = (mesh.index(), primitive.index());
        let (vertices, indices) = self.triangles(primitive, key)?;
        let name = format!(
            "{}#{} of node {}",
            mesh.name().unwrap_or("mesh"),
            primitive.index(),
            node.index()
        );
        Ok((self.scene.add_mesh(name, &vertices, &indices), vertices))
    }

    /// The mesh with reversed winding for mirroring transforms (created on first use), or
    /// the mesh itself when it is double-sided already.
    fn mirrored_mesh_id(&mut self, id: u32, primitive: &gltf::Primitive) -> u32 {
        if primitive.material().double_sided() {
            return id;
        }
        if let Some(&mirrored) = self.mirrored.get(&id) {
            return mirrored;
        }
        let mirrored = self.scene.add_mirrored_mesh(id);
        self.mirrored.insert(id, mirrored);
        mirrored
    }

    fn triangles(
        &mut self,
        primitive: &gltf::Primitive,
        key: (usize, usize),
    ) -> Step<(Vec<Vertex>, Vec<u32>)> {
        let where_ = format!("mesh {} primitive {}", key.0, key.1);
        if let Some(accessor) = primitive.indices() {
            let what = format!("{where_} indices");
            check_accessor(&accessor, accessor.data_type().size(), &what)?;
            let integer = matches!(
                accessor.data_type(),
                DataType::U8 | DataType::U16 | DataType::U32
            );
            if accessor.dimensions() != Dimensions::Scalar || !integer {
                return Err(format!(
                    "{what}: accessors[{}] is {:?} {:?}, not unsigned integer SCALAR",
                    accessor.index(),
                    accessor.dimensions(),
                    accessor.data_type()
                ));
            }
        }
        let attribute = |semantic: Semantic| {
            let what = format!("{where_} {semantic:?}");
            primitive
                .get(&semantic)
                .map(|a| self.floats::<3>(&a, &what))
        };
        let positions: Vec<Vec3> = attribute(Semantic::Positions)
            .ok_or_else(|| format!("{where_}: no POSITION"))??
            .into_iter()
            .map(Vec3::from)
            .collect();
        let buffers = self.buffers;
        let reader = primitive.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
        let indices: Vec<u32> = match reader.read_indices() {
            Some(i) => i.into_u32().collect(),
            None => (0..positions.len() as u32).collect(),
        };
        if let Some(bad) = indices.iter().find(|&&i| i as usize >= positions.len()) {
            return Err(format!(
                "{where_}: index {bad} out of range ({} vertices)",
                positions.len()
            ));
        }
        if !indices.len().is_multiple_of(3) {
            return Err(format!(
                "{where_}: {} indices is not a whole number of triangles",
                indices.len()
            ));
        }
        let normals: Vec<Vec3> = match attribute(Semantic::Normals) {
            Some(n) => n?.into_iter().map(Vec3::from).collect(),
            None => smooth_normals(&positions, &indices),
        };
        if normals.len() != positions.len() {
            return Err(format!("{where_}: NORMAL and POSITION differ in count"));
        }
        let material = self.material_id(&primitive.material())?;
        let [uvs, second] = self.uvs(primitive, &where_, positions.len())?;
        let mut vertices: Vec<Vertex> = (positions.iter().zip(&normals))
            .zip(uvs.into_iter().zip(second))
            .map(|((&p, &n), (uv, uv1))| Vertex {
                uv,
                uv1,
                material,
                ..Vertex::new(p, n)
            })
            .collect();
        self.tangents(primitive, &where_, &mut vertices, &indices)?;
        let indices = match primitive.material().double_sided() {
            true => both_windings(&indices),
            false => indices,
        };
        Ok((vertices, indices))
    }
}

impl Importer<'_> {
    /// The file's TANGENTs (VEC4 of float: xyz and handedness), or, for a material
    /// with a normal map, tangents generated from the coordinates (glTF asks for
    /// MikkTSpace; ours agree on meshes whose uv map does not shear); other vertices
    /// keep theirs, which nothing reads.
    fn tangents(
        &self,
        primitive: &gltf::Primitive,
        where_: &str,
        vertices: &mut [Vertex],
        indices: &[u32],
    ) -> Step<()> {
        let Some(accessor) = primitive.get(&Semantic::Tangents) else {
            if primitive.material().normal_texture().is_some() {
                crate::pbr::generate_tangents(vertices, indices);
            }
            return Ok(());
        };
        let what = format!("{where_} TANGENT");
        let tangents = self.floats::<4>(&accessor, &what)?;
        if tangents.len() != vertices.len() {
            return Err(format!("{what} and POSITION differ in count"));
        }
        if let Some(bad) = tangents.iter().find(|t| !t.iter().all(|c| c.is_finite())) {
            return Err(format!("{what}: {bad:?} is not finite"));
        }
        for (v, t) in vertices.iter_mut().zip(tangents) {
            let t = Vec4::from(t);
            let handedness = if t.w < 0.0 { -1.0 } else { 1.0 };
            v.tangent =
                crate::scene::pack_snorm8(t.truncate().normalize_or_zero().extend(handedness));
        }
        Ok(())
    }
}

/// Area-weighted vertex normals for primitives that carry none.
fn smooth_normals(positions: &[Vec3], indices: &[u32]) -> Vec<Vec3> {
    let mut normals = vec![Vec3::ZERO; positions.len()];
    for t in indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| positions[i as usize]);
        let n = (b - a).cross(c - a);
        for &i in t {
            normals[i as usize] += n;
        }
    }
    normals.iter().map(|n| n.normalize_or(Vec3::Y)).collect()
}
