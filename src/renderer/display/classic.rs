//! The classic stereo modes (`multi-camera`, `multi-pass`, `single-pass`): the CPU culls,
//! then one draw call per visible instance and eye, the way engines drew stereo before
//! GPU-driven submission. They draw the same images as the indirect path, so that each
//! can be profiled against it.

use super::occlusion::PyramidSets;
use super::{Display, DisplayPasses, Displays, PathInputs, Shared, drawn};
use crate::buffers::{Upload, storage_buffer, write};
use crate::contexts::context_buffer;
use crate::cull::CullOutput;
use crate::draw::{BinDraw, BinPipelines, DrawFeatures, Drawer, NO_OWN_PIPELINES};
use crate::error::Result;
use crate::records::CullLayout;
use crate::renderer::culler::{CullShape, Culler};
use crate::renderer::eye::{Eye, EyeInputs};
use crate::renderer::frame_stats::FrameStats;
use crate::renderer::options::StereoMode;
use crate::renderer::plan::{CullView, DisplayPlan};
use crate::renderer::recorder::{PassRecord, Recorder, begin_draw_pass};
use crate::renderer::targets::TargetViews;
use crate::renderer::uploads::Writes;
use crate::shaders::Bound;
use crate::shaders::DrawKey;

/// One display in a classic mode: its context, visible list and binding, its eyes'.
pub struct ClassicDisplay {
    index: usize,
    mode: StereoMode,
    context: wgpu::Buffer,
    /// The display's visible list (multi-camera: unused by stereo displays' eyes).
    visible: wgpu::Buffer,
    /// Mono displays draw with this; stereo ones with their eyes'.
    bind_group: wgpu::BindGroup,
    /// Two for stereo displays, four for foveated ones, none for mono.
    eyes: Vec<Eye>,
}

/// What a view the frame did not cull draws: nothing.
static NOTHING: CullOutput = CullOutput {
    visible: Vec::new(),
    draws: Vec::new(),
    draw_count: 0,
    bins: Vec::new(),
};

/// The classic path for `inputs`: the CPU's culler (the classic modes draw per
/// instance from its results), the one-view pipelines, and each display of its plan.
pub(super) fn build(
    device: &wgpu::Device,
    layout: CullLayout,
    inputs: &PathInputs,
) -> Result<Displays> {
    let (options, slots) = (inputs.options, inputs.slots);
    let clip = DrawFeatures::of(device).clip_distances;
    let windows = options.windows(device, slots);
    let keys = [DrawKey::new(1, clip)];
    let (drawer, draw_scene) = drawn(device, inputs, &keys, &layout.bins.kinds)?;
    let shape = CullShape {
        rig: Vec::new(),
        slots,
        levels: options.lod_levels(),
        coarse_slots: 0,
        floor: false,
        occlusion: Default::default(),
        tested: false,
        hidden_slots: 0,
        split: options.far_layer,
    };
    let shared = Shared {
        culler: Culler::new(device, options.cull, layout, shape, windows),
        drawer,
        draw_scene,
        far: None,
        keep: None,
    };
    let displays = (0..inputs.plan.displays.len())
        .map(|i| {
            let passes = ClassicDisplay::new(device, inputs, &shared, i);
            Display::new(inputs, i, DisplayPasses::Classic(Box::new(passes)))
        })
        .collect();
    Ok(Displays {
        shared,
        pyramids: PyramidSets::none(device),
        displays,
    })
}

impl ClassicDisplay {
    /// Display `index`'s contexts, visible lists and bindings: a stereo display's eyes
    /// get their own contexts, and in multi-camera their own visible lists.
    fn new(device: &wgpu::Device, inputs: &PathInputs, shared: &Shared, index: usize) -> Self {
        let (slots, mode) = (inputs.slots, inputs.options.mode);
        let per_eye_lists = mode == StereoMode::MultiCamera;
        let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
        let visible = storage_buffer(device, "stereocull.visible", 4 * slots as u64, usage);
        let drawing = shared.drawing();
        let planned = &inputs.plan.displays[index].context;
        let views = inputs.plan.resolved.displays[index].eyes.len();
        let context = context_buffer(device);
        let eye_inputs = EyeInputs {
            frame: inputs.frame,
            drawing,
            display_list: &visible,
            slots,
        };
        let eyes = (0..if views > 1 { views } else { 0 })
            .map(|e| {
                let viewport = planned.eye[e].viewport.to_array().map(|v| v as u32);
                Eye::new(device, &eye_inputs, per_eye_lists, viewport)
            })
            .collect();
        let bind_group = (drawing.drawer).bind_group(
            device,
            [inputs.frame, &context],
            drawing.scene,
            visible.bound(),
        );
        ClassicDisplay {
            index,
            mode,
            bind_group,
            context,
            visible,
            eyes,
        }
    }

