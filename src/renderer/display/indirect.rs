//! The GPU-driven path (`instanced` and `multiview`): per display, culling into a
//! visible list and per-mesh draws (three compute dispatches, or the CPU culler and an
//! upload), then one render pass with one multi-draw-indirect call.
//!
//! Per frame on the GPU-culled path the CPU writes one display context per display and
//! records a fixed number of commands: its cost does not depend on the instance count.

use super::far_layer::{FarDisplay, FarLayers};
use super::occlusion::{LatePhase, OcclusionCounts, PyramidSets, pyramid_shapes};
use super::{Display, DisplayPasses, Displays, PathInputs, Shared, drawn};
use crate::contexts::context_buffer;
use crate::cull::gpu_buffers::OcclusionRoom;
use crate::cull::targets::{COUNTS_BYTES, CullTargets};
use crate::cull::{BinDraws, CullOutput};
use crate::draw::mask::{DisplayMask, MaskPipeline};
use crate::draw::{BinPipelines, DrawFeatures, OwnPipeline};
use crate::draw::{OwnPipelines, mask};
use crate::error::{Error, Result};
use crate::keep::KeepUnchanged;
use crate::keep::clear::KeepTiles;
use crate::keep::clear::TileGrid;
use crate::occlusion::{Phase, PyramidShape};
use crate::readback::read_pod_at;
use crate::records::CullLayout;
use crate::records::DrawArgs;
use crate::renderer::culler::{CullShape, Culler};
use crate::renderer::frame_stats::FrameStats;
use crate::renderer::keeping;
use crate::renderer::options::StereoMode;
use crate::renderer::plan::{CullView, DisplayPlan, FramePlan, KeptTiles};
use crate::renderer::recorder::{PassRecord, Recorder, begin_draw_pass};
use crate::renderer::targets::{TargetShape, TargetViews};
use crate::renderer::uploads::Writes;
use crate::renderer::view::ViewPass;
use crate::scene::Shading;
use crate::shaders::DrawKey;

/// One display of the GPU-driven path: a view (its context, cull and draw bindings)
/// and its pipeline variant, which also fixes the instances per visible object; with
/// the inset cull, a foveated display's inset pair is one more view, drawn by the same
/// pipeline in the same pass; with occlusion its late phase, with the far layer its far
/// layer, with the visibility mask its mask pass, keeping pixels its kept tiles.
pub struct IndirectDisplay {
    index: usize,
    view: ViewPass,
    key: DrawKey,
    /// Pipelines of the caller's own for its [`crate::scene::Shading::Own`] bins.
    own: OwnPipelines,
    inset: Option<ViewPass>,
    /// With occlusion: the late phase (`view` is then the early one).
    late: Option<LatePhase>,
    /// With the far layer (a stereo display): its far layer.
    far: Option<FarDisplay>,
    /// The last prepared frame's far distance (with a far layer).
    far_distance: Option<f32>,
    /// With a visibility mask (and the option on): its mask pass, drawn first in the
    /// display's clearing draw pass.
    mask: Option<(MaskPipeline, DisplayMask)>,
    /// Whether this frame keeps its unchanged pixels, and how.
    kept: Option<Kept>,
}

/// A display whose frame keeps its unchanged pixels.
#[derive(Clone, Copy, Debug)]
struct Kept {
    /// Words of its tiles' bits.
    words: u32,
    /// The cull slot whose tiles the GPU marked (`None`: the CPU marked them).
    marked_in: Option<u32>,
}

