//! Frame, display and eye contexts (the chapter's Listing 1.3): what is computed once
//! per frame, once per display, and per eye. The WGSL twins live in
//! `wgsl/shared/contexts.wgsl`; encase lays these out to match (`tests/shaders.rs`
//! checks every member).

use encase::ShaderType;
use glam::{Mat4, Vec2, Vec3, Vec4};

use crate::cull::CoarseCull;
use crate::cull::rig::{MemberAt, RigOcclusion, RigView};
use crate::frustum::View;
use crate::rig::{ResolvedDisplay, ViewLayout, Viewer};
use crate::shadow::LightView;

/// Once per frame: the viewer (not any eye) and the time, bound to the cull and draw
/// pipelines. The draw pass animates instances from `time` ([`crate::scene::Animation`]).
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub struct FrameContext {
    /// The tracked head's position (not an eye's): levels of detail are chosen from it.
    pub viewer_position: Vec3,
    /// Seconds on the caller's clock.
    pub time: f32,
    /// Where the viewer looks (unit length): for material hooks (head-following
    /// effects); no built-in pass reads it.
    pub viewer_direction: Vec3,
    /// Level-of-detail scale: (pixels per radian / pixels of error allowed)^2 for the
    /// sharpest display, so that one level per instance serves every display and eye
    /// (see [`crate::records::lod_level`]).
    pub lod_scale: f32,
    /// The frame-level coarse cull's test ([`CoarseCull`]; read only when it is on).
    pub coarse_planes: [Vec4; 6],
    /// How much the coarse test grows radii (the largest Farkas weight sum).
    pub coarse_inflation: f32,
    /// The coarse test's rounding slack per unit of a center's coordinates.
    pub coarse_slack: f32,
    /// The frame's light ([`crate::shadow`]): world to its shadow map's clip space,
    /// where it comes from (unit), and 1 when the shadow map was drawn this frame.
    pub light_from_world: Mat4,
    /// Where the light comes from (unit length).
    pub light_direction: Vec3,
    /// 1 when the shadow map was drawn this frame, else 0.
    pub shadows: u32,
    /// The previous frame's time: with motion vectors, the draw animates each
    /// instance's previous position from it ([`crate::motion`]); else `time`.
    pub previous_time: f32,
    /// The camera's exposure: the scale of the light that reaches it
    /// ([`crate::exposure`]; 1 unless a renderer sets it).
    pub exposure: f32,
    /// Its tone mapper ([`crate::exposure::Tonemap::wgsl`]; 0, none, unless set).
    pub tonemap: u32,
}

impl FrameContext {
    /// The frame's context; `light` shades, and with `shadows` its view's shadow map
    /// darkens what it does not reach.
    pub fn new(
        viewer: &Viewer,
        time: f32,
        lod_scale: f32,
        coarse: &CoarseCull,
        light: &LightView,
        shadows: bool,
    ) -> FrameContext {
        let orientation = viewer.orientation();
        FrameContext {
            viewer_position: viewer.position().as_vec3(),
            time,
            viewer_direction: (orientation * -glam::DVec3::Z).as_vec3(),
            lod_scale,
            coarse_planes: coarse.planes,
            coarse_inflation: coarse.inflation,
            coarse_slack: coarse.slack,
            light_from_world: light.clip_from_world,
            light_direction: light.direction,
            shadows: u32::from(shadows),
            previous_time: time,
            exposure: 1.0,
            tonemap: 0,
        }
    }
}

/// One eye of a display: only what truly differs per eye. The built-in passes read
/// `clip_from_world`, `world_from_clip` and `position`; the view and clip matrices and
/// their inverses are for material hooks (view-space depth, fog, screen-space effects).
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub struct EyeContext {
    /// World to this eye's view space (the chapter's `mLocation`).
    pub view_from_world: Mat4,
    /// `view_from_world`'s inverse.
    pub world_from_view: Mat4,
    /// View to clip space (the chapter's `mProjection`), depth 0 at near.
    pub clip_from_view: Mat4,
    /// `clip_from_view`'s inverse.
    pub view_from_clip: Mat4,
    /// World to clip, composed in f64: what vertices use.
    pub clip_from_world: Mat4,
    /// Clip to world, composed in f64: how fragments find their world position.
    pub world_from_clip: Mat4,
    /// The previous frame's `clip_from_world` of this view, with motion vectors
    /// ([`crate::motion`]); else `clip_from_world`.
    pub previous_clip_from_world: Mat4,
    /// The eye's center of projection, for specular.
    pub position: Vec3,
    /// Seconds this view's frame lies after the frame context's `time`: a two-frame
    /// submission's second frame draws its views at `time + time_ahead`
    /// ([`crate::renderer::RendererOptions::frames_per_submit`]); else 0.
    pub time_ahead: f32,
    /// Where this view lies in its display's target: x, y, width, height in pixels.
    pub viewport: Vec4,
    /// How the view's clip space is placed into its viewport of a shared target (the
    /// instanced path, one draw for every view): `x' = x * p.x + w * p.y`,
    /// `y' = y * p.z + w * p.w`. Identity (1, 0, 1, 0) for a view that fills its target.
    pub placement: Vec4,
}

