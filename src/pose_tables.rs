//! Posing on the GPU: a scene's animations and skins flattened into the tables the
//! frame's pose pass reads (`wgsl/pose.wgsl`), so that what changes per frame is the
//! frame context's time and nothing else crosses the bus.
//!
//! The pass runs the CPU's posing ([`crate::pose`], [`crate::skin`]) in three
//! dispatches: each node's local transform from its channels sampled at the time,
//! each node's world transform (walking up to its root, then multiplying down in the
//! CPU's order), and each target (an instance on a node, or a skin: its culling sphere
//! from its posed joints, its transform and its joint matrices) written as the moves
//! scatter's edits. The CPU posing is its twin; `tests/posing.rs` compares them.
//!
//! A target whose slot a live scene vacated, or whose skin the engine poses itself
//! ([`crate::live::LiveScene::set_joints`]), has the slot [`Places::VACANT`]: the pass
//! writes a void edit for it and leaves its joints alone.

use bytemuck::{Pod, Zeroable};
use glam::{Affine3A, Vec4};

use crate::error::{Error, Result};
use crate::places::Places;
use crate::pose::{Interpolation, Property};
use crate::scene::{Scene, affine_rows};

/// The deepest posed tree the pass walks (a node and its ancestors); deeper trees are
/// posed on the CPU. Real skeletons are under 30 deep.
pub const MAX_DEPTH: usize = 64;

/// Invocations per workgroup of the pose pass (`POSE_GROUP`).
pub const POSE_GROUP: u32 = 64;

/// A posed node (`PoseNode` in `wgsl/pose.wgsl`, 112 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct PoseNodeRecord {
    /// The parent's index, or [`PoseNodeRecord::ROOT`].
    pub parent: u32,
    /// Its first channel in [`PoseTables::channels`]: its channels are in the CPU's
    /// order (clips, then channels), so the last one of a property wins on both.
    pub first_channel: u32,
    /// How many channels animate it.
    pub channels: u32,
    /// Zero (alignment).
    pub unused: u32,
    /// A root's placement above it (rows of a 3x4 transform; identity otherwise).
    pub root_from: [[f32; 4]; 3],
    /// Its rest translation (xyz).
    pub translation: [f32; 4],
    /// Its rest rotation (xyzw).
    pub rotation: [f32; 4],
    /// Its rest scale (xyz).
    pub scale: [f32; 4],
}

impl PoseNodeRecord {
    /// The parent of a root.
    pub const ROOT: u32 = u32::MAX;
}

/// A channel with its clip's timing (`PoseChannel`, 32 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct PoseChannelRecord {
    /// 0 translation, 1 rotation, 2 scale.
    pub property: u32,
    /// 0 step, 1 linear, 2 cubic spline.
    pub interpolation: u32,
    /// Its first key's time in [`PoseTables::times`].
    pub first_key: u32,
    /// Its keys.
    pub keys: u32,
    /// Its first value in [`PoseTables::values`] (three per key for a cubic spline).
    pub first_value: u32,
    /// Its clip's [`crate::pose::Clip::offset`].
    pub offset: f32,
    /// Its clip's [`crate::pose::Clip::speed`].
    pub speed: f32,
    /// Its clip's [`crate::pose::Clip::duration`].
    pub duration: f32,
}

/// What the pass poses: an instance on a node, or a skinned instance (`PoseTarget`,
/// 96 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct PoseTargetRecord {
    /// The instance's slot, or [`Places::VACANT`]: not posed by the pass.
    pub slot: u32,
    /// An instance on a node: the node. A skin: its first joint in
    /// [`PoseTables::joints`].
    pub node: u32,
    /// A skin's joint count; 0 for an instance on a node.
    pub joints: u32,
    /// A skin's first joint matrix.
    pub joint_base: u32,
    /// The mesh's bounding sphere (local), whose radius the edit's world radius scales.
    pub bounds: [f32; 4],
    /// An instance on a node: from its mesh's space to the node's (rows).
    pub node_from_local: [[f32; 4]; 3],
    /// The radius the instance's spin adds (scaled like the bounds), as
    /// [`crate::scene::Scene::world_sphere`].
    pub orbit: f32,
    /// The radius its bob adds (not scaled).
    pub bob: f32,
    /// Zeros (the record is 96 bytes).
    pub unused: [u32; 2],
}