/// The path for `inputs`: built for its plan (the rig as made, which sizes the far
/// layers) and its coarse cull.
pub(super) fn build(
    device: &wgpu::Device,
    layout: CullLayout,
    inputs: &PathInputs,
) -> Result<Displays> {
    let &PathInputs {
        scene,
        plan,
        options,
        slots,
        ..
    } = inputs;
    let windows = options.windows(device, slots);
    let shapes = pyramid_shapes(plan, options, scene.triangles());
    let views = plan.displays.iter().map(|d| d.context.views);
    let keeps = options.keep_unchanged != KeepUnchanged::Off
        && keeping::never(scene, views, options).is_none();
    let tiles = keeps.then(|| keeping::tiles(plan));
    let shape = cull_shape(plan, options, &shapes, tiles.as_deref(), slots);
    let kinds = layout.bins.kinds.clone();
    let mut culler = Culler::new(device, options.cull, layout, shape, windows);
    culler.track_visibility(device, &shapes);
    let keys = draw_keys(device, plan, options.mode);
    let shaders = options.shaders();
    let target = options.target_format();
    let keep = tiles.map(|tiles| KeepTiles::new(device, target, &tiles));
    let (drawer, draw_scene) = drawn(device, inputs, &keys, &kinds)?;
    let far = (options.far_layer).then(|| FarLayers::new(device, target, &kinds, shaders, windows));
    let shared = Shared {
        culler,
        drawer,
        draw_scene,
        far,
        keep,
    };
    let pyramids = PyramidSets::new(device, options, &keys, plan, &shapes, &shared.culler);
    let displays = (0..plan.displays.len())
        .map(|i| {
            let made = Made {
                device,
                inputs,
                shared: &shared,
            };
            let passes = IndirectDisplay::new(made, i, keys[i], shapes[i]);
            Display::new(inputs, i, DisplayPasses::Indirect(Box::new(passes)))
        })
        .collect();
    Ok(Displays {
        shared,
        pyramids,
        displays,
    })
}

/// What a display is made from: the device, the renderer's inputs and what its passes
/// share.
#[derive(Clone, Copy)]
struct Made<'a> {
    device: &'a wgpu::Device,
    inputs: &'a PathInputs<'a>,
    shared: &'a Shared,
}

/// The culler's shape for `plan`: its rig members, its occlusion room (with `shapes`,
/// the occluding displays' pyramids, and `tiles`, each kept display's), its hidden
/// slots and far split.
fn cull_shape(
    plan: &FramePlan,
    options: &crate::renderer::options::RendererOptions,
    shapes: &[Option<PyramidShape>],
    tiles: Option<&[u32]>,
    slots: u32,
) -> CullShape {
    let displays = plan.displays.len() as u32;
    let coarse_slots = match plan.cull.coarse {
        Some(_) => displays,
        None => 0,
    };
    let most_tiles = tiles.iter().copied().flatten().max().copied().unwrap_or(0);
    let occlusion = OcclusionRoom {
        displays: displays * u32::from(shapes.iter().any(Option::is_some)),
        pyramid_texels: shapes.iter().flatten().map(|s| s.len()).max().unwrap_or(0),
        tiles: match tiles {
            Some(_) => (displays, most_tiles.div_ceil(32)),
            None => (0, 0),
        },
    };
    CullShape {
        rig: match options.rig_cull {
            true => rig_members(plan, shapes, coarse_slots > 0),
            false => Vec::new(),
        },
        slots,
        levels: options.lod_levels(),
        coarse_slots,
        floor: options.cull_floor,
        occlusion,
        tested: options.far_layer && occlusion.displays > 0,
        hidden_slots: match plan.displays.iter().any(|d| d.hidden.is_some()) {
            true => displays,
            false => 0,
        },
        split: options.far_layer,
    }
}

impl IndirectDisplay {
    /// Display `index`, drawn with pipeline variant `key`, its pyramids `shape` where
    /// it occludes: its views (early and late with occlusion, its inset pair's), its far
    /// layer and its mask, made whole.
    fn new(made: Made, index: usize, key: DrawKey, shape: Option<PyramidShape>) -> Self {
        let Made {
            device,
            inputs,
            shared,
        } = made;
        let frame = inputs.frame;
        let drawing = shared.drawing();
        let culler = &shared.culler;
        let view = |v| ViewPass::new(device, drawing, frame, culler, v);
        let phased =
            |v, phase, context| ViewPass::phased(device, drawing, frame, culler, v, phase, context);
        let (view, late) = match shape {
            Some(shape) => {
                let early = phased(
                    CullView::Display(index),
                    Phase::Early,
                    context_buffer(device),
                );
                let context = early.context().clone();
                let late = phased(CullView::Late(index), Phase::Late, context);
                (early, Some(LatePhase::new(index, key, late, shape)))
            }
            None => (view(CullView::Display(index)), None),
        };
        let planned = &inputs.plan.displays[index];
        let inset = planned
            .inset
            .as_ref()
            .map(|_| ViewPass::new(device, drawing, frame, culler, CullView::Inset(index)));
        let far = far_display(made, index, planned, view.context(), late.is_some());
        IndirectDisplay {
            index,
            view,
            key,
            own: OwnPipelines::new(),
            inset,
            late,
            far,
            far_distance: None,
            mask: display_mask(made, index),
            kept: None,
        }
    }