impl EyeContext {
    /// A slot before its view is placed in it.
    const UNSET: EyeContext = EyeContext {
        view_from_world: Mat4::IDENTITY,
        world_from_view: Mat4::IDENTITY,
        clip_from_view: Mat4::IDENTITY,
        view_from_clip: Mat4::IDENTITY,
        clip_from_world: Mat4::IDENTITY,
        world_from_clip: Mat4::IDENTITY,
        previous_clip_from_world: Mat4::IDENTITY,
        position: Vec3::ZERO,
        time_ahead: 0.0,
        viewport: Vec4::ZERO,
        placement: IDENTITY_PLACEMENT,
    };

    /// The eye context of view `v`.
    pub fn from_view(v: &View) -> EyeContext {
        let mut context = EyeContext::UNSET;
        context.set_view(v);
        context
    }

    /// This slot holds view `v` (its viewport and placement unchanged), written field
    /// by field: the context is 496 bytes, and moving it whole costs more than its math.
    fn set_view(&mut self, v: &View) {
        let clip_from_view = v.clip_from_view();
        let [view_from_world, clip_from_world, world_from_clip] = v.world_matrices();
        self.view_from_world = view_from_world;
        self.world_from_view = v.world_from_view_f32();
        self.clip_from_view = clip_from_view;
        self.view_from_clip = v.view_from_clip();
        self.clip_from_world = clip_from_world;
        self.world_from_clip = world_from_clip;
        self.previous_clip_from_world = clip_from_world;
        self.position = v.position();
        self.time_ahead = 0.0;
    }

    /// This eye drawn into `viewport` (`[x, y, width, height]` pixels) of a target of
    /// `size` pixels. The placement is exact in f32 where the rectangle halves the target
    /// (0.5 and -+0.5 for double-wide stereo), so such draws land as a full-target draw
    /// with that viewport would.
    pub fn placed(self, viewport: [u32; 4], size: (u32, u32)) -> EyeContext {
        EyeContext {
            viewport: Vec4::from(viewport.map(|v| v as f32)),
            placement: placement(viewport, size),
            ..self
        }
    }
}

/// The placement of `viewport` (`[x, y, width, height]` pixels) in a target of `size`
/// pixels: a view's clip coordinates `(x, y, w)` land at `x * p.x + w * p.y`,
/// `y * p.z + w * p.w` of the target's.
pub fn placement(viewport: [u32; 4], size: (u32, u32)) -> Vec4 {
    let [x, y, w, h] = viewport.map(f64::from);
    let (tw, th) = (size.0 as f64, size.1 as f64);
    Vec4::new(
        (w / tw) as f32,
        ((2.0 * x + w) / tw - 1.0) as f32,
        (h / th) as f32,
        (1.0 - (2.0 * y + h) / th) as f32,
    )
}

/// A view that fills its target.
const IDENTITY_PLACEMENT: Vec4 = Vec4::new(1.0, 0.0, 1.0, 0.0);

