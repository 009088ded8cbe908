//! Posing: the first work of the frame context (the chapter: "posing the world's
//! animated characters"), done once per frame whatever the displays and eyes. glTF node
//! animations (translation, rotation and scale channels, `STEP`, `LINEAR` and
//! `CUBICSPLINE`) are sampled at the frame's time, the animated nodes' world transforms
//! follow down their trees, and every instance that hangs on one of them gets its
//! world transform. What moves is then an ordinary instance transform: the cull sees
//! its real place, and a live scene sends only the animated instances' records.

use glam::{Affine3A, Quat, Vec3, Vec4};
use rayon::prelude::*;

/// How a channel's keys are joined (glTF `sampler.interpolation`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    /// Each key's value holds until the next key.
    Step,
    /// Straight lines between keys; rotations along the shorter great arc.
    Linear,
    /// Hermite curves through the keys, each key with an in- and out-tangent.
    CubicSpline,
}

/// What a channel animates (glTF `target.path`; morph weights are not read).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Property {
    /// The node's translation (xyz).
    Translation,
    /// The node's rotation (a unit quaternion, xyzw).
    Rotation,
    /// The node's scale (xyz).
    Scale,
}

/// One property of one node over time.
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    /// The animated node, an index into [`Posing::nodes`].
    pub node: u32,
    /// What it animates.
    pub property: Property,
    /// How its keys are joined.
    pub interpolation: Interpolation,
    /// The keys' times in seconds, strictly increasing, at least one.
    pub times: Vec<f32>,
    /// Per key its value (xyz of a vector, or a quaternion's xyzw); for
    /// [`Interpolation::CubicSpline`] three per key: in-tangent, value, out-tangent.
    pub values: Vec<Vec4>,
}

/// One animation: channels played together, at its own phase and pace.
#[derive(Clone, Debug, PartialEq)]
pub struct Clip {
    /// The file's name for it, or `animations[i]`.
    pub name: String,
    /// Its channels.
    pub channels: Vec<Channel>,
    /// Seconds into the clip at frame time 0 (glTF's: 0).
    pub offset: f32,
    /// Clip seconds per frame second (glTF's: 1).
    pub speed: f32,
}

/// A node's local transform as glTF splits it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Trs {
    /// Applied last.
    pub translation: Vec3,
    /// Applied after the scale.
    pub rotation: Quat,
    /// Applied first.
    pub scale: Vec3,
}

impl Trs {
    /// The transform.
    pub fn affine(&self) -> Affine3A {
        Affine3A::from_scale_rotation_translation(self.scale, self.rotation, self.translation)
    }
}

/// A node of the posed trees: parents come before their children.
#[derive(Clone, Debug, PartialEq)]
pub struct PoseNode {
    /// The parent's index (smaller than the node's own), or `None` for a root; a root's
    /// transform starts from `root_from` (the scene placement above the posed nodes).
    pub parent: Option<u32>,
    /// The transform above a root (identity for other nodes).
    pub root_from: Affine3A,
    /// The local transform when no channel animates it.
    pub rest: Trs,
}

/// An instance that hangs on a node: its world transform is the node's world transform
/// times `node_from_local` (an `EXT_mesh_gpu_instancing` copy, or identity).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeInstance {
    /// The instance id.
    pub instance: u32,
    /// The node, an index into [`Posing::nodes`].
    pub node: u32,
    /// From the mesh's space to the node's.
    pub node_from_local: Affine3A,
}

/// A scene's animations: the nodes they move (and those nodes' ancestors), the clips,
/// and the instances that move with them. Empty for a still scene.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Posing {
    /// The animated trees, parents first.
    pub nodes: Vec<PoseNode>,
    /// The clips.
    pub clips: Vec<Clip>,
    /// The instances on those nodes.
    pub instances: Vec<NodeInstance>,
    /// The punctual lights on those nodes: each a light of [`crate::scene::Scene::lights`]
    /// that moves with its node (`instance` names the light, `node_from_local` is the
    /// identity: a glTF light is its node's).
    pub lights: Vec<NodeInstance>,
}

impl Posing {
    /// After the instances whose `kept` is false are dropped from the scene: the posed
    /// ones among them go, and the rest take their new ids.
    pub fn keep_instances(&mut self, kept: &[bool]) {
        let new_id = new_ids(kept);
        self.instances.retain_mut(|i| {
            let id = new_id.get(i.instance as usize).copied().flatten();
            i.instance = id.unwrap_or(u32::MAX);
            id.is_some()
        });
    }

    /// Each node's world transform with every clip at `time` seconds, each clip looping
    /// over its own duration (a clip's channels agree on it: glTF plays them together).
    pub fn node_worlds(&self, time: f32) -> Vec<Affine3A> {
        let mut local: Vec<Trs> = self.nodes.iter().map(|n| n.rest).collect();
        for clip in &self.clips {
            let t = clip.looped(time * clip.speed + clip.offset);
            for c in &clip.channels {
                let trs = &mut local[c.node as usize];
                match c.property {
                    Property::Translation => trs.translation = c.sample(t).truncate(),
                    Property::Rotation => trs.rotation = Quat::from_vec4(c.sample(t)).normalize(),
                    Property::Scale => trs.scale = c.sample(t).truncate(),
                }
            }
        }
        self.compose(&local)
    }