    /// Writes `plan`'s context and the culler's results for each of the display's
    /// views (its own, its late phase's record, its insets', its far layer's) and its
    /// kept tiles. Returns the bytes written.
    pub(super) fn prepare(&mut self, to: Writes, plan: &DisplayPlan, shared: &mut Shared) -> u64 {
        let culler = &shared.culler;
        let ctx = &plan.context;
        let mut bytes = self.view.prepare(to, ctx, culler);
        // The late phase shares the early one's context; a rig member has a record.
        if let Some(late) = &self.late {
            bytes += culler.write_member(to.pose, late.cull_pass(), ctx);
        }
        if let (Some(view), Some(inset)) = (&self.inset, &plan.inset) {
            bytes += view.prepare(to, inset, culler);
        }
        self.far_distance = plan.far.map(|p| p.distance);
        if let (Some(far), Some(far_plan)) = (&self.far, &plan.far) {
            bytes += far.prepare(to, far_plan, ctx, culler);
        }
        self.kept = None;
        if let (Some(keep), Some(tiles)) = (&mut shared.keep, &plan.tiles) {
            let (size, views) = (ctx.resolution.as_uvec2(), ctx.views.min(2));
            bytes += keep.write(to.queue, self.index, (size, views), tiles.mask());
            let g = crate::cull::tiles::grid(size, views);
            self.kept = Some(Kept {
                words: crate::cull::tiles::tile_words(g),
                marked_in: matches!(tiles, KeptTiles::Gpu).then_some(ctx.cull_slot),
            });
        }
        bytes
    }

    /// The display's view cull (the one the coarse cull and the floor timing read).
    pub fn cull_pass(&self) -> &crate::renderer::culler::CullPass {
        self.view.cull_pass()
    }

    /// The display up to what its late phase needs: its cull and its draw (with
    /// occlusion the early one). With occlusion, once every display's is recorded, the
    /// pyramids reduce every display's depth and the late culls follow (the rig's, or
    /// each display's own); culling on the CPU with occlusion the frame stops after the
    /// pyramids until the late culls have them.
    pub(super) fn encode_early(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        shared: &Shared,
        target: &TargetViews,
        rec: &mut Recorder,
    ) -> FrameStats {
        let culled = self.encode_cull(encoder, shared, false, rec);
        let multiview = self.key.multiview_mask();
        // With occlusion the far layer is drawn and composited in the late phase.
        let composite = self.late.is_none();
        let listed = self.encode_tile_list(encoder, shared);
        let mut open = rec.open(encoder, PassRecord::display("draw", self.index));
        let kept = self.kept.is_some();
        let mut pass = begin_draw_pass(encoder, rec, target, !kept, multiview, &mut open);
        let mut draw_calls = match (&shared.keep, kept) {
            (Some(keep), true) => keep.draw(&mut pass, self.index),
            _ => 0,
        };
        if let Some((pipeline, mask)) = &self.mask {
            pipeline.draw(&mut pass, mask);
            draw_calls += 1;
        }
        // The mask's own samples are not the scene's.
        rec.count_samples(&mut pass, &mut open);
        draw_calls += self.draw_views(&mut pass, shared, composite);
        rec.close_render(encoder, pass, open);
        FrameStats {
            draw_calls: culled.draw_calls + draw_calls,
            dispatches: culled.dispatches + listed,
            ..culled
        }
    }

    /// Where the display keeps this frame: its changed tiles listed for the tile pass,
    /// their bits first copied from where the GPU marked them (the culler's buffer).
    /// Returns the dispatches.
    fn encode_tile_list(&self, encoder: &mut wgpu::CommandEncoder, shared: &Shared) -> u32 {
        let (Some(keep), Some(kept)) = (&shared.keep, &self.kept) else {
            return 0;
        };
        let marked = (kept.marked_in).and_then(|s| shared.culler.marked_words(s, kept.words));
        keep.encode_list(encoder, self.index, marked)
    }

