//! The frame as a plan: everything a frame decides (the rig resolved once, the frame and
//! display contexts, every cull it runs, the levels of detail, the coarse cull, each
//! display's far/near split, the light), made once from the rig's pose, the options and
//! the time, as plain data before any buffer is written. The indirect path, the classic
//! path and the CLI's CPU cull consume a plan and decide nothing again; a test can build
//! one and inspect it without a device.

use std::sync::Arc;

use super::frames;
use super::options::StereoMode;
use super::options::{RendererOptions, frame_lod};
use crate::contexts::{DisplayContext, FrameContext};
use crate::cull::FrameCull;
use crate::cull::tiles::TileMask;
use crate::cull::{CoarseCull, CullJob, HiddenArea};
use crate::error::{Error, Result};
use crate::far_layer::FarPlan;
use crate::motion::PreviousFrame;
use crate::rig::{Display, ResolvedDisplay, ResolvedRig, Rig};
use crate::shadow::LightView;

/// The view a cull is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum CullView {
    /// Display `i` against its display frustum (both eyes).
    Display(usize),
    /// Eye `e` of stereo display `i` against its own frustum (`multi-camera` only).
    Eye(usize, usize),
    /// Display `i`'s far layer: its far instances, drawn once.
    Far(usize),
    /// Display `i`'s late occlusion phase: what the early phase did not draw and its
    /// depth pyramids do not hide (the display frustum, both eyes).
    Late(usize),
    /// Foveated display `i`'s insets (with the inset cull): the inset pair's frustum.
    Inset(usize),
    /// The frame's light (with shadows).
    Light,
}

impl CullView {
    /// The coarse cull's slot whose block list this view's GPU cull runs over, with the
    /// coarse cull on: its display's (a far layer shares its display's blocks). The
    /// light's box is not inside the frame frustum, so its cull never takes blocks; the
    /// inset cull takes none either (its planes are not the display's, whose grown block
    /// test the coarse cull's guarantee is stated for).
    pub fn coarse_slot(self) -> Option<u32> {
        match self {
            CullView::Display(i) | CullView::Eye(i, _) | CullView::Far(i) | CullView::Late(i) => {
                Some(i as u32)
            }
            CullView::Inset(_) | CullView::Light => None,
        }
    }
}

/// One cull of the frame.
#[derive(Clone, Debug, PartialEq)]
pub struct PlannedCull {
    /// Whom the cull is for.
    pub view: CullView,
    /// Its frustum, instances per object and far split.
    pub job: CullJob,
}

/// A spent plan's two largest vectors, for the next plan to fill: the display plans
/// (each with its 2.4 KB context) and the resolved displays. Both are too large for the
/// allocator's per-thread cache, and every frame (a latch on the submit's path) would
/// allocate and free them otherwise.
#[derive(Default)]
pub(crate) struct PlanStorage {
    displays: Vec<DisplayPlan>,
    resolved: Vec<ResolvedDisplay>,
}

/// Everything one frame decides: the frame level's (the contexts every pass reads, the
/// culls' shared inputs, the light) and one [`DisplayPlan`] per display.
#[derive(Clone, Debug, PartialEq)]
pub struct FramePlan {
    /// The rig's views, resolved once for this frame.
    pub resolved: ResolvedRig,
    /// What every pass reads once per frame.
    pub frame: FrameContext,
    /// What every cull of the frame shares: the levels of detail, the coarse test.
    pub cull: FrameCull,
    /// The frame's light: it shades every display, and with shadows draws the map
    /// (its box fitted only then: [`LightView::unfitted`]).
    pub light: LightView,
    /// With shadows: the light's cull, outside the frame frustum (never coarse).
    pub light_cull: Option<PlannedCull>,
    /// Per display, in the rig's order.
    pub displays: Vec<DisplayPlan>,
    /// Keeping unchanged pixels with the tiles marked on the GPU: the slots whose
    /// tiles change, each with its phases ([`crate::keep::marks::MARK_BEFORE`],
    /// [`crate::keep::marks::MARK_AFTER`]).
    pub marks: Vec<u32>,
}

