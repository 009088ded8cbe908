//! The embedding API: a [`Renderer`] takes the caller's device, queue and encoder,
//! renders into the caller's texture views (or targets it makes for them), and owns no
//! window and no global state.
//!
//! ```no_run
//! # fn demo(device: &wgpu::Device, queue: &wgpu::Queue) -> stereocull::Result<()> {
//! use stereocull::renderer::{Renderer, RendererOptions};
//! use stereocull::{rig::Rig, scene::Animation, scene_spec};
//!
//! let mut scene = scene_spec::load("procedural:10000")?;
//! // Every tenth instance turns and bobs on the GPU, from the frame's time alone.
//! for instance in scene.instances.iter_mut().step_by(10) {
//!     instance.animation = Animation { spin: 1.5, bob: 0.1 };
//! }
//! let mut rig = Rig::preset("hmd")?;
//! let mut renderer = Renderer::new(device, &scene, &rig, RendererOptions::default())?;
//! let targets = renderer.create_targets(device); // or views of your own textures
//! // Each frame: move the viewer, write the contexts, record, submit.
//! rig.viewer.yaw_deg += 1.0;
//! let seconds = 1.0 / 90.0; // your clock: animated instances move with it
//! renderer.prepare(queue, &rig, seconds)?;
//! let mut encoder = device.create_command_encoder(&Default::default());
//! let views: Vec<_> = targets.iter().map(|t| t.views()).collect();
//! renderer.encode(&mut encoder, &views, None)?; // or Some(&mut timer) for GPU timings
//! queue.submit([encoder.finish()]);
//! # Ok(()) }
//! ```
//!
//! An engine that owns its passes records the culls into its encoder, then draws each
//! display inside a pass it began, between its own passes (sky before, UI after):
//!
//! ```no_run
//! # fn demo(device: &wgpu::Device, queue: &wgpu::Queue, renderer: &mut stereocull::renderer::Renderer,
//! #         rig: &stereocull::rig::Rig, color: &wgpu::TextureView, depth: &wgpu::TextureView)
//! #         -> stereocull::Result<()> {
//! renderer.prepare(queue, rig, 0.0)?;
//! let mut encoder = device.create_command_encoder(&Default::default());
//! renderer.encode_culls(&mut encoder, None)?;
//! // ... the engine's sky pass on `color` ...
//! let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
//!     label: Some("engine opaque"),
//!     color_attachments: &[Some(wgpu::RenderPassColorAttachment {
//!         view: color, // 2W x H for a stereo display: both eyes, one draw call
//!         depth_slice: None,
//!         resolve_target: None,
//!         ops: wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store },
//!     })],
//!     depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
//!         view: depth,
//!         depth_ops: Some(wgpu::Operations {
//!             load: wgpu::LoadOp::Clear(1.0),
//!             store: wgpu::StoreOp::Store,
//!         }),
//!         stencil_ops: None,
//!     }),
//!     timestamp_writes: None,
//!     occlusion_query_set: None,
//!     multiview_mask: None,
//! });
//! renderer.draw_display(&mut pass, 0)?;
//! drop(pass);
//! // ... the engine's transparent and UI passes ...
//! queue.submit([encoder.finish()]);
//! # Ok(()) }
//! ```
//!
//! The chapter's levels are values. A [`FramePlan`] (`plan.rs`) is what one frame
//! decides: the frame level's (the rig resolved once, the frame context, the levels of
//! detail, the coarse cull, the light) and one [`DisplayPlan`] per display (its
//! context, culls, far layer, insets, hidden area, kept tiles). A `Renderer` holds the
//! frame level (`frame/`: `FrameLevel`, the frame context, the lights, the passes that
//! run once per frame and the live scene's edits), what every level's passes share
//! (the one culler, `culler/`, GPU passes or the CPU culler; the draw pipelines; the
//! scene as drawn) and one `Display` per rig display (`display/`: its target shape and
//! its passes on the path chosen once in [`Renderer::new`], `indirect.rs` for
//! `instanced` and `multiview` with its far layer, occlusion's late phase, mask and
//! kept tiles, `classic.rs` for the per-instance modes). The eye level (`eye/`) is
//! data on the indirect path (the contexts' `eye[e]`, read in the shaders) and an `Eye`
//! per view of a classic mode's stereo display (its context, viewport and list).
//!
//! `mod.rs` makes a renderer and answers questions about it; `submit.rs` holds a
//! frame's calls, and [`Renderer::encode`] reads top-down: the frame level's passes,
//! each display's cull and draw (with occlusion its early phase), every display's
//! pyramids, the late culls, each display's late phase. Every view (display, eye, far
//! layer, inset, light) is a `view.rs` culled through the one culler; `recorder.rs`
//! times and logs the passes; `checks.rs` holds every refusal of the options.