/// The pose pass's uniform (`PoseParams`, 20 bytes): the dispatches' rows and counts,
/// and how far ahead of the frame context's time it poses.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct PoseParamsRecord {
    /// Invocations per row of the node dispatches (x workgroups times [`POSE_GROUP`]).
    pub node_row: u32,
    /// ... and of the target dispatches.
    pub target_row: u32,
    /// The nodes (the buffers may be longer).
    pub nodes: u32,
    /// The targets.
    pub targets: u32,
    /// Seconds after the frame context's time: 0, or a two-frame submission's `dt` for
    /// its second frame's pose.
    pub ahead: f32,
}

/// One joint of a skin (`SkinJoint`, 80 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct SkinJointRecord {
    /// Its node.
    pub node: u32,
    /// Zeros (alignment).
    pub unused: [u32; 3],
    /// Its inverse bind matrix (rows).
    pub inverse_bind: [[f32; 4]; 3],
    /// The sphere around what it moves, in its bind space (negative radius: nothing).
    pub bounds: [f32; 4],
}

/// The pass's tables for one scene.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PoseTables {
    /// The posed nodes, parents first.
    pub nodes: Vec<PoseNodeRecord>,
    /// Every clip's channels, by node.
    pub channels: Vec<PoseChannelRecord>,
    /// The channels' key times.
    pub times: Vec<f32>,
    /// The channels' key values.
    pub values: Vec<[f32; 4]>,
    /// The instances on nodes, then the skinned instances.
    pub targets: Vec<PoseTargetRecord>,
    /// Every skin's joints.
    pub joints: Vec<SkinJointRecord>,
}

impl PoseTables {
    /// The tables of `scene`'s posing, `None` when nothing is animated. `posed(slot)`
    /// says whether the pass still poses the instance in `slot` (a live scene's: not
    /// removed, not posed by the engine). An error for a tree deeper than
    /// [`MAX_DEPTH`].
    pub fn new(scene: &Scene, posed: impl Fn(u32) -> bool) -> Result<Option<PoseTables>> {
        if !scene.is_animated() {
            return Ok(None);
        }
        check_depth(scene)?;
        let mut tables = PoseTables::default();
        tables.add_nodes(scene);
        let slot = |s: u32| if posed(s) { s } else { Places::VACANT };
        for i in &scene.posing.instances {
            tables.targets.push(PoseTargetRecord {
                slot: slot(i.instance),
                node: i.node,
                node_from_local: affine_rows(&i.node_from_local),
                ..target_of(scene, i.instance)
            });
        }
        for skin in &scene.skins.skins {
            tables.targets.push(PoseTargetRecord {
                slot: slot(skin.instance),
                node: tables.joints.len() as u32,
                joints: skin.joints.len() as u32,
                joint_base: skin.joint_base,
                ..target_of(scene, skin.instance)
            });
            let joints = (skin.joints.iter().zip(&skin.inverse_binds)).zip(&skin.joint_bounds);
            tables
                .joints
                .extend(joints.map(|((&node, ib), b)| SkinJointRecord {
                    node,
                    unused: [0; 3],
                    inverse_bind: affine_rows(ib),
                    bounds: b.to_array(),
                }));
        }
        Ok(Some(tables))
    }

