//! `KHR_lights_punctual`: a node's light into [`crate::lights`], placed by the node and
//! posed with it where the node is animated.

use glam::{Affine3A, Vec3};

use super::{Importer, Step};
use crate::lights::{Light, LightKind};
use crate::pose::NodeInstance;

impl Importer<'_> {
    /// The node's `KHR_lights_punctual` light, at the node's origin shining along its
    /// -z, moving with it where the node is posed.
    pub(super) fn place_light(
        &mut self,
        node: &gltf::Node,
        world: Affine3A,
        pose: Option<u32>,
    ) -> Step<()> {
        let Some(light) = node.light() else {
            return Ok(());
        };
        use gltf::khr_lights_punctual::Kind;
        let kind = match light.kind() {
            Kind::Directional => LightKind::Directional,
            Kind::Point => LightKind::Point,
            Kind::Spot {
                inner_cone_angle,
                outer_cone_angle,
            } => LightKind::Spot {
                inner: inner_cone_angle,
                outer: outer_cone_angle,
            },
        };
        let mut placed = Light {
            kind,
            color: Vec3::from(light.color()),
            intensity: light.intensity(),
            range: light.range(),
            position: Vec3::ZERO,
            direction: Vec3::NEG_Z,
        };
        placed.place(world);
        placed
            .check()
            .map_err(|e| format!("node {} light {}: {e}", node.index(), light.index()))?;
        if let Some(node) = pose {
            self.scene.posing.lights.push(NodeInstance {
                instance: self.scene.lights.len() as u32,
                node,
                node_from_local: Affine3A::IDENTITY,
            });
        }
        self.scene.lights.push(placed);
        self.scene.physical_lights = true;
        Ok(())
    }
}
