//! Occlusion's passes on the GPU-driven path (`indirect.rs`): after every display's
//! early draw, every display's depth pyramids in sets of displays (`PyramidSets`),
//! then each display's late cull (the rig cull's late members, or its own dispatches)
//! and its late draw ([`LatePhase`]); which displays cull by occlusion, and what it
//! costs in GPU memory. Culling on the CPU, the late culls between the frame's halves
//! are the culler's (`Culler::cull_late`, over the views `Renderer::encode_late` lists). The technique and its CPU twin are [`crate::occlusion`]'s; where the
//! late cull reads the pyramids is the culler's (`culler/occlusion.rs`).

use std::sync::Mutex;

use super::far_layer::{FarDisplay, FarLayers};
use crate::draw::{BinPipelines, Drawing, OwnPipelines};
use crate::occlusion::PyramidShape;
use crate::occlusion::pyramid::{PyramidDispatch, PyramidPass, PyramidSlice};
use crate::renderer::culler::{CullPass, Culler};
use crate::renderer::options::RendererOptions;
use crate::renderer::plan::FramePlan;
use crate::renderer::recorder::{PassRecord, Recorder, begin_draw_pass};
use crate::renderer::targets::TargetViews;
use crate::renderer::view::ViewPass;
use crate::shaders::{DrawKey, PYRAMID_SET_DEPTHS};

/// Display `index`'s late occlusion phase: its cull and draw (whose context is the
/// display's), its pipeline variant and the shape of its pyramids.
pub struct LatePhase {
    view: ViewPass,
    shape: PyramidShape,
    index: usize,
    key: DrawKey,
}

impl LatePhase {
    /// Display `index`'s late phase, drawn with pipeline variant `key` and culled and
    /// drawn by `view` (whose context is the display's), its pyramids `shape`.
    pub(super) fn new(
        index: usize,
        key: DrawKey,
        view: ViewPass,
        shape: PyramidShape,
    ) -> LatePhase {
        LatePhase {
            view,
            shape,
            index,
            key,
        }
    }

    /// The display's late cull in its own dispatches (culling on the GPU, where the
    /// rig cull does not take it), after every display's pyramids.
    pub(super) fn encode_cull(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        culler: &Culler,
        rec: &mut Recorder,
    ) -> u32 {
        let what = PassRecord::display("late_cull", self.index);
        self.view.encode_cull(encoder, culler, rec, what)
    }

    /// The late draw into `target`: a pass that keeps what the early one drew, opening
    /// with the display's far layer composited (where it has one). Returns the draw
    /// calls.
    pub(super) fn encode_draw(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        drawing: Drawing,
        own: &OwnPipelines,
        far: Option<(&FarLayers, &FarDisplay)>,
        target: &TargetViews,
        rec: &mut Recorder,
    ) -> u32 {
        let mut open = rec.open(encoder, PassRecord::display("late_draw", self.index));
        let mask = self.key.multiview_mask();
        let mut pass = begin_draw_pass(encoder, rec, target, false, mask, &mut open);
        rec.count_samples(&mut pass, &mut open);
        let composite = far.map_or(0, |(layers, far)| layers.composite(&mut pass, far));
        let with = BinPipelines::Draw(self.key, own);
        let calls = composite + self.view.draw(&mut pass, drawing, with);
        rec.close_render(encoder, pass, open);
        calls
    }

    /// Its cull, as the culler keeps it.
    pub fn cull_pass(&self) -> &CullPass {
        self.view.cull_pass()
    }

    /// Its cull outputs, per the cull contract.
    pub(super) fn cull(&self) -> &crate::cull::targets::CullTargets {
        self.view.cull()
    }

    /// The shape of its pyramids.
    pub(super) fn shape(&self) -> PyramidShape {
        self.shape
    }
}

/// Every display's pyramids, in sets of up to [`PYRAMID_SET_DEPTHS`] displays whose
/// depth targets one pass reads (side by side, or a layer per eye): one set of
/// dispatches each.
pub struct PyramidSets {
    sets: Vec<PyramidSetPass>,
    device: wgpu::Device,
}

/// One set: its pass, its slices' uniform and dispatches, its displays in
/// depth-binding order, and its bind group for the depth targets it was last made for (a caller
/// usually renders into the same targets every frame: no bind group per frame then).
struct PyramidSetPass {
    pass: PyramidPass,
    set: wgpu::Buffer,
    dispatches: Vec<PyramidDispatch>,
    displays: Vec<usize>,
    bound: Mutex<Option<(Vec<wgpu::TextureView>, wgpu::BindGroup)>>,
}

impl PyramidSets {
    /// No sets: no display occludes.
    pub(super) fn none(device: &wgpu::Device) -> PyramidSets {
        PyramidSets {
            sets: Vec::new(),
            device: device.clone(),
        }
    }

    /// The sets of the displays with a pyramid shape (`shapes`), drawn with pipeline
    /// variants `keys` into targets laid out as `plan`'s contexts say, into their
    /// regions of `culler`'s pyramids.
    pub(super) fn new(
        device: &wgpu::Device,
        options: &RendererOptions,
        keys: &[DrawKey],
        plan: &FramePlan,
        shapes: &[Option<PyramidShape>],
        culler: &Culler,
    ) -> PyramidSets {
        let samples = options.sample_count;
        let layered = |i: usize| keys[i].multiview && samples == 1;
        let mut sets = Vec::new();
        for variant in [false, true] {
            let displays: Vec<usize> = (0..shapes.len())
                .filter(|&i| shapes[i].is_some() && layered(i) == variant)
                .collect();
            if displays.is_empty() {
                continue;
            }
            let samples = if variant { 1 } else { samples };
            for chunk in displays.chunks(PYRAMID_SET_DEPTHS) {
                let slices = set_slices(chunk, plan, shapes, variant, culler);
                sets.push(PyramidSetPass {
                    pass: PyramidPass::new(device, samples, variant, chunk.len()),
                    set: PyramidPass::set_buffer(device, &slices),
                    dispatches: PyramidPass::dispatches(&slices),
                    displays: chunk.to_vec(),
                    bound: Mutex::new(None),
                });
            }
        }
        PyramidSets {
            sets,
            device: device.clone(),
        }
    }