/// What one frame decides for one display.
#[derive(Clone, Debug, PartialEq)]
pub struct DisplayPlan {
    /// Its context (with a far layer, its near cull's split).
    pub context: DisplayContext,
    /// Its culls against the display frustum: one, or in `multi-camera` one per eye
    /// of a stereo display.
    pub culls: Vec<PlannedCull>,
    /// Its far layer's plan (stereo displays with the far layer on).
    pub far: Option<FarPlan>,
    /// With the inset cull, a foveated display's inset context (the inset pair in the
    /// eye slots, the inset frustum's planes). Boxed: a context is 2.4 KB, and most
    /// displays have none.
    pub inset: Option<Box<DisplayContext>>,
    /// With the visibility mask on the GPU-driven path, the lens's hidden area its cull
    /// drops by (the display's own cull and its late phase; never its far layer's or
    /// its insets').
    pub hidden: Option<Arc<HiddenArea>>,
    /// Keeping unchanged pixels, its changed tiles, which its cull keeps only what
    /// touches and its draw pass alone redraws ([`crate::keep`]); `None`: drawn whole.
    /// The renderer sets them ([`crate::renderer::Renderer::prepare`]).
    pub tiles: Option<KeptTiles>,
}

impl DisplayPlan {
    /// Display `i`'s far cull (the display frustum's far side, drawn once), where it
    /// has a far layer.
    pub fn far_cull(&self, i: usize) -> Option<PlannedCull> {
        let plan = self.far.as_ref()?;
        Some(PlannedCull {
            view: CullView::Far(i),
            job: CullJob {
                planes: plan.view.frustum().planes,
                instances_per_object: 1,
                split: Some(plan.split(true)),
                hidden: None,
                tiles: None,
                sort_origin: plan.view.position(),
            },
        })
    }

    /// Display `i`'s inset cull (never coarse), where it culls its insets apart.
    pub fn inset_cull(&self, i: usize) -> Option<PlannedCull> {
        let context = self.inset.as_ref()?;
        Some(PlannedCull {
            view: CullView::Inset(i),
            job: CullJob {
                planes: context.planes,
                instances_per_object: context.instances_per_object,
                split: None,
                hidden: None,
                tiles: None,
                sort_origin: context.sort_origin(),
            },
        })
    }
}

/// A kept display's changed tiles: marked on the CPU (culling on the CPU: its cull and
/// its draw pass read this mask), or on the GPU by the marking pass, from the frame's
/// listed slots ([`FramePlan::marks`], [`crate::keep::marks`]).
#[derive(Clone, Debug, PartialEq)]
pub enum KeptTiles {
    /// The CPU marked them: the mask its cull and draw pass read.
    Cpu(Arc<TileMask>),
    /// The GPU's marking pass marks them.
    Gpu,
}

impl KeptTiles {
    /// The mask the CPU marked.
    pub fn mask(&self) -> Option<&TileMask> {
        match self {
            KeptTiles::Cpu(mask) => Some(mask),
            KeptTiles::Gpu => None,
        }
    }
}

impl FramePlan {
    /// This frame as the next one's previous, for motion vectors.
    pub fn as_previous(&self) -> PreviousFrame {
        PreviousFrame::of(&self.frame, self.displays.iter().map(|d| &d.context))
    }

    /// This frame's contexts measured from `previous` (motion vectors).
    pub fn measure_from(&mut self, previous: &PreviousFrame) {
        let contexts = self.displays.iter_mut().map(|d| &mut d.context);
        previous.carry_into(&mut self.frame, contexts);
    }

    /// The plan of the frame at `time` for `rig`'s pose under `options`; `coarse` is
    /// whether the renderer was built for the coarse cull ([`RendererOptions::coarse_for`],
    /// decided once: it sizes buffers).
    pub fn new(rig: &Rig, options: &RendererOptions, coarse: bool, time: f32) -> Result<FramePlan> {
        FramePlan::new_in(rig, options, coarse, time, PlanStorage::default())
    }

    /// [`FramePlan::new`] into the vectors of a spent plan ([`FramePlan::into_storage`]).
    pub(crate) fn new_in(
        rig: &Rig,
        options: &RendererOptions,
        coarse: bool,
        time: f32,
        storage: PlanStorage,
    ) -> Result<FramePlan> {
        let resolved = rig.resolve_into(storage.resolved)?;
        FramePlan::of_in(rig, resolved, options, coarse, time, storage.displays)
    }

