//! The frame level ([`FrameLevel`]): what exists and is recorded once per frame,
//! whatever the displays and eyes, before any display's cull: the frame context, the
//! live scene's edits scattered into place (`edits.rs`), posing animations on the GPU
//! (`pose.rs`), morph targets (`morph.rs`), skinning (`skin.rs`), the lights' clusters
//! (`lights.rs`) and the light's shadow map (`shadow.rs`, culled like one more view).

use crate::buffers::{Upload, uniform_buffer};
use crate::contexts::FrameContext;
use crate::draw::{DrawScene, Drawer, Drawing};
use crate::error::Result;
use crate::exposure;
use crate::renderer::culler::{CullPass, Culler};
use crate::renderer::frame_stats::FrameStats;
use crate::renderer::options::{PosingMode, RendererOptions};
use crate::renderer::plan::FramePlan;
use crate::renderer::recorder::{PassRecord, Recorder};
use crate::renderer::uploads::Writes;
use crate::scatter::ScatterTargets;
use crate::scene::Scene;
use crate::shaders::Windows;
use edits::Edits;
use lights::Lighting;
use morph::MorphPass;
use pose::PosePass;
use shadow::{ShadowMap, ShadowPass};
use skin::SkinPass;

/// What exists once per frame: the frame context's uniform (bound by every pass), the
/// lights and their clusters, the shadow map, the frame level's passes and the edits
/// staged for them.
pub struct FrameLevel {
    uniform: wgpu::Buffer,
    lighting: Lighting,
    /// The map the shadow pass draws (1 x 1 without shadows: the draw pipelines bind it
    /// either way).
    shadow_map: ShadowMap,
    /// Built over the scene's buffers (again when a sync reallocates them).
    pub passes: FramePasses,
    pub edits: Edits,
    /// `--exposure auto`'s reading of the scene as made ([`exposure::metered_ev100`]).
    metered: Option<f32>,
}

/// What the displays' passes bind of the frame level, made before them: the frame
/// context's uniform, the lights and the shadow map.
pub struct FrameBase {
    uniform: wgpu::Buffer,
    lighting: Lighting,
    shadow_map: ShadowMap,
    metered: Option<f32>,
}

impl FrameBase {
    /// The frame context, `scene`'s lights for `displays` displays and a shadow map as
    /// `options` ask.
    pub fn new(
        device: &wgpu::Device,
        scene: &Scene,
        displays: u32,
        options: &RendererOptions,
    ) -> Result<FrameBase> {
        let uniform = uniform_buffer::<FrameContext>(device, "stereocull.frame_context");
        let mut lighting = Lighting::new(device, &scene.lights, displays)?;
        if options.posing == PosingMode::Gpu {
            lighting.pose_with(&scene.posing, &scene.lights);
        }
        let size = options.shadow_size().unwrap_or(1);
        let (lights, views, clusters) = (&lighting.lights, &lighting.views, &lighting.clusters);
        let shadow_map = ShadowMap::new(device, size, lights, views, clusters);
        Ok(FrameBase {
            uniform,
            lighting,
            shadow_map,
            metered: exposure::metered_ev100(scene),
        })
    }

    /// The frame context's uniform.
    pub fn uniform(&self) -> &wgpu::Buffer {
        &self.uniform
    }

    /// Group 2 of the draw pipelines: the shadow map.
    pub fn shadow_group(&self) -> &wgpu::BindGroup {
        &self.shadow_map.bind_group
    }
}

/// What the frame level's passes record over: the scene as drawn (its records and
/// vertices, copied for motion or a second frame), the culler (its coarse cull, marks
/// and the light's cull), the draw pipelines, and the view the coarse cull binds (any
/// display's, on the GPU-driven path).
pub struct FrameScene<'a> {
    pub draw_scene: &'a mut DrawScene,
    pub culler: &'a mut Culler,
    pub drawer: &'a Drawer,
    pub any_view: Option<&'a CullPass>,
}

impl FrameLevel {
    /// The frame level over `base`, with its passes and edits.
    pub fn new(base: FrameBase, passes: FramePasses, edits: Edits) -> FrameLevel {
        let FrameBase {
            uniform,
            lighting,
            shadow_map,
            metered,
        } = base;
        FrameLevel {
            uniform,
            lighting,
            shadow_map,
            passes,
            edits,
            metered,
        }
    }

