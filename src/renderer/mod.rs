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
//! One frame, in the order it runs, by the chapter's levels (the directories below):
//! [`Renderer::prepare`] makes the frame's plan (`plan.rs`: the rig resolved once,
//! every context, every cull, the levels of detail, the coarse cull, the far/near split,
//! the light) and hands it to the path chosen once in [`Renderer::new`]
//! (`display/indirect.rs`: `instanced`, `multiview`; `display/classic.rs`: the
//! per-instance modes). [`Renderer::encode`] (`encode.rs`) records the frame level's
//! passes (the scatter of edits, `frame/`: posing, skinning, the shadow map; the coarse
//! cull), then each display's cull and passes (`display/`, with the far layer and
//! occlusion). Every view (display, eye, far layer, light) is a `view.rs` culled through
//! the one culler (`culler/`: GPU passes or the CPU culler); `recorder.rs` times and
//! logs the passes. The eye level lives in the contexts (`eye[e]`) and the shaders, and
//! in the classic modes' per-eye passes.

use crate::buffers::uniform_buffer;
use crate::contexts::FrameContext;
use crate::draw::DrawScene;
use crate::error::{Error, Result};
use crate::keep::Keeper;
pub use crate::keep::{KeepUnchanged, WholeRedraw};
use crate::motion::PreviousFrame;

use crate::places::Places;
use crate::records::{CullLayout, instance_records};
use crate::rig::Rig;
use crate::scatter::Scatters;
use crate::scene::Scene;

mod checks;
mod culler;
mod diagnostics;
mod display;
mod encode;
mod frame;
mod frame_stats;
pub mod frames;
mod keeping;
mod options;
mod own_passes;
mod plan;
mod prepare;
mod recorder;
mod second_frame;
mod sync;
mod targets;
mod uploads;
mod view;

pub use checks::check_rig;
pub use culler::WallCulls;
pub use diagnostics::{Diagnostics, FarSplit, OcclusionCounts};
use display::indirect::IndirectDisplay;
pub use display::occlusion::OcclusionBytes;
use display::occlusion::PyramidSets;
use display::{Display, PathInputs, Shared};
use frame::lights::Lighting;
use frame::morph::MorphPass;
use frame::pose::PosePass;
use frame::shadow::ShadowMap;
use frame::skin::SkinPass;
use frame::{FrameBindings, FramePasses};
pub use frame_stats::{DispatchLevels, FrameStats};
pub use options::{
    CoarseMode, CullMode, DEFAULT_DT, LOD_PIXELS, OcclusionMode, PosingMode, RendererOptions,
    StereoMode, frame_lod,
};
use plan::PlanStorage;
pub use plan::{CullView, DisplayPlan, FramePlan, KeptTiles, PlannedCull, instances_per_object};
pub use recorder::{Level, PassRecord};
use second_frame::SecondFrame;
pub use second_frame::grown;
pub use sync::SyncStats;
pub use targets::{DisplayTarget, TargetShape, TargetViews};
use uploads::Coalesced;

/// What the frame level's passes are built over: `frame`, the frame context, in
/// `windows`, and what the displays' passes share.
fn frame_bindings<'a>(
    shared: &'a Shared,
    frame: &'a wgpu::Buffer,
    windows: crate::shaders::Windows,
) -> FrameBindings<'a> {
    FrameBindings {
        frame,
        windows,
        drawing: shared.drawing(),
        culler: &shared.culler,
        scatter: shared.scatter_targets(),
    }
}

