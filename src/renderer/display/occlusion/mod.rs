//! Occlusion's passes on the GPU-driven path (`indirect.rs`): after a display's early
//! draw, its depth pyramids, its late cull and its late draw; which displays cull by
//! occlusion, and what it costs in GPU memory. The technique is [`crate::occlusion`]'s.

pub(in crate::renderer) mod read_back;

use std::sync::Mutex;

use crate::draw::{BinPipelines, Drawing, OwnPipelines};
use crate::error::Result;
use crate::occlusion::PyramidShape;
use crate::occlusion::pyramid::PyramidPass;
use crate::renderer::culler::Culler;
use crate::renderer::options::RendererOptions;
use crate::renderer::options::StereoMode;
use crate::renderer::plan::{FramePlan, FrameStats};
use crate::renderer::recorder::{PassRecord, Timing, compute_pass, draw_pass};
use crate::renderer::targets::TargetViews;
use crate::renderer::view::ViewPass;
use crate::shaders::DrawKey;

/// A display's late occlusion phase: its cull and draw, the shape of its pyramids and
/// their bind group for the depth target it was last made for (a caller usually
/// renders into the same targets every frame: no bind group per frame then).
pub(in crate::renderer) struct LatePhase {
    pub(in crate::renderer) view: ViewPass,
    pub(in crate::renderer) shape: PyramidShape,
    bound: Mutex<Option<(wgpu::TextureView, wgpu::BindGroup)>>,
}

impl LatePhase {
    /// The late phase of a display whose pyramids are `shape`, culled and drawn by `view`.
    pub(in crate::renderer) fn new(view: ViewPass, shape: PyramidShape) -> LatePhase {
        LatePhase {
            view,
            shape,
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
pub(in crate::renderer) struct Pyramids {
    side_by_side: PyramidPass,
    layered: Option<PyramidPass>,
    device: wgpu::Device,
}

impl Pyramids {
    /// The passes `options` need: a layered variant in single-sampled multiview.
    pub(in crate::renderer) fn new(device: &wgpu::Device, options: &RendererOptions) -> Pyramids {
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

/// What a display's late phase is recorded with besides its own state: the path's
/// culler, drawing and pyramid passes, and the display's index, pipeline variant,
/// context and target.
pub(in crate::renderer) struct LateInputs<'a> {
    pub(in crate::renderer) culler: &'a Culler,
    pub(in crate::renderer) drawing: Drawing<'a>,
    pub(in crate::renderer) pyramids: &'a Pyramids,
    /// The buffer the display's pyramids go into, and where they start (bytes).
    pub(in crate::renderer) texels: (&'a wgpu::Buffer, u64),
    pub(in crate::renderer) index: usize,
    pub(in crate::renderer) key: DrawKey,
    /// The display's pipelines of the caller's own.
    pub(in crate::renderer) own: &'a OwnPipelines,
    pub(in crate::renderer) context: &'a wgpu::Buffer,
    pub(in crate::renderer) target: &'a TargetViews<'a>,
}

impl LatePhase {
    /// The display's second phase after its early draw, up to its draw: the pyramids of
    /// the early depth and the late cull.
    pub(in crate::renderer) fn encode_cull(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        inputs: &LateInputs,
        (timer, display): Timing,
        log: &mut Vec<PassRecord>,
    ) -> FrameStats {
        let (buffer, offset) = inputs.texels;
        let pyramids = inputs.pyramids;
        let pyramid = match (inputs.key.multiview, &pyramids.layered) {
            (true, Some(layered)) => layered,
            _ => &pyramids.side_by_side,
        };
        let group = self.bind_group(inputs.target.depth, |depth| {
            let texels = wgpu::BufferBinding {
                buffer,
                offset,
                size: std::num::NonZeroU64::new(4 * self.shape.len() as u64),
            };
            pyramid.bind_group(&pyramids.device, inputs.context, texels, depth)
        });
        let mut dispatches = 0;
        let what = (&mut *log, PassRecord::display("pyramid", inputs.index));
        compute_pass(encoder, (&mut *timer, display), what, |pass| {
            dispatches += pyramid.encode(pass, &group, self.shape);
        });
        let what = (log, PassRecord::display("late_cull", inputs.index));
        dispatches += (self.view).encode_cull(encoder, inputs.culler, (timer, display), what);
        FrameStats {
            dispatches,
            ..FrameStats::default()
        }
    }

    /// The late draw: a pass that keeps what the early one drew, opening with what
    /// `first` draws (a far layer's composite). Returns the draw calls.
    pub(in crate::renderer) fn encode_draw(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        inputs: &LateInputs,
        first: impl FnOnce(&mut wgpu::RenderPass) -> u32,
        timing: Timing,
        log: &mut Vec<PassRecord>,
    ) -> u32 {
        let what = (log, PassRecord::display("late_draw", inputs.index));
        let mask = inputs.key.multiview_mask();
        let with = BinPipelines::Draw(inputs.key, inputs.own);
        draw_pass(encoder, inputs.target, false, mask, timing, what, |pass| {
            first(pass) + self.view.draw(pass, inputs.drawing, with)
        })
    }
}

/// Whether each display with occlusion (`late`, per display) can read its depth target
/// into its pyramids.
pub(in crate::renderer) fn check_depth<'a>(
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
pub(in crate::renderer) fn occlusion_bytes<'a>(
    late: impl Iterator<Item = &'a LatePhase> + Clone,
    culler: &Culler,
    read_back: Option<u64>,
) -> Option<OcclusionBytes> {
    let pyramids = 4 * late.clone().map(|l| l.shape.len() as u64).max()?;
    let targets = late.clone().next()?.view.cull();
    let outputs = targets.visible.size() + targets.draws.size() + targets.counts.size();
    if let Some(read_back) = read_back {
        return Some(OcclusionBytes {
            per_display: outputs,
            pyramids: read_back,
        });
    }
    let (_, words, _) = culler.occlusion()?;
    Some(OcclusionBytes {
        per_display: 4 * words as u64 + outputs,
        pyramids,
    })
}

/// Each display's pyramid shape where it culls by occlusion ([`RendererOptions::occludes`])
/// in a scene of `triangles` triangles.
pub(in crate::renderer) fn pyramid_shapes(
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
