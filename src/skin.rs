//! Skinning, frame-level work after posing: each skinned instance's vertices are moved by
//! its joints (posed nodes, [`crate::pose`]) once per frame, on the GPU
//! (`wgsl/skin.wgsl`), into the instance's own range of the one vertex buffer that every
//! display, both eyes, the shadow pass and the far layer draw from. Never per eye, never
//! per display.
//!
//! Culling a moving body: each joint keeps the sphere (in its bind space) around the
//! vertices it moves, found at import. A posed vertex is a weighted mean of its joints'
//! transforms of it, so it lies in the convex hull of those joints' posed spheres, and a
//! sphere around them all holds it. That sphere becomes the instance's transform (the
//! mesh's rest sphere scaled and moved onto it), so the cull, CPU and GPU alike, sees
//! the posed extent through the instance record as for any moved instance; the joint
//! matrices take the inverse of that transform, so the pass writes vertices in the
//! instance's local space.

use bytemuck::{Pod, Zeroable};
use glam::{Affine3A, Mat3, Vec3, Vec4};
use rayon::prelude::*;

/// A skinned vertex at rest, as the skinning pass reads it (`SkinVertex` in
/// `wgsl/skin.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct SkinVertex {
    /// In the skin's bind space (glTF: the mesh's space).
    pub position: [f32; 3],
    /// In the same space.
    pub normal: [f32; 3],
    /// Tangent and handedness as the vertex's (`Snorm8x4`).
    pub tangent: [i8; 4],
    /// Indices into the skin's joints.
    pub joints: [u16; 4],
    /// The joints' weights (summing to 1).
    pub weights: [f32; 4],
    /// The skin's first joint matrix in [`Skins::joint_matrices`].
    pub joint_base: u32,
    /// The vertex it writes: an index into the scene's vertices (the instance's own mesh).
    pub destination: u32,
}

/// One skinned instance.
#[derive(Clone, Debug, PartialEq)]
pub struct Skin {
    /// The instance it poses.
    pub instance: u32,
    /// The instance's own mesh's rest bounding sphere (xyz center, w radius): the
    /// instance transform maps it onto the posed sphere.
    pub rest_sphere: Vec4,
    /// Its joints: indices into [`crate::pose::Posing::nodes`].
    pub joints: Vec<u32>,
    /// Per joint, glTF's inverse bind matrix.
    pub inverse_binds: Vec<Affine3A>,
    /// Per joint, the sphere in its bind space (inverse bind times rest position) around
    /// the vertices it moves; a negative radius when it moves none.
    pub joint_bounds: Vec<Vec4>,
    /// Its vertices: a range of [`Skins::vertices`].
    pub vertices: std::ops::Range<u32>,
    /// Its first joint matrix in [`Skins::joint_matrices`].
    pub joint_base: u32,
}

/// A scene's skinned instances, their vertices at rest, and the current joint matrices
/// (what the skinning pass applies: [`Skins::set_poses`] and [`Skins::set_pose`] write them).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Skins {
    /// The skins.
    pub skins: Vec<Skin>,
    /// Every skin's vertices, in order.
    pub vertices: Vec<SkinVertex>,
    /// Every skin's joints' matrices, in order: from the skin's bind space to the
    /// instance's local space (`local_from_world * joint_world * inverse_bind`).
    pub joint_matrices: Vec<JointMatrix>,
}

/// A joint matrix as the pass reads it: the rows of a 3 x 4 transform.
pub type JointMatrix = [[f32; 4]; 3];

/// One skinned instance's pose for a frame.
#[derive(Clone, Debug, PartialEq)]
pub struct SkinPose {
    /// The instance's transform: its rest sphere onto the posed one.
    pub world_from_local: Affine3A,
    /// Per joint, what its vertices are multiplied by.
    pub joint_matrices: Vec<Affine3A>,
}

impl Skins {
    /// Whether nothing is skinned.
    pub fn is_empty(&self) -> bool {
        self.skins.is_empty()
    }

    /// Each skin's pose for the posed nodes' world transforms `node_worlds`.
    pub fn poses(&self, node_worlds: &[Affine3A]) -> Vec<SkinPose> {
        (self.skins.par_iter())
            .map(|s| s.pose(node_worlds))
            .collect()
    }

    /// The skin of instance `instance`, if it has one (skins are in instance order).
    pub fn of_instance(&self, instance: u32) -> Option<usize> {
        self.skins
            .binary_search_by_key(&instance, |s| s.instance)
            .ok()
    }

    /// Writes skin `s`'s `pose` into [`Skins::joint_matrices`]; returns the range written.
    pub fn set_pose(&mut self, s: usize, pose: &SkinPose) -> std::ops::Range<u32> {
        let start = self.skins[s].joint_base;
        for (k, m) in pose.joint_matrices.iter().enumerate() {
            self.joint_matrices[start as usize + k] = rows(m);
        }
        start..start + pose.joint_matrices.len() as u32
    }

    /// Writes `poses` (one per skin) into [`Skins::joint_matrices`]; returns each skin's
    /// instance and transform.
    pub fn set_poses(&mut self, poses: &[SkinPose]) -> Vec<(u32, Affine3A)> {
        self.joint_matrices.clear();
        for pose in poses {
            (self.joint_matrices).extend(pose.joint_matrices.iter().map(rows));
        }
        (self.skins.iter().zip(poses))
            .map(|(s, p)| (s.instance, p.world_from_local))
            .collect()
    }