    /// The plan's vectors that the next plan fills again ([`PlanStorage`]).
    pub(crate) fn into_storage(self) -> PlanStorage {
        PlanStorage {
            displays: self.displays,
            resolved: self.resolved.displays,
        }
    }

    /// [`FramePlan::new`] for a rig already resolved. With two frames per submission
    /// ([`RendererOptions::frames_per_submit`]) the second is the same pose `dt` later.
    pub fn of(
        rig: &Rig,
        resolved: ResolvedRig,
        options: &RendererOptions,
        coarse: bool,
        time: f32,
    ) -> Result<FramePlan> {
        FramePlan::of_in(rig, resolved, options, coarse, time, Vec::new())
    }

    /// [`FramePlan::of`] with the display plans in `displays`' allocation.
    fn of_in(
        rig: &Rig,
        resolved: ResolvedRig,
        options: &RendererOptions,
        coarse: bool,
        time: f32,
        displays: Vec<DisplayPlan>,
    ) -> Result<FramePlan> {
        if options.frames_per_submit == 2 {
            let pair = frames::pair(&resolved, &resolved)?;
            let times = [time, time + options.dt];
            return FramePlan::build(rig, pair, options, coarse, times, displays);
        }
        FramePlan::build(rig, resolved, options, coarse, [time; 2], displays)
    }

    /// The plan of a submission of two frames ([`RendererOptions::frames_per_submit`]
    /// 2): `now`'s rig at its time, then `next`'s (the viewer's pose a tracker predicts
    /// for the next display period) at its own, as one set of views per display. What
    /// the frame context holds of the viewer (the levels of detail, the coarse cull's
    /// frame frustum, the light's fit) is planned from both, from `now`'s viewer.
    pub fn pair(
        now: (&Rig, f32),
        next: (&Rig, f32),
        options: &RendererOptions,
        coarse: bool,
    ) -> Result<FramePlan> {
        if options.frames_per_submit != 2 {
            return Err(Error::Unsupported(
                "a pair of frames is planned for two frames per submission".into(),
            ));
        }
        let pair = frames::pair(&now.0.resolve()?, &next.0.resolve()?)?;
        FramePlan::build(now.0, pair, options, coarse, [now.1, next.1], Vec::new())
    }

    /// The plan from a resolved rig whose displays hold one frame's views (`times[0]`),
    /// or two frames' ([`frames::pair`]; the second at `times[1]`); its display plans
    /// in `displays`' allocation.
    fn build(
        rig: &Rig,
        resolved: ResolvedRig,
        options: &RendererOptions,
        coarse: bool,
        times: [f32; 2],
        mut displays: Vec<DisplayPlan>,
    ) -> Result<FramePlan> {
        if resolved.displays.len() != rig.displays.len() {
            return Err(Error::rig("plan", "the resolved rig's displays differ"));
        }
        let cull = FrameCull {
            lod: frame_lod(rig, &resolved, options.lod_levels()),
            coarse: coarse.then(|| resolved.coarse_cull(options.mode.culls_per_eye())),
        };
        let light = match options.shadows {
            true => LightView::fit(&options.light, &resolved),
            false => LightView::unfitted(&options.light),
        };
        let frame = FrameContext::new(
            &rig.viewer,
            times[0],
            cull.lod.lod_scale,
            &cull.coarse.unwrap_or(CoarseCull::EVERYTHING),
            &light,
            options.shadows,
        );
        let far: Vec<Option<FarPlan>> = match options.far_layer {
            true => crate::far_layer::plans(rig, &resolved, options.far_threshold_px),
            false => vec![None; rig.displays.len()],
        };
        let inset_cull = options.inset_cull && options.mode == StereoMode::Instanced;
        let hidden = hidden_areas(rig, &resolved, options, inset_cull);
        displays.truncate(rig.displays.len());
        displays.resize_with(rig.displays.len(), DisplayPlan::unset);
        let each = (rig.displays.iter().zip(&resolved.displays)).zip(far.into_iter().zip(hidden));
        for (i, (plan, ((d, r), (far, hidden)))) in displays.iter_mut().zip(each).enumerate() {
            let shown = Shown {
                options,
                inset_cull,
                ahead: times[1] - times[0],
            };
            plan.set(i, d, r, far, hidden, shown);
        }
        let light_cull = options.shadows.then(|| PlannedCull {
            view: CullView::Light,
            job: light.cull_job(),
        });
        Ok(FramePlan {
            resolved,
            frame,
            cull,
            light,
            light_cull,
            displays,
            marks: Vec::new(),
        })
    }