use crate::cull::targets::CullTargets;
use crate::draw::{DrawScene, OwnPipeline};
use crate::error::{Error, Result};
use crate::exposure::Tonemap;
use crate::keep::Keeper;
pub use crate::keep::{KeepUnchanged, WholeRedraw};
use crate::motion::PreviousFrame;

use crate::live::LiveScene;
use crate::places::Places;
use crate::records::{CullLayout, instance_records};
use crate::rig::Rig;
use crate::scene::Scene;

mod checks;
mod culler;
mod diagnostics;
mod display;
mod eye;
mod frame;
mod frame_stats;
pub mod frames;
mod keeping;
mod options;
mod plan;
mod recorder;
mod submit;
mod targets;
mod uploads;
mod view;

pub use checks::check_rig;
pub use culler::WallCulls;
pub use diagnostics::{Diagnostics, FarSplit};
use display::indirect::IndirectDisplay;
use display::occlusion::PyramidSets;
pub use display::occlusion::{OcclusionBytes, OcclusionCounts};
use display::{Display, PathInputs, Shared};
pub use frame::edits::SyncStats;
use frame::edits::{self, Edits};
use frame::morph::MorphPass;
use frame::pose::PosePass;
use frame::skin::SkinPass;
use frame::{FrameBase, FrameBindings, FrameLevel, FramePasses};
pub use frame_stats::{DispatchLevels, FrameStats};
pub use frames::grown;
pub use options::{
    CoarseMode, CullMode, DEFAULT_DT, LOD_PIXELS, OcclusionMode, PosingMode, RendererOptions,
    StereoMode, frame_lod,
};
use plan::PlanStorage;
pub use plan::{CullView, DisplayPlan, FramePlan, KeptTiles, PlannedCull, instances_per_object};
pub use recorder::{Level, PassRecord};
pub use targets::{DisplayTarget, TargetShape, TargetViews};
use uploads::Coalesced;

/// The scene submission backend: one per scene and rig shape, see the module docs for the
/// calls in order.
pub struct Renderer {
    options: RendererOptions,
    /// What exists once per frame: the frame context, the lights, the frame level's
    /// passes and the edits staged for them.
    frame: FrameLevel,
    /// What every level's passes share: the culler, the draw pipelines, the scene.
    shared: Shared,
    /// With occlusion: every occluding display's pyramids, built together.
    pyramids: PyramidSets,
    /// Each rig display, in the rig's order.
    displays: Vec<Display>,
    /// What `prepare` and `latch` write of the pose, as one upload.
    uploads: Coalesced,
    /// Instance slots the buffers have room for.
    slots: u32,
    /// The rig as made: the displays (and far layer sizes) a reallocation rebuilds for.
    rig: Rig,
    /// Whether each frame starts with the coarse cull ([`RendererOptions::coarse_for`]),
    /// decided once: it sizes buffers.
    coarse: bool,
    /// What the last `encode` or `encode_culls` recorded, pass by pass.
    passes: Vec<PassRecord>,
    /// The time the last `prepare` planned for: what a `latch` plans at again.
    prepared: Option<f32>,
    /// With motion vectors: the frame this one's motion is measured from, and the frame
    /// last written (prepared or latched), the next one's.
    motion_from: Option<PreviousFrame>,
    motion_last: Option<PreviousFrame>,
    /// The last written plan's vectors, which the next plan fills.
    spare: PlanStorage,
    /// What changed since the last frame, to keep the pixels nothing changed.
    keeper: Keeper,
    /// Whether the frame last prepared keeps pixels (a latch would move them all).
    keeps: bool,
}