    /// The nodes, each with its channels (sorted by node, in the CPU's order).
    fn add_nodes(&mut self, scene: &Scene) {
        let posing = &scene.posing;
        let mut by_node: Vec<Vec<PoseChannelRecord>> = vec![Vec::new(); posing.nodes.len()];
        let mut keys = KeyStore::default();
        for clip in &posing.clips {
            for c in &clip.channels {
                let (first_key, first_value) = keys.add(self, c);
                by_node[c.node as usize].push(PoseChannelRecord {
                    property: match c.property {
                        Property::Translation => 0,
                        Property::Rotation => 1,
                        Property::Scale => 2,
                    },
                    interpolation: match c.interpolation {
                        Interpolation::Step => 0,
                        Interpolation::Linear => 1,
                        Interpolation::CubicSpline => 2,
                    },
                    first_key,
                    keys: c.times.len() as u32,
                    first_value,
                    offset: clip.offset,
                    speed: clip.speed,
                    duration: clip.duration(),
                });
            }
        }
        for (node, channels) in posing.nodes.iter().zip(by_node) {
            self.nodes.push(PoseNodeRecord {
                parent: node.parent.unwrap_or(PoseNodeRecord::ROOT),
                first_channel: self.channels.len() as u32,
                channels: channels.len() as u32,
                unused: 0,
                root_from: affine_rows(&node.root_from),
                translation: node.rest.translation.extend(0.0).to_array(),
                rotation: node.rest.rotation.to_array(),
                scale: node.rest.scale.extend(0.0).to_array(),
            });
            self.channels.extend(channels);
        }
    }

    /// GPU bytes: the tables, and the pass's local and world transforms per node.
    pub fn gpu_bytes(&self) -> u64 {
        let scratch = 2 * size_of::<[[f32; 4]; 3]>() * self.nodes.len();
        (size_of_val(&self.nodes[..])
            + size_of_val(&self.channels[..])
            + size_of_val(&self.times[..])
            + size_of_val(&self.values[..])
            + size_of_val(&self.targets[..])
            + size_of_val(&self.joints[..])
            + scratch) as u64
    }
}

/// Channels' keys stored once however many channels share them (a crowd's figures play
/// one walk at their own phases: each clip is its own, its keys the same).
#[derive(Default)]
struct KeyStore {
    /// Where each channel's keys were stored, by their bits.
    stored: std::collections::HashMap<KeyBits, (u32, u32)>,
}

/// A channel's times and values, bit for bit.
type KeyBits = (Vec<u32>, Vec<[u32; 4]>);

impl KeyStore {
    /// Where `c`'s times and values lie in `tables`, added unless stored already.
    fn add(&mut self, tables: &mut PoseTables, c: &crate::pose::Channel) -> (u32, u32) {
        let bits = (
            c.times.iter().map(|t| t.to_bits()).collect(),
            c.values
                .iter()
                .map(|v| v.to_array().map(f32::to_bits))
                .collect(),
        );
        *self.stored.entry(bits).or_insert_with(|| {
            let at = (tables.times.len() as u32, tables.values.len() as u32);
            tables.times.extend(&c.times);
            tables.values.extend(c.values.iter().map(|v| v.to_array()));
            at
        })
    }
}

/// A target's mesh bounds and motion, as [`crate::scene::Scene::world_sphere`] reads
/// them.
fn target_of(scene: &Scene, instance: u32) -> PoseTargetRecord {
    let instance = &scene.instances[instance as usize];
    // A live scene's vacated slot has no mesh; its target is void anyway.
    let mesh = scene.meshes.get(instance.mesh as usize);
    let bounds: Vec4 = mesh.map_or(Vec4::ZERO, |m| m.bounds);
    let a = instance.animation;
    PoseTargetRecord {
        slot: Places::VACANT,
        node: 0,
        joints: 0,
        joint_base: 0,
        bounds: bounds.to_array(),
        node_from_local: affine_rows(&Affine3A::IDENTITY),
        orbit: if a.spin == 0.0 {
            0.0
        } else {
            2.0 * bounds.x.hypot(bounds.z)
        },
        bob: a.bob.abs(),
        unused: [0; 2],
    }
}

/// An error if a posed tree is deeper than the pass walks.
fn check_depth(scene: &Scene) -> Result<()> {
    let nodes = &scene.posing.nodes;
    let mut depth = vec![0usize; nodes.len()];
    for (i, n) in nodes.iter().enumerate() {
        depth[i] = n.parent.map_or(1, |p| depth[p as usize] + 1);
        if depth[i] > MAX_DEPTH {
            return Err(Error::InvalidScene(format!(
                "posed node {i} is {} deep; GPU posing walks at most {MAX_DEPTH} (pose on the CPU)",
                depth[i]
            )));
        }
    }
    Ok(())
}
