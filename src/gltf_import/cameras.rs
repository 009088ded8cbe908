//! A node's camera into [`crate::scene::Camera`]: placed by the node's world transform,
//! its scale removed (a camera looks down its node's -Z, +Y up).

use glam::Affine3A;

use super::{Importer, Step};
use crate::scene::{Camera, Projection};

impl Importer<'_> {
    /// The node's camera, where it has one, as placed at import (a camera's node
    /// animation is not followed: `--camera` frames a still view).
    pub(super) fn place_camera(&mut self, node: &gltf::Node, world: Affine3A) -> Step<()> {
        let Some(camera) = node.camera() else {
            return Ok(());
        };
        let (_, orientation, position) = world.to_scale_rotation_translation();
        let finite = orientation.is_finite() && position.is_finite();
        let projection = match camera.projection() {
            gltf::camera::Projection::Perspective(p) => Projection::Perspective {
                yfov: p.yfov(),
                aspect: p.aspect_ratio(),
                znear: p.znear(),
                zfar: p.zfar(),
            },
            gltf::camera::Projection::Orthographic(o) => Projection::Orthographic {
                xmag: o.xmag(),
                ymag: o.ymag(),
            },
        };
        if !finite {
            // A camera nobody can look through; the scene itself still draws.
            log::warn!(
                "node {}: camera skipped (its transform is not finite)",
                node.index()
            );
            return Ok(());
        }
        self.scene.cameras.push(Camera {
            name: camera.name().or(node.name()).map(str::to_string),
            position,
            orientation: orientation.normalize(),
            projection,
        });
        Ok(())
    }
}