    /// Each far layer at the size it was made for (`sizes`, from the plan of the rig
    /// the renderer was made with, per display): a layer's texture keeps its size, while
    /// a posed view's field of view may move the size a new plan asks for.
    pub(super) fn with_far_sizes(
        mut self,
        sizes: impl Iterator<Item = Option<(u32, u32)>>,
    ) -> FramePlan {
        for (display, size) in self.displays.iter_mut().zip(sizes) {
            if let (Some(far), Some(size)) = (&mut display.far, size) {
                far.size = size;
            }
        }
        self
    }

    /// The culls the frame frustum holds, in the order the CPU culler runs them: each
    /// display's (each eye's in `multi-camera`), then each far layer's.
    pub fn culls(&self) -> Vec<PlannedCull> {
        let own = self.displays.iter().flat_map(|d| d.culls.iter().cloned());
        let far = (self.displays.iter().enumerate()).filter_map(|(i, d)| d.far_cull(i));
        own.chain(far).collect()
    }

    /// The inset culls (never coarse), one per display with an inset context.
    pub fn inset_culls(&self) -> Vec<PlannedCull> {
        (self.displays.iter().enumerate())
            .filter_map(|(i, d)| d.inset_cull(i))
            .collect()
    }

    /// The jobs of [`FramePlan::culls`], in order: what the CPU culler takes.
    pub fn jobs(&self) -> Vec<CullJob> {
        self.culls().into_iter().map(|c| c.job).collect()
    }

    /// The job of [`FramePlan::culls`] for `view` (`None` if the frame frustum's culls
    /// have none).
    pub fn job(&self, view: CullView) -> Option<CullJob> {
        match view {
            CullView::Far(i) => Some(self.displays.get(i)?.far_cull(i)?.job),
            CullView::Display(i) | CullView::Eye(i, _) => (self.displays.get(i)?.culls.iter())
                .find(|c| c.view == view)
                .map(|c| c.job.clone()),
            CullView::Late(_) | CullView::Inset(_) | CullView::Light => None,
        }
    }
}

/// How a display's views are shown: what its plan reads of the options, and how far
/// ahead of the first frame's views a second frame's are.
struct Shown<'a> {
    options: &'a RendererOptions,
    inset_cull: bool,
    ahead: f32,
}

impl DisplayPlan {
    /// A plan to be set ([`DisplayPlan::set`]).
    fn unset() -> DisplayPlan {
        DisplayPlan {
            context: DisplayContext::UNSET,
            culls: Vec::new(),
            far: None,
            inset: None,
            hidden: None,
            tiles: None,
        }
    }

