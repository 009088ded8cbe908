//! The GPU-driven path (`instanced` and `multiview`): per display, culling into a
//! visible list and per-mesh draws (three compute dispatches, or the CPU culler and an
//! upload), then one render pass with one multi-draw-indirect call.
//!
//! Per frame on the GPU-culled path the CPU writes one display context per display and
//! records a fixed number of commands: its cost does not depend on the instance count.

use std::time::Instant;

use super::far_layer::{Far, FarDisplay, FarLayers};
use super::occlusion::{LatePhase, PyramidSets, pyramid_shapes};
use super::{PathCore, PathInputs};
use crate::contexts::context_buffer;
use crate::cull::gpu_buffers::OcclusionRoom;
use crate::cull::targets::CullTargets;
use crate::draw::keep_tiles::KeepTiles;
use crate::draw::mask::{DisplayMask, MaskPipeline};
use crate::draw::{
    BinPipelines, DrawFeatures, DrawScene, Drawer, Drawing, OwnPipeline, OwnPipelines,
};
use crate::error::{Error, Result};
use crate::keep::KeepUnchanged;
use crate::occlusion::{Phase, PyramidShape};
use crate::renderer::culler::{CullShape, Culler};
use crate::renderer::frame_stats::FrameStats;
use crate::renderer::keeping;
use crate::renderer::options::StereoMode;
use crate::renderer::plan::KeptTiles;
use crate::renderer::plan::{CullView, FramePlan};
use crate::renderer::recorder::{PassRecord, Recorder, begin_draw_pass};
use crate::renderer::targets::TargetViews;
use crate::renderer::uploads::Writes;
use crate::renderer::view::ViewPass;
use crate::scene::Shading;
use crate::shaders::DrawKey;

/// One display: a view (its context, cull and draw bindings) and its pipeline variant,
/// which also fixes the instances per visible object; with the inset cull, a foveated
/// display's inset pair is one more view, drawn by the same pipeline in the same pass.
pub(super) struct IndirectDisplay {
    pub(super) view: ViewPass,
    key: DrawKey,
    /// Pipelines of the caller's own for its [`crate::scene::Shading::Own`] bins.
    pub(super) own: OwnPipelines,
    pub(super) inset: Option<ViewPass>,
    /// With occlusion: the late phase (`view` is then the early one).
    pub(super) late: Option<LatePhase>,
}

pub(in crate::renderer) struct IndirectPath {
    pub(in crate::renderer) core: PathCore,
    pub(super) displays: Vec<IndirectDisplay>,
    /// With the far layer: the stereo displays' far layers.
    pub(super) far: Option<Far>,
    /// With occlusion: every display's pyramids, in sets of displays.
    pub(super) pyramids: PyramidSets,
    /// Per display with a visibility mask (and the option on): its mask pass, drawn
    /// first in the display's clearing draw pass.
    pub(in crate::renderer) masks: Vec<Option<(MaskPipeline, DisplayMask)>>,
    /// Keeping unchanged pixels where frames may: the pass that clears changed tiles.
    pub(super) keep: Option<KeepTiles>,
    /// Per display: whether this frame keeps its unchanged pixels, and how.
    pub(super) kept: Vec<Option<Kept>>,
}

/// A display whose frame keeps its unchanged pixels.
#[derive(Clone, Copy, Debug)]
pub(super) struct Kept {
    /// Words of its tiles' bits.
    pub words: u32,
    /// The cull slot whose tiles the GPU marked (`None`: the CPU marked them).
    pub marked_in: Option<u32>,
}

