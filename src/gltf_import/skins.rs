//! glTF skins into [`crate::skin`]: a skinned node's primitives each get a mesh of
//! their own (the skinning pass writes that instance's posed vertices into it), their
//! `JOINTS_0` / `WEIGHTS_0` become rest vertices for the pass, and the skin's joints
//! become posed nodes with their inverse bind matrices and the bounds of what each
//! moves. Malformed skins are errors naming the part.

use glam::{Affine3A, Mat4, Vec3, Vec4};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::util::{ReadJoints, ReadWeights};

use super::{Importer, Step, check_accessor};
use crate::scene::{Animation, Instance, sphere_around};
use crate::skin::{Skin, SkinVertex};

/// A skinned instance read before its joints are placed: its skin, and its vertices'
/// range of the scene's skin vertices.
pub(super) struct PendingSkin {
    skin: usize,
    instance: u32,
    mesh: u32,
    vertices: std::ops::Range<u32>,
}

/// The nodes skins use as joints (they are posed, animated or not).
pub(super) fn joints(document: &gltf::Document) -> Vec<usize> {
    (document.skins())
        .flat_map(|s| s.joints().map(|j| j.index()).collect::<Vec<_>>())
        .collect()
}

impl Importer<'_> {
    /// A skinned node's primitives: each its own mesh and instance (the node's own
    /// transform does not apply: glTF places skinned vertices by their joints).
    pub(super) fn place_skinned(&mut self, node: &gltf::Node, skin: gltf::Skin) -> Step<()> {
        let Some(mesh) = node.mesh() else {
            return Ok(());
        };
        for primitive in mesh.primitives() {
            if primitive.mode() != gltf::mesh::Mode::Triangles {
                self.skipped += 1;
                continue;
            }
            let key = (mesh.index(), primitive.index());
            let (id, vertices) = self.own_mesh(node, &mesh, &primitive)?;
            let where_ = format!("mesh {} primitive {}", key.0, key.1);
            let influences = self.influences(&primitive, &where_, vertices.len())?;
            let joints = skin.joints().count();
            if let Some(j) = influences
                .iter()
                .flat_map(|(j, _)| j)
                .find(|&&j| j as usize >= joints)
            {
                return Err(format!(
                    "{where_} JOINTS_0: joint {j} is past skins[{}]'s {joints} joints",
                    skin.index()
                ));
            }
            let first = self.scene.skins.vertices.len() as u32;
            let base = self.scene.meshes[id as usize].base_vertex as u32;
            for (i, (v, (joints, weights))) in vertices.iter().zip(influences).enumerate() {
                self.scene.skins.vertices.push(SkinVertex {
                    position: v.position,
                    normal: v.normal,
                    tangent: v.tangent,
                    joints,
                    weights,
                    joint_base: 0,
                    destination: base + i as u32,
                });
            }
            let destinations = first..self.scene.skins.vertices.len() as u32;
            self.add_morph((node, &primitive), (&vertices, destinations), (id, true))?;
            let color = Vec4::from(
                primitive
                    .material()
                    .pbr_metallic_roughness()
                    .base_color_factor(),
            );
            self.pending_skins.push(PendingSkin {
                skin: skin.index(),
                instance: self.scene.instances.len() as u32,
                mesh: id,
                vertices: first..self.scene.skins.vertices.len() as u32,
            });
            self.scene.instances.push(Instance {
                world_from_local: Affine3A::IDENTITY,
                mesh: id,
                color,
                material: None,
                animation: Animation::NONE,
            });
        }
        Ok(())
    }

    /// Each vertex's `JOINTS_0` and `WEIGHTS_0` (unsigned byte or short joints; float,
    /// or normalized unsigned byte or short weights), the weights finite and scaled to
    /// sum to 1.
    fn influences(
        &self,
        primitive: &gltf::Primitive,
        where_: &str,
        count: usize,
    ) -> Step<Vec<([u16; 4], [f32; 4])>> {
        let attribute = |semantic: gltf::Semantic, types: &[DataType]| {
            let what = format!("{where_} {semantic:?}");
            let accessor = primitive
                .get(&semantic)
                .ok_or_else(|| format!("{what}: a skinned primitive needs it"))?;
            let fit =
                accessor.dimensions() == Dimensions::Vec4 && types.contains(&accessor.data_type());
            if !fit {
                return Err(format!(
                    "{what}: accessors[{}] holds {:?} {:?}; VEC4 of {types:?} is read",
                    accessor.index(),
                    accessor.dimensions(),
                    accessor.data_type()
                ));
            }
            check_accessor(&accessor, 4 * accessor.data_type().size(), &what)?;
            if accessor.count() != count {
                return Err(format!(
                    "{what}: {} values for {count} vertices",
                    accessor.count()
                ));
            }
            Ok(())
        };
        attribute(gltf::Semantic::Joints(0), &[DataType::U8, DataType::U16])?;
        attribute(
            gltf::Semantic::Weights(0),
            &[DataType::F32, DataType::U8, DataType::U16],
        )?;
        let buffers = self.buffers;
        let reader = primitive.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
        let joints: Vec<[u16; 4]> = reader
            .read_joints(0)
            .map(ReadJoints::into_u16)
            .into_iter()
            .flatten()
            .collect();
        let weights: Vec<[f32; 4]> = reader
            .read_weights(0)
            .map(ReadWeights::into_f32)
            .into_iter()
            .flatten()
            .collect();
        if joints.len() != count || weights.len() != count {
            return Err(format!(
                "{where_}: JOINTS_0 or WEIGHTS_0 could not be read whole"
            ));
        }
        let mut out = Vec::with_capacity(count);
        for (i, (j, w)) in joints.into_iter().zip(weights).enumerate() {
            let sum: f32 = w.iter().sum();
            let usable = w.iter().all(|x| x.is_finite() && *x >= 0.0) && sum > 0.0;
            if !(usable && sum.is_finite()) {
                return Err(format!(
                    "{where_} WEIGHTS_0: vertex {i} has weights {w:?}; they must be finite, not negative, and not all zero"
                ));
            }
            out.push((j, w.map(|x| x / sum)));
        }
        Ok(out)
    }

    /// The skins read while placing nodes, now that every joint is a posed node: their
    /// joints, inverse bind matrices and joints' bounds; then every skin posed at rest
    /// (the node-animated instances keep the file's placement). A morphed skin's
    /// `(mesh, reach)` in `morphed` grows its joints' bounds by that reach, stretched by
    /// each inverse bind matrix (the morph moves rest vertices in the mesh's space).
    pub(super) fn resolve_skins(&mut self, morphed: &[(u32, f32)]) -> Step<()> {
        for pending in std::mem::take(&mut self.pending_skins) {
            let skin = self
                .document
                .skins()
                .nth(pending.skin)
                .ok_or("a skin vanished")?;
            let at = format!("skins[{}]", skin.index());
            let mut joints = Vec::new();
            for node in skin.joints() {
                let posed = self.pose_nodes.get(&node.index()).copied();
                joints.push(posed.ok_or_else(|| {
                    format!(
                        "{at}: joint node {} is not in the scene drawn",
                        node.index()
                    )
                })?);
            }
            let inverse_binds = self.inverse_binds(&skin, joints.len(), &at)?;
            let base = self.scene.skins.joint_matrices.len() as u32;
            self.scene
                .skins
                .joint_matrices
                .extend(std::iter::repeat_n([[0.0; 4]; 3], joints.len()));
            let range = pending.vertices.start as usize..pending.vertices.end as usize;
            let vertices = &mut self.scene.skins.vertices[range];
            for v in vertices.iter_mut() {
                v.joint_base = base;
            }
            let mut joint_bounds = joint_bounds(vertices, &inverse_binds);
            if let Some(&(_, reach)) = morphed.iter().find(|(m, _)| *m == pending.mesh) {
                for (b, ib) in joint_bounds.iter_mut().zip(&inverse_binds) {
                    if b.w >= 0.0 {
                        b.w += reach * super::morphs::bind_stretch(ib);
                    }
                }
            }
            self.scene.skins.skins.push(Skin {
                instance: pending.instance,
                rest_sphere: self.scene.meshes[pending.mesh as usize].bounds,
                joints,
                inverse_binds,
                joint_bounds,
                vertices: pending.vertices,
                joint_base: base,
            });
        }
        self.scene.pose_skins_at_rest();
        Ok(())
    }

    /// The skin's inverse bind matrices (identity without them), at least one per joint.
    fn inverse_binds(&self, skin: &gltf::Skin, joints: usize, at: &str) -> Step<Vec<Affine3A>> {
        let Some(accessor) = skin.inverse_bind_matrices() else {
            return Ok(vec![Affine3A::IDENTITY; joints]);
        };
        let what = format!("{at}.inverseBindMatrices");
        if accessor.dimensions() != Dimensions::Mat4 || accessor.data_type() != DataType::F32 {
            return Err(format!(
                "{what}: accessors[{}] is not MAT4 of float",
                accessor.index()
            ));
        }
        let matrices: Vec<[[f32; 4]; 4]> = self.read(accessor.index() as u64, &|| what.clone())?;
        if matrices.len() < joints {
            return Err(format!(
                "{what}: {} matrices for {joints} joints",
                matrices.len()
            ));
        }
        let affine: Vec<Affine3A> = matrices
            .iter()
            .take(joints)
            .map(|m| Affine3A::from_mat4(Mat4::from_cols_array_2d(m)))
            .collect();
        match affine.iter().position(|m| !Mat4::from(*m).is_finite()) {
            Some(j) => Err(format!("{what}: matrix {j} is not finite")),
            None => Ok(affine),
        }
    }
}

/// Per joint, the sphere in its bind space around the vertices it moves (a weight
/// above 0): the box's center, the farthest vertex, grown for rounding; radius -1 for
/// a joint that moves none.
fn joint_bounds(vertices: &[SkinVertex], inverse_binds: &[Affine3A]) -> Vec<Vec4> {
    (inverse_binds.iter().enumerate())
        .map(|(j, ib)| {
            let moved = || {
                (vertices.iter())
                    .filter(move |v| {
                        (0..4).any(|k| v.weights[k] > 0.0 && usize::from(v.joints[k]) == j)
                    })
                    .map(move |v| ib.transform_point3(Vec3::from(v.position)))
            };
            sphere_around(moved).unwrap_or(Vec4::new(0.0, 0.0, 0.0, -1.0))
        })
        .collect()
}
