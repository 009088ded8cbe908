//! The classic stereo modes (`multi-camera`, `multi-pass`, `single-pass`): the CPU culls,
//! then one draw call per visible instance and eye, the way engines drew stereo before
//! GPU-driven submission. They draw the same images as the indirect path, so that each
//! can be profiled against it.

use std::time::Instant;

use super::{PathCore, PathInputs};
use crate::buffers::{Upload, storage_buffer, write};
use crate::contexts::context_buffer;
use crate::cull::CullOutput;
use crate::draw::{
    BinDraw, BinPipelines, DrawFeatures, DrawScene, Drawer, Drawing, NO_OWN_PIPELINES, set_viewport,
};
use crate::error::Result;
use crate::renderer::culler::{CullShape, Culler};
use crate::renderer::frame_stats::FrameStats;
use crate::renderer::options::StereoMode;
use crate::renderer::plan::{CullView, FramePlan};
use crate::renderer::recorder::{PassRecord, Recorder, begin_draw_pass};
use crate::renderer::targets::TargetViews;
use crate::renderer::uploads::Writes;
use crate::shaders::Bound;
use crate::shaders::DrawKey;

/// One view of a stereo display (an eye, or a foveated display's inset): its own
/// context (that view in every eye slot), its viewport, and for multi-camera its own
/// visible list.
struct EyeState {
    context: wgpu::Buffer,
    visible: Option<wgpu::Buffer>,
    bind_group: wgpu::BindGroup,
    /// `[x, y, width, height]` in the display's target.
    viewport: [u32; 4],
}

struct ClassicDisplay {
    context: wgpu::Buffer,
    /// The display's visible list (multi-camera: unused by stereo displays' eyes).
    visible: wgpu::Buffer,
    /// Mono displays draw with this; stereo ones with their eyes'.
    bind_group: wgpu::BindGroup,
    /// Two for stereo displays, four for foveated ones, none for mono.
    eyes: Vec<EyeState>,
}

pub(in crate::renderer) struct ClassicPath {
    mode: StereoMode,
    /// The culler is the CPU's (the classic modes draw per instance from its results).
    pub(in crate::renderer) core: PathCore,
    displays: Vec<ClassicDisplay>,
}

/// What a view the frame did not cull draws: nothing.
static NOTHING: CullOutput = CullOutput {
    visible: Vec::new(),
    draws: Vec::new(),
    draw_count: 0,
    bins: Vec::new(),
};

impl ClassicPath {
    /// The path for `inputs`, for the displays of its plan.
    pub(in crate::renderer) fn new(
        device: &wgpu::Device,
        inputs: PathInputs,
    ) -> Result<ClassicPath> {
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
        let clip = DrawFeatures::of(device).clip_distances;
        let windows = options.windows(device, slots);
        let keys = [DrawKey::new(1, clip)];
        let shaders = options.shaders();
        let target = options.target_format();
        let drawer = Drawer::new(
            device,
            target,
            (&keys, &layout.bins.kinds),
            shaders,
            options.shadow_size(),
            windows,
        );
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
        let culler = Culler::new(device, options.cull, layout, shape, windows);
        let draw_scene = DrawScene::new(device, &drawer, (scene, records, shadow_group), slots)?;
        let drawing = Drawing {
            drawer: &drawer,
            scene: &draw_scene,
        };
        let per_eye_lists = options.mode == StereoMode::MultiCamera;
        let displays = classic_displays(device, plan, drawing, frame, slots, per_eye_lists);
        Ok(ClassicPath {
            mode: options.mode,
            core: PathCore {
                culler,
                drawer,
                draw_scene,
            },
            displays,
        })
    }