/// One display: its combined frustum, both eyes, and what the cull pass needs. The
/// combined frustum's matrices are for material hooks (no built-in pass reads them).
#[derive(Clone, Copy, Debug, PartialEq, ShaderType)]
pub struct DisplayContext {
    /// World to the combined frustum's view space.
    pub view_from_world: Mat4,
    /// `view_from_world`'s inverse.
    pub world_from_view: Mat4,
    /// The combined frustum's projection.
    pub clip_from_view: Mat4,
    /// `clip_from_view`'s inverse.
    pub view_from_clip: Mat4,
    /// Left then right, then (foveated) the left and right insets; a display of fewer
    /// views repeats its last.
    pub eye: [EyeContext; MAX_VIEWS],
    /// The combined frustum's apex (behind the eyes): the far split's origin.
    pub position: Vec3,
    /// Pixels of one eye's view (a foveated display's outer view); a stereo target is
    /// twice as wide.
    pub resolution: Vec2,
    /// The display frustum's planes (left, right, bottom, top, near, far): what the cull
    /// tests.
    pub planes: [Vec4; 6],
    /// Instances drawn per visible object (the cull contract's V): 2 where one
    /// multi-draw covers both eyes (`instanced` stereo), 1 for mono, for multiview
    /// (the hardware repeats each instance per view) and for the per-eye classic modes.
    pub instances_per_object: u32,
    /// Which eye `eye[0]` is: 0, or 1 in the per-eye contexts of the classic modes
    /// (which hold one eye in both slots), so that shaders see the true eye index.
    pub first_eye: u32,
    /// The far split ([`crate::cull::Split`], the cull's `in_split`): 0 none, 1 keep
    /// near, 2 keep far instances, those entirely beyond `split_distance` from
    /// `position` (the display's apex).
    pub split_keep: u32,
    /// Meters from `position` beyond which whole instances are far.
    pub split_distance: f32,
    /// Which of the frame coarse cull's block lists this cull runs over: its display's
    /// index (the far layer's cull shares its display's). Read only over candidates.
    pub cull_slot: u32,
    /// The display's views: 1 mono, 2 stereo, 4 foveated stereo (occlusion tests each
    /// eye's pyramid, whatever the instances per object).
    pub views: u32,
    /// Pixels a sphere's projected bounds grow by on each side in the occlusion test:
    /// [`BOUNDS_GROWTH_PX`] for the rounding of the projection, and in a far layer's
    /// cull also how far its composite may carry a far point from where the eye sees it
    /// ([`crate::far_layer::FarPlan::composite_reach_px`]).
    pub occlusion_margin_px: f32,
    /// 1 where the cull also drops what the display's hidden area
    /// ([`crate::cull::HiddenArea`], at `cull_slot`) hides in every masked view; else 0.
    pub hidden: u32,
}

/// Pixels the projected bounds grow by on each side in the occlusion test, for the
/// rounding of the projection (errors of about 1e-6 of the pixel coordinates).
pub const BOUNDS_GROWTH_PX: f32 = 1.0;

/// Views a display context holds: four for foveated stereo.
pub const MAX_VIEWS: usize = 4;

impl DisplayContext {
    /// Where the display's blended instances are sorted from: the midpoint of its two
    /// eyes (one order for both, each eye's view of it nearly the same), or its one
    /// view's position; a far layer's cull sorts from its apex, `position`, whichever
    /// eyes it holds for the occlusion test. The GPU's blend pass computes it alike
    /// (`wgsl/cull_blend.wgsl`).
    pub fn sort_origin(&self) -> Vec3 {
        match (self.split_keep, self.views >= 2) {
            (2, _) => self.position,
            (_, true) => (self.eye[0].position + self.eye[1].position) * 0.5,
            (_, false) => self.eye[0].position,
        }
    }

    /// Its record as a member of the rig cull, its outputs `at`, culled in the early
    /// occlusion phase where `early`: what it culls by.
    pub fn rig_view(&self, at: MemberAt, early: bool) -> RigView {
        RigView {
            planes: self.planes,
            position: self.position,
            split_keep: self.split_keep,
            sort_origin: self.sort_origin(),
            split_distance: self.split_distance,
            instances_per_object: self.instances_per_object,
            visible_at: at.visible,
            draws_at: at.draws,
            counts_at: at.counts,
            cull_slot: self.cull_slot,
            early: u32::from(early),
            hidden: self.hidden,
            block: CoarseCull::around(self.planes),
        }
    }

    /// What this display's late cull tests against its pyramids, for a rig member in
    /// the late phase: what [`crate::occlusion`]'s test reads from the context.
    pub fn rig_occlusion(&self) -> RigOcclusion {
        RigOcclusion {
            view_from_world: [0, 1].map(|e| self.eye[e].view_from_world),
            clip_from_view: [0, 1].map(|e| self.eye[e].clip_from_view),
            resolution: self.resolution,
            margin_px: self.occlusion_margin_px,
            views: self.views,
        }
    }

    /// The context of a resolved display whose views lie in its target as `layout` says.
    pub fn new(
        display: &ResolvedDisplay,
        layout: &ViewLayout,
        instances_per_object: u32,
    ) -> DisplayContext {
        let mut context = DisplayContext::UNSET;
        context.set(display, layout, instances_per_object);
        context
    }

    /// A context before its display is set in it.
    pub const UNSET: DisplayContext = DisplayContext {
        view_from_world: Mat4::IDENTITY,
        world_from_view: Mat4::IDENTITY,
        clip_from_view: Mat4::IDENTITY,
        view_from_clip: Mat4::IDENTITY,
        eye: [EyeContext::UNSET; MAX_VIEWS],
        position: Vec3::ZERO,
        resolution: Vec2::ZERO,
        planes: [Vec4::ZERO; 6],
        instances_per_object: 0,
        first_eye: 0,
        split_keep: 0,
        split_distance: 0.0,
        cull_slot: 0,
        views: 0,
        occlusion_margin_px: BOUNDS_GROWTH_PX,
        hidden: 0,
    };

