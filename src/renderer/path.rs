//! The two paths a renderer takes ([`Path`]): the GPU-driven indirect path, or the
//! classic modes' per-instance passes, and what both give the frame level's passes.

use super::display::classic::ClassicPath;
use super::display::indirect::IndirectPath;
use super::display::{PathCore, PathInputs};
use super::frame::morph::MorphPass;
use super::frame::pose::{self, PosePass};
use super::frame::shadow::ShadowPass;
use super::frame::skin::SkinPass;
use super::options::RendererOptions;
use crate::error::{Error, Result};
use crate::scatter::ScatterTargets;
use crate::scene::Scene;
use crate::shaders::Windows;

/// The path chosen in [`Renderer::new`] (boxed: each holds its pipelines, and they
/// differ in size by what the indirect path adds).
pub(super) enum Path {
    Indirect(Box<IndirectPath>),
    Classic(Box<ClassicPath>),
}

impl Path {
    /// The path `inputs.options` choose, for the displays (and coarse cull) of
    /// `inputs.plan`.
    pub(super) fn new(device: &wgpu::Device, inputs: PathInputs) -> Result<Path> {
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let path = match inputs.options.mode.per_instance() {
            false => IndirectPath::new(device, inputs).map(|p| Path::Indirect(Box::new(p))),
            true => ClassicPath::new(device, inputs).map(|p| Path::Classic(Box::new(p))),
        };
        // Popped before returning any error, so the caller's device keeps its scopes.
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(Error::Wgpu(e));
        }
        path
    }

    /// The GPU-driven path, if it is the one.
    pub(super) fn indirect(&self) -> Option<&IndirectPath> {
        match self {
            Path::Indirect(p) => Some(p),
            Path::Classic(_) => None,
        }
    }

    /// The path's culler, pipelines and scene.
    pub(super) fn core(&self) -> &PathCore {
        match self {
            Path::Indirect(p) => &p.core,
            Path::Classic(p) => &p.core,
        }
    }

    pub(super) fn core_mut(&mut self) -> &mut PathCore {
        match self {
            Path::Indirect(p) => &mut p.core,
            Path::Classic(p) => &mut p.core,
        }
    }

    /// Where the scatter passes (and the pose pass) write edits.
    pub(super) fn scatter_targets(&self) -> ScatterTargets<'_> {
        let core = self.core();
        let (spheres, visibility) = core.culler.scatter_targets();
        ScatterTargets {
            instances: &core.draw_scene.instances,
            spheres,
            visibility,
        }
    }

    /// The frame level's passes over this path's scene and culler, bound to `frame` and
    /// in `windows`: skinning (with skins), posing on the GPU (with animations;
    /// `posed(slot)`: whether it poses the instance in `slot`) and the shadow pass (with
    /// shadows).
    pub(super) fn frame_passes(
        &self,
        device: &wgpu::Device,
        (scene, options): (&Scene, &RendererOptions),
        (frame, windows): (&wgpu::Buffer, Windows),
        posed: impl Fn(u32) -> bool,
    ) -> Result<FramePasses> {
        let core = self.core();
        let skin = SkinPass::new(device, &scene.skins, &core.draw_scene.vertices);
        let targets = (&core.draw_scene.vertices, skin.as_ref().map(SkinPass::rest));
        let morph = MorphPass::new(device, &scene.morphs, targets);
        let gpu = pose::GpuParts {
            frame,
            skin: skin.as_ref(),
            windows,
            scatter: self.scatter_targets(),
        };
        let pose = pose::build(device, scene, options, gpu, posed)?;
        let shadow =
            (options.shadows).then(|| ShadowPass::new(device, core.drawing(), frame, &core.culler));
        Ok(FramePasses {
            skin,
            morph,
            pose,
            shadow,
        })
    }
}

/// The frame level's passes a renderer records (each where its scene needs it).
pub(super) struct FramePasses {
    pub(super) skin: Option<SkinPass>,
    pub(super) morph: Option<MorphPass>,
    pub(super) pose: Option<PosePass>,
    pub(super) shadow: Option<ShadowPass>,
}
