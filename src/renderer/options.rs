//! What a renderer is made with ([`RendererOptions`]: the stereo mode, where culling
//! runs, ...), and the level-of-detail choice those options and a rig make for each
//! frame.

use crate::exposure::{Exposure, Tonemap};
use crate::keep::KeepUnchanged;
use std::sync::Arc;

use crate::cull::FrameLod;
use crate::draw::{DEPTH_FORMAT, TargetFormat};
use crate::far_layer::FAR_THRESHOLD_PX;
use crate::rig::{ResolvedRig, Rig};
use crate::scene::MAX_LODS;
use crate::shaders::{Shaders, Windows};
use crate::shadow::Light;

/// A stereo technique: how much of the work is done per eye. All draw the same scene into
/// the same images, so that each can be profiled against the others (the modes Unity
/// names multi-camera, multi-pass, single-pass, single-pass instanced and multiview).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum StereoMode {
    /// A full cull and render per eye: each eye culls against its own frustum and draws
    /// every visible instance with its own draw call, in its own pass.
    MultiCamera,
    /// One shared cull against the display frustum, then one pass per eye with a draw
    /// call per visible instance.
    MultiPass,
    /// One shared cull and one pass into the double-wide target; per visible instance one
    /// draw per eye, switching eye (viewport and eye binding) in the left, right, right,
    /// left cadence to halve the switches.
    SinglePass,
    /// The GPU-driven path: per display one multi-draw-indirect call with doubled
    /// instance counts (`instance >> 1` the object, `instance & 1` the eye).
    #[default]
    Instanced,
    /// `MULTIVIEW` into a two-layer target: the same culling with one view per instance
    /// (counts not doubled), the hardware repeating each draw per layer.
    Multiview,
}

impl StereoMode {
    /// Every mode, classic first.
    pub const ALL: [StereoMode; 5] = [
        StereoMode::MultiCamera,
        StereoMode::MultiPass,
        StereoMode::SinglePass,
        StereoMode::Instanced,
        StereoMode::Multiview,
    ];

    /// Draws recorded one per instance from a CPU cull (so culling is on the CPU).
    pub fn per_instance(self) -> bool {
        matches!(
            self,
            StereoMode::MultiCamera | StereoMode::MultiPass | StereoMode::SinglePass
        )
    }

    /// Culls each eye of a stereo display against its own frustum (not the display's).
    pub fn culls_per_eye(self) -> bool {
        self == StereoMode::MultiCamera
    }

    /// The mode as the CLI spells it.
    pub fn name(self) -> &'static str {
        match self {
            StereoMode::MultiCamera => "multi-camera",
            StereoMode::MultiPass => "multi-pass",
            StereoMode::SinglePass => "single-pass",
            StereoMode::Instanced => "instanced",
            StereoMode::Multiview => "multiview",
        }
    }
}

/// Where the per-display cull runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum CullMode {
    /// Compute passes on the GPU; nothing per instance crosses the bus each frame.
    #[default]
    Gpu,
    /// The rayon culler, then an upload of its results.
    Cpu,
}

/// Whether each frame starts with the coarse cull ([`crate::cull::coarse`]): blocks of
/// the cull order tested once against the frame frustum and each display's, then each
/// display's cull over its own blocks only. The draws are the same either way; only the
/// work differs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum CoarseMode {
    /// On where it is expected to save sphere tests by a fifth or more
    /// ([`crate::rig::ResolvedRig::expected_coarse_tests`]): rigs of several displays
    /// (`hmd-peripheral`, `cave`), not one display. Off for GPU culling with the rig
    /// cull ([`RendererOptions::rig_cull`]: each sphere is read once for the rig
    /// already) and on software adapters (lavapipe), where wgpu's validation of
    /// indirect calls (on by default) costs milliseconds per indirect dispatch, more
    /// than the cull saves.
    #[default]
    Auto,
    /// Always.
    On,
    /// Never.
    Off,
}

/// Whether displays cull what nearer geometry hides ([`crate::occlusion`]): two phases
/// per display (what it drew last frame, then the rest against the early depth's
/// pyramids, one per eye). The image is the same either way.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum OcclusionMode {
    /// On where it applies ([`OcclusionMode::On`]), culling on the GPU, for a display
    /// when the scene, at its finest levels, has at least as many triangles as the
    /// display has pixels (both eyes): decided when the renderer is made. Culling on the
    /// CPU it stays off: each frame would wait for its pyramids halfway. Below that a frame draws so little that
    /// the pyramids cost more than they save (on lavapipe, `hmd` at 1440 x 1600:
    /// `procedural:1000`, 0.15 triangles a pixel, GPU frame 1.22 with occlusion; 10,000,
    /// 1.5 a pixel, 0.82; `rooms:20000`, 0.23; docs/performance.md).
    #[default]
    Auto,
    /// On wherever it applies: `instanced` mode (or `multiview` without MSAA), displays
    /// of one or two views (with the far layer, its far instances are tested against the
    /// pyramids too); culling on the CPU too, each frame then reading the pyramids back
    /// halfway ([`super::Renderer::encode_late`]).
    On,
    /// Never.
    Off,
}