/// What the GPU holds of a scene: the frame level's passes and edits, what the levels
/// share, the pyramids and the displays ([`Renderer::new`]; again when a sync
/// reallocates).
struct Built {
    passes: FramePasses,
    edits: Edits,
    shared: Shared,
    pyramids: PyramidSets,
    displays: Vec<Display>,
}

/// What a renderer's GPU copy of a scene is built from: the scene (with its slots'
/// records, and its instances' places of the cull order), the room, and what it binds
/// of the frame level.
#[derive(Clone, Copy)]
struct Made<'a> {
    scene: &'a Scene,
    records: &'a [crate::records::InstanceRecord],
    places: &'a Places,
    slots: u32,
    /// Whether the pose pass poses each slot.
    posed: &'a dyn Fn(u32) -> bool,
}

impl Renderer {
    /// Uploads the scene once and builds the chosen path's pipelines and displays (and
    /// nothing the other path would need).
    pub fn new(
        device: &wgpu::Device,
        scene: &Scene,
        rig: &Rig,
        options: RendererOptions,
    ) -> Result<Renderer> {
        checks::check_renderer(device, scene, rig, &options)?;
        let never = keeping::never(scene, rig.displays.iter().map(|d| d.views()), &options);
        let measures = options.cull == CullMode::Cpu;
        let keeper = Keeper::new(
            scene,
            options.keep_unchanged,
            never,
            options.shadows,
            measures,
        );
        let resolved = rig.resolve()?;
        let coarse = options.coarse_for(&resolved, Some(device));
        let base = FrameBase::new(device, scene, rig.displays.len() as u32, &options)?;
        let records = instance_records(scene);
        let made = Made {
            scene,
            records: &records,
            places: &Places::tight(scene),
            slots: scene.instances.len() as u32,
            posed: &|_| true,
        };
        let (frame, shadow) = (base.uniform(), base.shadow_group());
        let built = build(device, made, rig, coarse, &options, frame, shadow)?;
        Ok(Renderer {
            frame: FrameLevel::new(base, built.passes, built.edits),
            shared: built.shared,
            pyramids: built.pyramids,
            displays: built.displays,
            uploads: Coalesced::new(device, options.late_latch),
            slots: made.slots,
            options,
            rig: rig.clone(),
            coarse,
            passes: Vec::new(),
            prepared: None,
            motion_from: None,
            motion_last: None,
            spare: PlanStorage::default(),
            keeper,
            keeps: false,
        })
    }

    /// Builds the GPU copy of `live` again into new buffers with room for `room`
    /// slots (a sync's reallocation, when the scene outgrew its buffers or gained
    /// meshes: half as much room again): the displays and frame passes as `new` made
    /// them, over the same frame context, lights and shadow map.
    fn reallocate(
        &mut self,
        device: &wgpu::Device,
        live: &LiveScene,
        room: u32,
    ) -> Result<SyncStats> {
        let scene = live.scene();
        checks::check_device(device, scene, &self.options)?;
        // The records with their slots' generations (a reused slot's went up).
        let records = live.instance_records();
        let made = Made {
            scene,
            records: &records,
            places: live.places(),
            slots: room,
            posed: &|s| live.animates(s),
        };
        let (frame, shadow) = (self.frame.uniform(), self.frame.shadow_group());
        let built = build(
            device,
            made,
            &self.rig,
            self.coarse,
            &self.options,
            frame,
            shadow,
        )?;
        (self.frame.passes, self.frame.edits) = (built.passes, built.edits);
        (self.shared, self.pyramids, self.displays) =
            (built.shared, built.pyramids, built.displays);
        self.slots = room;
        Ok(SyncStats {
            bytes_uploaded: std::mem::size_of_val(&records[..]) as u64,
            reloaded: true,
            reallocated: true,
            ..SyncStats::default()
        })
    }