    /// Each node's world transform at rest: no clip applied (the file's placement).
    pub fn rest_worlds(&self) -> Vec<Affine3A> {
        let rest: Vec<Trs> = self.nodes.iter().map(|n| n.rest).collect();
        self.compose(&rest)
    }

    /// World transforms from each node's `local` one, parents first.
    fn compose(&self, local: &[Trs]) -> Vec<Affine3A> {
        let mut world: Vec<Affine3A> = Vec::with_capacity(self.nodes.len());
        for (node, trs) in self.nodes.iter().zip(local) {
            let above = node.parent.map_or(node.root_from, |p| world[p as usize]);
            world.push(above * trs.affine());
        }
        world
    }

    /// Every posed instance's world transform at `time`, in [`Posing::instances`] order
    /// (in parallel: a crowd has many).
    pub fn instance_transforms(&self, time: f32) -> Vec<Affine3A> {
        self.instance_transforms_in(&self.node_worlds(time))
    }

    /// Every posed instance's world transform with the nodes at `world`.
    pub fn instance_transforms_in(&self, world: &[Affine3A]) -> Vec<Affine3A> {
        (self.instances.par_iter())
            .map(|i| world[i.node as usize] * i.node_from_local)
            .collect()
    }
}

/// Each instance's id after those whose `kept` is false are dropped (`None`: dropped).
pub fn new_ids(kept: &[bool]) -> Vec<Option<u32>> {
    let mut next = 0u32;
    (kept.iter())
        .map(|&k| {
            let id = k.then_some(next);
            next += u32::from(k);
            id
        })
        .collect()
}

impl Clip {
    /// The last key's time over every channel.
    pub fn duration(&self) -> f32 {
        (self.channels.iter())
            .filter_map(|c| c.times.last().copied())
            .fold(0.0, f32::max)
    }

    /// `time` wrapped into the clip's duration (a clip of no duration stays at 0).
    pub fn looped(&self, time: f32) -> f32 {
        let d = self.duration();
        if d > 0.0 { time.rem_euclid(d) } else { 0.0 }
    }
}

impl Channel {
    /// Its value at `t` seconds (glTF's sampling: held before the first key and after
    /// the last; a rotation is not yet normalized).
    pub fn sample(&self, t: f32) -> Vec4 {
        let times = &self.times;
        let value = |k: usize| match self.interpolation {
            Interpolation::CubicSpline => self.values[3 * k + 1],
            _ => self.values[k],
        };
        let last = times.len() - 1;
        if t <= times[0] {
            return value(0);
        }
        if t >= times[last] {
            return value(last);
        }
        // The key at or before t: times[k] <= t < times[k + 1].
        let k = times.partition_point(|&x| x <= t) - 1;
        let dt = times[k + 1] - times[k];
        let u = (t - times[k]) / dt;
        match self.interpolation {
            Interpolation::Step => value(k),
            Interpolation::Linear if self.property == Property::Rotation => {
                let (a, b) = (Quat::from_vec4(value(k)), Quat::from_vec4(value(k + 1)));
                Vec4::from(a.slerp(b, u))
            }
            Interpolation::Linear => value(k).lerp(value(k + 1), u),
            Interpolation::CubicSpline => {
                let out_tangent = self.values[3 * k + 2];
                let in_tangent = self.values[3 * (k + 1)];
                let (u2, u3) = (u * u, u * u * u);
                value(k) * (2.0 * u3 - 3.0 * u2 + 1.0)
                    + out_tangent * (dt * (u3 - 2.0 * u2 + u))
                    + value(k + 1) * (-2.0 * u3 + 3.0 * u2)
                    + in_tangent * (dt * (u3 - u2))
            }
        }
    }

    /// Whether its keys are well formed: at least one, times finite and strictly
    /// increasing, as many values as the interpolation needs, every value finite.
    pub fn check(&self) -> std::result::Result<(), String> {
        if self.times.is_empty() {
            return Err("has no keyframes".into());
        }
        if let Some(t) = self.times.iter().find(|t| !t.is_finite()) {
            return Err(format!("keyframe time {t} is not a finite number"));
        }
        if let Some(k) = (1..self.times.len()).find(|&k| self.times[k] <= self.times[k - 1]) {
            return Err(format!(
                "keyframe times are not increasing: key {k} at {} s follows {} s",
                self.times[k],
                self.times[k - 1]
            ));
        }
        let per_key = match self.interpolation {
            Interpolation::CubicSpline => 3,
            _ => 1,
        };
        if self.values.len() != per_key * self.times.len() {
            return Err(format!(
                "{} output values for {} keyframe times ({per_key} per key for {:?})",
                self.values.len(),
                self.times.len(),
                self.interpolation
            ));
        }
        match self.values.iter().position(|v| !v.is_finite()) {
            Some(k) => Err(format!("output value {k} is not finite")),
            None => Ok(()),
        }
    }
}

/// Places each light of `on_nodes` (an index into `lights`) at its node's world
/// transform in `worlds` ([`Posing::node_worlds`]).
pub fn place_lights(
    on_nodes: &[NodeInstance],
    worlds: &[Affine3A],
    lights: &mut [crate::lights::Light],
) {
    for l in on_nodes {
        let light = lights.get_mut(l.instance as usize);
        if let (Some(light), Some(world)) = (light, worlds.get(l.node as usize)) {
            light.place(*world * l.node_from_local);
        }
    }
}
