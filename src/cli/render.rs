//! `stereocull render`: one frame of every display to PNG, with stats.json.

use std::path::PathBuf;
use std::time::Instant;

use clap::Parser;
use serde::Serialize;

use super::edits::EditArgs;
use super::motion::{MotionStats, PreviousArgs, write_motion};
use super::occlusion_report::occlusion_report;
use super::session::{FrameFigures, Session};
use super::{SceneArgs, save, write_json};
use crate::error::{Error, Result};
use crate::foveated_composite::{CompositeParams, FoveatedComposite, composite_cpu};
use crate::profiling::{FrameQueries, GpuTimer};
use crate::readback::read_rgba8;
use crate::renderer::{CullMode, FrameStats, Level, Renderer, StereoMode};
use crate::rig::Rig;

#[derive(Parser)]
pub struct RenderArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Output directory for `<display>.png` and `stats.json`.
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    #[arg(long, value_enum, default_value = "gpu")]
    pub cull: CullMode,
    #[arg(long, value_enum, default_value = "instanced")]
    pub mode: StereoMode,
    /// The frame's time in seconds (animated instances are drawn at it).
    #[arg(long, default_value_t = 0.0)]
    pub time: f32,
    /// MSAA samples per pixel (1: none); `stereocull info` lists the adapter's counts.
    /// Default: 4 where the adapter has it for this mode, else 1.
    #[arg(long)]
    pub msaa: Option<u32>,
    /// Also write each display's depth as an XR compositor's depth layer takes it:
    /// `<display>-depth.f32` (little-endian f32, rows from the top, multiview's layers
    /// side by side; under MSAA each pixel's nearest sample) and its contract (each
    /// view's rectangle or layer, planes, depth range) in `stats.json`.
    #[arg(long)]
    pub compositor_depth: bool,
    /// With `--motion-vectors on`: the frame the motion is measured from (drawn first).
    #[command(flatten)]
    pub previous: PreviousArgs,
}

/// One pass of a frame as the reports list it ([`Renderer::passes`]).
#[derive(Clone, Debug, Serialize)]
pub struct PassReport {
    pub level: Level,
    pub name: &'static str,
    pub display: Option<String>,
    pub eye: Option<u32>,
    /// Vertex-shader invocations (pipeline statistics, where the adapter has them; draw
    /// and shadow passes).
    pub vertex_invocations: Option<u64>,
}

/// The last frame's passes in recording order, with the displays named and each
/// counted pass's vertex-shader invocations from `queries`.
pub fn pass_reports(
    renderer: &Renderer,
    rig: &Rig,
    queries: Option<&FrameQueries>,
) -> Vec<PassReport> {
    renderer
        .passes()
        .iter()
        .map(|p| PassReport {
            level: p.level,
            name: p.name,
            display: p.display.map(|d| rig.displays[d as usize].name.clone()),
            eye: p.eye,
            vertex_invocations: p
                .statistics
                .zip(queries)
                .and_then(|(i, q)| q.vertex_invocations_per_query.get(i as usize).copied()),
        })
        .collect()
}

/// The last frame's far/near split, per display with a far layer, named.
pub fn far_near(session: &Session) -> Result<Vec<serde_json::Value>> {
    let device = (&session.gpu.device, &session.gpu.queue);
    let splits = session
        .renderer
        .diagnostics(device.0, device.1)
        .far_split()?;
    Ok(session
        .rig
        .displays
        .iter()
        .zip(splits)
        .filter_map(|(d, s)| s.map(|s| serde_json::json!({ "display": d.name, "split": s })))
        .collect())
}

/// How many passes of each level `passes` holds: (frame, display, eye).
pub fn passes_per_level(passes: &[PassReport]) -> serde_json::Value {
    let count = |level| passes.iter().filter(|p| p.level == level).count();
    serde_json::json!({
        "frame": count(Level::Frame),
        "display": count(Level::Display),
        "eye": count(Level::Eye),
    })
}

#[derive(Serialize)]
struct DisplayStats {
    name: String,
    views: u32,
    image: String,
    width: u32,
    height: u32,
    visible: u32,
    /// Each view's `[x, y, width, height]` in the display's target.
    viewports: Vec<[u32; 4]>,
    /// Pixels of all views together: what the frame shades (per sample).
    pixels: u64,
    /// Foveated displays: the target as drawn (`<name>-views.png`); `image` is then the
    /// composite of each eye's inset over its outer view.
    #[serde(skip_serializing_if = "Option::is_none")]
    views_image: Option<String>,
    /// With two frames per submission: the second frame (`<name>-next.png`, drawn
    /// `--dt` seconds after `image`).
    #[serde(skip_serializing_if = "Option::is_none")]
    next_image: Option<String>,
    /// Foveated displays: whether the gaze was moved to keep an inset inside its view.
    #[serde(skip_serializing_if = "Option::is_none")]
    gaze_clamped: Option<bool>,
    /// With `--compositor-depth`: the depth file and its contract.
    #[serde(skip_serializing_if = "Option::is_none")]
    depth: Option<DepthStats>,
    /// With `--motion-vectors on`: the motion files.
    #[serde(skip_serializing_if = "Option::is_none")]
    motion: Option<MotionStats>,
}

