//! glTF node animations into [`crate::pose`]: the nodes the channels move (and their
//! descendants, which move with them) become posed nodes, parents first; each channel's
//! keys are read and checked, and a malformed one is an error naming it.

use std::collections::HashSet;

use glam::{Affine3A, Quat, Vec3, Vec4};
use gltf::animation::{Interpolation as GltfInterpolation, Property as GltfProperty};

use super::{Importer, Step};
use crate::pose::{Channel, Clip, Interpolation, PoseNode, Property, Trs};

/// The nodes some channel animates.
pub(super) fn targets(document: &gltf::Document) -> HashSet<usize> {
    (document.animations())
        .flat_map(|a| {
            a.channels()
                .map(|c| c.target().node().index())
                .collect::<Vec<_>>()
        })
        .collect()
}

impl Importer<'_> {
    /// `node`'s posed index, when an animation moves it or an ancestor (`parent_pose`):
    /// its rest transform, and for the topmost such node the still transform above it
    /// (`parent`, its parent's world transform).
    pub(super) fn pose_node(
        &mut self,
        node: &gltf::Node,
        parent: Affine3A,
        parent_pose: Option<u32>,
    ) -> Option<u32> {
        if parent_pose.is_none() && !self.animated.contains(&node.index()) {
            return None;
        }
        let (t, r, s) = node.transform().decomposed();
        let nodes = &mut self.scene.posing.nodes;
        nodes.push(PoseNode {
            parent: parent_pose,
            root_from: match parent_pose {
                Some(_) => Affine3A::IDENTITY,
                None => parent,
            },
            rest: Trs {
                translation: Vec3::from(t),
                rotation: Quat::from_array(r),
                scale: Vec3::from(s),
            },
        });
        let index = nodes.len() as u32 - 1;
        self.pose_nodes.insert(node.index(), index);
        Some(index)
    }

    /// Every animation's channels that move a node of the scene, each checked
    /// ([`Channel::check`]); its channels of morph weights go to the node's morphs.
    pub(super) fn read_clips(&mut self) -> Step<()> {
        for animation in self.document.animations() {
            let at = format!("animations[{}]", animation.index());
            let mut clip = Clip {
                name: animation.name().map_or_else(|| at.clone(), str::to_owned),
                channels: Vec::new(),
                offset: 0.0,
                speed: 1.0,
            };
            let mut duration = 0.0f32;
            for sampler in animation.samplers() {
                let input = sampler.input().index() as u64;
                let times: Vec<f32> = self.read(input, &|| at.clone())?;
                duration = times.iter().fold(duration, |d, &t| d.max(t));
            }
            for channel in animation.channels() {
                let at = format!("{at}.channels[{}]", channel.index());
                if channel.target().property() == GltfProperty::MorphTargetWeights {
                    self.weight_channel(&channel, (&at, duration))?;
                } else if let Some(c) = self.channel(&channel, &at)? {
                    clip.channels.push(c);
                }
            }
            if !clip.channels.is_empty() {
                self.scene.posing.clips.push(clip);
            }
        }
        Ok(())
    }

    fn channel(&self, channel: &gltf::animation::Channel, at: &str) -> Step<Option<Channel>> {
        let target = channel.target();
        let Some(&node) = self.pose_nodes.get(&target.node().index()) else {
            return Ok(None); // a node outside the scene drawn
        };
        let property = match target.property() {
            GltfProperty::Translation => Property::Translation,
            GltfProperty::Rotation => Property::Rotation,
            GltfProperty::Scale => Property::Scale,
            GltfProperty::MorphTargetWeights => return Ok(None), // read_clips takes them
        };
        let sampler = channel.sampler();
        let where_ = || at.to_owned();
        let times: Vec<f32> = self.read(sampler.input().index() as u64, &where_)?;
        let output = sampler.output().index() as u64;
        let values: Vec<Vec4> = match property {
            Property::Rotation => self
                .read_floats::<4>(output, &where_)?
                .into_iter()
                .map(Vec4::from)
                .collect(),
            _ => (self.read_floats::<3>(output, &where_)?.into_iter())
                .map(|v| Vec3::from(v).extend(0.0))
                .collect(),
        };
        let c = Channel {
            node,
            property,
            interpolation: match sampler.interpolation() {
                GltfInterpolation::Step => Interpolation::Step,
                GltfInterpolation::Linear => Interpolation::Linear,
                GltfInterpolation::CubicSpline => Interpolation::CubicSpline,
            },
            times,
            values,
        };
        c.check().map_err(|e| format!("{at}: {e}"))?;
        Ok(Some(c))
    }
}