impl IndirectPath {
    /// The path for `inputs`: built for its plan (the rig as made, which sizes the far
    /// layers) and its coarse cull.
    pub(in crate::renderer) fn new(
        device: &wgpu::Device,
        inputs: PathInputs,
    ) -> Result<IndirectPath> {
        let PathInputs {
            scene,
            records,
            layout,
            plan,
            frame,
            options,
            slots,
            shadow_group,
        } = inputs;
        let windows = options.windows(device, slots);
        let coarse_slots = match plan.cull.coarse {
            Some(_) => plan.displays.len() as u32,
            None => 0,
        };
        let shapes = pyramid_shapes(plan, options, scene.triangles());
        let views = plan.displays.iter().map(|d| d.context.views);
        let keeps = options.keep_unchanged != KeepUnchanged::Off
            && keeping::never(scene, views, options).is_none();
        let tiles = keeps.then(|| keeping::tiles(plan));
        let most_tiles = tiles.iter().flatten().max().copied().unwrap_or(0);
        let occlusion = OcclusionRoom {
            displays: plan.displays.len() as u32 * u32::from(shapes.iter().any(Option::is_some)),
            pyramid_texels: shapes.iter().flatten().map(|s| s.len()).max().unwrap_or(0),
            tiles: match keeps {
                true => (plan.displays.len() as u32, most_tiles.div_ceil(32)),
                false => (0, 0),
            },
        };
        let shape = CullShape {
            rig: match options.rig_cull {
                true => rig_members(plan, &shapes, coarse_slots > 0),
                false => Vec::new(),
            },
            slots,
            levels: options.lod_levels(),
            coarse_slots,
            floor: options.cull_floor,
            occlusion,
            tested: options.far_layer && occlusion.displays > 0,
            hidden_slots: match plan.displays.iter().any(|d| d.hidden.is_some()) {
                true => plan.displays.len() as u32,
                false => 0,
            },
            split: options.far_layer,
        };
        let kinds = layout.bins.kinds.clone();
        let mut culler = Culler::new(device, options.cull, layout, shape, windows);
        culler.track_visibility(device, &shapes);
        let keys = draw_keys(device, plan, options.mode);
        let shaders = options.shaders();
        let target = options.target_format();
        let keep = tiles.map(|tiles| KeepTiles::new(device, target, &tiles));
        let drawer = Drawer::new(
            device,
            target,
            (&keys, &kinds),
            shaders,
            options.shadow_size(),
            windows,
        );
        let draw_scene = DrawScene::new(device, &drawer, (scene, records, shadow_group), slots)?;
        let drawing = Drawing {
            drawer: &drawer,
            scene: &draw_scene,
        };
        let shaped = (&keys[..], plan, &shapes[..]);
        let displays = indirect_displays(device, shaped, drawing, frame, &culler);
        let pyramids = PyramidSets::new(device, options, shaped, &culler);
        let far = options.far_layer.then(|| {
            let layers = FarLayers::new(device, (target, &kinds), shaders, windows);
            let contexts: Vec<&wgpu::Buffer> = displays.iter().map(|d| d.view.context()).collect();
            let tested: Vec<bool> = displays.iter().map(|d| d.late.is_some()).collect();
            let scene = (&draw_scene, frame);
            Far::new(device, (layers, plan), scene, (&contexts, &tested), &culler)
        });
        Ok(IndirectPath {
            core: PathCore {
                culler,
                drawer,
                draw_scene,
            },
            displays,
            far,
            pyramids,
            masks: Vec::new(),
            keep,
            kept: vec![None; plan.displays.len()],
        })
    }

    /// Pixels the visibility masks cover in each frame, all displays together.
    pub(in crate::renderer) fn masked_pixels(&self) -> u64 {
        self.masks.iter().flatten().map(|(_, m)| m.pixels).sum()
    }