/// Where a scene's animations ([`crate::pose`], [`crate::skin`]) are posed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum PosingMode {
    /// By the caller on the CPU ([`crate::live::LiveScene::pose`], or
    /// [`crate::scene::Scene::pose`] before the renderer is made); each frame's poses go
    /// up with `sync` (an instance move per posed instance, 48 bytes per joint). The
    /// default: the engine owns its animation clock, and nothing moves unless it poses.
    #[default]
    Cpu,
    /// By the renderer on the GPU, every clip at the frame context's time, once per
    /// frame before the skinning pass ([`crate::pose_tables`]): nothing of a pose
    /// crosses the bus. Needs GPU culling (the culling spheres are written on the GPU).
    /// A skin the engine poses itself ([`crate::live::LiveScene::set_joints`]) is no
    /// longer posed by its clips.
    Gpu,
}

/// What a [`super::Renderer`] is made with; `Default` is the GPU-driven `instanced` mode
/// with GPU culling.
#[derive(Clone, Debug)]
pub struct RendererOptions {
    /// The color attachment's format (the caller's, when drawing into its passes).
    pub color_format: wgpu::TextureFormat,
    /// MSAA samples per pixel of the color and depth attachments (1: none). Every device
    /// has 1 and 4; 2, 8 and 16 where the adapter has them and the device was opened with
    /// `TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES` (`device::Gpu::sample_counts`).
    pub sample_count: u32,
    /// The depth attachment's format (the caller's, when drawing into its passes).
    pub depth_format: wgpu::TextureFormat,
    /// The caller's shading, compiled into every draw pipeline (which keep the instance
    /// decode, the eye routing and the seam): WGSL defining `fn material(s: Surface) ->
    /// vec4<f32>`, with `Surface` (world position, normal, color, eye, instance) and the
    /// bindings `frame` and `display` (`display.eye[s.eye]` is the eye's context) in
    /// scope; `base_color(s)` samples the material's texture. `None`: the built-in
    /// shading. Materials of [`crate::scene::Shading::Lit`] use it.
    pub material: Option<Arc<str>>,
    /// Shading functions that materials name ([`crate::scene::Shading::Hook`]`(i)` is
    /// `hooks[i]`), each WGSL defining `fn material(s: Surface) -> vec4<f32>` as
    /// `material` does. Each is its own pipeline, so its materials form their own bins.
    pub hooks: Vec<Arc<str>>,
    /// Where the per-display cull runs (the classic modes cull on the CPU).
    pub cull: CullMode,
    /// The stereo technique.
    pub mode: StereoMode,
    /// Levels of detail ([`crate::scene::Mesh::lods`]), one per instance and frame from
    /// the viewer's position, at most [`LOD_PIXELS`] of error on the sharpest display.
    pub lod: bool,
    /// Whether frames start with the coarse cull.
    pub coarse_cull: CoarseMode,
    /// GPU culling: every view that culls by its frustum alone over every instance
    /// (each display without occlusion, its far layer, its inset pair) culled by one
    /// set of dispatches for the whole rig ([`crate::cull::rig`]), each sphere read once;
    /// off, each view runs its own (what profiles compare the rig cull against). The
    /// outputs are the same byte for byte either way.
    pub rig_cull: bool,
    /// The frame's shadow map ([`crate::shadow`]): drawn once per frame from `light`,
    /// sampled by every display and eye.
    pub shadows: bool,
    /// The one directional light: shading, and with `shadows` the shadow map.
    pub light: Light,
    /// Distant instances drawn once per stereo display into a far layer both eyes share
    /// ([`crate::far_layer`]; the `instanced` mode).
    pub far_layer: bool,
    /// Where a display carries the lens's hidden area ([`crate::rig::VisibilityMask`]),
    /// it is written to depth before the scene so that no fragment is shaded there (the
    /// `instanced` and `multiview` modes; the classic modes, there for comparison, do
    /// not mask). Off by default, so that every mode draws the same image.
    pub visibility_mask: bool,
    /// Pixels the eyes' images of a far instance may differ by: sets the far distance.
    pub far_threshold_px: f32,
    /// Foveated displays (`instanced`): cull the insets' frustum too, so that the inset
    /// pair draws only what it can show (a second cull and a second multi-draw in the
    /// display's one pass) instead of every visible object four times (one multi-draw).
    pub inset_cull: bool,
    /// Bytes one storage binding may hold; `None`: the device's limit. Per-instance
    /// arrays larger than this are bound as several windows of one buffer
    /// ([`Windows`]); a smaller value than the device's exercises that on small scenes.
    pub binding_limit: Option<u64>,
    /// Also run, each frame, the floor kernel the GPU cull is measured against (one read
    /// of every sphere, one flag written per instance), timed as the frame pass
    /// `cull_floor`: for `profile`'s `cull_over_floor`. GPU culling, `instanced` and
    /// `multiview` only; it draws nothing.
    pub cull_floor: bool,
    /// Occlusion culling ([`OcclusionMode`], [`crate::occlusion`]): in the renderer's
    /// own passes (`encode`, `submit_frame`); the depth targets then need
    /// `TEXTURE_BINDING` (those of `create_targets` have it).
    pub occlusion: OcclusionMode,
    /// Where animations are posed ([`PosingMode`]).
    pub posing: PosingMode,
    /// Each display's draw also writes each pixel's motion since the previous frame
    /// into a second color target ([`crate::motion`]; `TargetViews::motion`): the
    /// `instanced` mode, without the far layer or foveated displays.
    pub motion_vectors: bool,
    /// Frames drawn per submission: 1, or 2 for the talk's "dt multiview"
    /// ([`super::frames`]): each display draws its eyes at the frame's time and `dt`
    /// later as one set of views (left and right, now and next) in one target, from one
    /// cull and one multi-draw (`instanced`).
    pub frames_per_submit: u32,
    /// Seconds between a submission's two frames (one display period).
    pub dt: f32,
    /// Whether a frame whose pose, rig and options are the last frame's redraws only
    /// the tiles that something changed ([`crate::keep`]); `on` and `auto` turn
    /// occlusion's `auto` off (its phases need every instance tested each frame).
    pub keep_unchanged: KeepUnchanged,
    /// The camera's exposure ([`crate::exposure`]): `auto` meters a scene lit in
    /// physical units (a file's lights) as the renderer is made, and keeps a scene lit
    /// in our units at unit exposure; or an EV100.
    pub exposure: Exposure,
    /// The tone mapper after the exposure; `auto`: PBR Neutral where the exposure is
    /// physical, none at unit exposure.
    pub tonemap: Tonemap,
    /// Every frame's pose is latched at its submit ([`super::Renderer::latch`]): the
    /// pose's writes wait in memory mapped before the pose is sampled, which the latch
    /// fills and closes, so that a latch makes no staging of its own. Every encoded
    /// frame is then latched (at the planned pose where nothing newer came) before its
    /// submit, and submitted before the next `prepare`: wgpu refuses a submit that reads
    /// a mapped buffer. Needs GPU culling, one frame per submission and
    /// `keep_unchanged` off, as latching does.
    pub late_latch: bool,
}