    /// The scene's punctual lights from the next frame on (each display's clusters
    /// follow): an engine moves, adds and removes lights so. More than
    /// [`crate::lights::MAX_LIGHTS`], or a light that is not valid, is an error.
    pub fn set_lights(&mut self, lights: &[crate::lights::Light]) -> Result<()> {
        self.keeper.redraw_whole();
        self.frame.lighting_mut().set(lights)
    }

    /// The camera's exposure and tone mapper from the next frame on: an engine's
    /// camera settings, which may change per frame. `auto` keeps the meter reading
    /// taken when the renderer was made. A change redraws the next frame whole (it
    /// moves every pixel).
    pub fn set_exposure(&mut self, exposure: crate::exposure::Exposure, tonemap: Tonemap) {
        if (exposure, tonemap) != (self.options.exposure, self.options.tonemap) {
            self.keeper.redraw_whole();
        }
        (self.options.exposure, self.options.tonemap) = (exposure, tonemap);
    }

    /// Morph `m`'s weights ([`crate::morph::Morphs::morphs`], in the scene the
    /// renderer was made with; `Morph::mesh` names the mesh it moves) from the next
    /// `prepare` on, its animations stopped: for an engine that plays its own blend
    /// shapes. Weights past the largest the file gives (or 1) are an error: the morphed
    /// mesh's culling sphere holds no more ([`crate::morph::Morph::weight_bound`]).
    pub fn set_morph_weights(&mut self, m: usize, weights: &[f32]) -> Result<()> {
        let morph = (self.frame.passes.morph.as_mut())
            .ok_or_else(|| Error::InvalidScene("the scene has no morph targets".into()))?;
        morph.set_weights(m, weights).map_err(Error::InvalidScene)?;
        self.keeper.redraw_whole();
        Ok(())
    }

    /// Vertices the frame's morph pass moves (0 without morph targets).
    pub fn morphed_vertices(&self) -> u32 {
        self.frame
            .passes
            .morph
            .as_ref()
            .map_or(0, MorphPass::vertices)
    }

    /// Vertices the frame's skinning pass poses (0 without skins): the same for any
    /// rig, since it runs once per frame.
    pub fn skinned_vertices(&self) -> u32 {
        self.frame
            .passes
            .skin
            .as_ref()
            .map_or(0, SkinPass::vertices)
    }

    /// GPU bytes the pose pass holds (its tables and per-node scratch); 0 without it.
    pub fn posing_bytes(&self) -> u64 {
        self.frame
            .passes
            .pose
            .as_ref()
            .map_or(0, PosePass::gpu_bytes)
    }

    /// Where display `index`'s views lie in its target: side by side at their own sizes,
    /// or in multiview one layer each (read back side by side, as
    /// [`crate::readback::read_rgba8`] places them). What a foveated display's composite
    /// takes ([`crate::foveated_composite::CompositeParams::new`]).
    pub fn layout(&self, index: usize) -> Option<crate::rig::ViewLayout> {
        self.displays.get(index).map(|d| d.shape().layout)
    }

    /// Display `index`'s depth as an XR compositor's depth layer takes it: each view's
    /// rectangle or layer of the target, its planes, and how MSAA is resolved
    /// ([`crate::compositor`]); `rig` as the frame was drawn.
    pub fn depth_layer(&self, rig: &Rig, index: usize) -> Result<crate::compositor::DepthLayer> {
        let resolved = rig.resolve()?;
        let shape = self.displays.get(index).map(Display::shape);
        let (Some(shape), Some(display)) = (shape, resolved.displays.get(index)) else {
            return Err(Error::Unsupported(format!("no display {index}")));
        };
        let samples = self.options.sample_count;
        Ok(crate::compositor::DepthLayer::new(
            display,
            &shape.layout,
            shape.layered,
            samples,
        ))
    }

    /// Pixels the displays' visibility masks keep from being shaded each frame (0 with
    /// `RendererOptions::visibility_mask` off or no masks; the classic modes mask
    /// nothing).
    pub fn masked_pixels(&self) -> u64 {
        (self.displays.iter())
            .filter_map(Display::indirect)
            .map(IndirectDisplay::masked_pixels)
            .sum()
    }