    /// The EV100 frames are exposed at (`None`: unit exposure) and the tone mapper,
    /// as `options` ask, `auto` from the scene's meter reading as the renderer was made.
    pub fn exposure(&self, options: &RendererOptions) -> (Option<f32>, exposure::Tonemap) {
        exposure::resolve(options.exposure, options.tonemap, self.metered)
    }

    /// Sets the frame context's exposure and tone mapper as `options` ask.
    pub fn expose(&self, frame: &mut FrameContext, options: &RendererOptions) {
        let (ev100, curve) = self.exposure(options);
        frame.exposure = ev100.map_or(1.0, exposure::scale_of_ev100);
        frame.tonemap = curve.wgsl();
    }

    /// The frame context's uniform, as a reallocation binds it again.
    pub fn uniform(&self) -> &wgpu::Buffer {
        &self.uniform
    }

    /// Group 2 of the draw pipelines: the shadow map.
    pub fn shadow_group(&self) -> &wgpu::BindGroup {
        &self.shadow_map.bind_group
    }

    /// The lights and their clusters.
    pub fn lighting(&self) -> &Lighting {
        &self.lighting
    }

    pub fn lighting_mut(&mut self) -> &mut Lighting {
        &mut self.lighting
    }

    /// Writes `plan`'s frame context and the lights' views. Returns the bytes.
    pub fn write(&mut self, to: Writes, plan: &FramePlan) -> u64 {
        to.pose.write_uniform(&self.uniform, 0, &plan.frame) + self.lighting.prepare(to.pose, plan)
    }

    /// With shadows, writes `plan`'s light and the culler's result for it. Returns the
    /// bytes.
    pub fn write_shadow(&self, to: Writes, plan: &FramePlan, culler: &Culler) -> u64 {
        let light = plan.light_cull.as_ref().map(|_| plan.light);
        match (&self.passes.shadow, light) {
            (Some(shadow), Some(light)) => shadow.prepare(to, &light, self.shadow_map.size, culler),
            _ => 0,
        }
    }

    /// The frame level's passes, before any display's: with motion vectors the copy of
    /// the previous frame's records and vertices, the frame's pose (the scatter of
    /// moved instances, posing, morph targets, skinning), with two frames per
    /// submission the second frame's pose after a copy of the first's
    /// ([`crate::renderer::frames`]), then the coarse cull and the shadow pass.
    pub fn encode(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        scene: FrameScene,
        rec: &mut Recorder,
    ) -> FrameStats {
        let FrameScene {
            draw_scene,
            culler,
            drawer,
            any_view,
        } = scene;
        let pairs = self.edits.pairs();
        if !pairs {
            draw_scene.keep_previous(encoder);
        }
        // A kept frame's changed tiles: the spheres as last drawn, then as posed now.
        let marked = culler.encode_marks(encoder, false);
        let (mut posing, mut cpu_staging) = self.encode_pose(encoder, rec, draw_scene, false);
        if pairs {
            draw_scene.keep_previous(encoder);
            let (second, staging) = self.encode_pose(encoder, rec, draw_scene, true);
            (posing, cpu_staging) = (posing + second, cpu_staging + staging);
        }
        let marked = marked + culler.encode_marks(encoder, true);
        if marked > 0 {
            rec.log(PassRecord::frame("keep_mark"));
        }
        let coarse = match any_view {
            Some(view) => culler.encode_frame(encoder, Some(view), rec),
            None => 0,
        };
        let drawing = Drawing {
            drawer,
            scene: draw_scene,
        };
        let (shadowed, draw_calls) = match &self.passes.shadow {
            Some(shadow) => shadow.encode(encoder, drawing, culler, &self.shadow_map, rec),
            None => (0, 0),
        };
        FrameStats {
            dispatches: posing + marked + coarse + shadowed,
            draw_calls,
            cpu_staging,
            ..Default::default()
        }
    }

