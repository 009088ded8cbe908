//! The display level: everything that exists once per rig display, as one value
//! ([`Display`]: its name, target shape and passes), and what every display's passes
//! share ([`Shared`]). A display's passes are those of the path chosen once in
//! `Renderer::new` ([`indirect`]: the GPU-driven `instanced` and `multiview`, one cull
//! and one multi-draw per display, with its far layer (`far_layer.rs`), occlusion's
//! late phase (`occlusion.rs`), its mask and kept tiles; [`classic`]: the
//! per-instance modes, the only ones with passes per eye).

pub mod classic;
pub mod far_layer;
pub mod indirect;
pub mod occlusion;

use classic::ClassicDisplay;
use far_layer::FarLayers;
use indirect::IndirectDisplay;
use occlusion::PyramidSets;

use crate::bins::Bin;
use crate::cull::CullOutput;
use crate::draw::{DrawScene, Drawer, Drawing};
use crate::error::{Error, Result};
use crate::keep::clear::KeepTiles;
use crate::records::{CullLayout, InstanceRecord};
use crate::renderer::culler::Culler;
use crate::renderer::frame_stats::FrameStats;
use crate::renderer::options::RendererOptions;
use crate::renderer::plan::{DisplayPlan, FramePlan};
use crate::renderer::recorder::Recorder;
use crate::renderer::targets::{TargetShape, TargetViews};
use crate::renderer::uploads::Writes;
use crate::rig::Rig;
use crate::scene::Scene;
use crate::shaders::DrawKey;
use indirect::Gpu;

/// What a renderer's displays are made from: the scene, the rig and
/// the frame plan of the rig as made, and the options.
pub struct PathInputs<'a> {
    pub scene: &'a Scene,
    /// The instance records the draw starts from: the scene's, or a live scene's (with
    /// its slots' generations) when a sync reallocates.
    pub records: &'a [InstanceRecord],
    /// The rig as made: its displays' names, shapes and masks.
    pub rig: &'a Rig,
    /// Its plan: its displays, coarse cull and far layer sizes.
    pub plan: &'a FramePlan,
    /// The frame context's uniform, bound by every pass.
    pub frame: &'a wgpu::Buffer,
    pub options: &'a RendererOptions,
    /// Instance slots (and places) of room.
    pub slots: u32,
    /// Group 2 of the draw pipelines: the frame's shadow map.
    pub shadow_group: &'a wgpu::BindGroup,
}

/// What every display's passes share: the one culler all views cull through, the draw
/// pipelines, the scene as the GPU draws it, and on the GPU-driven path the far layers'
/// pipelines and the kept tiles' pass.
pub struct Shared {
    pub culler: Culler,
    pub drawer: Drawer,
    pub draw_scene: DrawScene,
    /// With the far layer: what every far layer shares.
    far: Option<FarLayers>,
    /// Keeping unchanged pixels where frames may: the pass that clears changed tiles.
    keep: Option<KeepTiles>,
}

impl Shared {
    /// The pipelines and the scene, as a pass draws them.
    pub fn drawing(&self) -> Drawing<'_> {
        Drawing {
            drawer: &self.drawer,
            scene: &self.draw_scene,
        }
    }

    /// The kept tiles' pass (keeping unchanged pixels on the GPU-driven path).
    pub fn keep(&self) -> Option<&KeepTiles> {
        self.keep.as_ref()
    }
}

/// What one rig display has, made whole by [`Display::new`]: its name (its timer
/// scope), its target's shape, its far layer's size as made, and its passes.
pub struct Display {
    name: String,
    shape: TargetShape,
    /// Its far layer's texels as made (every frame's plan is sized so).
    far_size: Option<(u32, u32)>,
    passes: DisplayPasses,
}

/// A display's passes on the path chosen once for the renderer.
pub enum DisplayPasses {
    Indirect(Box<IndirectDisplay>),
    Classic(Box<ClassicDisplay>),
}

/// What a renderer's displays are: what they share, occlusion's pyramids (every
/// occluding display's, built together), and each display.
pub struct Displays {
    pub shared: Shared,
    pub pyramids: PyramidSets,
    pub displays: Vec<Display>,
}

/// The displays of `inputs` on the path its options choose, culled over `layout`
/// (the scene's instances at their places of the cull order).
pub fn build(device: &wgpu::Device, layout: CullLayout, inputs: &PathInputs) -> Result<Displays> {
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let built = match inputs.options.mode.per_instance() {
        false => indirect::build(device, layout, inputs),
        true => classic::build(device, layout, inputs),
    };
    // Popped before returning any error, so the caller's device keeps its scopes.
    if let Some(e) = pollster::block_on(scope.pop()) {
        return Err(Error::Wgpu(e));
    }
    built
}

/// The draw pipelines of `inputs`' target for the pipeline variants `keys` over the
/// material bins `kinds`, and the scene as they draw it.
fn drawn(
    device: &wgpu::Device,
    inputs: &PathInputs,
    keys: &[DrawKey],
    kinds: &[Bin],
) -> Result<(Drawer, DrawScene)> {
    let options = inputs.options;
    let windows = options.windows(device, inputs.slots);
    let format = options.target_format();
    let shaders = options.shaders();
    let drawer = Drawer::new(
        device,
        format,
        (keys, kinds),
        shaders,
        options.shadow_size(),
        windows,
    );
    let scene = (inputs.scene, inputs.records, inputs.shadow_group);
    let draw_scene = DrawScene::new(device, &drawer, scene, inputs.slots)?;
    Ok((drawer, draw_scene))
}