    /// Writes `plan`'s display contexts and the culler's results for every view: each
    /// display's, each far layer's, the light's.
    pub(in crate::renderer) fn prepare(&mut self, to: Writes, plan: &FramePlan) -> FrameStats {
        let mut stats = FrameStats::default();
        let start = Instant::now();
        stats.bytes_uploaded += self.core.culler.prepare(to.pose, plan);
        stats.cpu_cull = start.elapsed();
        let start = Instant::now();
        let culler = &self.core.culler;
        for (state, display) in self.displays.iter().zip(&plan.displays) {
            let (ctx, inset) = (&display.context, &display.inset);
            stats.bytes_uploaded += state.view.prepare(to, ctx, culler);
            // The late phase shares the early one's context; a rig member has a record.
            if let Some(late) = &state.late {
                stats.bytes_uploaded += culler.write_member(to.pose, late.view.view_cull(), ctx);
            }
            if let (Some(view), Some(inset)) = (&state.inset, inset) {
                stats.bytes_uploaded += view.prepare(to, inset, culler);
            }
        }
        if let Some(far) = &mut self.far {
            stats.bytes_uploaded += far.prepare(to, plan, &self.core.culler);
        }
        for (i, display) in plan.displays.iter().enumerate() {
            self.kept[i] = None;
            if let (Some(keep), Some(tiles)) = (&mut self.keep, &display.tiles) {
                let c = &display.context;
                let (size, views) = (c.resolution.as_uvec2(), c.views.min(2));
                stats.bytes_uploaded += keep.write(to.queue, i, (size, views), tiles.mask());
                let g = crate::cull::tiles::grid(size, views);
                self.kept[i] = Some(Kept {
                    words: crate::cull::tiles::tile_words(g),
                    marked_in: matches!(tiles, KeptTiles::Gpu).then_some(c.cull_slot),
                });
            }
        }
        stats.cpu_upload = start.elapsed();
        stats
    }

    /// The path's frame-level pass: the coarse cull (when it runs, on the GPU).
    /// Returns the dispatches.
    pub(in crate::renderer) fn encode_frame(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder,
    ) -> u32 {
        let any = self.displays.first().map(|d| d.view.view_cull());
        self.core.culler.encode_frame(encoder, any, rec)
    }

    /// Display `index` up to what its late phase needs: its cull and its draw (with
    /// occlusion the early one). With occlusion, once every display's is recorded,
    /// [`IndirectPath::encode_pyramids`] reduces every display's depth, and the late
    /// culls follow ([`IndirectPath::encode_late_rig`], or each display's own). Culling
    /// on the CPU with occlusion the frame stops after the pyramids until
    /// [`IndirectPath::cull_late`] has them.
    pub(in crate::renderer) fn encode_early(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        (index, target): (usize, &TargetViews),
        rec: &mut Recorder,
    ) -> FrameStats {
        let culled = self.encode_cull(encoder, (index, false), rec);
        let multiview = self.displays[index].key.multiview_mask();
        // With occlusion the far layer is drawn and composited in the late phase.
        let composite = self.displays[index].late.is_none();
        let listed = self.encode_tile_list(encoder, index);
        let mut open = rec.open(encoder, PassRecord::display("draw", index));
        let kept = self.kept[index].is_some();
        let mut pass = begin_draw_pass(encoder, rec, (target, !kept, multiview), &mut open);
        let mut draw_calls = match (&self.keep, kept) {
            (Some(keep), true) => keep.draw(&mut pass, index),
            _ => 0,
        };
        if let Some((pipeline, mask)) = self.masks.get(index).and_then(Option::as_ref) {
            pipeline.draw(&mut pass, mask);
            draw_calls += 1;
        }
        // The mask's own samples are not the scene's.
        rec.count_samples(&mut pass, &mut open);
        draw_calls += self.draw_views(&mut pass, index, composite);
        rec.close_render(encoder, pass, open);
        FrameStats {
            draw_calls: culled.draw_calls + draw_calls,
            dispatches: culled.dispatches + listed,
            ..culled
        }
    }

    /// Where display `index` keeps this frame: its changed tiles listed for the tile
    /// pass, their bits first copied from where the GPU marked them (the culler's
    /// buffer). Returns the dispatches.
    fn encode_tile_list(&self, encoder: &mut wgpu::CommandEncoder, index: usize) -> u32 {
        let (Some(keep), Some(kept)) = (&self.keep, &self.kept[index]) else {
            return 0;
        };
        let marked = (kept.marked_in).and_then(|s| self.core.culler.marked_words(s, kept.words));
        keep.encode_list(encoder, index, marked)
    }

    /// Display `index`'s far layer, with what every far layer shares (`None` without).
    pub(super) fn far_layer(&self, index: usize) -> Option<(&Far, &FarDisplay)> {
        let far = self.far.as_ref()?;
        Some((far, far.displays[index].as_ref()?))
    }