    /// With a far layer, its far cull in `phase` and far layer pass.
    fn encode_far(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        shared: &Shared,
        phase: Phase,
        rec: &mut Recorder,
    ) -> FrameStats {
        let (Some(layers), Some(far)) = (&shared.far, &self.far) else {
            return FrameStats::default();
        };
        let (scene, culler) = (&shared.draw_scene, &shared.culler);
        let (dispatches, draw_calls) = layers.encode(encoder, far, phase, scene, culler, rec);
        FrameStats {
            dispatches,
            draw_calls,
            ..FrameStats::default()
        }
    }

    /// The display's cull (on the GPU; the culler's upload wrote a CPU cull) and, with
    /// a far layer, its far cull and far layer pass, timed inside its scope. For a
    /// display drawn in `one_pass` (the caller's), with occlusion its cull is the
    /// frustum's alone, which draws everything in that pass.
    pub(super) fn encode_cull(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        shared: &Shared,
        one_pass: bool,
        rec: &mut Recorder,
    ) -> FrameStats {
        let culler = &shared.culler;
        let what = PassRecord::display("cull", self.index);
        let dispatches = match one_pass {
            true => culler.encode(encoder, self.view.cull_pass(), Phase::Frustum, rec, what),
            false => self.view.encode_cull(encoder, culler, rec, what),
        };
        let mut stats = FrameStats {
            dispatches,
            ..FrameStats::default()
        };
        if let Some(inset) = &self.inset {
            let what = PassRecord::display("inset_cull", self.index);
            stats.dispatches += inset.encode_cull(encoder, culler, rec, what);
        }
        // With occlusion in the renderer's passes, the far layer waits for the pyramids.
        if one_pass || self.late.is_none() {
            stats = stats + self.encode_far(encoder, shared, Phase::Frustum, rec);
        }
        stats
    }

    /// The display's one multi-draw-indirect call into `pass`, whose pipeline the
    /// caller set (built on [`crate::draw::Drawer::layout`] and the decode).
    pub fn draw_with_own_pipeline(&self, pass: &mut wgpu::RenderPass, shared: &Shared) {
        self.view.draw(pass, shared.drawing(), BinPipelines::Own);
    }

    /// Sets the display's pipeline of the caller's own for its
    /// [`Shading::Own`]`(shading)` bins.
    pub fn set_own_pipeline(&mut self, shading: u32, own: OwnPipeline) {
        self.own.insert(shading, own);
    }

    /// The display must have a pipeline for each [`Shading::Own`] bin it draws.
    pub fn check_own_pipelines(&self, culler: &Culler) -> Result<()> {
        let missing = (culler.bins().iter()).find_map(|b| match b.kind.shading {
            Shading::Own(i) if !self.own.contains_key(&i) => Some(i),
            _ => None,
        });
        match missing {
            Some(shading) => Err(Error::MissingOwnPipeline {
                index: self.index,
                shading,
            }),
            None => Ok(()),
        }
    }

    /// With occlusion, its late phase.
    pub fn late(&self) -> Option<&LatePhase> {
        self.late.as_ref()
    }

    /// Its late phase where its late cull takes dispatches of its own (GPU culling
    /// with occlusion, where the rig cull does not take it).
    pub(super) fn late_apart(&self, culler: &Culler) -> Option<&LatePhase> {
        self.late.as_ref().filter(|l| culler.records(l.cull_pass()))
    }

    /// With occlusion, the rest of its late phase after its early half and the late
    /// culls: with a far layer its cull against the pyramids and its pass, then the
    /// late draw (opening with the far composite).
    pub(super) fn encode_late(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        shared: &Shared,
        target: &TargetViews,
        rec: &mut Recorder,
    ) -> FrameStats {
        let Some(late) = &self.late else {
            return FrameStats::default();
        };
        let mut stats = self.encode_far(encoder, shared, Phase::Tested, rec);
        let far = shared.far.as_ref().zip(self.far.as_ref());
        let drawing = shared.drawing();
        stats.draw_calls += late.encode_draw(encoder, drawing, &self.own, far, target, rec);
        stats
    }

