//! The frame level: passes recorded once per frame, whatever the displays and eyes,
//! before any display's cull: posing animations on the GPU (`pose.rs`), morph targets
//! (`morph.rs`), skinning (`skin.rs`) and the light's shadow map (`shadow.rs`, culled
//! like one more view).

use crate::draw::Drawing;
use crate::error::Result;
use crate::renderer::culler::Culler;
use crate::renderer::options::RendererOptions;
use crate::renderer::recorder::Recorder;
use crate::scatter::ScatterTargets;
use crate::scene::Scene;
use crate::shaders::Windows;
use morph::MorphPass;
use pose::PosePass;
use shadow::ShadowPass;
use skin::SkinPass;

pub(super) mod lights;
pub(super) mod morph;
pub(super) mod pose;
pub(super) mod shadow;
pub(super) mod skin;

/// The frame level's passes a renderer records (each where its scene needs it).
pub(super) struct FramePasses {
    pub(super) skin: Option<SkinPass>,
    pub(super) morph: Option<MorphPass>,
    pub(super) pose: Option<PosePass>,
    pub(super) shadow: Option<ShadowPass>,
}

/// What the frame level's passes are built over: the frame context, the binding
/// windows, and what the displays' passes share (the scene as drawn, the culler, where
/// edits go).
pub(super) struct FrameBindings<'a> {
    pub(super) frame: &'a wgpu::Buffer,
    pub(super) windows: Windows,
    pub(super) drawing: Drawing<'a>,
    pub(super) culler: &'a Culler,
    pub(super) scatter: ScatterTargets<'a>,
}

impl FramePasses {
    /// The frame level's passes of `scene` under `options`, over `bound`: skinning
    /// (with skins), morph targets, posing on the GPU (with animations; `posed(slot)`:
    /// whether it poses the instance in `slot`) and the shadow pass (with shadows).
    pub(super) fn new(
        device: &wgpu::Device,
        (scene, options): (&Scene, &RendererOptions),
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
        let morph = MorphPass::new(device, &scene.morphs, (vertices, rest));
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
pub(super) fn one_dispatch(
    encoder: &mut wgpu::CommandEncoder,
    rec: &mut Recorder,
    name: &'static str,
    (pipeline, group, size): (&wgpu::ComputePipeline, &wgpu::BindGroup, (u32, u32)),
) -> u32 {
    let (mut pass, open) = rec.frame_pass(encoder, name);
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, group, &[]);
    pass.dispatch_workgroups(size.0, size.1, 1);
    rec.close_frame_pass(encoder, pass, open);
    1
}
