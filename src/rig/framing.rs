//! The viewer placed from the scene rather than from the rig: `--viewer fit`, which
//! stands back until every eye sees the whole scene, and `--camera N`, which looks
//! through one of the file's cameras. Both move a head-mounted rig's viewer; a CAVE's
//! walls or a runtime's posed views are fixed in the room and are refused.

use glam::{DVec3, Vec4};

use super::{Mount, Rig};
use crate::frustum::{Fov, View};
use crate::scene::{Camera, Projection};

/// How far above the scene's center a fitted viewer stands, as the angle it looks
/// down at the center (degrees): the front and a little above, where a model viewer
/// starts.
pub const FIT_ELEVATION_DEG: f32 = 20.0;

/// A display is fitted when its eyes look within this angle of the viewer's axis
/// (degrees): canted optics do; a peripheral panel, turned 45 degrees, sees the scene's
/// side at most.
pub const FACING_DEG: f64 = 30.0;

/// Places the viewer, turned as it is, on the line through `sphere`'s center along its
/// view axis, at the nearest distance at which every eye of every display that faces
/// that way ([`FACING_DEG`]) holds the whole sphere inside its four side planes (exact
/// for each eye's own window and offset: a plane's distance to the center grows
/// linearly with the viewer's distance). The near plane moves in to half the distance
/// to the sphere's front where it would cut it, and the far plane out past its back.
/// Returns the distance.
pub fn fit_viewer(rig: &mut Rig, sphere: Vec4) -> Result<f64, String> {
    head_mounted(rig, "--viewer fit")?;
    let (center, radius) = (sphere.truncate().as_dvec3(), f64::from(sphere.w));
    rig.viewer.position = [0.0; 3];
    let at_origin = rig.resolve().map_err(|e| e.to_string())?;
    let forward = rig.viewer.orientation() * DVec3::NEG_Z;
    let facing = |eye: &&View| {
        let axis = eye.world_from_view.transform_vector3(DVec3::NEG_Z);
        axis.dot(forward) >= FACING_DEG.to_radians().cos()
    };
    let outer_eyes = at_origin
        .displays
        .iter()
        .flat_map(|d| d.eyes.iter().take(2));
    let mut fitted = None;
    for eye in outer_eyes.filter(facing) {
        let offset = eye.world_from_view.translation;
        for normal in side_normals(eye) {
            let along = normal.dot(forward);
            if along <= 1e-9 {
                return Err("an eye's window does not hold the viewer's view axis".into());
            }
            let needed = (radius + normal.dot(offset)) / along;
            fitted = Some(fitted.map_or(needed, |d: f64| d.max(needed)));
        }
    }
    let distance = fitted
        .ok_or("no display looks where the viewer looks")?
        .max(radius);
    let position = center - forward * distance;
    rig.viewer.position = position.as_vec3().to_array();
    let front = (distance - radius).max(distance * 1e-3);
    rig.near = rig.near.min((0.5 * front) as f32);
    rig.far = rig.far.max((1.01 * (distance + radius)) as f32);
    Ok(distance)
}

/// Looks through `camera`: the viewer where it is and turned as it is, each display's
/// window its vertical field of view, symmetric about the axis and as wide as the
/// display's pixels make it (the file's aspect ratio yields to the display's), and the
/// near and far planes the camera's (an infinite far plane keeps the rig's). The rig's
/// IPD stays: both eyes look along the camera's axis (canted optics straightened),
/// half an IPD to either side; a panel turned from the head (a peripheral one) stays
/// turned.
pub fn view_through(rig: &mut Rig, camera: &Camera) -> Result<(), String> {
    head_mounted(rig, "--camera")?;
    let Projection::Perspective {
        yfov, znear, zfar, ..
    } = camera.projection
    else {
        return Err("an orthographic camera: stereo views are perspective".into());
    };
    let usable = yfov > 0.0 && yfov < std::f32::consts::PI && znear > 0.0;
    if !usable || zfar.is_some_and(|f| f.is_nan() || f <= znear) {
        return Err(format!(
            "camera with vertical FOV {yfov} rad, near {znear}, far {zfar:?}: not a view"
        ));
    }
    let [yaw, pitch, roll] = camera.yaw_pitch_roll_deg();
    rig.viewer.position = camera.position.to_array();
    (
        rig.viewer.yaw_deg,
        rig.viewer.pitch_deg,
        rig.viewer.roll_deg,
    ) = (yaw, pitch, roll);
    for display in &mut rig.displays {
        let [width, height] = display.resolution.map(|v| v as f32);
        if let Mount::Head(head) = &mut display.mount {
            let up = (0.5 * yfov).tan();
            let side = up * width / height;
            let window = Fov {
                left: side,
                right: side,
                up,
                down: up,
            };
            (head.fov, head.fov_right, head.cant_deg) = (window, None, 0.0);
        }
    }
    rig.near = znear;
    rig.far = zfar.unwrap_or(rig.far).max(2.0 * znear);
    Ok(())
}

/// Whether every display of `rig` moves with the viewer's head (what fitting and a
/// camera can move).
pub fn moves_with_head(rig: &Rig) -> bool {
    (rig.displays.iter()).all(|d| matches!(d.mount, Mount::Head(_)))
}

/// Refuses a rig with a display that does not move with the viewer.
fn head_mounted(rig: &Rig, option: &str) -> Result<(), String> {
    let fixed = (rig.displays.iter()).find(|d| !matches!(d.mount, Mount::Head(_)));
    match fixed {
        Some(d) => Err(format!(
            "{option} moves a head-mounted rig's viewer; display {} is fixed in the room",
            d.name
        )),
        None => Ok(()),
    }
}

/// The eye's four side planes' inward unit normals, in world space.
fn side_normals(eye: &View) -> [DVec3; 4] {
    let [l, r, u, d] = eye.fov.tangents();
    [
        DVec3::new(1.0, 0.0, -l),
        DVec3::new(-1.0, 0.0, -r),
        DVec3::new(0.0, 1.0, -d),
        DVec3::new(0.0, -1.0, -u),
    ]
    .map(|n| eye.world_from_view.transform_vector3(n.normalize()))
}