/// One period of a 90 Hz display: the default distance between a submission's frames.
pub const DEFAULT_DT: f32 = 1.0 / 90.0;

/// Screen-space error, in pixels, a level of detail may show.
pub const LOD_PIXELS: f32 = 1.0;

impl RendererOptions {
    /// The shading functions the draw pipelines compile.
    pub fn shaders(&self) -> Shaders<'_> {
        Shaders {
            lit: self.material.as_deref(),
            hooks: &self.hooks,
        }
    }

    /// Levels of detail culled into: [`MAX_LODS`], or 1 with LOD off.
    pub fn lod_levels(&self) -> u32 {
        if self.lod { MAX_LODS as u32 } else { 1 }
    }

    /// Whether frames on a rig resolved as `resolved` run the coarse cull: [`CoarseMode`]
    /// decided for the rig as it stands and, culling on the GPU, for `device`'s adapter
    /// (`None`: no GPU culling).
    pub fn coarse_for(&self, resolved: &ResolvedRig, device: Option<&wgpu::Device>) -> bool {
        match self.coarse_cull {
            CoarseMode::On => true,
            CoarseMode::Off => false,
            CoarseMode::Auto => {
                let software =
                    |d: &wgpu::Device| d.adapter_info().device_type == wgpu::DeviceType::Cpu;
                let gains = resolved.expected_coarse_tests() <= 0.8;
                // GPU culling with the rig cull reads each sphere once for the whole
                // rig already, in a fixed number of dispatches that the coarse cull's
                // per-display passes would multiply again.
                let gpu = self.cull == CullMode::Gpu;
                gains && !(gpu && (self.rig_cull || device.is_some_and(software)))
            }
        }
    }

    /// How per-instance arrays of `slots` instances are bound on `device`.
    pub fn windows(&self, device: &wgpu::Device, slots: u32) -> Windows {
        Windows::new(slots, self.binding_bytes(device))
    }

    /// Bytes one storage binding may hold: the device's limit, or `binding_limit` below it.
    pub fn binding_bytes(&self, device: &wgpu::Device) -> u64 {
        let device_limit = device.limits().max_storage_buffer_binding_size;
        self.binding_limit
            .map_or(device_limit, |l| l.min(device_limit))
    }

    /// The shadow map's texels a side, with shadows on.
    pub fn shadow_size(&self) -> Option<u32> {
        self.shadows.then_some(self.light.shadow_map_size)
    }

    /// Whether a display of `views` views and `pixels` pixels (all views) culls by
    /// occlusion in a scene of `triangles` triangles (instances at their finest level):
    /// on, or auto, culling on the GPU and at least a triangle a pixel (culling on the
    /// CPU a frame waits for its pyramids halfway: on only when asked); one or two views
    /// (a foveated display's insets see through gaps its outer views' pixels miss), in
    /// `instanced` mode or in `multiview` without MSAA (a pyramid per layer; WebGPU has
    /// no multisampled array textures to read). With the far layer, the display's far
    /// instances are tested against its pyramids too.
    pub fn occludes(&self, views: usize, pixels: u64, triangles: u64) -> bool {
        let asked = match self.occlusion {
            OcclusionMode::On => true,
            OcclusionMode::Auto => {
                self.cull == CullMode::Gpu
                    && triangles >= pixels
                    && self.keep_unchanged == KeepUnchanged::Off
            }
            OcclusionMode::Off => false,
        };
        // Multiview's layered depth has one sample (no multisampled array textures).
        let mode = match self.mode {
            StereoMode::Instanced => true,
            StereoMode::Multiview => self.sample_count == 1,
            _ => false,
        };
        asked && mode && views <= 2 && self.frames_per_submit == 1
    }

    /// The attachments the draw pipelines are built for.
    pub fn target_format(&self) -> TargetFormat {
        TargetFormat {
            color: self.color_format,
            depth: self.depth_format,
            samples: self.sample_count,
            motion: self.motion_vectors,
            first_pose: self.frames_per_submit == 2,
        }
    }
}

