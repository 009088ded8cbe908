//! A scene file's cameras: where its author looked from (`info --scene` lists them,
//! `--camera N` views through one, [`crate::rig::framing`]).

use glam::{EulerRot, Quat, Vec3};

/// How a camera projects (glTF's `camera.type`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// A perspective camera: its vertical field of view (radians), the width / height
    /// it was authored for (`None`: the viewport's) and its near plane and far plane
    /// (`None`: infinite).
    Perspective {
        /// Vertical field of view, radians.
        yfov: f32,
        /// Width / height, if the file states it.
        aspect: Option<f32>,
        /// Near plane, meters.
        znear: f32,
        /// Far plane, meters (`None`: infinite).
        zfar: Option<f32>,
    },
    /// An orthographic camera: half its width and height, meters.
    Orthographic {
        /// Half the width.
        xmag: f32,
        /// Half the height.
        ymag: f32,
    },
}

/// One camera of the scene, in the order its nodes are visited (depth first, child
/// order: the instance order).
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// The camera's name, or its node's, where the file gives one.
    pub name: Option<String>,
    /// Where it is, in world space.
    pub position: Vec3,
    /// Which way it looks: its -Z forward and +Y up, the node's scale removed.
    pub orientation: Quat,
    /// How it projects.
    pub projection: Projection,
}

impl Camera {
    /// The viewer's yaw, pitch and roll in degrees that look as the camera does (the
    /// rig's viewer turns by yaw about +Y, then pitch about the turned +X, then roll
    /// about the view axis).
    pub fn yaw_pitch_roll_deg(&self) -> [f32; 3] {
        let (yaw, pitch, roll) = self.orientation.to_euler(EulerRot::YXZ);
        [yaw, pitch, roll].map(f32::to_degrees)
    }

    /// One line for `info --scene`.
    pub fn describe(&self) -> String {
        let [yaw, pitch, roll] = self.yaw_pitch_roll_deg();
        let p = self.position;
        let what = match self.projection {
            Projection::Perspective { yfov, aspect, .. } => {
                let aspect = aspect.map_or(String::new(), |a| format!(", aspect {a:.3}"));
                format!(
                    "perspective, vertical FOV {:.1} deg{aspect}",
                    yfov.to_degrees()
                )
            }
            Projection::Orthographic { xmag, ymag } => {
                format!("orthographic, {:.3} x {:.3} m", 2.0 * xmag, 2.0 * ymag)
            }
        };
        format!(
            "{} at {:.3},{:.3},{:.3}, yaw {yaw:.1} pitch {pitch:.1} roll {roll:.1}: {what}",
            self.name.as_deref().unwrap_or("(unnamed)"),
            p.x,
            p.y,
            p.z
        )
    }
}