    /// Writes the display's contexts from `plan` (the CPU culled it in the culler's
    /// `prepare`) and uploads the visible lists its draws index. Returns the bytes.
    pub(super) fn prepare(&self, to: Writes, plan: &DisplayPlan, culler: &Culler) -> u64 {
        let ctx = &plan.context;
        let mut bytes = to.pose.write_uniform(&self.context, 0, ctx);
        for (e, eye) in self.eyes.iter().enumerate() {
            bytes += eye.prepare(to, ctx, e);
        }
        for (out, buffer) in self.visible_lists(culler) {
            bytes += write(to.queue, buffer, bytemuck::cast_slice(&out.visible));
        }
        bytes
    }

    /// The visible lists the display's draws index, and the cull each holds: each
    /// eye's own in multi-camera, else the display's one.
    fn visible_lists<'a>(&'a self, culler: &'a Culler) -> Vec<(&'a CullOutput, &'a wgpu::Buffer)> {
        let own: Vec<_> = (self.eyes.iter().enumerate())
            .filter_map(|(e, eye)| Some((self.cull_of(culler, Some(e)), eye.visible()?)))
            .collect();
        match own.is_empty() {
            true => vec![(self.cull_of(culler, None), &self.visible)],
            false => own,
        }
    }

    /// This frame's cull that the display (or its eye `eye`, culled on its own in
    /// multi-camera) draws from: the eye's own where the plan culled it, else the
    /// display's.
    fn cull_of<'a>(&self, culler: &'a Culler, eye: Option<usize>) -> &'a CullOutput {
        let own = eye.and_then(|e| culler.output(CullView::Eye(self.index, e)));
        own.or_else(|| culler.output(CullView::Display(self.index)))
            .unwrap_or(&NOTHING)
    }

    /// The display into its own passes, inside its scope: one per eye for a stereo
    /// display in multi-pass and multi-camera, else one.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        shared: &Shared,
        target: &TargetViews,
        rec: &mut Recorder,
    ) -> FrameStats {
        let (index, views) = (self.index, self.eyes.len());
        let draw_calls = match self.mode {
            StereoMode::MultiCamera | StereoMode::MultiPass if views > 0 => (0..views)
                .map(|e| {
                    let mut open = rec.open(encoder, PassRecord::eye("draw", index, e));
                    let mut pass = begin_draw_pass(encoder, rec, target, e == 0, None, &mut open);
                    rec.count_samples(&mut pass, &mut open);
                    let calls = self.draw_eye(&mut pass, shared, e);
                    rec.close_render(encoder, pass, open);
                    calls
                })
                .sum(),
            _ => {
                let mut open = rec.open(encoder, PassRecord::display("draw", index));
                let mut pass = begin_draw_pass(encoder, rec, target, true, None, &mut open);
                rec.count_samples(&mut pass, &mut open);
                let calls = self.draw(&mut pass, shared);
                rec.close_render(encoder, pass, open);
                calls
            }
        };
        FrameStats {
            draw_calls,
            ..Default::default()
        }
    }

    /// The display into one pass: a mono display's instances; a stereo display's in
    /// the single-pass cadence, or (multi-pass, multi-camera) each eye in turn in its
    /// half. Returns the draw calls.
    pub(super) fn draw(&self, pass: &mut wgpu::RenderPass, shared: &Shared) -> u32 {
        let cull = self.cull_of(&shared.culler, None);
        match (self.mode, self.eyes.as_slice()) {
            (_, []) => {
                Drawer::bind(pass, &shared.draw_scene, &self.bind_group);
                let mut drawer = bin_drawer(shared);
                instance_draws(cull).map(|d| drawer.draw(pass, d)).count() as u32
            }
            (StereoMode::SinglePass, eyes) => {
                eyes[0].bind(pass, &shared.draw_scene);
                single_pass_cadence(pass, cull, bin_drawer(shared), eyes)
            }
            (_, eyes) => (0..eyes.len())
                .map(|e| self.draw_eye(pass, shared, e))
                .sum(),
        }
    }

    /// View `e` of the stereo display into its viewport, from its cull (multi-camera)
    /// or the display's.
    fn draw_eye(&self, pass: &mut wgpu::RenderPass, shared: &Shared, e: usize) -> u32 {
        self.eyes[e].bind(pass, &shared.draw_scene);
        let out = self.cull_of(&shared.culler, Some(e));
        let mut drawer = bin_drawer(shared);
        instance_draws(out).map(|d| drawer.draw(pass, d)).count() as u32
    }

    /// This frame's cull of the display (multi-camera: its left eye's).
    pub fn cull_output(&self, culler: &Culler) -> CullOutput {
        self.cull_of(culler, Some(0)).clone()
    }

    /// This frame's visible total (multi-camera: its left eye's).
    pub fn visible_count(&self, culler: &Culler) -> u32 {
        self.cull_of(culler, Some(0)).visible.len() as u32
    }
}