    /// The options the renderer was made with.
    pub fn options(&self) -> &RendererOptions {
        &self.options
    }

    /// The EV100 its frames are exposed at (`None`: unit exposure, a scene lit in our
    /// units) and their tone mapper: [`RendererOptions::exposure`] and `tonemap` with
    /// `auto` resolved ([`crate::exposure`]).
    pub fn exposure(&self) -> (Option<f32>, Tonemap) {
        self.frame.exposure(&self.options)
    }

    /// The stereo mode it was made for.
    pub fn mode(&self) -> StereoMode {
        self.options.mode
    }

    /// Whether frames start with the coarse cull: [`crate::renderer::CoarseMode`] as
    /// decided for the rig.
    pub fn coarse_cull(&self) -> bool {
        self.coarse
    }

    /// GPU bytes per instance: the 80-byte instance record, the GPU culler's layout and
    /// scratch (GPU culling only), and 4 bytes of visible list per display.
    pub fn gpu_bytes_per_instance(&self) -> u64 {
        let culling = culler::Culler::bytes_per_instance(self.options.cull);
        DrawScene::BYTES_PER_INSTANCE + culling + 4 * self.displays.len() as u64
    }

    /// GPU bytes occlusion culling adds, per display that runs it (its visibility bits,
    /// the late phase's visible list and draws) and once for the renderer (the depth
    /// pyramids, which the displays share); `None` without occlusion.
    pub fn occlusion_bytes(&self) -> Option<OcclusionBytes> {
        let late = self.displays.iter().filter_map(|d| d.indirect()?.late());
        display::occlusion::occlusion_bytes(late, &self.shared.culler)
    }

    /// The formats of the color and the data texture array: RGBA8, or BC7 where every
    /// texture of the encoding came as Basis Universal and the device samples BC.
    pub fn texture_formats(&self) -> [wgpu::TextureFormat; 2] {
        self.shared.draw_scene.materials.formats()
    }

    /// Color (`RENDER_ATTACHMENT | COPY_SRC`) and depth textures for every display, shaped
    /// as [`TargetViews`] describes for this renderer's mode.
    pub fn create_targets(&self, device: &wgpu::Device) -> Vec<DisplayTarget> {
        (self.displays.iter())
            .map(|d| d.shape().create(device, self.options.target_format()))
            .collect()
    }

    /// Draws display `index` into a render pass the caller began, after
    /// [`Renderer::encode_culls`] was recorded for this frame. The pass must render into
    /// that display's target shape ([`super::TargetViews`]) with the formats and sample count of
    /// [`super::RendererOptions`], and with `multiview_mask` `0b11` for a stereo display in
    /// multiview. Its load and store operations, and whatever the caller draws before and
    /// after (sky, UI, transparent geometry), are the caller's. Returns the draw calls.
    pub fn draw_display(&self, pass: &mut wgpu::RenderPass, index: usize) -> Result<u32> {
        self.display(index)?.draw(pass, &self.shared)
    }

    /// Display `index`, or [`Error::NoSuchDisplay`].
    fn display(&self, index: usize) -> Result<&Display> {
        let displays = self.displays.len();
        self.displays
            .get(index)
            .ok_or(Error::NoSuchDisplay { index, displays })
    }

    /// Sets display `index`'s pipeline of the caller's own for the material bins of
    /// [`crate::scene::Shading::Own`]`(shading)` (the GPU-driven modes): from now on
    /// every draw of the display, in the renderer's passes and in
    /// [`Renderer::draw_display`], issues those bins' multi-draw with it. One pipeline
    /// may serve several displays of one target shape. A frame whose display draws an
    /// own bin without its pipeline is [`Error::MissingOwnPipeline`].
    pub fn set_own_pipeline(&mut self, index: usize, shading: u32, own: OwnPipeline) -> Result<()> {
        if self.options.mode.per_instance() {
            return Err(self.per_instance());
        }
        self.display(index)?;
        if let Some(d) = self.displays[index].indirect_mut() {
            d.set_own_pipeline(shading, own);
        }
        Ok(())
    }