impl Default for RendererOptions {
    fn default() -> Self {
        RendererOptions {
            color_format: wgpu::TextureFormat::Rgba8UnormSrgb,
            sample_count: 1,
            depth_format: DEPTH_FORMAT,
            material: None,
            hooks: Vec::new(),
            cull: CullMode::Gpu,
            mode: StereoMode::Instanced,
            lod: false,
            coarse_cull: CoarseMode::Auto,
            rig_cull: true,
            shadows: false,
            light: Light::default(),
            far_layer: false,
            visibility_mask: false,
            far_threshold_px: FAR_THRESHOLD_PX,
            inset_cull: false,
            binding_limit: None,
            cull_floor: false,
            occlusion: OcclusionMode::Auto,
            posing: PosingMode::Cpu,
            motion_vectors: false,
            frames_per_submit: 1,
            dt: DEFAULT_DT,
            keep_unchanged: KeepUnchanged::Off,
            exposure: Exposure::Auto,
            tonemap: Tonemap::Auto,
            late_latch: false,
        }
    }
}

/// The frame's level-of-detail choice for `rig`: the viewer, and the scale that holds
/// the error under [`LOD_PIXELS`] on the display with the most pixels per radian.
pub fn frame_lod(rig: &Rig, resolved: &ResolvedRig, levels: u32) -> FrameLod {
    // Over every display planned for, drawn or not: a subset decides as the whole rig.
    let pixels_per_radian = rig
        .frame_displays()
        .zip(resolved.frame_displays())
        .flat_map(|(d, r)| {
            r.eyes.iter().map(move |e| {
                let across = e.fov.left.atan() + e.fov.right.atan();
                d.resolution[0] as f32 / across.max(1e-6)
            })
        })
        .fold(0.0, f32::max);
    FrameLod {
        viewer: rig.viewer.position().as_vec3(),
        lod_scale: (pixels_per_radian / LOD_PIXELS).powi(2),
        levels,
    }
}
