//! Occlusion's passes on the GPU-driven path (`indirect.rs`): after a display's early
//! draw, its depth pyramids, its late cull and its late draw; which displays cull by
//! occlusion, and what it costs in GPU memory. The technique is [`crate::occlusion`]'s;
//! where the late cull reads the pyramids, and culling on the CPU its late phase
//! between the frame's halves, is the culler's (`culler/occlusion.rs`).

use std::sync::Mutex;

use super::far_layer::{Far, FarDisplay};
use crate::draw::{BinPipelines, Drawing, OwnPipelines};
use crate::error::Result;
use crate::occlusion::PyramidShape;
use crate::occlusion::pyramid::PyramidPass;
use crate::renderer::culler::Culler;
use crate::renderer::options::RendererOptions;
use crate::renderer::options::StereoMode;
use crate::renderer::plan::{FramePlan, FrameStats};
use crate::renderer::recorder::{PassRecord, Recorder, begin_draw_pass};
use crate::renderer::targets::TargetViews;
use crate::renderer::view::ViewPass;
use crate::shaders::DrawKey;

/// Display `index`'s late occlusion phase, with what it is recorded with: its cull and
/// draw (whose context is the display's, which the pyramids read too), its pipeline
/// variant, the pyramid pass for its depth target and the shape of its pyramids, and
/// their bind group for the depth target it was last made for (a caller usually renders
/// into the same targets every frame: no bind group per frame then).
pub(in crate::renderer) struct LatePhase {
    pub(in crate::renderer::display) view: ViewPass,
    pub(in crate::renderer::display) shape: PyramidShape,
    index: usize,
    key: DrawKey,
    pyramid: PyramidPass,
    device: wgpu::Device,
    bound: Mutex<Option<(wgpu::TextureView, wgpu::BindGroup)>>,
}

impl LatePhase {
    /// Display `index`'s late phase, drawn with pipeline variant `key` and culled and
    /// drawn by `view` (whose context is the display's), its pyramids `shape` reduced
    /// by the pass of `pyramids` its variant's target needs.
    pub(in crate::renderer::display) fn new(
        (index, key): (usize, DrawKey),
        view: ViewPass,
        shape: PyramidShape,
        pyramids: &Pyramids,
    ) -> LatePhase {
        let pyramid = match (key.multiview, &pyramids.layered) {
            (true, Some(layered)) => layered,
            _ => &pyramids.side_by_side,
        };
        LatePhase {
            view,
            shape,
            index,
            key,
            pyramid: pyramid.clone(),
            device: pyramids.device.clone(),
            bound: Mutex::new(None),
        }
    }

    /// The pyramids' bind group for `depth`: the last one if made for it, else one
    /// `make` makes (and kept).
    fn bind_group(
        &self,
        depth: &wgpu::TextureView,
        make: impl FnOnce(&wgpu::TextureView) -> wgpu::BindGroup,
    ) -> wgpu::BindGroup {
        let mut bound = self
            .bound
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        match &*bound {
            Some((view, group)) if view == depth => group.clone(),
            _ => {
                let group = make(depth);
                *bound = Some((depth.clone(), group.clone()));
                group
            }
        }
    }
}

/// The depth pyramids' passes (over side-by-side eyes, and over a layer per eye for
/// multiview), and the device that binds each frame's depth target to them.
pub(in crate::renderer::display) struct Pyramids {
    side_by_side: PyramidPass,
    layered: Option<PyramidPass>,
    device: wgpu::Device,
}

impl Pyramids {
    /// The passes `options` need: a layered variant in single-sampled multiview.
    pub(in crate::renderer::display) fn new(
        device: &wgpu::Device,
        options: &RendererOptions,
    ) -> Pyramids {
        let samples = options.sample_count;
        let layered = (options.mode == StereoMode::Multiview && samples == 1)
            .then(|| PyramidPass::new(device, 1, true));
        Pyramids {
            side_by_side: PyramidPass::new(device, samples, false),
            layered,
            device: device.clone(),
        }
    }
}

/// GPU memory occlusion culling adds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct OcclusionBytes {
    /// Per display with occlusion: visibility bits (a word per span of places) and the
    /// late phase's cull outputs (a visible list with room for every instance, the
    /// draws, the counts).
    pub per_display: u64,
    /// Once: the depth pyramids of the largest display's eyes, which displays share
    /// (culling on the CPU, every display's, read back together).
    pub pyramids: u64,
}