    /// What the classic modes answer a call for the indirect modes' own pipelines.
    fn per_instance(&self) -> Error {
        Error::Unsupported(format!(
            "{} draws per instance; pipelines of the caller's own draw the indirect modes",
            self.options.mode.name()
        ))
    }

    /// For an engine's own draw pipeline (the indirect modes): group 0's layout, to
    /// build its pipeline layout on (its own bind groups from group 1), with
    /// [`Renderer::decode_source`] as the shader's start. `None` in the classic modes.
    pub fn bind_group_layout(&self) -> Option<&wgpu::BindGroupLayout> {
        (!self.options.mode.per_instance()).then(|| self.shared.drawer.layout())
    }

    /// Display `index`'s cull outputs on the GPU (the indirect modes): the visible list,
    /// the draws and the counts, per the README's cull contract.
    pub fn cull_buffers(&self, index: usize) -> Option<&CullTargets> {
        Some(self.displays.get(index)?.indirect()?.cull_targets())
    }

    /// Display `index`'s one multi-draw-indirect call, in a pass the caller began with a
    /// pipeline of its own already set (layout from [`Renderer::bind_group_layout`]):
    /// binds group 0, the vertex and index buffers, and draws. The indirect modes only.
    pub fn draw_display_with_own_pipeline(
        &self,
        pass: &mut wgpu::RenderPass,
        index: usize,
    ) -> Result<()> {
        if self.options.mode.per_instance() {
            return Err(self.per_instance());
        }
        if self.options.far_layer {
            return Err(Error::Unsupported(
                "with the far layer the renderer composites before its draws; draw_display draws both".into(),
            ));
        }
        if let Some(d) = self.display(index)?.indirect() {
            d.draw_with_own_pipeline(pass, &self.shared);
        }
        Ok(())
    }

    /// The stereo decode for an engine's own pipeline on this renderer's group 0
    /// ([`crate::shaders::decode_source_with`] with this renderer's binding windows):
    /// `None` in the classic modes.
    pub fn decode_source(&self, views: u32) -> Option<String> {
        (!self.options.mode.per_instance())
            .then(|| crate::shaders::decode_source_with(views, &self.shared.drawer.windows))
    }

    /// The last submitted frame's diagnostics, read back through `device` and `queue`
    /// (the renderer's own).
    pub fn diagnostics<'a>(
        &'a self,
        device: &'a wgpu::Device,
        queue: &'a wgpu::Queue,
    ) -> Diagnostics<'a> {
        Diagnostics::new(self, device, queue)
    }
}

/// The GPU copy of `made` for `rig` (planned at time 0: its displays and far layer
/// sizes; `coarse`, whether frames start with the coarse cull) under `options`, bound
/// to `frame`, the frame context, and `shadow_group`, the shadow map.
fn build(
    device: &wgpu::Device,
    made: Made,
    rig: &Rig,
    coarse: bool,
    options: &RendererOptions,
    frame: &wgpu::Buffer,
    shadow_group: &wgpu::BindGroup,
) -> Result<Built> {
    let plan = FramePlan::new(rig, options, coarse, 0.0)?;
    let inputs = PathInputs {
        scene: made.scene,
        records: made.records,
        rig,
        plan: &plan,
        frame,
        options,
        slots: made.slots,
        shadow_group,
    };
    let layout = CullLayout::with_places(made.scene, made.places);
    let built = display::build(device, layout, &inputs)?;
    let windows = options.windows(device, made.slots);
    let (culler, draw_scene) = (&built.shared.culler, &built.shared.draw_scene);
    let bindings = FrameBindings {
        frame,
        windows,
        drawing: built.shared.drawing(),
        culler,
        scatter: edits::scatter_targets(culler, draw_scene),
    };
    let passes = FramePasses::new(device, made.scene, options, bindings, made.posed)?;
    let pairs = options.frames_per_submit == 2;
    Ok(Built {
        passes,
        edits: Edits::new(device, windows, made.scene, pairs),
        shared: built.shared,
        pyramids: built.pyramids,
        displays: built.displays,
    })
}