    /// Culls on the CPU (every display and eye of `plan` in one pass over the spheres),
    /// writes the contexts and uploads the visible lists the draws index.
    pub(in crate::renderer) fn prepare(&mut self, to: Writes, plan: &FramePlan) -> FrameStats {
        let mut stats = FrameStats::default();
        let start = Instant::now();
        stats.bytes_uploaded += self.core.culler.prepare(to.pose, plan);
        stats.cpu_cull = start.elapsed();
        let start = Instant::now();
        let contexts = plan.displays.iter().map(|d| &d.context);
        for (i, (state, ctx)) in self.displays.iter().zip(contexts).enumerate() {
            stats.bytes_uploaded += to.pose.write_uniform(&state.context, 0, ctx);
            for (e, eye) in state.eyes.iter().enumerate() {
                stats.bytes_uploaded += to.pose.write_uniform(&eye.context, 0, &ctx.for_eye(e));
            }
            for (out, buffer) in self.visible_lists(i) {
                let visible = bytemuck::cast_slice(&out.visible);
                stats.bytes_uploaded += write(to.queue, buffer, visible);
            }
        }
        stats.cpu_upload = start.elapsed();
        stats
    }

    /// The visible lists display `index`'s draws index, and the cull each holds: each
    /// eye's own in multi-camera, else the display's one.
    fn visible_lists(&self, index: usize) -> Vec<(&CullOutput, &wgpu::Buffer)> {
        let state = &self.displays[index];
        let own: Vec<_> = (state.eyes.iter().enumerate())
            .filter_map(|(e, eye)| Some((self.cull_of(index, Some(e)), eye.visible.as_ref()?)))
            .collect();
        match own.is_empty() {
            true => vec![(self.cull_of(index, None), &state.visible)],
            false => own,
        }
    }

    /// This frame's cull that display `index` (or its eye `eye`, culled on its own in
    /// multi-camera) draws from: the eye's own where the plan culled it, else the
    /// display's.
    fn cull_of(&self, index: usize, eye: Option<usize>) -> &CullOutput {
        let own = eye.and_then(|e| self.core.culler.output(CullView::Eye(index, e)));
        own.or_else(|| self.core.culler.output(CullView::Display(index)))
            .unwrap_or(&NOTHING)
    }

    /// Display `index` into its own passes, inside its display's scope: one per eye for
    /// a stereo display in multi-pass and multi-camera, else one.
    pub(in crate::renderer) fn encode_display(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        (index, target): (usize, &TargetViews),
        rec: &mut Recorder,
    ) -> FrameStats {
        let views = self.displays[index].eyes.len();
        let draw_calls = match self.mode {
            StereoMode::MultiCamera | StereoMode::MultiPass if views > 0 => (0..views)
                .map(|e| {
                    let mut open = rec.open(encoder, PassRecord::eye("draw", index, e));
                    let mut pass = begin_draw_pass(encoder, rec, (target, e == 0, None), &mut open);
                    rec.count_samples(&mut pass, &mut open);
                    let calls = self.draw_eye(&mut pass, index, e);
                    rec.close_render(encoder, pass, open);
                    calls
                })
                .sum(),
            _ => {
                let mut open = rec.open(encoder, PassRecord::display("draw", index));
                let mut pass = begin_draw_pass(encoder, rec, (target, true, None), &mut open);
                rec.count_samples(&mut pass, &mut open);
                let calls = self.draw(&mut pass, index);
                rec.close_render(encoder, pass, open);
                calls
            }
        };
        FrameStats {
            draw_calls,
            ..Default::default()
        }
    }

    /// Display `index` into one pass: a mono display's instances; a stereo display's in
    /// the single-pass cadence, or (multi-pass, multi-camera) each eye in turn in its
    /// half. Returns the draw calls.
    pub(in crate::renderer) fn draw(&self, pass: &mut wgpu::RenderPass, index: usize) -> u32 {
        let (state, cull) = (&self.displays[index], self.cull_of(index, None));
        match (self.mode, state.eyes.as_slice()) {
            (_, []) => {
                self.bind(pass, &state.bind_group);
                let mut drawer = self.bin_drawer();
                instance_draws(cull).map(|d| drawer.draw(pass, d)).count() as u32
            }
            (StereoMode::SinglePass, eyes) => {
                self.bind(pass, &eyes[0].bind_group);
                single_pass_cadence(pass, (cull, self.bin_drawer()), eyes)
            }
            (_, eyes) => (0..eyes.len()).map(|e| self.draw_eye(pass, index, e)).sum(),
        }
    }