impl LatePhase {
    /// The display's second phase after its early draw, up to its draw: the pyramids of
    /// the early depth (in `target`), reduced where `culler` reads them, and the late
    /// cull.
    pub(in crate::renderer::display) fn encode_cull(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        (culler, target): (&Culler, &TargetViews),
        rec: &mut Recorder,
    ) -> FrameStats {
        let Some((buffer, offset)) = culler.pyramid_texels(self.index) else {
            return FrameStats::default();
        };
        let group = self.bind_group(target.depth, |depth| {
            let texels = wgpu::BufferBinding {
                buffer,
                offset,
                size: std::num::NonZeroU64::new(4 * self.shape.len() as u64),
            };
            (self.pyramid).bind_group(&self.device, self.view.context(), texels, depth)
        });
        let (mut pass, open) =
            rec.compute_pass(encoder, PassRecord::display("pyramid", self.index));
        let mut dispatches = self.pyramid.encode(&mut pass, &group, self.shape);
        rec.close_compute(encoder, pass, open);
        let what = PassRecord::display("late_cull", self.index);
        dispatches += (self.view).encode_cull(encoder, culler, rec, what);
        FrameStats {
            dispatches,
            ..FrameStats::default()
        }
    }

    /// The late draw into `target`: a pass that keeps what the early one drew, opening
    /// with the display's far layer composited (where it has one). Returns the draw
    /// calls.
    pub(in crate::renderer::display) fn encode_draw(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        (drawing, own, far): (Drawing, &OwnPipelines, Option<(&Far, &FarDisplay)>),
        target: &TargetViews,
        rec: &mut Recorder,
    ) -> u32 {
        let mut open = rec.open(encoder, PassRecord::display("late_draw", self.index));
        let mask = self.key.multiview_mask();
        let mut pass = begin_draw_pass(encoder, rec, (target, false, mask), &mut open);
        rec.count_samples(&mut pass, &mut open);
        let composite = far.map_or(0, |(far, layer)| far.layers.composite(&mut pass, layer));
        let with = BinPipelines::Draw(self.key, own);
        let calls = composite + self.view.draw(&mut pass, drawing, with);
        rec.close_render(encoder, pass, open);
        calls
    }
}

/// Whether each display with occlusion (`late`, per display) can read its depth target
/// into its pyramids.
pub(in crate::renderer::display) fn check_depth<'a>(
    late: impl Iterator<Item = Option<&'a LatePhase>>,
    targets: &[TargetViews],
) -> Result<()> {
    let bindable = wgpu::TextureUsages::TEXTURE_BINDING;
    for (display, (late, target)) in late.zip(targets).enumerate() {
        if late.is_some() && !target.depth.texture().usage().contains(bindable) {
            return Err(crate::error::Error::DepthNotBindable { display });
        }
    }
    Ok(())
}

/// What occlusion adds in GPU memory for displays' `late` phases (`None` without any):
/// culling on the GPU, the bits and the shared pyramids; culling on the CPU, the
/// `read_back` pyramids (one region per display; the bits stay on the CPU).
pub(in crate::renderer::display) fn occlusion_bytes<'a>(
    late: impl Iterator<Item = &'a LatePhase> + Clone,
    culler: &Culler,
) -> Option<OcclusionBytes> {
    let shared = 4 * late.clone().map(|l| l.shape.len() as u64).max()?;
    let targets = late.clone().next()?.view.cull();
    let outputs = targets.visible.size() + targets.draws.size() + targets.counts.size();
    let (words, pyramids) = culler.occlusion_bytes(shared);
    Some(OcclusionBytes {
        per_display: words + outputs,
        pyramids,
    })
}

/// Each display's pyramid shape where it culls by occlusion ([`RendererOptions::occludes`])
/// in a scene of `triangles` triangles.
pub(in crate::renderer::display) fn pyramid_shapes(
    plan: &FramePlan,
    options: &RendererOptions,
    triangles: u64,
) -> Vec<Option<PyramidShape>> {
    (plan.resolved.displays.iter().zip(&plan.displays))
        .map(|(d, context)| {
            let shape = PyramidShape {
                eye: context.resolution.as_uvec2(),
                eyes: d.eyes.len() as u32,
            };
            let pixels = shape.eye.element_product() as u64 * shape.eyes as u64;
            options
                .occludes(d.eyes.len(), (pixels, triangles))
                .then_some(shape)
        })
        .collect()
}