#[derive(Serialize)]
struct DepthStats {
    file: String,
    /// Of the file: the layers side by side.
    width: u32,
    height: u32,
    #[serde(flatten)]
    layer: crate::compositor::DepthLayer,
}

/// Display `index`'s compositor depth written to `<name>-depth.f32` under `out`.
fn write_depth(session: &Session, index: usize, out: &std::path::Path) -> Result<DepthStats> {
    let (device, queue) = (&session.gpu.device, &session.gpu.queue);
    let depth = &session.targets[index].depth;
    let (width, values) = crate::compositor::read_layer(device, queue, depth)?;
    let path = out.join(format!("{}-depth.f32", session.rig.displays[index].name));
    let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    std::fs::write(&path, bytes).map_err(|e| Error::io(&path, e))?;
    Ok(DepthStats {
        file: path.display().to_string(),
        width,
        height: depth.height(),
        layer: session.renderer.depth_layer(&session.rig, index)?,
    })
}

/// Display `index`'s image as drawn and, for a foveated display, its composite (each
/// eye's inset over its outer view, by the GPU composite).
pub(super) fn display_images(
    session: &Session,
    index: usize,
) -> Result<(image::RgbaImage, Option<image::RgbaImage>)> {
    let (device, queue) = (&session.gpu.device, &session.gpu.queue);
    let target = &session.targets[index];
    let drawn = read_rgba8(device, queue, &target.color)?;
    let layout = session
        .renderer
        .layout(index)
        .unwrap_or(session.rig.displays[index].layout());
    let Some(params) = CompositeParams::of_display(&session.rig, index, &layout)? else {
        return Ok((drawn, None));
    };
    // Multiview's layers are no 2D texture the GPU composite could read: the CPU twin
    // composites them as read back, side by side.
    if target.color.depth_or_array_layers() > 1 {
        let composite = composite_cpu(&drawn, &params);
        return Ok((drawn, Some(composite)));
    }
    let format = target.color.format();
    let output = FoveatedComposite::create_output(device, &params, format);
    let mut encoder = device.create_command_encoder(&Default::default());
    let source = target.color.create_view(&Default::default());
    let view = output.create_view(&Default::default());
    FoveatedComposite::new(device, format).encode(device, &mut encoder, &source, &params, &view);
    queue.submit([encoder.finish()]);
    Ok((drawn, Some(read_rgba8(device, queue, &output)?)))
}

/// The frame's figures, with the fragments it shaded (pipeline statistics, where the
/// adapter counts them) and the pixels the visibility masks kept from being shaded.
fn frame_json(
    stats: &FrameStats,
    queries: Option<&crate::profiling::FrameQueries>,
    masked_pixels: u64,
) -> serde_json::Value {
    let mut frame = serde_json::json!(stats);
    frame["fragment_invocations"] = serde_json::json!(queries.and_then(|q| q.fragment_invocations));
    frame["samples_passed"] = serde_json::json!(queries.and_then(|q| q.samples_passed));
    frame["masked_pixels"] = serde_json::json!(masked_pixels);
    frame
}

/// A display's image of `frames` frames (their views side by side, each frame's after
/// the one before) as the first frame's image and the second's.
fn frames_apart(
    drawn: image::RgbaImage,
    frames: u32,
) -> (image::RgbaImage, Option<image::RgbaImage>) {
    if frames == 1 {
        return (drawn, None);
    }
    let (w, h) = (drawn.width() / frames, drawn.height());
    let crop = |x| image::imageops::crop_imm(&drawn, x, 0, w, h).to_image();
    (crop(0), Some(crop(w)))
}