    /// View `e` of stereo display `index` into its viewport, from its cull
    /// (multi-camera) or the display's.
    fn draw_eye(&self, pass: &mut wgpu::RenderPass, index: usize, e: usize) -> u32 {
        let state = &self.displays[index];
        self.bind(pass, &state.eyes[e].bind_group);
        set_viewport(pass, state.eyes[e].viewport);
        let out = self.cull_of(index, Some(e));
        let mut drawer = self.bin_drawer();
        instance_draws(out).map(|d| drawer.draw(pass, d)).count() as u32
    }

    fn bind(&self, pass: &mut wgpu::RenderPass, bind_group: &wgpu::BindGroup) {
        Drawer::bind(pass, &self.core.draw_scene, bind_group);
    }

    /// The one-view pipelines of the scene's material bins.
    fn bin_drawer(&self) -> BinDrawer<'_> {
        let with = BinPipelines::Draw(self.core.drawer.key(1), NO_OWN_PIPELINES);
        let pipeline = |kind| match self.core.drawer.bin_pipeline(with, kind) {
            Some(BinDraw::BuiltIn(pipeline)) => Some(pipeline),
            _ => None,
        };
        BinDrawer {
            pipelines: (self.core.culler.bins().iter())
                .filter_map(|b| pipeline(b.kind))
                .collect(),
            current: None,
        }
    }

    /// This frame's cull of display `index` (multi-camera: its left eye's).
    pub(in crate::renderer) fn cull_output(&self, index: usize) -> CullOutput {
        self.cull_of(index, Some(0)).clone()
    }

    pub(in crate::renderer) fn visible_counts(&self) -> Vec<u32> {
        (0..self.displays.len())
            .map(|i| self.cull_of(i, Some(0)).visible.len() as u32)
            .collect()
    }
}

/// Each display's contexts, visible lists and bindings: a stereo display's eyes get
/// their own contexts, and with `per_eye_lists` (multi-camera) their own visible lists
/// of `slots` instances.
fn classic_displays(
    device: &wgpu::Device,
    plan: &FramePlan,
    drawing: Drawing,
    frame: &wgpu::Buffer,
    slots: u32,
    per_eye_lists: bool,
) -> Vec<ClassicDisplay> {
    let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
    let visible_list = || storage_buffer(device, "stereocull.visible", 4 * slots as u64, usage);
    let bind = |context: &wgpu::Buffer, list: &wgpu::Buffer| {
        (drawing.drawer).bind_group(device, [frame, context], drawing.scene, list.bound())
    };
    let views = plan.resolved.displays.iter().map(|r| r.eyes.len());
    (plan.displays.iter().map(|d| &d.context))
        .zip(views)
        .map(|(d, views)| {
            let context = context_buffer(device);
            let visible = visible_list();
            let eyes = (0..if views > 1 { views } else { 0 })
                .map(|e| {
                    let context = context_buffer(device);
                    let own = per_eye_lists.then(visible_list);
                    EyeState {
                        bind_group: bind(&context, own.as_ref().unwrap_or(&visible)),
                        context,
                        visible: own,
                        viewport: d.eye[e].viewport.to_array().map(|v| v as u32),
                    }
                })
                .collect();
            ClassicDisplay {
                bind_group: bind(&context, &visible),
                context,
                visible,
                eyes,
            }
        })
        .collect()
}

/// Single-pass stereo: each instance drawn for every view in the left, right, right,
/// left cadence (foveated: 0 1 2 3, then 3 2 1 0) so that the view (viewport and
/// binding) switches once per view per instance, not once more. Multi-pass and
/// multi-camera instead draw one pass per view into its viewport.
fn single_pass_cadence(
    pass: &mut wgpu::RenderPass,
    (out, mut drawer): (&CullOutput, BinDrawer),
    eyes: &[EyeState],
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
                pass.set_bind_group(0, &eyes[e].bind_group, &[]);
                set_viewport(pass, eyes[e].viewport);
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
