//! Every refusal of a renderer's options, in one place, each with its reason: what a
//! device must have for the options and scene asked of it, what a rig and two frames
//! per submission can draw, when pixels can be kept and a pose latched; said before
//! anything is built.

use super::options::{CullMode, PosingMode, RendererOptions};
use super::options::{OcclusionMode, StereoMode};
use crate::draw::DrawScene;
use crate::error::{Error, Result};
use crate::keep::KeepUnchanged;
use crate::records::MeshRecord;
use crate::rig::Rig;
use crate::scene::{Scene, Shading, Vertex};
use crate::shaders::{Windowed, check_shading};

/// MSAA the device can do for the options' color format and the depth format. Without
/// `TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES` that is WebGPU's guarantee (1 and 4);
/// with it the adapter decides, which only the adapter knows: wgpu then checks.
fn check_sample_count(features: wgpu::Features, options: &RendererOptions) -> Result<()> {
    let n = options.sample_count;
    let specific = features.contains(wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES);
    let counts = match specific {
        true => vec![1, 2, 4, 8, 16],
        false => crate::device::guaranteed_sample_counts(
            features,
            options.color_format,
            options.depth_format,
        ),
    };
    if !counts.contains(&n) {
        return Err(Error::Unsupported(format!(
            "{n}x MSAA is not available for {:?}; this device has {}",
            options.color_format,
            crate::device::list_counts(&counts)
        )));
    }
    if n > 1
        && options.mode == StereoMode::Multiview
        && !features.contains(wgpu::Features::MULTISAMPLE_ARRAY)
    {
        return Err(Error::Unsupported(
            "multiview with MSAA needs MULTISAMPLE_ARRAY (multisampled two-layer targets), which this device lacks".into(),
        ));
    }
    Ok(())
}

/// What the mode cannot draw of the rig: multiview draws a foveated display's four
/// views as four layers, which the device must have (`max_multiview_views`, its
/// `max_multiview_view_count`); every other mode draws any number of views. Motion
/// vectors take no foveated display.
pub fn check_rig(rig: &Rig, options: &RendererOptions, max_multiview_views: u32) -> Result<()> {
    let foveated = rig.displays.iter().find(|d| d.views() > 2);
    if let (true, Some(d)) = (options.motion_vectors, foveated) {
        return Err(Error::rig(
            &d.name,
            "motion vectors: a foveated display's composite would have to carry the insets' motion into the outer views, and does not",
        ));
    }
    let too_many = |d: &&crate::rig::Display| d.views() > max_multiview_views.max(2);
    let Some(d) = rig.displays.iter().find(too_many) else {
        return Ok(());
    };
    if options.mode != StereoMode::Multiview {
        return Ok(());
    }
    Err(Error::rig(
        &d.name,
        format!(
            "foveated display: multiview of {} views needs max_multiview_view_count >= {}, and this device has {max_multiview_views}: use --mode instanced",
            d.views(),
            d.views()
        ),
    ))
}

/// Motion vectors are written by the instanced path's draw alone: say what else cannot.
fn check_motion(options: &RendererOptions) -> Result<()> {
    if !options.motion_vectors {
        return Ok(());
    }
    let why = match (options.mode, options.far_layer) {
        (StereoMode::Multiview, _) => {
            "multiview: its draw carries a varying more, the previous clip position, and lavapipe (Mesa 22.3) misroutes clipped triangles of multiview pipelines as varyings grow (see wgsl/shared/draw_clip_distances.wgsl)"
        }
        (mode, _) if mode.per_instance() => {
            "the classic modes, kept to compare submission costs against, draw the same image and no motion target"
        }
        (_, true) => {
            "the far layer: its composite would have to carry each far pixel's motion into the display's target, and does not"
        }
        _ => return Ok(()),
    };
    Err(Error::Unsupported(format!(
        "motion vectors are written by the instanced mode's draw; not with {why}"
    )))
}

/// Late latching latches every frame: what a latch refuses, the renderer does.
fn check_late_latch(options: &RendererOptions) -> Result<()> {
    if !options.late_latch {
        return Ok(());
    }
    let why = why_no_latch(options).or_else(|| {
        (options.keep_unchanged != KeepUnchanged::Off).then_some(
            "a latched pose moves every pixel, so no frame keeps the last one's: keep_unchanged off",
        )
    });
    match why {
        Some(why) => Err(Error::Unsupported(format!("late latching: {why}"))),
        None => Ok(()),
    }
}