impl Display {
    /// Display `index` of `inputs`' rig, drawn by `passes`.
    fn new(inputs: &PathInputs, index: usize, passes: DisplayPasses) -> Display {
        let d = &inputs.rig.displays[index];
        Display {
            name: d.name.clone(),
            shape: TargetShape::of(d, inputs.options),
            far_size: inputs.plan.displays[index].far.map(|p| p.size),
            passes,
        }
    }

    /// What its targets must look like.
    pub fn shape(&self) -> &TargetShape {
        &self.shape
    }

    /// Its far layer's size as made.
    pub fn far_size(&self) -> Option<(u32, u32)> {
        self.far_size
    }

    /// Its passes on the GPU-driven path (`None` in the classic modes).
    pub fn indirect(&self) -> Option<&IndirectDisplay> {
        match &self.passes {
            DisplayPasses::Indirect(d) => Some(d),
            DisplayPasses::Classic(_) => None,
        }
    }

    pub fn indirect_mut(&mut self) -> Option<&mut IndirectDisplay> {
        match &mut self.passes {
            DisplayPasses::Indirect(d) => Some(d),
            DisplayPasses::Classic(_) => None,
        }
    }

    /// Its cull result of the last frame: on the GPU-driven path its buffers read back
    /// through `gpu`; in the classic modes the CPU cull they drew from (multi-camera:
    /// the left eye's).
    pub fn read_cull(&self, gpu: Gpu, culler: &Culler) -> Result<CullOutput> {
        match &self.passes {
            DisplayPasses::Indirect(d) => d.read_cull(gpu, culler),
            DisplayPasses::Classic(d) => Ok(d.cull_output(culler)),
        }
    }

    /// Its visible total of the last frame: read back on the GPU-driven path (with
    /// occlusion both phases'), the CPU cull's in the classic modes.
    pub fn visible_count(&self, gpu: Gpu, culler: &Culler) -> Result<u32> {
        match &self.passes {
            DisplayPasses::Indirect(d) => d.visible_count(gpu),
            DisplayPasses::Classic(d) => Ok(d.visible_count(culler)),
        }
    }

    /// Writes this frame's contexts from `plan` (the display's) and the culler's
    /// results for its views. Returns the bytes written.
    pub fn prepare(&mut self, to: Writes, plan: &DisplayPlan, shared: &mut Shared) -> u64 {
        match &mut self.passes {
            DisplayPasses::Indirect(d) => d.prepare(to, plan, shared),
            DisplayPasses::Classic(d) => d.prepare(to, plan, &shared.culler),
        }
    }

    /// The display's first half of a frame into `target`: its cull and draw (with
    /// occlusion, the early phase's), inside its scope.
    pub fn encode_early(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        shared: &Shared,
        target: &TargetViews,
        rec: &mut Recorder,
    ) -> FrameStats {
        rec.enter(encoder, &self.name);
        let recorded = match &self.passes {
            DisplayPasses::Indirect(d) => d.encode_early(encoder, shared, target, rec),
            DisplayPasses::Classic(d) => d.encode(encoder, shared, target, rec),
        };
        rec.leave(encoder);
        recorded.at_display_level()
    }

    /// For a display drawn in the caller's pass: its cull (with occlusion the
    /// frustum's alone) and far layer, inside its scope (GPU-driven; nothing in the
    /// classic modes, culled in `prepare`).
    pub fn encode_cull(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        shared: &Shared,
        rec: &mut Recorder,
    ) -> FrameStats {
        let Some(d) = self.indirect() else {
            return FrameStats::default();
        };
        rec.enter(encoder, &self.name);
        let culled = d.encode_cull(encoder, shared, true, rec);
        rec.leave(encoder);
        culled.at_display_level()
    }

    /// With occlusion, after every display's pyramids: the display's late cull in
    /// dispatches of its own (culling on the GPU where the rig cull does not take it),
    /// inside its scope; nothing, and no scope, for a display without one.
    pub fn encode_late_cull(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        shared: &Shared,
        rec: &mut Recorder,
    ) -> FrameStats {
        let Some(late) = self.indirect().and_then(|d| d.late_apart(&shared.culler)) else {
            return FrameStats::default();
        };
        rec.enter(encoder, &self.name);
        let dispatches = late.encode_cull(encoder, &shared.culler, rec);
        rec.leave(encoder);
        FrameStats::display_level(0, dispatches)
    }

    /// With occlusion, after the late culls: the rest of the display's late phase into
    /// `target` (its far layer tested against its pyramids, its late draw), inside its
    /// scope; nothing, and no scope, for a display without one.
    pub fn encode_late(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        shared: &Shared,
        target: &TargetViews,
        rec: &mut Recorder,
    ) -> FrameStats {
        let Some(d) = self.indirect().filter(|d| d.late().is_some()) else {
            return FrameStats::default();
        };
        rec.enter(encoder, &self.name);
        let recorded = d.encode_late(encoder, shared, target, rec);
        rec.leave(encoder);
        recorded.at_display_level()
    }

    /// The display drawn into a pass the caller began. Returns the draw calls.
    pub fn draw(&self, pass: &mut wgpu::RenderPass, shared: &Shared) -> Result<u32> {
        Ok(match &self.passes {
            DisplayPasses::Indirect(d) => {
                d.check_own_pipelines(&shared.culler)?;
                d.draw(pass, shared)
            }
            DisplayPasses::Classic(d) => d.draw(pass, shared),
        })
    }
}
