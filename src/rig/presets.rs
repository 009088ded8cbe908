//! The rigs `Rig::preset` knows.

use super::VisibilityMask;
use super::{
    Display, Foveation, HeadFixed, Mount, Rig, Screen, Viewer, default_far, default_ipd,
    default_near,
};
use crate::frustum::Fov;

pub(super) fn hmd() -> Rig {
    Rig {
        viewer: Viewer {
            position: [0.0, 1.6, 2.0],
            yaw_deg: 0.0,
            pitch_deg: 0.0,
            roll_deg: 0.0,
            ipd: default_ipd(),
        },
        near: default_near(),
        far: default_far(),
        frame_only: Vec::new(),
        displays: vec![Display {
            name: "hmd".into(),
            stereo: true,
            resolution: [1440, 1600],
            // Outer half-angle wider than the nasal one, like shipping headsets.
            foveation: None,
            mount: Mount::Head(HeadFixed {
                fov: Fov {
                    left: 1.19,
                    right: 0.84,
                    up: 1.11,
                    down: 1.19,
                },
                fov_right: None,
                yaw_deg: 0.0,
                pitch_deg: 0.0,
                cant_deg: 0.0,
            }),
            visibility_mask: Some(VisibilityMask::headset()),
            rank: None,
        }],
    }
}

/// A 3 m cube of walls around the origin, floor at y = 0.
pub(super) fn cave() -> Rig {
    let h = 1.5;
    let wall = |name: &str, ll: [f32; 3], lr: [f32; 3], ul: [f32; 3]| Display {
        name: name.into(),
        stereo: true,
        resolution: [1024, 1024],
        foveation: None,
        visibility_mask: None,
        rank: None,
        mount: Mount::Screen(Screen {
            lower_left: ll,
            lower_right: lr,
            upper_left: ul,
        }),
    };
    Rig {
        viewer: Viewer {
            position: [0.2, 1.6, 0.3],
            yaw_deg: 10.0,
            pitch_deg: 0.0,
            roll_deg: 0.0,
            ipd: default_ipd(),
        },
        near: default_near(),
        far: default_far(),
        frame_only: Vec::new(),
        displays: vec![
            wall("front", [-h, 0.0, -h], [h, 0.0, -h], [-h, 2.0 * h, -h]),
            wall("left", [-h, 0.0, h], [-h, 0.0, -h], [-h, 2.0 * h, h]),
            wall("right", [h, 0.0, -h], [h, 0.0, h], [h, 2.0 * h, -h]),
            wall("floor", [-h, 0.0, h], [h, 0.0, h], [-h, 0.0, -h]),
            wall(
                "ceiling",
                [-h, 2.0 * h, -h],
                [h, 2.0 * h, -h],
                [-h, 2.0 * h, h],
            ),
        ],
    }
}

pub(super) fn hmd_peripheral() -> Rig {
    let mut rig = hmd();
    let center = Fov {
        left: 1.0,
        right: 0.84,
        up: 1.0,
        down: 1.0,
    };
    if let Mount::Head(h) = &mut rig.displays[0].mount {
        h.fov = center;
    }
    rig.displays[0].name = "center".into();
    let side = |name: &str, yaw_deg: f32| Display {
        name: name.into(),
        stereo: false,
        resolution: [480, 800],
        foveation: None,
        visibility_mask: None,
        rank: None,
        mount: Mount::Head(HeadFixed {
            fov: Fov {
                left: 0.58,
                right: 0.58,
                up: 0.84,
                down: 0.84,
            },
            fov_right: None,
            yaw_deg,
            pitch_deg: 0.0,
            cant_deg: 0.0,
        }),
    };
    rig.displays.push(side("peripheral-left", 45.0));
    rig.displays.push(side("peripheral-right", -45.0));
    rig
}

/// The `hmd` with foveated insets at the defaults of shipping runtimes: the outer pair
/// at half the panel's density, an inset per eye at full density over half the width
/// and 45 % of the height of each eye's window (fixed foveation: no gaze).
pub(super) fn hmd_foveated() -> Rig {
    let mut rig = hmd();
    rig.displays[0].foveation = Some(Foveation::default());
    rig
}