pub fn render(args: &RenderArgs) -> Result<()> {
    let edits = EditArgs::default();
    let how = (args.cull, args.mode, args.msaa, false);
    let mut session = Session::open(&args.scene, how, &edits, args.time)?;
    // Room for every display's draw passes (one per eye, or two with occlusion, at
    // most) and the shadow pass.
    let counted = 3 * session.rig.displays.len() as u32 + 1;
    // Occlusion's early phase draws what the display drew last frame: a first frame
    // draws everything late (no depth yet to hide behind), the second draws that early
    // and finds what it hides. Two frames before this one prime it, as in a running
    // application.
    let primed = session.renderer.occlusion_bytes().is_some();
    for _ in 0..2 * u32::from(primed) {
        session.frame(args.time)?;
        session.gpu.wait()?;
    }
    let motion = session.renderer.options().motion_vectors;
    if motion {
        args.previous.draw(&mut session, args.time)?;
    }
    session.timer = GpuTimer::new(&session.gpu.device, &session.gpu.queue, counted);
    let FrameFigures { stats, cpu_ms, .. } = session.frame(args.time)?;
    let start = Instant::now();
    session.gpu.wait()?;
    let gpu_wait_ms = start.elapsed().as_secs_f64() * 1e3;
    let queries = match session.timer.as_mut() {
        Some(t) => Some(t.read(&session.gpu.device, &session.gpu.queue)?),
        None => None,
    };
    let passes = pass_reports(&session.renderer, &session.rig, queries.as_ref());
    let far_near = far_near(&session)?;
    let occlusion = occlusion_report(
        &session.gpu,
        &session.renderer,
        (&session.rig, args.time),
        session.current_scene(),
    )?;
    std::fs::create_dir_all(&args.out).map_err(|e| Error::io(&args.out, e))?;
    let visible = session
        .renderer
        .diagnostics(&session.gpu.device, &session.gpu.queue)
        .visible_counts()?;
    let candidates = session
        .renderer
        .diagnostics(&session.gpu.device, &session.gpu.queue)
        .candidates()?;
    let resolved = session.rig.resolve()?;
    let frames = session.renderer.options().frames_per_submit;
    let mut displays = Vec::new();
    for (index, (display, visible)) in session.rig.displays.iter().zip(visible).enumerate() {
        let path = args.out.join(format!("{}.png", display.name));
        let (drawn, composite) = display_images(&session, index)?;
        let views_path = composite
            .as_ref()
            .map(|_| args.out.join(format!("{}-views.png", display.name)));
        if let Some(views_path) = &views_path {
            save(&drawn, views_path)?;
        }
        let (image, next) = frames_apart(composite.unwrap_or(drawn), frames);
        save(&image, &path)?;
        let next_path = next
            .map(|next| {
                let next_path = args.out.join(format!("{}-next.png", display.name));
                save(&next, &next_path).map(|()| next_path.display().to_string())
            })
            .transpose()?;
        let gaze_clamped = (display.views() == 4).then(|| resolved.displays[index].gaze_clamped);
        if gaze_clamped == Some(true) {
            eprintln!(
                "{}: the gaze would put an inset outside its eye's view; the inset was moved inside",
                display.name
            );
        }
        let layout = display.layout();
        println!(
            "{:>18}: {} views, {}x{}, {visible} visible -> {}",
            display.name,
            display.views(),
            image.width(),
            image.height(),
            path.display()
        );
        displays.push(DisplayStats {
            name: display.name.clone(),
            views: display.views(),
            image: path.display().to_string(),
            width: image.width(),
            height: image.height(),
            visible,
            viewports: layout.viewports().to_vec(),
            pixels: layout.pixels(),
            views_image: views_path.map(|p| p.display().to_string()),
            next_image: next_path,
            gaze_clamped,
            depth: match args.compositor_depth {
                true => Some(write_depth(&session, index, &args.out)?),
                false => None,
            },
            motion: match motion {
                true => Some(write_motion(&session, index, &args.out)?),
                false => None,
            },
        });
    }
    println!(
        "{} instances, {} with cull {:?}, {}x MSAA: {} draw calls, {} dispatches, {} bytes uploaded, CPU {cpu_ms:.2} ms, GPU wait {gpu_wait_ms:.1} ms",
        session.scene.instances.len(),
        args.mode.name(),
        args.cull,
        session.renderer.options().sample_count,
        stats.draw_calls,
        stats.dispatches,
        stats.bytes_uploaded
    );
    let (ev100, tonemap) = session.renderer.exposure();
    if let Some(ev) = ev100 {
        println!("exposure: EV100 {ev:.2}, tone mapping {tonemap:?}");
    }
    for r in occlusion.iter().flatten() {
        println!(
            "{:>18}: occlusion: {} in the frustum, {} drawn early, {} late, {} occluded",
            r.display, r.frustum, r.early, r.late, r.occluded
        );
    }
    let out = args.out.join("stats.json");
    write_json(
        &out,
        &serde_json::json!({
            "adapter": session.gpu.adapter_line(),
            "scene": args.scene.scene,
            "rig": args.scene.rig,
            "cull": args.cull,
            "mode": args.mode,
            "msaa": session.renderer.options().sample_count,
            "frames_per_submit": frames,
            "dt": session.renderer.options().dt,
            "instances": session.scene.instances.len(),
            "gpu_bytes_per_instance": session.renderer.gpu_bytes_per_instance(),
            "frame": frame_json(&stats, queries.as_ref(), session.renderer.masked_pixels()),
            "coarse_cull": session.renderer.coarse_cull(),
            "coarse_candidates": candidates,
            "shadows": session.renderer.options().shadows,
            "exposure": { "ev100": ev100, "tonemap": tonemap },
            "far_layer": session.renderer.options().far_layer,
            "far_near": far_near,
            "occlusion": occlusion,
            "occlusion_primed_by_two_frames": primed,
            "occlusion_bytes": session.renderer.occlusion_bytes(),
            "passes_per_level": passes_per_level(&passes),
            "passes": passes,
            "cpu_encode_submit_ms": cpu_ms,
            "gpu_wait_ms": gpu_wait_ms,
            "displays": displays,
        }),
    )
}