/// Materials drawn by a pipeline of the caller's own need the GPU-driven modes, whose
/// bins are one multi-draw each, and no far layer (its own pass draws far instances
/// with the built-in pipelines into a layer of its own shape).
fn check_own_shading(scene: &Scene, options: &RendererOptions) -> Result<()> {
    let own = scene
        .materials
        .iter()
        .find(|m| matches!(m.shading, Shading::Own(_)));
    let Some(m) = own else {
        return Ok(());
    };
    let why = match (options.mode.per_instance(), options.far_layer) {
        (true, _) => format!("{} draws per instance", options.mode.name()),
        (false, true) => "the far layer draws with the built-in pipelines alone".into(),
        (false, false) => return Ok(()),
    };
    Err(Error::Unsupported(format!(
        "material {:?} is drawn by a pipeline of the caller's own, and {why}: use --mode instanced or multiview{}",
        m.name,
        if options.far_layer {
            " without the far layer"
        } else {
            ""
        }
    )))
}

/// Whether a renderer can be made for `scene` and `rig` with `options` on `device`.
pub fn check_renderer(
    device: &wgpu::Device,
    scene: &Scene,
    rig: &Rig,
    options: &RendererOptions,
) -> Result<()> {
    check_device(device, scene, options)?;
    check_rig(rig, options, device.limits().max_multiview_view_count)?;
    check_frames(scene, rig, options)?;
    let views = rig.displays.iter().map(|d| d.views());
    match (
        options.keep_unchanged,
        super::keeping::never(scene, views, options),
    ) {
        (KeepUnchanged::On, Some(why)) => Err(Error::Unsupported(format!(
            "keeping unchanged pixels: {why} (--keep-unchanged auto draws such frames whole)"
        ))),
        _ => Ok(()),
    }
}

/// What a mode cannot do without, said before anything is built.
pub fn check_device(device: &wgpu::Device, scene: &Scene, options: &RendererOptions) -> Result<()> {
    let features = device.features();
    let mode = options.mode.name();
    check_sample_count(features, options)?;
    check_shading(scene, options.shaders())?;
    if options.mode.per_instance() && options.cull == CullMode::Gpu {
        return Err(Error::Unsupported(format!(
            "{mode} records a draw call per visible instance, so it culls on the CPU: use --cull cpu"
        )));
    }
    if !options.mode.per_instance() && !features.contains(wgpu::Features::INDIRECT_FIRST_INSTANCE) {
        return Err(Error::Unsupported(format!(
            "{mode} needs INDIRECT_FIRST_INSTANCE (per-mesh offsets in indirect draws), which this device lacks"
        )));
    }
    if options.mode == StereoMode::Multiview && !features.contains(wgpu::Features::MULTIVIEW) {
        return Err(Error::Unsupported(
            "multiview is unavailable: the device lacks MULTIVIEW".into(),
        ));
    }
    check_own_shading(scene, options)?;
    check_motion(options)?;
    check_late_latch(options)?;
    if options.posing == PosingMode::Gpu && options.cull != CullMode::Gpu {
        return Err(Error::Unsupported(
            "posing on the GPU writes the culling spheres on the GPU, which a CPU cull cannot read: use --posing cpu or --cull gpu".into(),
        ));
    }
    let limits = device.limits();
    check_shadows(features, &limits, options)?;
    if options.far_layer && options.mode != StereoMode::Instanced {
        return Err(Error::Unsupported(format!(
            "the far layer shares distant geometry between the eyes of instanced's doubled draws; {mode} has none"
        )));
    }
    if options.far_layer
        && !(options.far_threshold_px > 0.0 && options.far_threshold_px.is_finite())
    {
        return Err(Error::Unsupported(format!(
            "a far threshold of {} pixels: it must be a positive number",
            options.far_threshold_px
        )));
    }
    // Storage buffers bound whole must fit one binding; instance records and spheres
    // are bound in windows (`shaders::Windows`), and vertex and index buffers are no
    // bindings: those only need to fit one buffer.
    let storage = options.binding_bytes(device).min(limits.max_buffer_size);
    let per_level = 4 * options.lod_levels() as u64;
    let buffers = [
        (
            "instance records",
            DrawScene::BYTES_PER_INSTANCE,
            scene.instances.len(),
            limits.max_buffer_size,
        ),
        (
            "world bounding spheres",
            Windowed::Spheres.stride(),
            scene.instances.len(),
            limits.max_buffer_size,
        ),
        (
            "cull flags (4 bytes per instance and level of detail)",
            per_level,
            scene.instances.len(),
            storage,
        ),
        (
            "mesh records",
            size_of::<MeshRecord>() as u64,
            scene.meshes.len(),
            storage,
        ),
        (
            "vertices",
            size_of::<Vertex>() as u64,
            scene.vertices.len(),
            // The skinning pass binds them whole to write its meshes.
            match scene.skins.is_empty() {
                true => limits.max_buffer_size,
                false => storage,
            },
        ),
        (
            "indices",
            size_of::<u32>() as u64,
            scene.indices.len(),
            limits.max_buffer_size,
        ),
    ];
    for (what, size, count, max) in buffers {
        let bytes = size * count as u64;
        if bytes > max {
            return Err(Error::Limits(format!(
                "the scene's {count} {what} need a {bytes}-byte buffer but the device allows {max}"
            )));
        }
    }
    Ok(())
}