    /// Records every set's pyramids of the early depth in `targets` (one per
    /// display), where `culler` reads them, as one frame-level pass `pyramid`.
    /// Returns the dispatches.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        culler: &Culler,
        targets: &[TargetViews],
        rec: &mut Recorder,
    ) -> u32 {
        if self.sets.is_empty() {
            return 0;
        }
        let (mut pass, open) = rec.frame_pass(encoder, "pyramid");
        let mut dispatches = 0;
        for set in &self.sets {
            let Some((pyramids, _)) = culler.pyramid_texels(set.displays[0]) else {
                continue;
            };
            let depths: Vec<&wgpu::TextureView> =
                set.displays.iter().map(|&i| targets[i].depth).collect();
            let group = set.bind_group(&depths, |views| {
                set.pass
                    .bind_group(&self.device, (&set.set, pyramids), views)
            });
            dispatches += set.pass.encode(&mut pass, &group, &set.dispatches);
        }
        rec.close_frame_pass(encoder, pass, open);
        dispatches
    }
}

impl PyramidSetPass {
    /// The bind group for `depths`: the last one if made for them, else one `make`
    /// makes (and kept).
    fn bind_group(
        &self,
        depths: &[&wgpu::TextureView],
        make: impl FnOnce(&[&wgpu::TextureView]) -> wgpu::BindGroup,
    ) -> wgpu::BindGroup {
        let mut bound = self
            .bound
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        match &*bound {
            Some((views, group)) if views.iter().eq(depths.iter().copied()) => group.clone(),
            _ => {
                let group = make(depths);
                let views = depths.iter().map(|&v| v.clone()).collect();
                *bound = Some((views, group.clone()));
                group
            }
        }
    }
}

/// The slices of a set of `displays` (in depth-binding order): each eye's viewport
/// (its display's context's, or a layer's corner when `layered`), its pixels, and its
/// display's region of `culler`'s pyramids.
fn set_slices(
    displays: &[usize],
    plan: &FramePlan,
    shapes: &[Option<PyramidShape>],
    layered: bool,
    culler: &Culler,
) -> Vec<PyramidSlice> {
    let mut slices = Vec::new();
    for (depth, &i) in displays.iter().enumerate() {
        let (Some(shape), Some((_, at))) = (shapes[i], culler.pyramid_texels(i)) else {
            continue;
        };
        for eye in 0..shape.eyes {
            let viewport = plan.displays[i].context.eye[eye as usize].viewport;
            slices.push(PyramidSlice {
                origin: match layered {
                    true => glam::UVec2::ZERO,
                    false => glam::UVec2::new(viewport.x as u32, viewport.y as u32),
                },
                size: shape.eye,
                base: (at / 4) as u32,
                eye,
                depth: depth as u32,
            });
        }
    }
    slices
}

/// What one display's occlusion phases drew in a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct OcclusionCounts {
    /// Instances drawn early: drawn last frame, kept by the frustum.
    pub early: u32,
    /// Instances drawn late: not drawn last frame, not hidden by the early depth.
    pub late: u32,
}

/// GPU memory occlusion culling adds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct OcclusionBytes {
    /// Per display with occlusion: visibility bits (a word per span of places) and the
    /// late phase's cull outputs (a visible list with room for every instance, the
    /// draws, the counts).
    pub per_display: u64,
    /// Once: every display's depth pyramids, each in its own region (on the GPU every
    /// display slot's region is the largest display's size), so that all are built
    /// before the late culls read them (culling on the CPU, read back together).
    pub pyramids: u64,
}

/// What occlusion adds in GPU memory for displays' `late` phases (`None` without any):
/// culling on the GPU, the bits and the shared pyramids; culling on the CPU, the
/// `read_back` pyramids (one region per display; the bits stay on the CPU).
pub fn occlusion_bytes<'a>(
    late: impl Iterator<Item = &'a LatePhase> + Clone,
    culler: &Culler,
) -> Option<OcclusionBytes> {
    let targets = late.clone().next()?.view.cull();
    let outputs = targets.visible.size() + targets.draws.size() + targets.counts.size();
    let (words, pyramids) = culler.occlusion_bytes();
    Some(OcclusionBytes {
        per_display: words + outputs,
        pyramids,
    })
}

/// Each display's pyramid shape where it culls by occlusion ([`RendererOptions::occludes`])
/// in a scene of `triangles` triangles.
pub(super) fn pyramid_shapes(
    plan: &FramePlan,
    options: &RendererOptions,
    triangles: u64,
) -> Vec<Option<PyramidShape>> {
    (plan.resolved.displays.iter().zip(&plan.displays))
        .map(|(d, display)| {
            let shape = PyramidShape {
                eye: display.context.resolution.as_uvec2(),
                eyes: d.eyes.len() as u32,
            };
            let pixels = shape.eye.element_product() as u64 * shape.eyes as u64;
            options
                .occludes(d.eyes.len(), pixels, triangles)
                .then_some(shape)
        })
        .collect()
}