    /// [`DisplayContext::new`] in place, field by field: a context is 2.4 KB, moving it
    /// whole costs more than its math, and a latch builds every display's on the
    /// submit's path. Leaves the split, the cull slot and the hidden flag as they are.
    pub fn set(
        &mut self,
        display: &ResolvedDisplay,
        layout: &ViewLayout,
        instances_per_object: u32,
    ) {
        // The combined frustum's view and projection only: it is culled by, never drawn.
        let combined = &display.combined;
        let clip_from_view = combined.clip_from_view();
        let viewports = layout.viewports();
        let [_, _, w, h] = viewports[0];
        self.view_from_world = combined.view_from_world();
        self.world_from_view = combined.world_from_view_f32();
        self.clip_from_view = clip_from_view;
        self.view_from_clip = combined.view_from_clip();
        self.position = combined.position();
        self.resolution = Vec2::new(w as f32, h as f32);
        self.planes = display.planes;
        self.instances_per_object = instances_per_object;
        self.first_eye = 0;
        self.views = display.eyes.len() as u32;
        self.occlusion_margin_px = BOUNDS_GROWTH_PX;
        // Each view's context once (its f64 compositions and inverses), then repeated.
        let views = display.eyes.len().min(viewports.len());
        for (slot, (v, &viewport)) in self.eye.iter_mut().zip(display.eyes.iter().zip(viewports)) {
            slot.set_view(v);
            slot.viewport = Vec4::from(viewport.map(|v| v as f32));
            slot.placement = placement(viewport, layout.size);
        }
        let (set, repeated) = self.eye.split_at_mut(views);
        repeated.fill(set[views - 1]);
    }

    /// A foveated display's inset context (from its own, `self`): the insets in the eye
    /// slots the decode reads (0, 1) and in their own (2, 3), so that `first_eye = 2`
    /// makes the views' true indices 2 and 3; culled against `insets`, the frustum
    /// holding both, each visible object drawn twice.
    pub fn insets(&self, insets: &View) -> DisplayContext {
        let [_, _, left, right] = self.eye;
        DisplayContext {
            eye: [left, right, left, right],
            first_eye: 2,
            planes: insets.frustum().planes,
            instances_per_object: 2,
            // The insets are not masked.
            hidden: 0,
            ..*self
        }
    }

    /// This context narrowed to eye `e`: every eye slot holds that eye (the classic
    /// modes bind one eye at a time), and `first_eye` says which it is.
    pub fn for_eye(&self, e: usize) -> DisplayContext {
        DisplayContext {
            eye: [self.eye[e]; MAX_VIEWS],
            first_eye: e as u32,
            ..*self
        }
    }
}

impl DisplayContext {
    /// The frame's light as a display: its one view in both eye slots, so that the draw
    /// decode (`display.eye[0].clip_from_world`) projects into the `size`-texel shadow
    /// map, and its box's planes for its cull.
    pub fn light(view: &LightView, size: u32) -> DisplayContext {
        let clip_from_world = view.clip_from_world;
        let world_from_clip = clip_from_world.inverse();
        let eye = EyeContext {
            view_from_world: Mat4::IDENTITY,
            world_from_view: Mat4::IDENTITY,
            clip_from_view: clip_from_world,
            view_from_clip: world_from_clip,
            clip_from_world,
            world_from_clip,
            previous_clip_from_world: clip_from_world,
            position: Vec3::ZERO,
            time_ahead: 0.0,
            viewport: Vec4::new(0.0, 0.0, size as f32, size as f32),
            placement: IDENTITY_PLACEMENT,
        };
        DisplayContext {
            view_from_world: Mat4::IDENTITY,
            world_from_view: Mat4::IDENTITY,
            clip_from_view: clip_from_world,
            view_from_clip: world_from_clip,
            eye: [eye; MAX_VIEWS],
            position: Vec3::ZERO,
            resolution: Vec2::splat(size as f32),
            planes: view.planes,
            instances_per_object: 1,
            first_eye: 0,
            split_keep: 0,
            split_distance: 0.0,
            cull_slot: 0,
            views: 1,
            occlusion_margin_px: BOUNDS_GROWTH_PX,
            hidden: 0,
        }
    }
}

/// A uniform buffer for one [`DisplayContext`].
pub(crate) fn context_buffer(device: &wgpu::Device) -> wgpu::Buffer {
    crate::buffers::uniform_buffer::<DisplayContext>(device, "stereocull.display_context")
}