    /// With occlusion, whether its depth target can be read into its pyramids.
    pub fn check_depth(&self, target: &TargetViews) -> Result<()> {
        let bindable = wgpu::TextureUsages::TEXTURE_BINDING;
        match self.late.is_some() && !target.depth.texture().usage().contains(bindable) {
            true => Err(Error::DepthNotBindable {
                display: self.index,
            }),
            false => Ok(()),
        }
    }

    /// Its far layer's cull (with one).
    pub fn far_cull_pass(&self) -> Option<&crate::renderer::culler::CullPass> {
        self.far.as_ref().map(FarDisplay::cull_pass)
    }

    /// The display's cull outputs, per the cull contract.
    pub fn cull_targets(&self) -> &CullTargets {
        self.view.cull()
    }

    /// Pixels its visibility mask covers in each frame.
    pub fn masked_pixels(&self) -> u64 {
        self.mask.as_ref().map_or(0, |(_, m)| m.pixels)
    }

    /// The display's one multi-draw-indirect call into `pass`. With a far layer, its
    /// composite goes first (one more draw call); with an inset cull, the inset pair's
    /// multi-draw follows (one more).
    pub(super) fn draw(&self, pass: &mut wgpu::RenderPass, shared: &Shared) -> u32 {
        self.draw_views(pass, shared, true)
    }

    /// [`IndirectDisplay::draw`], with the far composite only where `composite`.
    fn draw_views(&self, pass: &mut wgpu::RenderPass, shared: &Shared, composite: bool) -> u32 {
        let composite = match (&shared.far, &self.far) {
            (Some(layers), Some(far)) if composite => layers.composite(pass, far),
            _ => 0,
        };
        let with = BinPipelines::Draw(self.key, &self.own);
        let outer = self.view.draw(pass, shared.drawing(), with);
        let insets = match &self.inset {
            Some(inset) => inset.draw(pass, shared.drawing(), with),
            None => 0,
        };
        composite + outer + insets
    }
}

/// Display `index`'s far layer (`planned`'s, where it has one), composited into the
/// display whose context is `context` and, where `tested` (it occludes), culled against
/// its pyramids.
fn far_display(
    made: Made,
    index: usize,
    planned: &DisplayPlan,
    context: &wgpu::Buffer,
    tested: bool,
) -> Option<FarDisplay> {
    let Made {
        device,
        inputs,
        shared,
    } = made;
    let (layers, plan) = (shared.far.as_ref()?, planned.far.as_ref()?);
    let drawing = layers.drawing(&shared.draw_scene);
    let (frame, culler, view) = (inputs.frame, &shared.culler, CullView::Far(index));
    let view = match tested {
        true => ViewPass::tested(device, drawing, frame, culler, view),
        false => ViewPass::new(device, drawing, frame, culler, view),
    };
    Some(layers.display(device, index, view, context, plan))
}

