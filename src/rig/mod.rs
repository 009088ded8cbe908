//! The viewing rig: a tracked viewer and its displays, each stereo or mono, head-fixed
//! (an HMD panel), world-fixed (a CAVE wall given by its corners), or given as an XR
//! runtime's posed views.
//!
//! Everything is in meters, in tracking space, which is also world space here: the
//! scene is authored at real scale and nothing rescales it.

use std::path::Path;

use glam::{DQuat, DVec3, EulerRot};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::frustum::Fov;

mod foveation;
pub mod framing;
mod mask;
mod posed;
mod presets;
mod resolve;

pub use foveation::{Foveation, Gaze, ViewLayout};
pub use mask::{MAX_MASK_TRIANGLES, MaskTriangle, VisibilityMask};
pub use posed::{FovAngles, PosedView};
pub use resolve::{ResolvedDisplay, ResolvedRig};

/// The tracked head. Orientation is yaw (about +Y, positive turns left), then pitch
/// (about the turned +X, positive looks up), then roll; at zero it looks down -Z.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Viewer {
    /// Meters, in tracking space.
    pub position: [f32; 3],
    /// Degrees about +Y, positive turns left.
    #[serde(default)]
    pub yaw_deg: f32,
    /// Degrees about the turned +X, positive looks up.
    #[serde(default)]
    pub pitch_deg: f32,
    /// Degrees about the view axis.
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
    /// Yaw, then pitch, then roll.
    pub fn orientation(&self) -> DQuat {
        euler(self.yaw_deg, self.pitch_deg, self.roll_deg)
    }

    /// The position in f64.
    pub fn position(&self) -> DVec3 {
        DVec3::from(self.position.map(f64::from))
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
    /// Degrees: the panel tilted up from the head's axis.
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
    /// The screen's lower left corner, meters in tracking space.
    pub lower_left: [f32; 3],
    /// Its lower right corner.
    pub lower_right: [f32; 3],
    /// Its upper left corner.
    pub upper_left: [f32; 3],
}

/// Where a display's image is fixed: to the head, or in the world; or its views as
/// an XR runtime gives them each frame.
#[derive(Clone, Debug, PartialEq)]
pub enum Mount {
    /// An HMD panel: moves with the viewer's head.
    Head(HeadFixed),
    /// A CAVE wall: fixed in tracking space, seen off-axis from each eye.
    Screen(Screen),
    /// Each view's pose and field-of-view angles, in the runtime's order (left, then
    /// right), replaced every frame by the caller; the viewer's pose still places the
    /// frame (levels of detail, the frame frustum, the shadow fit).
    Views(Vec<PosedView>),
}

/// One display: a head-fixed panel or a world-fixed screen, stereo or mono.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "DisplayFile", into = "DisplayFile")]
pub struct Display {
    /// Names its image (`<name>.png`) and its timer scope.
    pub name: String,
    /// Two views (left, right) when true, one otherwise.
    pub stereo: bool,
    /// Pixels per eye: the stereo target is twice as wide.
    pub resolution: [u32; 2],
    /// Where its image is fixed.
    pub mount: Mount,
    /// Four views instead of two: an outer pair at a peripheral density and an inset
    /// per eye at the focus density (stereo displays only).
    pub foveation: Option<Foveation>,
    /// The lens's hidden area per view, as the runtime gives it: written to depth
    /// before the scene (`RendererOptions::visibility_mask`).
    pub visibility_mask: Option<VisibilityMask>,
    /// The MPI rank that draws it under `stereocull cluster` (none: round robin).
    pub rank: Option<u32>,
}

impl Display {
    /// Views: 1 for mono, 2 for stereo, 4 for foveated stereo (outer left, outer right,
    /// inset left, inset right).
    pub fn views(&self) -> u32 {
        match (self.stereo, self.foveation) {
            (false, _) => 1,
            (true, None) => 2,
            (true, Some(_)) => 4,
        }
    }