/// The one-view pipelines of the scene's material bins.
fn bin_drawer(shared: &Shared) -> BinDrawer<'_> {
    let with = BinPipelines::Draw(shared.drawer.key(1), NO_OWN_PIPELINES);
    let pipeline = |kind| match shared.drawer.bin_pipeline(with, kind) {
        Some(BinDraw::BuiltIn(pipeline)) => Some(pipeline),
        _ => None,
    };
    BinDrawer {
        pipelines: (shared.culler.bins().iter())
            .filter_map(|b| pipeline(b.kind))
            .collect(),
        current: None,
    }
}

/// Single-pass stereo: each instance drawn for every view in the left, right, right,
/// left cadence (foveated: 0 1 2 3, then 3 2 1 0) so that the view (viewport and
/// binding) switches once per view per instance, not once more. Multi-pass and
/// multi-camera instead draw one pass per view into its viewport.
fn single_pass_cadence(
    pass: &mut wgpu::RenderPass,
    out: &CullOutput,
    mut drawer: BinDrawer,
    eyes: &[Eye],
) -> u32 {
    let mut current = usize::MAX;
    let mut calls = 0;
    for (k, d) in instance_draws(out).enumerate() {
        let up = 0..eyes.len();
        let order: Vec<usize> = if k % 2 == 0 {
            up.collect()
        } else {
            up.rev().collect()
        };
        for e in order {
            if e != current {
                eyes[e].switch_to(pass);
                current = e;
            }
            drawer.draw(pass, d.clone());
            calls += 1;
        }
    }
    calls
}

/// One per-instance draw: its material bin, index range, base vertex, and the slot in
/// the visible list.
type InstanceDraw = (usize, std::ops::Range<u32>, i32, u32);

/// The per-instance draws of a one-view cull result, in visible-list order.
fn instance_draws(out: &CullOutput) -> impl Iterator<Item = InstanceDraw> + '_ {
    (out.bins.iter().enumerate()).flat_map(move |(bin, b)| {
        let draws = &out.draws[b.first as usize..(b.first + b.count) as usize];
        draws.iter().flat_map(move |d| {
            let indices = d.first_index..d.first_index + d.index_count;
            (d.first_instance..d.first_instance + d.instance_count)
                .map(move |slot| (bin, indices.clone(), d.base_vertex, slot))
        })
    })
}

/// Draws per instance, setting each material bin's pipeline where the bin changes.
struct BinDrawer<'a> {
    pipelines: Vec<&'a wgpu::RenderPipeline>,
    current: Option<usize>,
}

impl BinDrawer<'_> {
    fn draw(
        &mut self,
        pass: &mut wgpu::RenderPass,
        (bin, indices, base_vertex, slot): InstanceDraw,
    ) {
        if self.current != Some(bin) {
            pass.set_pipeline(self.pipelines[bin]);
            self.current = Some(bin);
        }
        pass.draw_indexed(indices, base_vertex, slot..slot + 1);
    }
}