/// The shadow pass draws indirectly in every mode, into a map the device can hold.
fn check_shadows(
    features: wgpu::Features,
    limits: &wgpu::Limits,
    options: &RendererOptions,
) -> Result<()> {
    let Some(size) = options.shadow_size() else {
        return Ok(());
    };
    if !features.contains(wgpu::Features::INDIRECT_FIRST_INSTANCE) {
        return Err(Error::Unsupported(
            "shadows need INDIRECT_FIRST_INSTANCE (the shadow pass draws indirectly), which this device lacks".into(),
        ));
    }
    if size == 0 || size > limits.max_texture_dimension_2d {
        return Err(Error::Limits(format!(
            "a {size} x {size} shadow map; the device's 2D textures hold 1 to {} a side",
            limits.max_texture_dimension_2d
        )));
    }
    Ok(())
}

/// What two frames per submission cannot draw: it takes the `instanced` mode's one
/// multi-draw, content posed on the CPU for each frame (or by the draw, from the time),
/// and none of the features whose state belongs to a single frame.
fn check_frames(scene: &Scene, rig: &Rig, options: &RendererOptions) -> Result<()> {
    match options.frames_per_submit {
        1 => return Ok(()),
        2 => {}
        n => {
            return Err(Error::Unsupported(format!(
                "{n} frames per submission: 1 or 2"
            )));
        }
    }
    if !(options.dt.is_finite() && options.dt > 0.0) {
        return Err(Error::Unsupported(format!(
            "dt {} s between a submission's frames: it must be a positive number",
            options.dt
        )));
    }
    let why = unjoined_option(options).or_else(|| unjoined_content(scene, rig, options));
    match why {
        Some(why) => Err(Error::Unsupported(format!(
            "two frames per submission: {why}"
        ))),
        None => Ok(()),
    }
}

/// The options that keep state of a single frame.
fn unjoined_option(options: &RendererOptions) -> Option<&'static str> {
    Some(match options {
        o if o.mode != StereoMode::Instanced => {
            "the instanced mode draws both frames' views in one multi-draw; the other modes, kept to compare submission costs against, draw each frame in passes of its own: submit their frames one at a time"
        }
        o if o.occlusion == OcclusionMode::On => {
            "occlusion's early phase draws what the previous frame saw, and the second frame's previous is the first, drawn in the same pass: use --occlusion off or auto"
        }
        o if o.far_layer => {
            "the far layer is one shared image per frame, composited before the display's draw: the second frame would need a layer of its own"
        }
        o if o.motion_vectors => {
            "motion vectors measure each frame from the one before, and the second frame's is in the same target: not built yet"
        }
        _ => return None,
    })
}

/// The rig and scene content whose second frame cannot be drawn so: a foveated
/// display's views, and posed content (`frames.rs`) where the lights or the
/// shadow are one per submission.
fn unjoined_content(scene: &Scene, rig: &Rig, options: &RendererOptions) -> Option<&'static str> {
    if rig.displays.iter().any(|d| d.views() > 2) {
        return Some(
            "a foveated display's four views would make eight, and a display context holds four",
        );
    }
    let posed = !scene.posing.clips.is_empty() || !scene.skins.is_empty();
    if !posed && scene.morphs.is_empty() {
        return None;
    }
    if !scene.posing.lights.is_empty() {
        return Some(
            "lights on animated nodes light both frames of a submission as one set: posed once per submission",
        );
    }
    options.shadows.then_some(
        "the shadow map is drawn once per submission, at the second frame's pose of node animations, skins and morph targets: use --shadows off",
    )
}

/// Why a renderer made with `options` cannot latch a pose, where it cannot.
pub fn why_no_latch(options: &RendererOptions) -> Option<&'static str> {
    if options.frames_per_submit != 1 {
        return Some(
            "latching a pose takes one frame per submission: the second frame's pose is a prediction already",
        );
    }
    if options.cull == CullMode::Cpu {
        return Some(
            "latching a pose needs the GPU cull: the CPU cull ran in prepare, from the planned pose, and the recorded draws hold its results",
        );
    }
    None
}