    /// With a far layer, display `index`'s far cull in `phase` and far layer pass.
    pub(super) fn encode_far(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        (index, phase): (usize, Phase),
        rec: &mut Recorder,
    ) -> FrameStats {
        let Some((far, layer)) = self.far_layer(index) else {
            return FrameStats::default();
        };
        let culling = (&self.core.draw_scene, &self.core.culler);
        let (dispatches, draw_calls) = (far.layers).encode(encoder, (layer, phase), culling, rec);
        FrameStats {
            dispatches,
            draw_calls,
            ..FrameStats::default()
        }
    }

    /// Display `index`'s cull (on the GPU; the culler's upload wrote a CPU cull) and,
    /// with a far layer, its far cull and far layer pass, timed inside `display`. For a
    /// display drawn in `one_pass` (the caller's), with occlusion its cull is the
    /// frustum's alone, which draws everything in that pass.
    pub(in crate::renderer) fn encode_cull(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        (index, one_pass): (usize, bool),
        rec: &mut Recorder,
    ) -> FrameStats {
        let state = &self.displays[index];
        let what = PassRecord::display("cull", index);
        let dispatches = match one_pass {
            true => {
                let frustum = (state.view.view_cull(), Phase::Frustum);
                self.core.culler.encode(encoder, frustum, rec, what)
            }
            false => state
                .view
                .encode_cull(encoder, &self.core.culler, rec, what),
        };
        let mut stats = FrameStats {
            dispatches,
            ..FrameStats::default()
        };
        if let Some(inset) = &state.inset {
            let what = PassRecord::display("inset_cull", index);
            stats.dispatches += inset.encode_cull(encoder, &self.core.culler, rec, what);
        }
        // With occlusion in the renderer's passes, the far layer waits for the pyramids.
        if one_pass || state.late.is_none() {
            stats = stats + self.encode_far(encoder, (index, Phase::Frustum), rec);
        }
        stats
    }

    /// Display `index`'s one multi-draw-indirect call into `pass`, whose pipeline the
    /// caller set (built on [`Drawer::layout`] and the decode).
    pub(in crate::renderer) fn draw_with_own_pipeline(
        &self,
        pass: &mut wgpu::RenderPass,
        index: usize,
    ) {
        self.displays[index]
            .view
            .draw(pass, self.core.drawing(), BinPipelines::Own);
    }

    /// Sets display `index`'s pipeline of the caller's own for its
    /// [`Shading::Own`]`(shading)` bins.
    pub(in crate::renderer) fn set_own_pipeline(
        &mut self,
        index: usize,
        shading: u32,
        own: OwnPipeline,
    ) {
        self.displays[index].own.insert(shading, own);
    }

    /// Display `index` must have a pipeline for each [`Shading::Own`] bin it draws.
    pub(in crate::renderer) fn check_own_pipelines(&self, index: usize) -> Result<()> {
        let own = &self.displays[index].own;
        let missing = (self.core.culler.bins().iter()).find_map(|b| match b.kind.shading {
            Shading::Own(i) if !own.contains_key(&i) => Some(i),
            _ => None,
        });
        match missing {
            Some(shading) => Err(Error::MissingOwnPipeline { index, shading }),
            None => Ok(()),
        }
    }

    /// How the instance records are bound.
    pub(in crate::renderer) fn windows(&self) -> crate::shaders::Windows {
        self.core.drawer.windows
    }

    pub(in crate::renderer) fn bind_group_layout(&self) -> &wgpu::BindGroupLayout {
        self.core.drawer.layout()
    }

    pub(in crate::renderer) fn cull_targets(&self, index: usize) -> &CullTargets {
        self.displays[index].view.cull()
    }

    /// Display `index`'s one multi-draw-indirect call into `pass`.
    /// With a far layer, its composite goes first (one more draw call); with an inset
    /// cull, the inset pair's multi-draw follows (one more).
    pub(in crate::renderer) fn draw(&self, pass: &mut wgpu::RenderPass, index: usize) -> u32 {
        self.draw_views(pass, index, true)
    }