    /// Where each view lies in the display's target: one eye's resolution per view,
    /// side by side; a foveated display's outer pair then its insets, at their densities.
    pub fn layout(&self) -> ViewLayout {
        let (w, h) = (self.resolution[0], self.resolution[1]);
        match (self.views(), self.foveation) {
            (4, Some(f)) => {
                let [outer, inset] = f.view_sizes(self.resolution);
                ViewLayout::side_by_side(&[outer, outer, inset, inset])
            }
            (views, _) => ViewLayout::side_by_side(&[(w, h); 4][..views as usize]),
        }
    }

    /// The layout of the display's views, as layers of one size (`layered`: multiview,
    /// whose layers share one size, the largest view's, read back side by side) or
    /// packed side by side at their own sizes ([`Display::layout`]).
    pub fn layout_in(&self, layered: bool) -> ViewLayout {
        let packed = self.layout();
        if !layered {
            return packed;
        }
        let size = |v: &[u32; 4]| (v[2], v[3]);
        let (w, h) = (packed.viewports().iter().map(size))
            .fold((0, 0), |(w, h), (x, y)| (w.max(x), h.max(y)));
        ViewLayout::side_by_side(&[(w, h); 4][..packed.views as usize])
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
    #[serde(default, skip_serializing_if = "Option::is_none")]
    views: Option<Vec<PosedView>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    foveation: Option<Foveation>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    visibility_mask: Option<VisibilityMask>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    rank: Option<u32>,
}

impl TryFrom<DisplayFile> for Display {
    type Error = String;

    fn try_from(f: DisplayFile) -> std::result::Result<Display, String> {
        let mount = match (f.head, f.screen, f.views) {
            (Some(h), None, None) => Mount::Head(h),
            (None, Some(s), None) => Mount::Screen(s),
            (None, None, Some(v)) => Mount::Views(v),
            _ => {
                return Err(format!(
                    "display {:?} needs exactly one of `head`, `screen` or `views`",
                    f.name
                ));
            }
        };
        Ok(Display {
            name: f.name,
            stereo: f.stereo,
            resolution: f.resolution,
            mount,
            foveation: f.foveation,
            visibility_mask: f.visibility_mask,
            rank: f.rank,
        })
    }
}

impl From<Display> for DisplayFile {
    fn from(d: Display) -> DisplayFile {
        let (head, screen, views) = match d.mount {
            Mount::Head(h) => (Some(h), None, None),
            Mount::Screen(s) => (None, Some(s), None),
            Mount::Views(v) => (None, None, Some(v)),
        };
        DisplayFile {
            name: d.name,
            stereo: d.stereo,
            resolution: d.resolution,
            head,
            screen,
            views,
            foveation: d.foveation,
            visibility_mask: d.visibility_mask,
            rank: d.rank,
        }
    }
}

/// The tracked viewer and the displays it looks at (a preset or a rig file).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rig {
    /// The tracked head.
    pub viewer: Viewer,
    /// Near plane in meters (default 0.05).
    #[serde(default = "default_near")]
    pub near: f32,
    /// Far plane in meters (default 1000).
    #[serde(default = "default_far")]
    pub far: f32,
    /// The displays, each drawn into its own target.
    pub displays: Vec<Display>,
    /// Displays of the whole rig that this process does not draw ([`Rig::subset`]):
    /// their views still shape what the frame decides once for all displays (the
    /// level-of-detail density, the shadow fit, the frame frustum), so that each process
    /// of a clustered CAVE decides as the whole rig would. Not part of rig files.
    #[serde(skip)]
    pub frame_only: Vec<Display>,
}

fn default_near() -> f32 {
    0.05
}
fn default_far() -> f32 {
    1000.0
}

/// The preset names `Rig::preset` knows.
pub const PRESETS: [&str; 4] = ["hmd", "cave", "hmd-peripheral", "hmd-foveated"];