/// Display `index`'s mask pass, where it has a visibility mask and the option is on.
fn display_mask(made: Made, index: usize) -> Option<(MaskPipeline, DisplayMask)> {
    let options = made.inputs.options;
    let d = made
        .inputs
        .rig
        .displays
        .get(index)
        .filter(|_| options.visibility_mask)?;
    let frames = options.frames_per_submit;
    let masked = crate::renderer::frames::masked(d.visibility_mask.as_ref()?, d.views(), frames);
    let shape = TargetShape::of(d, options);
    Some(mask::display_mask(
        made.device,
        &masked,
        (&shape.layout, shape.layered),
        options.target_format(),
    ))
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

/// What a submitted frame holds, read back for [`crate::renderer::Diagnostics`]: the
/// display's cull buffers (its early and late phases, its far layer's and inset
/// pair's), visible totals, occlusion counts and kept tiles.
impl IndirectDisplay {
    /// Its cull buffers.
    pub fn read_cull(&self, gpu: Gpu, culler: &Culler) -> Result<CullOutput> {
        read_targets(gpu, culler, self.view.cull())
    }

    /// Its changed tiles in the last frame (`None`: drawn whole), as its tile pass read
    /// them (marked on the CPU or the GPU), with its grid.
    pub fn read_changed_tiles(
        &self,
        gpu: Gpu,
        keep: Option<&KeepTiles>,
    ) -> Result<Option<(Vec<u32>, TileGrid)>> {
        let (Some(keep), Some(kept)) = (keep, self.kept) else {
            return Ok(None);
        };
        let (at, Some(grid)) = keep.words(self.index) else {
            return Ok(None);
        };
        let words = read_pod_at(gpu.0, gpu.1, at, 4 * u64::from(kept.words))?;
        Ok(Some((words, grid)))
    }

    /// Its far layer's cull buffers (`None` without one).
    pub fn read_far_cull(&self, gpu: Gpu, culler: &Culler) -> Result<Option<CullOutput>> {
        let far = self.far.as_ref().map(FarDisplay::cull);
        far.map(|cull| read_targets(gpu, culler, cull)).transpose()
    }

    /// Its inset cull buffers (`None` without an inset cull).
    pub fn read_inset_cull(&self, gpu: Gpu, culler: &Culler) -> Result<Option<CullOutput>> {
        let inset = self.inset.as_ref().map(ViewPass::cull);
        inset
            .map(|cull| read_targets(gpu, culler, cull))
            .transpose()
    }

    /// Its late phase's cull buffers (`None` without occlusion).
    pub fn read_late_cull(&self, gpu: Gpu, culler: &Culler) -> Result<Option<CullOutput>> {
        let late = self.late.as_ref().map(LatePhase::cull);
        late.map(|cull| read_targets(gpu, culler, cull)).transpose()
    }

    /// The last prepared frame's far distance (`None` without a far layer).
    pub fn far_distance(&self) -> Option<f32> {
        self.far_distance
    }

    /// Its visible total, from its counts buffer (with occlusion, both phases': what
    /// it drew).
    pub fn visible_count(&self, gpu: Gpu) -> Result<u32> {
        let late = self.late.as_ref().map(LatePhase::cull);
        let late = match late {
            Some(cull) => read_counts(gpu, cull)?[1],
            None => 0,
        };
        Ok(read_counts(gpu, self.view.cull())?[1] + late)
    }

    /// What its two occlusion phases drew (`None` without occlusion).
    pub fn read_occlusion_counts(&self, gpu: Gpu) -> Result<Option<OcclusionCounts>> {
        let Some(late) = &self.late else {
            return Ok(None);
        };
        let early = read_counts(gpu, self.view.cull())?[1];
        let late = read_counts(gpu, late.cull())?[1];
        Ok(Some(OcclusionCounts { early, late }))
    }

    /// Its pyramids' shape (`None` without occlusion).
    pub fn pyramid_shape(&self) -> Option<PyramidShape> {
        self.late.as_ref().map(LatePhase::shape)
    }
}

/// The device and queue a read waits on.
pub type Gpu<'a> = (&'a wgpu::Device, &'a wgpu::Queue);

/// A view's cull buffers as `culler`'s layout lays them out, read back.
fn read_targets(gpu: Gpu, culler: &Culler, cull: &CullTargets) -> Result<CullOutput> {
    let counts = read_counts(gpu, cull)?;
    let [draw_count, visible_total] = [counts[0], counts[1]];
    let (device, queue) = gpu;
    let visible = match visible_total {
        0 => Vec::new(),
        n => read_pod_at(
            device,
            queue,
            (&cull.visible, cull.visible_at),
            4 * n as u64,
        )?,
    };
    let draws_bytes = (size_of::<DrawArgs>() as u32 * culler.draws()) as u64;
    Ok(CullOutput {
        visible,
        draws: read_pod_at(device, queue, (&cull.draws, cull.draws_at), draws_bytes)?,
        draw_count,
        bins: (culler.bins().iter().zip(&counts[2..]))
            .map(|(r, &count)| BinDraws {
                first: r.first,
                count,
            })
            .collect(),
    })
}

/// The counts buffer: the draw count, the visible total, each bin's draw count.
fn read_counts((device, queue): Gpu, cull: &CullTargets) -> Result<Vec<u32>> {
    read_pod_at(device, queue, (&cull.counts, cull.counts_at), COUNTS_BYTES)
}