/// The scene submission backend: one per scene and rig shape, see the module docs for the
/// calls in order.
pub struct Renderer {
    options: RendererOptions,
    /// The frame context's uniform, written once per frame, bound by every pass.
    frame: wgpu::Buffer,
    /// The frame level's passes: posing, morph targets, skinning, the shadow pass (the
    /// light culled as one more view of the displays' culler).
    frame_passes: FramePasses,
    /// Moved instances, staged by `sync`, dispatched by the next `encode`.
    scatter: Scatters,
    /// Two frames per submission: the second frame's own edits (`sync_next`).
    second: Option<SecondFrame>,
    /// The punctual lights and their clusters.
    lighting: Lighting,
    /// The map the shadow pass draws (1 x 1 without shadows: the draw pipelines bind it
    /// either way).
    shadow_map: ShadowMap,
    /// What every display's passes share: the culler, the draw pipelines, the scene.
    shared: Shared,
    /// With occlusion: every occluding display's pyramids, built together.
    pyramids: PyramidSets,
    /// Each rig display, in the rig's order.
    displays: Vec<Display>,
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
    /// What `prepare` and `latch` write of the pose, as one upload.
    uploads: Coalesced,
    /// The last written plan's vectors, which the next plan fills.
    spare: PlanStorage,
    /// What changed since the last frame, to keep the pixels nothing changed.
    keeper: Keeper,
    /// Whether the frame last prepared keeps pixels (a latch would move them all).
    keeps: bool,
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
        let uploads = Coalesced::new(device, options.late_latch);
        let keeper = Keeper::new(
            scene,
            options.keep_unchanged,
            never,
            options.shadows,
            measures,
        );
        let resolved = rig.resolve()?;
        let coarse = options.coarse_for(&resolved, Some(device));
        let plan = FramePlan::of(rig, resolved, &options, coarse, 0.0)?;
        let slots = scene.instances.len() as u32;
        let windows = options.windows(device, slots);
        let scatter = Scatters::new(device, windows);
        let frame = uniform_buffer::<FrameContext>(device, "stereocull.frame_context");
        let mut lighting = Lighting::new(device, &scene.lights, rig.displays.len() as u32)?;
        if options.posing == PosingMode::Gpu {
            lighting.pose_with(&scene.posing, &scene.lights);
        }
        let lit = (&lighting.lights, &lighting.views, &lighting.clusters);
        let shadow_map = ShadowMap::new(device, options.shadow_size().unwrap_or(1), lit);
        let records = instance_records(scene);
        let inputs = PathInputs {
            scene,
            records: &records,
            rig,
            plan: &plan,
            frame: &frame,
            options: &options,
            slots,
            shadow_group: &shadow_map.bind_group,
        };
        let layout = CullLayout::with_places(scene, &Places::tight(scene));
        let built = display::build(device, layout, &inputs)?;
        let made = (scene, &options);
        let bound = frame_bindings(&built.shared, &frame, windows);
        let frame_passes = FramePasses::new(device, made, bound, |_| true)?;
        let second =
            (options.frames_per_submit == 2).then(|| SecondFrame::new(device, windows, scene));
        Ok(Renderer {
            options,
            frame,
            frame_passes,
            scatter,
            second,
            lighting,
            shadow_map,
            shared: built.shared,
            pyramids: built.pyramids,
            displays: built.displays,
            slots,
            rig: rig.clone(),
            coarse,
            passes: Vec::new(),
            prepared: None,
            motion_from: None,
            motion_last: None,
            uploads,
            spare: PlanStorage::default(),
            keeper,
            keeps: false,
        })
    }

    /// The scene's punctual lights from the next frame on (each display's clusters
    /// follow): an engine moves, adds and removes lights so. More than
    /// [`crate::lights::MAX_LIGHTS`], or a light that is not valid, is an error.
    pub fn set_lights(&mut self, lights: &[crate::lights::Light]) -> Result<()> {
        self.keeper.redraw_whole();
        self.lighting.set(lights)
    }

    /// Morph `m`'s weights ([`crate::morphing::Morphs::morphs`], in the scene the
    /// renderer was made with; `Morph::mesh` names the mesh it moves) from the next
    /// `prepare` on, its animations stopped: for an engine that plays its own blend
    /// shapes. Weights past the largest the file gives (or 1) are an error: the morphed
    /// mesh's culling sphere holds no more ([`crate::morphing::Morph::weight_bound`]).
    pub fn set_morph_weights(&mut self, m: usize, weights: &[f32]) -> Result<()> {
        let morph = (self.frame_passes.morph.as_mut())
            .ok_or_else(|| Error::InvalidScene("the scene has no morph targets".into()))?;
        morph.set_weights(m, weights).map_err(Error::InvalidScene)?;
        self.keeper.redraw_whole();
        Ok(())
    }

    /// Vertices the frame's morph pass moves (0 without morph targets).
    pub fn morphed_vertices(&self) -> u32 {
        self.frame_passes
            .morph
            .as_ref()
            .map_or(0, MorphPass::vertices)
    }

    /// Vertices the frame's skinning pass poses (0 without skins): the same for any
    /// rig, since it runs once per frame.
    pub fn skinned_vertices(&self) -> u32 {
        self.frame_passes
            .skin
            .as_ref()
            .map_or(0, SkinPass::vertices)
    }

    /// GPU bytes the pose pass holds (its tables and per-node scratch); 0 without it.
    pub fn posing_bytes(&self) -> u64 {
        self.frame_passes
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
}