impl Rig {
    /// `hmd`, `cave`, `hmd-peripheral` or `hmd-foveated`; see the README for what each is.
    pub fn preset(name: &str) -> Result<Rig> {
        let rig = match name {
            "hmd" => presets::hmd(),
            "cave" => presets::cave(),
            "hmd-peripheral" => presets::hmd_peripheral(),
            "hmd-foveated" => presets::hmd_foveated(),
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

    /// The rig with only the displays named in `names` drawn, in the rig's order; the
    /// others become [`Rig::frame_only`], so the frame is planned as for the whole rig and
    /// each drawn display culls and draws byte for byte as it does in a full run.
    pub fn subset(&self, names: &[String], origin: &str) -> Result<Rig> {
        let known: Vec<&str> = self.displays.iter().map(|d| d.name.as_str()).collect();
        if names.is_empty() {
            return Err(Error::rig(origin, "--displays: name at least one display"));
        }
        for (i, name) in names.iter().enumerate() {
            if !known.contains(&name.as_str()) {
                let list = known.join(", ");
                let m = format!("--displays: the rig has no display {name:?} (it has {list})");
                return Err(Error::rig(origin, m));
            }
            if names[..i].contains(name) {
                return Err(Error::rig(
                    origin,
                    format!("--displays: {name:?} named twice"),
                ));
            }
        }
        let (drawn, others) = self
            .displays
            .iter()
            .cloned()
            .partition(|d| names.contains(&d.name));
        let mut frame_only: Vec<Display> = others;
        frame_only.extend(self.frame_only.iter().cloned());
        Ok(Rig {
            displays: drawn,
            frame_only,
            ..self.clone()
        })
    }

    /// Sets where the eyes look on every foveated display (the drawn and the frame-only
    /// ones); an error naming the rig's displays when none is foveated.
    pub fn set_gaze(&mut self, gaze: Gaze) -> std::result::Result<(), String> {
        let mut foveated = self
            .displays
            .iter_mut()
            .chain(&mut self.frame_only)
            .filter_map(|d| d.foveation.as_mut())
            .peekable();
        if foveated.peek().is_none() {
            return Err("the rig has no foveated display (e.g. --rig hmd-foveated)".into());
        }
        foveated.for_each(|f| f.gaze = Some(gaze));
        Ok(())
    }

    /// Every display the frame is planned for: the drawn ones, then the frame-only ones.
    pub fn frame_displays(&self) -> impl Iterator<Item = &Display> {
        self.displays.iter().chain(&self.frame_only)
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
        self.frame_displays().enumerate().try_for_each(|(i, d)| {
            validate_display(d).or_else(|m| fail(format!("displays[{i}] ({}): {m}", d.name)))
        })
    }
}

fn validate_display(d: &Display) -> std::result::Result<(), String> {
    if d.resolution[0] == 0 || d.resolution[1] == 0 {
        return Err(format!(
            "resolution {:?} must be at least 1x1",
            d.resolution
        ));
    }
    if let Some(f) = &d.foveation {
        if !d.stereo {
            return Err("foveation needs a stereo display (an inset per eye)".into());
        }
        f.check()?;
    }
    if let Some(mask) = &d.visibility_mask {
        mask.check(d.views())?;
    }
    match &d.mount {
        Mount::Head(h) => validate_head(h),
        Mount::Screen(s) => validate_screen(s),
        Mount::Views(v) => posed::check_views(v, d.views()),
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

/// The rig's angle convention, in degrees: yaw about +Y, then pitch about the turned +X,
/// then roll.
fn euler(yaw_deg: f32, pitch_deg: f32, roll_deg: f32) -> DQuat {
    let rad = |deg: f32| (deg as f64).to_radians();
    DQuat::from_euler(EulerRot::YXZ, rad(yaw_deg), rad(pitch_deg), rad(roll_deg))
}
