//! Resolving a rig for one frame: each display's eyes (head-fixed panels, or off-axis
//! views through world-fixed screens) and its display frustum, in f64, once.

use glam::{DAffine3, DMat3, DQuat, DVec3, Vec4};

use super::posed::{self, PosedView};
use super::{Display, HeadFixed, Mount, Rig, Screen, Viewer, euler};
use crate::cull::coarse::expected_tests;
use crate::cull::{CoarseCull, CullJob};
use crate::error::{Error, Result};
use crate::frustum::{Fov, View, enclosing_view};

impl Rig {
    /// This frame's views, resolved once: every display's eyes and display frustum (and
    /// from them, on demand, the frame frustum). Validates first, so that what is built
    /// from the result (contexts, cull jobs) cannot fail.
    pub fn resolve(&self) -> Result<ResolvedRig> {
        self.resolve_into(Vec::new())
    }

    /// [`Rig::resolve`] with the displays in `displays`' allocation (a spent frame's).
    pub(crate) fn resolve_into(&self, mut displays: Vec<ResolvedDisplay>) -> Result<ResolvedRig> {
        self.validate("(this frame's pose)")?;
        let head = Head::of(&self.viewer);
        let resolve =
            |d: &Display| (self.resolve_display(d, &head)).map_err(|m| Error::rig(&d.name, m));
        displays.clear();
        for d in &self.displays {
            displays.push(resolve(d)?);
        }
        let frame_only = self.frame_only.iter().map(resolve).collect::<Result<_>>()?;
        Ok(ResolvedRig {
            displays,
            frame_only,
            viewer_position: head.position,
            viewer_orientation: head.orientation,
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

    fn resolve_display(
        &self,
        d: &Display,
        head: &Head,
    ) -> std::result::Result<ResolvedDisplay, String> {
        let (eyes, gaze_clamped) = self.views(d, head)?;
        let combined = match (eyes.as_slice(), &d.mount) {
            ([mono], _) => Some(*mono),
            (_, mount) => {
                let (orientation, origin) = match mount {
                    Mount::Head(h) => (head.panel(h), head.position),
                    Mount::Screen(_) => (
                        DQuat::from_mat3(&eyes[0].world_from_view.matrix3),
                        head.position,
                    ),
                    Mount::Views(v) => (posed::middle_rotation(v), posed::middle_position(v)),
                };
                enclosing_view(orientation, origin, &eyes)
            }
        };
        let combined = combined
            .ok_or("the eyes' frusta span 180 degrees or more; no display frustum holds them")?;
        let planes = combined.frustum().planes;
        // The inset pair from the display frustum's apex and orientation: inside the
        // display frustum, so it exists whenever that does.
        let insets = eyes.get(2..).filter(|i| !i.is_empty()).map(|insets| {
            let origin = combined.world_from_view.translation;
            let orientation = DQuat::from_mat3(&combined.world_from_view.matrix3);
            enclosing_view(orientation, origin, insets)
        });
        Ok(ResolvedDisplay {
            eyes,
            combined,
            planes,
            gaze_clamped,
            insets: insets.flatten(),
        })
    }

    /// [`Rig::eyes`] with a foveated display's insets after its eyes (each inside its
    /// eye's window, around the gaze), and whether a gaze was moved to keep an inset
    /// inside. Posed views bring their insets with them.
    fn views(&self, d: &Display, head: &Head) -> std::result::Result<(Vec<View>, bool), String> {
        let mut views = Vec::with_capacity(d.views() as usize);
        self.eyes(d, head, &mut views)?;
        let (Some(foveation), false) = (d.foveation, matches!(d.mount, Mount::Views(_))) else {
            return Ok((views, false));
        };
        let mut clamped = false;
        for e in 0..2 {
            let (inset, moved) = foveation.inset(views[e].fov, e);
            clamped |= moved;
            views.push(View {
                fov: inset,
                ..views[e]
            });
        }
        Ok((views, clamped))
    }

    /// Each eye's view, pushed onto `views`: placed from the viewer and the panel, from
    /// the viewer and the screen, or as the runtime posed it.
    fn eyes(
        &self,
        d: &Display,
        head: &Head,
        views: &mut Vec<View>,
    ) -> std::result::Result<(), String> {
        let eyes = d.views().min(2);
        let view = |position, orientation, fov| View {
            world_from_view: DAffine3::from_rotation_translation(orientation, position),
            fov,
            near: self.near,
            far: self.far,
        };
        match &d.mount {
            Mount::Head(h) => {
                let panel = head.panel(h);
                for e in 0..eyes as usize {
                    let (orientation, fov) = head_fixed_basis(panel, h, e, eyes);
                    views.push(view(head.eye(e, eyes), orientation, fov));
                }
            }
            Mount::Screen(s) => {
                let screen = ScreenBasis::of(s);
                for e in 0..eyes as usize {
                    let p = head.eye(e, eyes);
                    let (orientation, fov) = screen.seen_from(p)?;
                    views.push(view(p, orientation, fov));
                }
            }
            Mount::Views(posed) => {
                let fov = |v: &PosedView| v.fov.tangents();
                views.extend(
                    posed
                        .iter()
                        .map(|v| view(v.position(), v.rotation(), fov(v))),
                );
            }
        }
        Ok(())
    }
}

/// The viewer's pose for one frame, made once from its angles (every display's eyes
/// are placed from it).
pub(crate) struct Head {
    position: DVec3,
    orientation: DQuat,
    /// Half the eye separation, along the head's right.
    half_ipd: DVec3,
}

impl Head {
    pub(crate) fn of(viewer: &Viewer) -> Head {
        let orientation = viewer.orientation();
        Head {
            position: viewer.position(),
            orientation,
            half_ipd: orientation * DVec3::X * (0.5 * viewer.ipd as f64),
        }
    }

    /// Eye `e`'s center of a display of `views` views: the cyclopean point for mono,
    /// left then right for stereo, and for foveated stereo left, right, left, right
    /// (the insets share their eye's center).
    pub(crate) fn eye(&self, e: usize, views: u32) -> DVec3 {
        match (views, e % 2) {
            (1, _) => self.position,
            (_, 0) => self.position - self.half_ipd,
            _ => self.position + self.half_ipd,
        }
    }

    /// A head-fixed panel's orientation.
    fn panel(&self, h: &HeadFixed) -> DQuat {
        self.orientation * euler(h.yaw_deg, h.pitch_deg, 0.0)
    }
}

/// One frame's views of a rig: what [`Rig::resolve`] builds once per frame.
#[derive(Clone, Debug, PartialEq)]
pub struct ResolvedRig {
    /// In the rig's display order.
    pub displays: Vec<ResolvedDisplay>,
    /// [`Rig::frame_only`]'s, in order: planned for, not drawn.
    pub frame_only: Vec<ResolvedDisplay>,
    viewer_position: DVec3,
    viewer_orientation: DQuat,
}

impl ResolvedRig {
    /// The frame frustum, holding every display frustum (oriented as the viewer), or
    /// `None` when the displays surround the viewer (a CAVE) and no single frustum can.
    /// Built on demand: no per-frame pass uses it yet.
    pub fn frame(&self) -> Option<View> {
        let combined: Vec<View> = self.frame_displays().map(|d| d.combined).collect();
        enclosing_view(self.viewer_orientation, self.viewer_position, &combined)
    }

    /// Every display the frame is planned for: the drawn ones, then the frame-only ones.
    pub fn frame_displays(&self) -> impl Iterator<Item = &ResolvedDisplay> {
        self.displays.iter().chain(&self.frame_only)
    }

    /// The frame's coarse cull test: the frame frustum's planes made safe for every
    /// display's cull, and with `per_eye` for every eye's instead (the multi-camera mode
    /// culls per eye), or [`CoarseCull::EVERYTHING`] without a frame frustum. Only the
    /// culls that will run are held: each costs a search per frame plane.
    pub fn coarse_cull(&self, per_eye: bool) -> CoarseCull {
        let Some(frame) = self.frame() else {
            return CoarseCull::EVERYTHING;
        };
        let views: Vec<[Vec4; 6]> = match per_eye {
            false => self.displays.iter().map(|d| d.planes).collect(),
            true => self
                .displays
                .iter()
                .flat_map(|d| d.eyes.iter().map(|e| e.frustum().planes))
                .collect(),
        };
        CoarseCull::holding(frame.frustum().planes, &views).unwrap_or(CoarseCull::EVERYTHING)
    }

    /// This frame and `next` as one set of views per display, for a submission of two
    /// frames ([`crate::renderer::RendererOptions::frames_per_submit`]): each display's
    /// eyes, then the next frame's, and a display frustum holding all of them, oriented
    /// and placed as this frame's. The frame frustum is this frame's viewer's. `None`
    /// where no one frustum holds a display's eyes at both poses (they span 180 degrees
    /// or more), or the rigs' displays differ in number.
    pub fn followed_by(&self, next: &ResolvedRig) -> Option<ResolvedRig> {
        let pair = |(a, b): (&ResolvedDisplay, &ResolvedDisplay)| a.followed_by(b);
        let same = |a: &[ResolvedDisplay], b: &[ResolvedDisplay]| a.len() == b.len();
        if !same(&self.displays, &next.displays) || !same(&self.frame_only, &next.frame_only) {
            return None;
        }
        Some(ResolvedRig {
            displays: (self.displays.iter().zip(&next.displays))
                .map(pair)
                .collect::<Option<_>>()?,
            frame_only: (self.frame_only.iter().zip(&next.frame_only))
                .map(pair)
                .collect::<Option<_>>()?,
            ..*self
        })
    }

    /// [`expected_tests`] for this frame's displays.
    pub fn expected_coarse_tests(&self) -> f64 {
        let views: Vec<View> = self.displays.iter().map(|d| d.combined).collect();
        expected_tests(&views)
    }
}

/// One display's views for a frame.
#[derive(Clone, Debug, PartialEq)]
pub struct ResolvedDisplay {
    /// Left then right for stereo; the one eye for mono; for foveated stereo the outer
    /// left and right, then the insets of the left and right eye.
    pub eyes: Vec<View>,
    /// The display frustum's view: one frustum holding every eye of the display, the
    /// only one culling ever uses (never per eye).
    pub combined: View,
    /// `combined`'s planes, built once for the context and the cull of this frame.
    pub planes: [Vec4; 6],
    /// A foveated display's gaze fell where an inset would leave its eye's window, and
    /// the inset was moved back inside.
    pub gaze_clamped: bool,
    /// A foveated display's inset frustum: one frustum holding both insets (what the
    /// inset cull tests, [`crate::renderer::RendererOptions::inset_cull`]).
    pub insets: Option<View>,
}

impl ResolvedDisplay {
    /// This display's eyes then `next`'s, in a display frustum that holds all of them,
    /// oriented halfway between the two frames' display frusta (so that a turn widens
    /// it on both sides alike, not twice on one) and built from the midpoint of their
    /// apexes.
    fn followed_by(&self, next: &ResolvedDisplay) -> Option<ResolvedDisplay> {
        let eyes: Vec<View> = self.eyes.iter().chain(&next.eyes).copied().collect();
        let (a, b) = (self.combined.world_from_view, next.combined.world_from_view);
        let (qa, qb) = (DQuat::from_mat3(&a.matrix3), DQuat::from_mat3(&b.matrix3));
        let origin = (a.translation + b.translation) * 0.5;
        let combined = enclosing_view(qa.slerp(qb, 0.5), origin, &eyes)?;
        Some(ResolvedDisplay {
            eyes,
            combined,
            planes: combined.frustum().planes,
            gaze_clamped: self.gaze_clamped || next.gaze_clamped,
            insets: None,
        })
    }

    /// Culling against the display frustum, each visible object drawn
    /// `instances_per_object` times.
    pub fn cull_job(&self, instances_per_object: u32) -> CullJob {
        let eye = |e: usize| self.eyes[e].position();
        CullJob {
            planes: self.planes,
            instances_per_object,
            split: None,
            hidden: None,
            tiles: None,
            // As DisplayContext::sort_origin, from the same f32 positions.
            sort_origin: match self.eyes.len() >= 2 {
                true => (eye(0) + eye(1)) * 0.5,
                false => eye(0),
            },
        }
    }
}

fn head_fixed_basis(panel: DQuat, h: &HeadFixed, eye: usize, views: u32) -> (DQuat, Fov) {
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
/// inward normal and its window is the screen rectangle seen from the eye.
///
/// The rectangle is the screen's completion: the lower edge as given, the up direction
/// made perpendicular to it (Gram-Schmidt), and the height of `upper_left` above the
/// lower edge. Validation allows corners a hair off a right angle; this is then the
/// rectangle both the projection and the culling frustum use. The basis is the same for
/// every eye, so it is made once per display; each eye finds its window from it.
struct ScreenBasis {
    corners: [DVec3; 3],
    right: DVec3,
    up: DVec3,
    normal: DVec3,
    orientation: DQuat,
}

impl ScreenBasis {
    fn of(s: &Screen) -> ScreenBasis {
        let corners =
            [s.lower_left, s.lower_right, s.upper_left].map(|p| DVec3::from(p.map(f64::from)));
        let [pa, pb, pc] = corners;
        let right = (pb - pa).normalize();
        let up = (pc - pa).reject_from_normalized(right).normalize();
        let normal = right.cross(up);
        ScreenBasis {
            corners,
            right,
            up,
            normal,
            orientation: DQuat::from_mat3(&DMat3::from_cols(right, up, normal)),
        }
    }

    /// The view's orientation and window from `eye`.
    fn seen_from(&self, eye: DVec3) -> std::result::Result<(DQuat, Fov), String> {
        let (vr, vu) = (self.right, self.up);
        let [va, vb, vc] = self.corners.map(|p| p - eye);
        let dist = -va.dot(self.normal);
        if dist <= 1e-4 {
            return Err(format!("the eye at {eye} is on or behind the screen"));
        }
        let fov = Fov {
            left: (-vr.dot(va) / dist) as f32,
            right: (vr.dot(vb) / dist) as f32,
            up: (vu.dot(vc) / dist) as f32,
            down: (-vu.dot(va) / dist) as f32,
        };
        Ok((self.orientation, fov))
    }
}