    /// After the instances whose `kept` is false are dropped: their skins go (their
    /// vertices stay, writing their own meshes, which nothing draws), the rest take the
    /// instances' new ids.
    pub fn keep_instances(&mut self, kept: &[bool]) {
        let new_id = crate::pose::new_ids(kept);
        self.skins.retain_mut(|s| {
            let id = new_id.get(s.instance as usize).copied().flatten();
            s.instance = id.unwrap_or(u32::MAX);
            id.is_some()
        });
    }
}

impl Skin {
    /// Its pose for the posed nodes' world transforms.
    pub fn pose(&self, node_worlds: &[Affine3A]) -> SkinPose {
        let joint_worlds: Vec<Affine3A> = (self.joints.iter())
            .map(|&j| node_worlds[j as usize])
            .collect();
        self.pose_joints(&joint_worlds)
    }

    /// Its pose for its joints' world transforms, in its joint order.
    pub fn pose_joints(&self, joint_worlds: &[Affine3A]) -> SkinPose {
        // The joints' bounds are in their bind spaces: the joints' own transforms move
        // them; the vertices take the inverse bind matrices first.
        let sphere = posed_sphere(joint_worlds, &self.joint_bounds);
        let world_joints = (joint_worlds.iter().zip(&self.inverse_binds)).map(|(m, ib)| *m * *ib);
        let world_from_local = onto(self.rest_sphere, sphere);
        let local_from_world = world_from_local.inverse();
        SkinPose {
            world_from_local,
            joint_matrices: world_joints.map(|m| local_from_world * m).collect(),
        }
    }
}

/// The transform that maps sphere `from` onto sphere `to`: a uniform scale and a move
/// (a degenerate `from` is only moved).
fn onto(from: Vec4, to: Vec4) -> Affine3A {
    let scale = if from.w > 0.0 { to.w / from.w } else { 1.0 };
    Affine3A::from_translation(to.truncate())
        * Affine3A::from_scale(Vec3::splat(scale))
        * Affine3A::from_translation(-from.truncate())
}

/// A sphere around every joint's posed sphere (`bounds[j]` moved by `joints[j]`, its
/// radius grown by the matrix's largest axis), grown one at a time.
fn posed_sphere(joints: &[Affine3A], bounds: &[Vec4]) -> Vec4 {
    let mut out: Option<Vec4> = None;
    for (m, b) in joints.iter().zip(bounds).filter(|(_, b)| b.w >= 0.0) {
        let axes = [m.matrix3.x_axis, m.matrix3.y_axis, m.matrix3.z_axis];
        let stretch = axes.iter().map(|a| a.length()).fold(0.0, f32::max);
        let s = m.transform_point3(b.truncate()).extend(b.w * stretch);
        out = Some(match out {
            None => s,
            Some(o) => enclose(o, s),
        });
    }
    // Rounding in the moves can leave a vertex a hair outside: grow by 2^-16 of the
    // magnitudes involved.
    out.map_or(Vec4::ZERO, |s| {
        let slack = (s.truncate().abs().max_element() + s.w) * (1.0 / 65536.0);
        s.truncate().extend(s.w + slack)
    })
}

/// The smallest sphere around spheres `a` and `b`.
fn enclose(a: Vec4, b: Vec4) -> Vec4 {
    let d = b.truncate().distance(a.truncate());
    if d + b.w <= a.w {
        return a;
    }
    if d + a.w <= b.w {
        return b;
    }
    let radius = 0.5 * (d + a.w + b.w);
    let toward = (b.truncate() - a.truncate()) / d;
    (a.truncate() + toward * (radius - a.w)).extend(radius)
}

/// The rows of `m`, as the pass reads them.
fn rows(m: &Affine3A) -> JointMatrix {
    let t = glam::Mat4::from(*m).transpose();
    [t.x_axis.into(), t.y_axis.into(), t.z_axis.into()]
}

/// The skinning pass's CPU twin for one vertex: its position, normal and packed tangent
/// with `joint_matrices` (all of [`Skins::joint_matrices`]), in the pass's operations.
pub fn skin_vertex(
    v: &SkinVertex,
    joint_matrices: &[JointMatrix],
) -> ([f32; 3], [f32; 3], [i8; 4]) {
    let mut blended = [Vec4::ZERO; 3];
    for k in 0..4 {
        let m = joint_matrices[(v.joint_base + u32::from(v.joints[k])) as usize];
        for (row, r) in blended.iter_mut().zip(m) {
            *row += Vec4::from(r) * v.weights[k];
        }
    }
    let apply = |p: Vec4| Vec3::new(blended[0].dot(p), blended[1].dot(p), blended[2].dot(p));
    let position = apply(Vec3::from(v.position).extend(1.0));
    let linear = Mat3::from_cols(
        blended[0].truncate(),
        blended[1].truncate(),
        blended[2].truncate(),
    )
    .transpose();
    let (a, b, c) = (linear.x_axis, linear.y_axis, linear.z_axis);
    let cofactor = Mat3::from_cols(b.cross(c), c.cross(a), a.cross(b));
    let n = Vec3::from(v.normal);
    let normal = a.dot(b.cross(c)).signum() * cofactor * n;
    let t = Vec4::from(v.tangent.map(|c| (f32::from(c) / 127.0).max(-1.0)));
    let tangent = (linear * t.truncate()).normalize_or_zero().extend(t.w);
    (position.into(), normal.into(), pack_snorm8_as_wgsl(tangent))
}

/// WGSL's `pack4x8snorm`: `floor(0.5 + 127 * clamp(e, -1, 1))` per component.
fn pack_snorm8_as_wgsl(v: Vec4) -> [i8; 4] {
    v.to_array()
        .map(|c| (0.5 + 127.0 * c.clamp(-1.0, 1.0)).floor() as i8)
}
