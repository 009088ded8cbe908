//! The viewing rig: a tracked viewer and its displays, each stereo or mono, head-fixed
//! (an HMD panel) or world-fixed (a CAVE wall given by its corners).
//!
//! Everything is in meters, in tracking space, which is also world space here: the
//! scene is authored at real scale and nothing rescales it.

use std::path::Path;

use glam::{DAffine3, DMat3, DQuat, DVec3, EulerRot, Vec4};
use serde::{Deserialize, Serialize};

use crate::cull::CullJob;
use crate::error::{Error, Result};
use crate::frustum::{Fov, View, enclosing_view};

/// The tracked head. Orientation is yaw (about +Y, positive turns left), then pitch
/// (about the turned +X, positive looks up), then roll; at zero it looks down -Z.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Viewer {
    pub position: [f32; 3],
    #[serde(default)]
    pub yaw_deg: f32,
    #[serde(default)]
    pub pitch_deg: f32,
    #[serde(default)]
    pub roll_deg: f32,
    /// Inter-pupillary distance in meters.
    #[serde(default = "default_ipd")]
    pub ipd: f32,
}

fn default_ipd() -> f32 {
    0.063
}

impl Viewer {
    pub fn orientation(&self) -> DQuat {
        euler(self.yaw_deg, self.pitch_deg, self.roll_deg)
    }

    pub fn position(&self) -> DVec3 {
        DVec3::from(self.position.map(f64::from))
    }

    /// Eye centers: left then right for stereo, the cyclopean point for mono.
    pub fn eye_positions(&self, views: u32) -> Vec<DVec3> {
        let right = self.orientation() * DVec3::X * (0.5 * self.ipd as f64);
        match views {
            1 => vec![self.position()],
            _ => vec![self.position() - right, self.position() + right],
        }
    }
}

/// A panel fixed to the head, like an HMD's.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HeadFixed {
    /// The left eye's window (or the only eye's, for mono), as tangents.
    pub fov: Fov,
    /// The right eye's window; default: `fov` mirrored.
    #[serde(default)]
    pub fov_right: Option<Fov>,
    /// Direction of the panel relative to the head (peripheral panels turn 45 degrees).
    #[serde(default)]
    pub yaw_deg: f32,
    #[serde(default)]
    pub pitch_deg: f32,
    /// Each eye's panel turned outwards by this angle (canted HMD optics).
    #[serde(default)]
    pub cant_deg: f32,
}

/// A planar screen fixed in tracking space, given by three of its corners; the view is
/// the generalized (off-axis) perspective projection from each eye through it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Screen {
    pub lower_left: [f32; 3],
    pub lower_right: [f32; 3],
    pub upper_left: [f32; 3],
}

/// Where a display's image is fixed: to the head, or in the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Mount {
    /// An HMD panel: moves with the viewer's head.
    Head(HeadFixed),
    /// A CAVE wall: fixed in tracking space, seen off-axis from each eye.
    Screen(Screen),
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "DisplayFile", into = "DisplayFile")]
pub struct Display {
    pub name: String,
    /// Two views (left, right) when true, one otherwise.
    pub stereo: bool,
    /// Pixels per eye: the stereo target is twice as wide.
    pub resolution: [u32; 2],
    pub mount: Mount,
}

impl Display {
    pub fn views(&self) -> u32 {
        if self.stereo { 2 } else { 1 }
    }
}

/// A display as rig files spell it: the mount is a `head` or a `screen` table.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct DisplayFile {
    name: String,
    stereo: bool,
    resolution: [u32; 2],
    #[serde(default, skip_serializing_if = "Option::is_none")]
    head: Option<HeadFixed>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    screen: Option<Screen>,
}

impl TryFrom<DisplayFile> for Display {
    type Error = String;

    fn try_from(f: DisplayFile) -> std::result::Result<Display, String> {
        let mount = match (f.head, f.screen) {
            (Some(h), None) => Mount::Head(h),
            (None, Some(s)) => Mount::Screen(s),
            _ => {
                return Err(format!(
                    "display {:?} needs exactly one of `head` or `screen`",
                    f.name
                ));
            }
        };
        Ok(Display {
            name: f.name,
            stereo: f.stereo,
            resolution: f.resolution,
            mount,
        })
    }
}