    /// Display `i`'s plan (`d` as resolved `r`), in place (a context is large, and the
    /// culls' vector is kept): its context, where it has a far plan keeping its near
    /// instances only, where it has a hidden area culling by it, and with the inset
    /// cull a foveated display's own cull drawing its outer pair only.
    fn set(
        &mut self,
        i: usize,
        d: &Display,
        r: &ResolvedDisplay,
        far: Option<FarPlan>,
        hidden: Option<Arc<HiddenArea>>,
        shown: Shown,
    ) {
        let Shown {
            options,
            inset_cull,
            ahead,
        } = shown;
        let (mode, frames) = (options.mode, options.frames_per_submit);
        let views = match inset_cull {
            true => d.views().min(2),
            false => d.views() * frames,
        };
        let layered = mode == StereoMode::Multiview && d.stereo;
        let per_object = instances_per_object(mode, views);
        let layout = frames::layout(d, layered, frames);
        let context = &mut self.context;
        *context = DisplayContext::UNSET;
        context.set(r, &layout, per_object);
        context.cull_slot = i as u32;
        context.hidden = u32::from(hidden.is_some());
        if let Some(plan) = &far {
            context.split_keep = 1;
            context.split_distance = plan.distance;
        }
        frames::time_views(context, d, ahead);
        self.inset = (r.insets.as_ref())
            .filter(|_| inset_cull)
            .map(|v| Box::new(self.context.insets(v)));
        self.culls.clear();
        let split = far.map(|plan| plan.split(false));
        let context = &self.context;
        match (mode.culls_per_eye(), r.eyes.as_slice()) {
            (true, eyes) if eyes.len() > 1 => {
                self.culls
                    .extend(eyes.iter().enumerate().map(|(e, eye)| PlannedCull {
                        view: CullView::Eye(i, e),
                        job: CullJob {
                            planes: eye.frustum().planes,
                            instances_per_object: 1,
                            split,
                            hidden: None,
                            tiles: None,
                            // One order for both eyes, as the display draws it.
                            sort_origin: context.sort_origin(),
                        },
                    }))
            }
            _ => self.culls.push(PlannedCull {
                view: CullView::Display(i),
                job: CullJob {
                    split,
                    hidden: hidden.clone(),
                    tiles: None,
                    sort_origin: context.sort_origin(),
                    ..r.cull_job(context.instances_per_object)
                },
            }),
        }
        self.far = far;
        self.hidden = hidden;
        self.tiles = None;
    }
}

/// How many instances each visible object becomes in `mode`'s draws of a display with
/// `views` views: doubled for `instanced` stereo; multiview repeats each draw per layer
/// and the classic modes draw per eye, so one.
pub fn instances_per_object(mode: StereoMode, views: u32) -> u32 {
    match mode {
        StereoMode::Instanced => views,
        _ => 1,
    }
}

/// Each display's hidden area where its cull drops by it: the visibility mask on, a
/// path that draws the mask (the GPU-driven one: the classic modes do not mask), a
/// display with a mask, and at most the two masked views drawn by its cull (a
/// foveated display's insets may reach into the mask's area unless they cull apart).
fn hidden_areas(
    rig: &Rig,
    resolved: &ResolvedRig,
    options: &RendererOptions,
    inset_cull: bool,
) -> Vec<Option<Arc<HiddenArea>>> {
    let masked = options.visibility_mask && !options.mode.per_instance();
    (rig.displays.iter().zip(&resolved.displays))
        .map(|(d, r)| {
            let mask = d.visibility_mask.as_ref().filter(|_| masked)?;
            if d.views() > 2 && !inset_cull {
                return None;
            }
            let layered = options.mode == StereoMode::Multiview && d.stereo;
            let [_, _, w, h] = d.layout_in(layered).viewports()[0];
            // A foveated display's insets lie inside its outer pair; two frames' views
            // are each frame's eyes, masked alike.
            let frames = options.frames_per_submit;
            let eyes = &r.eyes[..r.eyes.len().min(2 * frames as usize)];
            let mask = frames::masked(mask, d.views(), frames);
            HiddenArea::new(eyes, &mask.views, (w, h)).map(Arc::new)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A plan made in a spent plan's vectors equals one made afresh, whatever the spent
    /// plan held: more displays, far splits, another pose and time.
    #[test]
    fn a_plan_in_a_spent_plans_vectors_is_a_fresh_plan() {
        let cave = Rig::preset("cave").unwrap();
        let far = RendererOptions {
            far_layer: true,
            ..RendererOptions::default()
        };
        let spent = FramePlan::new(&cave, &far, false, 0.5).unwrap();
        assert!(spent.displays.iter().all(|d| d.context.split_keep != 0));
        let mut hmd = Rig::preset("hmd").unwrap();
        hmd.viewer.yaw_deg = 20.0;
        let options = RendererOptions::default();
        let storage = spent.into_storage();
        let reused = FramePlan::new_in(&hmd, &options, false, 1.0, storage).unwrap();
        assert_eq!(reused, FramePlan::new(&hmd, &options, false, 1.0).unwrap());
    }
}