    /// A frame's pose: its edits scattered, its animations posed on the GPU, its morph
    /// targets and skins, the lights' clusters; for the `second` frame of a submission,
    /// its own edits, morph weights and joint matrices (the rest serves both frames).
    /// Returns the dispatches and the CPU time of staging the edits.
    fn encode_pose(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        rec: &mut Recorder,
        draw_scene: &mut DrawScene,
        second: bool,
    ) -> (u32, std::time::Duration) {
        let (scattered, cpu_staging) = self.edits.encode(encoder, rec, second);
        let FramePasses {
            skin, morph, pose, ..
        } = &mut self.passes;
        let posed = match (pose, second) {
            (Some(pose), false) => pose.encode(encoder, rec),
            (Some(pose), true) => pose.encode_next(encoder, rec),
            (None, _) => 0,
        };
        let morphed = match (morph, second) {
            (Some(morph), false) => morph.encode(encoder, rec),
            (Some(morph), true) => morph.encode_next(encoder, rec),
            (None, _) => 0,
        };
        let clustered = match second {
            false => self.lighting.encode(encoder, rec),
            true => 0,
        };
        let skinned = match (skin, second) {
            (Some(skin), false) => skin.encode(encoder, rec),
            (Some(skin), true) => skin.encode_next(encoder, rec),
            (None, _) => 0,
        };
        draw_scene.rewritten(scattered + posed > 0, skinned + morphed > 0);
        let dispatches = scattered + posed + morphed + clustered + skinned;
        (dispatches, cpu_staging)
    }
}

pub mod edits;
pub mod lights;
pub mod morph;
pub mod pose;
pub mod shadow;
pub mod skin;

/// The frame level's passes a renderer records (each where its scene needs it).
pub struct FramePasses {
    pub skin: Option<SkinPass>,
    pub morph: Option<MorphPass>,
    pub pose: Option<PosePass>,
    pub shadow: Option<ShadowPass>,
}

/// What the frame level's passes are built over: the frame context, the binding
/// windows, and what the displays' passes share (the scene as drawn, the culler, where
/// edits go).
pub struct FrameBindings<'a> {
    pub frame: &'a wgpu::Buffer,
    pub windows: Windows,
    pub drawing: Drawing<'a>,
    pub culler: &'a Culler,
    pub scatter: ScatterTargets<'a>,
}

impl FramePasses {
    /// The frame level's passes of `scene` under `options`, over `bound`: skinning
    /// (with skins), morph targets, posing on the GPU (with animations; `posed(slot)`:
    /// whether it poses the instance in `slot`) and the shadow pass (with shadows).
    pub fn new(
        device: &wgpu::Device,
        scene: &Scene,
        options: &RendererOptions,
        bound: FrameBindings,
        posed: impl Fn(u32) -> bool,
    ) -> Result<FramePasses> {
        let FrameBindings {
            frame,
            windows,
            drawing,
            culler,
            scatter,
        } = bound;
        let vertices = &drawing.scene.vertices;
        let skin = SkinPass::new(device, &scene.skins, vertices);
        let rest = skin.as_ref().map(SkinPass::rest);
        let morph = MorphPass::new(device, &scene.morphs, vertices, rest);
        let gpu = pose::GpuParts {
            frame,
            skin: skin.as_ref(),
            windows,
            scatter,
        };
        let pose = pose::build(device, scene, options, gpu, posed)?;
        let shadow = (options.shadows).then(|| ShadowPass::new(device, drawing, frame, culler));
        Ok(FramePasses {
            skin,
            morph,
            pose,
            shadow,
        })
    }
}

/// A frame pass of one dispatch, `size` workgroups of `pipeline` over `group`, logged as
/// the frame pass `name`; returns the dispatches.
pub fn one_dispatch(
    encoder: &mut wgpu::CommandEncoder,
    rec: &mut Recorder,
    name: &'static str,
    pipeline: &wgpu::ComputePipeline,
    group: &wgpu::BindGroup,
    size: (u32, u32),
) -> u32 {
    let (mut pass, open) = rec.frame_pass(encoder, name);
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, group, &[]);
    pass.dispatch_workgroups(size.0, size.1, 1);
    rec.close_frame_pass(encoder, pass, open);
    1
}