impl From<Display> for DisplayFile {
    fn from(d: Display) -> DisplayFile {
        let (head, screen) = match d.mount {
            Mount::Head(h) => (Some(h), None),
            Mount::Screen(s) => (None, Some(s)),
        };
        DisplayFile {
            name: d.name,
            stereo: d.stereo,
            resolution: d.resolution,
            head,
            screen,
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rig {
    pub viewer: Viewer,
    #[serde(default = "default_near")]
    pub near: f32,
    #[serde(default = "default_far")]
    pub far: f32,
    pub displays: Vec<Display>,
}

fn default_near() -> f32 {
    0.05
}
fn default_far() -> f32 {
    1000.0
}

/// The preset names `Rig::preset` knows.
pub const PRESETS: [&str; 3] = ["hmd", "cave", "hmd-peripheral"];

impl Rig {
    /// `hmd`, `cave` or `hmd-peripheral`; see the README for what each is.
    pub fn preset(name: &str) -> Result<Rig> {
        let rig = match name {
            "hmd" => hmd(),
            "cave" => cave(),
            "hmd-peripheral" => hmd_peripheral(),
            _ => {
                return Err(Error::rig(
                    name,
                    format!("unknown preset; known: {}", PRESETS.join(", ")),
                ));
            }
        };
        rig.validate(name)?;
        Ok(rig)
    }

    /// A preset name, or a `.json` / `.toml` rig file.
    pub fn load(spec: &str) -> Result<Rig> {
        let path = Path::new(spec);
        // A bare name that is no file is meant as a preset: say which ones exist.
        if PRESETS.contains(&spec) || (path.extension().is_none() && !path.exists()) {
            return Rig::preset(spec);
        }
        let text = std::fs::read_to_string(path).map_err(|e| {
            Error::rig(
                spec,
                format!("{e} (not a file, and not a preset: {})", PRESETS.join(", ")),
            )
        })?;
        let rig = Rig::parse(&text, path.extension().and_then(|e| e.to_str()))
            .map_err(|m| Error::rig(spec, m))?;
        rig.validate(spec)?;
        Ok(rig)
    }

    /// Parses rig text; `extension` picks TOML for `toml`, JSON otherwise. The message
    /// names the line and column (JSON) or the span and field (TOML).
    pub fn parse(text: &str, extension: Option<&str>) -> std::result::Result<Rig, String> {
        match extension {
            Some("toml") => toml::from_str(text).map_err(|e| e.to_string().replace('\n', " ")),
            _ => serde_json::from_str(text).map_err(|e| e.to_string()),
        }
    }

    /// Checks what serde cannot: numbers in range, one placement per display, screens
    /// with area. `origin` names the rig in the error.
    pub fn validate(&self, origin: &str) -> Result<()> {
        let fail = |m: String| Err(Error::rig(origin, m));
        let v = &self.viewer;
        let pose = [v.yaw_deg, v.pitch_deg, v.roll_deg, v.ipd];
        if !v.position.iter().chain(&pose).all(|x| x.is_finite()) {
            return fail("viewer: every number must be finite".into());
        }
        if v.ipd < 0.0 {
            return fail(format!("viewer.ipd = {} must not be negative", v.ipd));
        }
        if !(self.near > 0.0 && self.far > self.near && self.far.is_finite()) {
            return fail(format!(
                "near = {} and far = {} need 0 < near < far",
                self.near, self.far
            ));
        }
        if self.displays.is_empty() {
            return fail("displays: at least one display is needed".into());
        }
        self.displays.iter().enumerate().try_for_each(|(i, d)| {
            validate_display(d).or_else(|m| fail(format!("displays[{i}] ({}): {m}", d.name)))
        })
    }

    /// This frame's views, resolved once: every display's eyes and display frustum (and
    /// from them, on demand, the frame frustum). Validates first, so that what is built
    /// from the result (contexts, cull jobs) cannot fail.
    pub fn resolve(&self) -> Result<ResolvedRig> {
        self.validate("(this frame's pose)")?;
        let displays = self
            .displays
            .iter()
            .map(|d| self.resolve_display(d).map_err(|m| Error::rig(&d.name, m)))
            .collect::<Result<Vec<_>>>()?;
        Ok(ResolvedRig {
            displays,
            viewer_position: self.viewer.position(),
            viewer_orientation: self.viewer.orientation(),
        })
    }

    /// Every display's cull against its display frustum, as the `instanced` mode culls
    /// (each visible object drawn once per view): the CPU reference of the cull dump.
    pub fn cull_jobs(&self) -> Result<Vec<CullJob>> {
        let resolved = self.resolve()?;
        Ok(self
            .displays
            .iter()
            .zip(&resolved.displays)
            .map(|(d, r)| r.cull_job(d.views()))
            .collect())
    }

    fn resolve_display(&self, d: &Display) -> std::result::Result<ResolvedDisplay, String> {
        let eyes = self
            .viewer
            .eye_positions(d.views())
            .into_iter()
            .enumerate()
            .map(|(e, position)| {
                let (orientation, fov) = match &d.mount {
                    Mount::Head(h) => head_fixed_basis(&self.viewer, h, e, d.views()),
                    Mount::Screen(s) => screen_basis(s, position)?,
                };
                Ok(View {
                    world_from_view: DAffine3::from_rotation_translation(orientation, position),
                    fov,
                    near: self.near,
                    far: self.far,
                })
            })
            .collect::<std::result::Result<Vec<View>, String>>()?;
        let combined = match (eyes.as_slice(), &d.mount) {
            ([mono], _) => Some(*mono),
            (_, mount) => {
                let orientation = match mount {
                    Mount::Head(h) => head_panel_orientation(&self.viewer, h),
                    Mount::Screen(_) => DQuat::from_mat3(&eyes[0].world_from_view.matrix3),
                };
                let origin = self.viewer.position();
                let corners: Vec<_> = eyes.iter().map(|e| e.corners_from(origin)).collect();
                enclosing_view(orientation, origin, &corners)
            }
        };
        let combined = combined
            .ok_or("the eyes' frusta span 180 degrees or more; no display frustum holds them")?;
        let planes = combined.frustum().planes;
        Ok(ResolvedDisplay {
            eyes,
            combined,
            planes,
        })
    }
}

/// One frame's views of a rig: what [`Rig::resolve`] builds once per frame.
#[derive(Clone, Debug, PartialEq)]
pub struct ResolvedRig {
    /// In the rig's display order.
    pub displays: Vec<ResolvedDisplay>,
    viewer_position: DVec3,
    viewer_orientation: DQuat,
}

impl ResolvedRig {
    /// The frame frustum, holding every display frustum (oriented as the viewer), or
    /// `None` when the displays surround the viewer (a CAVE) and no single frustum can.
    /// Built on demand: no per-frame pass uses it yet.
    pub fn frame(&self) -> Option<View> {
        let origin = self.viewer_position;
        let corners: Vec<_> = self
            .displays
            .iter()
            .map(|d| d.combined.corners_from(origin))
            .collect();
        enclosing_view(self.viewer_orientation, origin, &corners)
    }
}

/// One display's views for a frame.
#[derive(Clone, Debug, PartialEq)]
pub struct ResolvedDisplay {
    /// Left then right for stereo; the one eye for mono.
    pub eyes: Vec<View>,
    /// The display frustum's view: one frustum holding every eye of the display, the
    /// only one culling ever uses (never per eye).
    pub combined: View,
    /// `combined`'s planes, built once for the context and the cull of this frame.
    pub planes: [Vec4; 6],
}

impl ResolvedDisplay {
    /// Culling against the display frustum, each visible object drawn
    /// `instances_per_object` times.
    pub fn cull_job(&self, instances_per_object: u32) -> CullJob {
        CullJob {
            planes: self.planes,
            instances_per_object,
        }
    }
}

fn euler(yaw_deg: f32, pitch_deg: f32, roll_deg: f32) -> DQuat {
    let rad = |deg: f32| (deg as f64).to_radians();
    DQuat::from_euler(EulerRot::YXZ, rad(yaw_deg), rad(pitch_deg), rad(roll_deg))
}

fn head_panel_orientation(viewer: &Viewer, h: &HeadFixed) -> DQuat {
    viewer.orientation() * euler(h.yaw_deg, h.pitch_deg, 0.0)
}

fn head_fixed_basis(viewer: &Viewer, h: &HeadFixed, eye: usize, views: u32) -> (DQuat, Fov) {
    let panel = head_panel_orientation(viewer, h);
    if views == 1 {
        return (panel, h.fov);
    }
    // Left eye turns left (+yaw), right eye right.
    let cant = if eye == 0 { h.cant_deg } else { -h.cant_deg };
    let fov = if eye == 0 {
        h.fov
    } else {
        h.fov_right.unwrap_or(h.fov.mirrored())
    };
    (panel * euler(cant, 0.0, 0.0), fov)
}

/// Kooima's generalized perspective projection: the view looks along the screen's
/// inward normal and its window is the screen rectangle seen from `eye`.
///
/// The rectangle is the screen's completion: the lower edge as given, the up direction
/// made perpendicular to it (Gram-Schmidt), and the height of `upper_left` above the
/// lower edge. Validation allows corners a hair off a right angle; this is then the
/// rectangle both the projection and the culling frustum use.
fn screen_basis(s: &Screen, eye: DVec3) -> std::result::Result<(DQuat, Fov), String> {
    let [pa, pb, pc] =
        [s.lower_left, s.lower_right, s.upper_left].map(|p| DVec3::from(p.map(f64::from)));
    let vr = (pb - pa).normalize();
    let vu = (pc - pa).reject_from_normalized(vr).normalize();
    let vn = vr.cross(vu);
    let (va, vb, vc) = (pa - eye, pb - eye, pc - eye);
    let dist = -va.dot(vn);
    if dist <= 1e-4 {
        return Err(format!("the eye at {eye} is on or behind the screen"));
    }
    let fov = Fov {
        left: (-vr.dot(va) / dist) as f32,
        right: (vr.dot(vb) / dist) as f32,
        up: (vu.dot(vc) / dist) as f32,
        down: (-vu.dot(va) / dist) as f32,
    };
    Ok((DQuat::from_mat3(&DMat3::from_cols(vr, vu, vn)), fov))
}

fn validate_display(d: &Display) -> std::result::Result<(), String> {
    if d.resolution[0] == 0 || d.resolution[1] == 0 {
        return Err(format!(
            "resolution {:?} must be at least 1x1",
            d.resolution
        ));
    }
    match &d.mount {
        Mount::Head(h) => validate_head(h),
        Mount::Screen(s) => validate_screen(s),
    }
}

fn validate_head(h: &HeadFixed) -> std::result::Result<(), String> {
    let angles = [h.yaw_deg, h.pitch_deg, h.cant_deg];
    if !angles.iter().all(|a| a.is_finite()) {
        return Err("head: angles must be finite".into());
    }
    for (name, fov) in [("fov", Some(h.fov)), ("fov_right", h.fov_right)] {
        if let Some(f) = fov
            && !f.is_valid()
        {
            return Err(format!(
                "head.{name}: tangents must be finite with left + right > 0 and up + down > 0 (a field of view under 180 degrees), got {f:?}"
            ));
        }
    }
    Ok(())
}

fn validate_screen(s: &Screen) -> std::result::Result<(), String> {
    let pts = [s.lower_left, s.lower_right, s.upper_left];
    if !pts.iter().flatten().all(|x| x.is_finite()) {
        return Err("screen: corners must be finite".into());
    }
    let [pa, pb, pc] =
        [s.lower_left, s.lower_right, s.upper_left].map(|p| DVec3::from(p.map(f64::from)));
    let (w, h) = (pb - pa, pc - pa);
    if w.length() < 1e-4 || h.length() < 1e-4 {
        return Err("screen: degenerate corners (an edge shorter than 0.1 mm)".into());
    }
    if w.normalize().dot(h.normalize()).abs() > 1e-3 {
        return Err(
            "screen: lower_left->lower_right and lower_left->upper_left must be perpendicular"
                .into(),
        );
    }
    Ok(())
}

fn hmd() -> Rig {
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
        displays: vec![Display {
            name: "hmd".into(),
            stereo: true,
            resolution: [1440, 1600],
            // Outer half-angle wider than the nasal one, like shipping headsets.
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
        }],
    }
}

/// A 3 m cube of walls around the origin, floor at y = 0.
fn cave() -> Rig {
    let h = 1.5;
    let wall = |name: &str, ll: [f32; 3], lr: [f32; 3], ul: [f32; 3]| Display {
        name: name.into(),
        stereo: true,
        resolution: [1024, 1024],
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

fn hmd_peripheral() -> Rig {
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