    /// [`IndirectPath::draw`], with the far composite only where `composite`.
    fn draw_views(&self, pass: &mut wgpu::RenderPass, index: usize, composite: bool) -> u32 {
        let state = &self.displays[index];
        let composite = match self.far_layer(index) {
            Some((far, layer)) if composite => far.layers.composite(pass, layer),
            _ => 0,
        };
        let with = BinPipelines::Draw(state.key, &state.own);
        let outer = state.view.draw(pass, self.core.drawing(), with);
        let insets = match &state.inset {
            Some(inset) => inset.draw(pass, self.core.drawing(), with),
            None => 0,
        };
        composite + outer + insets
    }
}

/// Each display's view, for its pipeline variant `keys[i]`, and its inset view where
/// `plan` culls the display's insets.
fn indirect_displays(
    device: &wgpu::Device,
    (keys, plan, shapes): (&[DrawKey], &FramePlan, &[Option<PyramidShape>]),
    drawing: Drawing,
    frame: &wgpu::Buffer,
    culler: &Culler,
) -> Vec<IndirectDisplay> {
    let view = |v| ViewPass::new(device, drawing, frame, culler, v);
    let phased = |v, context| ViewPass::phased(device, drawing, frame, culler, v, context);
    (keys.iter().enumerate().zip(shapes))
        .map(|((i, &key), shape)| {
            let (display, late) = match shape {
                Some(shape) => {
                    let early =
                        phased((CullView::Display(i), Phase::Early), context_buffer(device));
                    let context = early.context().clone();
                    let late = phased((CullView::Late(i), Phase::Late), context);
                    (early, Some(LatePhase::new((i, key), late, *shape)))
                }
                _ => (view(CullView::Display(i)), None),
            };
            IndirectDisplay {
                view: display,
                key,
                own: OwnPipelines::new(),
                inset: plan.displays[i]
                    .inset
                    .as_ref()
                    .map(|_| view(CullView::Inset(i))),
                late,
            }
        })
        .collect()
}

/// The views the rig cull culls together: every view of `plan` that culls over every
/// instance (not over the coarse cull's blocks) by its frustum alone or in the early
/// occlusion phase: each display (with occlusion, `shapes[i]`, its early phase), its
/// far layer (where it is not tested against its display's pyramids), and each inset
/// pair; then the displays' late phases, culled together once every display's early
/// draw and pyramids are recorded. The light's cull stays apart: it runs in the
/// frame's shadow pass, before the displays' culls, and its box is no display's. A far
/// layer tested against its display's pyramids stays apart too: its frustum is its
/// own (a far split), and it is culled and drawn in its display's late half.
fn rig_members(plan: &FramePlan, shapes: &[Option<PyramidShape>], coarse: bool) -> Vec<CullView> {
    if coarse {
        return Vec::new();
    }
    let late = (shapes.iter().enumerate())
        .filter(|(_, shape)| shape.is_some())
        .map(|(i, _)| CullView::Late(i));
    let displays = (0..shapes.len()).map(CullView::Display);
    let far = (plan.displays.iter().zip(shapes).enumerate())
        .filter(|(_, (d, shape))| d.far.is_some() && shape.is_none())
        .map(|(i, _)| CullView::Far(i));
    let insets = (plan.displays.iter().enumerate())
        .filter(|(_, d)| d.inset.is_some())
        .map(|(i, _)| CullView::Inset(i));
    displays.chain(far).chain(insets).chain(late).collect()
}

/// Each display's pipeline variant: multiview for stereo in `multiview`, else one, two
/// or (foveated) four views per visible object, with clip distances where the device
/// has them; a foveated display with the inset cull draws two per cull, each view into
/// its own viewport.
fn draw_keys(device: &wgpu::Device, plan: &FramePlan, mode: StereoMode) -> Vec<DrawKey> {
    let clip = DrawFeatures::of(device).clip_distances;
    (plan.resolved.displays.iter().zip(&plan.displays))
        .map(|(d, display)| match (d.eyes.len(), mode, &display.inset) {
            (2, StereoMode::Multiview, _) => DrawKey::MULTIVIEW,
            (4, StereoMode::Multiview, _) => DrawKey::MULTIVIEW_QUAD,
            (4, _, Some(_)) => DrawKey::placed(2, clip),
            (views, _, _) => DrawKey::new(views as u32, clip),
        })
        .collect()
}
