//! The `stereocull` command line.

mod chart;
#[cfg(feature = "cluster")]
mod cluster;
mod cull;
mod diff;
mod edits;
mod motion;
mod occlusion_report;
mod profile;
mod profile_args;
mod profile_measure;
mod profile_ratios;
mod profile_report;
mod render;
mod session;
mod stress;

pub use cull::{DisplayDump, DrawDump, display_dump};

use std::path::Path;

use clap::{Args, Parser, Subcommand};
use serde::Serialize;

use crate::device::{Gpu, OPTIONAL_FEATURES, Tier};
use crate::error::{Error, Result};
use crate::exposure::{Exposure, Tonemap};
use crate::renderer::{CoarseMode, CullMode, OcclusionMode, PosingMode, RendererOptions};
use crate::rig::{Gaze, Rig, framing};
use crate::scene::Scene;
use crate::scene_spec::DEFAULT_SCENE;

/// The clock of `stress` and `profile`: frames of a 90 Hz headset.
pub const FRAME_SECONDS: f32 = 1.0 / 90.0;

#[derive(Parser)]
#[command(
    name = "stereocull",
    version,
    about = "GPU-driven stereo and multi-display scene submission on wgpu"
)]
struct Cli {
    /// Without a command: `render` with its defaults (the built-in room on `hmd`, into `out/`).
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Print the adapter, backend, driver and which optional features are present; with
    /// `--scene`, what a scene file uses and what of it is read instead.
    Info(InfoArgs),
    /// Cull a scene for every display of a rig and dump the visible lists and draws.
    Cull(cull::CullArgs),
    /// Render one frame: one PNG per display (double-wide for stereo) and stats.json.
    Render(render::RenderArgs),
    /// Run frames headless with a moving viewer and report timings and counts.
    Stress(stress::StressArgs),
    /// Compare every stereo mode and cull mode across instance counts: table, CSV, JSON, chart.
    Profile(profile::ProfileArgs),
    /// Under `mpirun`: the rig's displays over MPI ranks, frame-locked (feature
    /// `cluster`).
    #[cfg(feature = "cluster")]
    Cluster(cluster::ClusterArgs),
    /// Compare two images: how many pixels differ and by how much (e.g. LOD on and off).
    Diff(diff::DiffArgs),
}

#[derive(Args, Clone, Debug)]
pub struct InfoArgs {
    /// A scene (as `render --scene` takes it) to describe instead of the adapter: a glTF
    /// file's extensions, which of them are read, and what it loads as.
    #[arg(long)]
    pub scene: Option<String>,
}

/// Where the scene and viewer come from; shared by every command that draws.
#[derive(Args, Clone, Debug)]
pub struct SceneArgs {
    /// `default` (the built-in room), a .gltf/.glb file, `procedural:N[:MESHES[:SEED]]`,
    /// `city:N[:SEED]` or `rooms:N[:SEED]` (rooms with doorways: occluders).
    #[arg(long, default_value = DEFAULT_SCENE)]
    pub scene: String,
    /// A preset (hmd, cave, hmd-peripheral, hmd-foveated) or a .json/.toml rig file.
    #[arg(long, default_value = "hmd")]
    pub rig: String,
    /// N[:SEED]: N point lights more, scattered over the scene (deterministic from
    /// SEED, default 1), shaded through each display's clusters (`rooms:` has a lamp
    /// per room already).
    #[arg(long, value_parser = parse_lights)]
    pub lights: Option<(u32, u64)>,
    /// Draw only these displays of the rig (names, comma-separated), the frame planned
    /// as for the whole rig: one process per CAVE wall (default: every display).
    #[arg(long, value_delimiter = ',')]
    pub displays: Vec<String>,
    /// Where the viewer stands: x,y,z in meters, or `fit`: back from the scene's
    /// bounds, looking at them from the front and 20 degrees above, until both eyes of
    /// every display see all of them (`--yaw` walks around the scene, `--pitch` sets
    /// the look down). Default: the rig's spot; for a .gltf/.glb scene its first
    /// camera, or `fit` where it has none or `--yaw`/`--pitch` is given.
    #[arg(long, value_parser = parse_viewer, allow_hyphen_values = true)]
    pub viewer: Option<ViewerSpot>,
    /// The camera's exposure: `auto` (a file lit in physical units metered as an
    /// incident-light meter reads its brightest light at the scene's center; our own
    /// scenes at unit exposure) or an EV100 (Bevy's default is 9.7).
    #[arg(long, value_parser = parse_exposure, default_value = "auto", allow_hyphen_values = true)]
    pub exposure: Exposure,
    /// The tone mapper after the exposure (auto: neutral where the exposure is
    /// physical, none at unit exposure).
    #[arg(long, value_enum, default_value = "auto")]
    pub tonemap: Tonemap,
    /// View through the scene file's camera N (0 first, in `info --scene`'s order): its
    /// pose, vertical field of view and clip planes; the rig's IPD kept.
    #[arg(long, conflicts_with_all = ["viewer", "yaw", "pitch"])]
    pub camera: Option<usize>,
    /// Viewer yaw override in degrees (positive turns left).
    #[arg(long, allow_hyphen_values = true)]
    pub yaw: Option<f32>,
    /// Viewer pitch override in degrees (positive looks up).
    #[arg(long, allow_hyphen_values = true)]
    pub pitch: Option<f32>,
    /// Both eyes' gaze for the foveated displays: yaw,pitch in degrees from each eye's
    /// axis; their insets follow it (default: fixed foveation, larger insets).
    #[arg(long, value_parser = parse_pair, allow_hyphen_values = true)]
    pub gaze: Option<[f32; 2]>,
    /// Per-eye width in pixels for every display (default: the rig's).
    #[arg(long)]
    pub width: Option<u32>,
    /// Per-eye height in pixels for every display (default: the rig's).
    #[arg(long)]
    pub height: Option<u32>,
    /// Levels of detail chosen on the GPU from the viewer's position.
    #[arg(long, value_enum, default_value = "off")]
    pub lod: Switch,
    /// The frame-level coarse cull before the display culls (auto: where the rig gains).
    #[arg(long, value_enum, default_value = "auto")]
    pub coarse_cull: CoarseMode,
    /// GPU culling: the displays' frustum culls in one set of dispatches for the whole
    /// rig (off: a set per display, to compare against).
    #[arg(long, value_enum, default_value = "on")]
    pub rig_cull: Switch,
    /// Occlusion culling: what the display drew last frame first, then the rest against
    /// each eye's depth pyramid (auto: off; on where it applies: GPU cull, instanced).
    #[arg(long, value_enum, default_value = "auto")]
    pub occlusion: OcclusionMode,
    /// The frame's shadow map: drawn once per frame, sampled by every display and eye.
    #[arg(long, value_enum, default_value = "off")]
    pub shadows: Switch,
    /// Distant instances drawn once per stereo display into a far layer both eyes share.
    #[arg(long, value_enum, default_value = "off")]
    pub far_layer: Switch,
    /// Pixels the eyes' images of a far instance may differ by (sets the far distance).
    #[arg(long, default_value_t = crate::far_layer::FAR_THRESHOLD_PX)]
    pub far_threshold: f32,
    /// The lens's hidden area (a rig display's `visibility_mask`; the `hmd` presets
    /// have one) written to depth before the scene: no fragment is shaded there
    /// (`instanced` and `multiview`; off by default, so that every mode draws the same
    /// image).
    #[arg(long, value_enum, default_value = "off")]
    pub visibility_mask: Switch,
    /// Foveated displays: cull the insets' frustum too, so the inset pair draws only what
    /// it can show (one more cull and multi-draw per display).
    #[arg(long, value_enum, default_value = "off")]
    pub inset_cull: Switch,
    /// The scene's glTF node animations, posed once per frame at the frame's time (off:
    /// the file's rest pose).
    #[arg(long, value_enum, default_value = "on")]
    pub animation: Switch,
    /// Where animations are posed each frame: on the GPU from the frame's time alone
    /// (needs --cull gpu), or on the CPU with the poses uploaded (auto: the GPU where
    /// the cull runs there). `render`, `stress`.
    #[arg(long, value_enum, default_value = "auto")]
    pub posing: PosingArg,
    /// Each pixel's motion since the previous frame, written by the draw into a second
    /// target (`instanced`, without the far layer or foveated displays).
    #[arg(long, value_enum, default_value = "off")]
    pub motion_vectors: Switch,
    /// Frames per submission: 2 draws each display's eyes at the frame's time and
    /// `--dt` later as one set of views in one pass, from one cull (`instanced`; the
    /// multiview talk's "dt multiview"). `render` writes the second as
    /// `<display>-next.png`.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=2))]
    pub frames_per_submit: u32,
    /// Seconds between a submission's two frames (default: one 90 Hz period).
    #[arg(long, default_value_t = crate::renderer::DEFAULT_DT)]
    pub dt: f32,
    /// Keep unchanged pixels: a frame at the last frame's pose redraws only the tiles
    /// something changed (`on` refuses what never can; `auto` draws such frames whole).
    #[arg(long, value_enum, default_value = "off")]
    pub keep_unchanged: crate::keep::KeepUnchanged,
}

/// Where animations are posed, as the command line asks.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum PosingArg {
    /// On the GPU where the cull runs there (the faster: docs/performance.md), else on
    /// the CPU.
    Auto,
    Cpu,
    Gpu,
}

impl PosingArg {
    /// The renderer's posing for a cull on `cull`.
    pub fn resolve(self, cull: CullMode) -> PosingMode {
        match (self, cull) {
            (PosingArg::Gpu, _) | (PosingArg::Auto, CullMode::Gpu) => PosingMode::Gpu,
            _ => PosingMode::Cpu,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Switch {
    On,
    Off,
}

impl Switch {
    pub fn on(self) -> bool {
        self == Switch::On
    }
}

/// Writes `image` to `path` (its extension names the format).
/// The tiles and pixels a frame with `stats` redrew (no tiles where drawn whole), read
/// back: the GPU marks the tiles where it culls.
pub(crate) fn redrawn(
    renderer: &crate::renderer::Renderer,
    gpu: &crate::device::Gpu,
    stats: &crate::renderer::FrameStats,
) -> Result<(u32, u64)> {
    let diagnostics = renderer.diagnostics(&gpu.device, &gpu.queue);
    let tiles = match stats.whole_redraw {
        Some(_) => 0,
        None => diagnostics.tiles_changed()?,
    };
    Ok((tiles, diagnostics.pixels_redrawn()?))
}

pub(crate) fn save(image: &image::RgbaImage, path: &std::path::Path) -> Result<()> {
    image.save(path).map_err(|source| Error::Image {
        path: path.to_path_buf(),
        source,
    })
}

impl SceneArgs {
    /// The renderer options these arguments choose (LOD, coarse cull).
    pub fn options(&self) -> RendererOptions {
        RendererOptions {
            lod: self.lod.on(),
            coarse_cull: self.coarse_cull,
            rig_cull: self.rig_cull.on(),
            occlusion: self.occlusion,
            shadows: self.shadows.on(),
            far_layer: self.far_layer.on(),
            far_threshold_px: self.far_threshold,
            inset_cull: self.inset_cull.on(),
            visibility_mask: self.visibility_mask.on(),
            motion_vectors: self.motion_vectors.on(),
            frames_per_submit: self.frames_per_submit,
            dt: self.dt,
            keep_unchanged: self.keep_unchanged,
            exposure: self.exposure,
            tonemap: self.tonemap,
            ..Default::default()
        }
    }

    /// The rig `--rig` names, with the viewer and resolution options applied; `scene`
    /// (what `--scene` loads) places the viewer where `--viewer fit` or a camera does.
    pub fn load_rig(&self, scene: &Scene) -> Result<Rig> {
        let mut rig = Rig::load(&self.rig)?;
        if let Some(y) = self.yaw {
            rig.viewer.yaw_deg = y;
        }
        if let Some(p) = self.pitch {
            rig.viewer.pitch_deg = p;
        }
        for d in &mut rig.displays {
            d.resolution = [
                self.width.unwrap_or(d.resolution[0]),
                self.height.unwrap_or(d.resolution[1]),
            ];
        }
        self.place_viewer(&mut rig, scene)
            .map_err(|m| Error::rig(&self.rig, m))?;
        if let Some([yaw, pitch]) = self.gaze {
            rig.set_gaze(Gaze::both(yaw, pitch))
                .map_err(|m| Error::rig(&self.rig, format!("--gaze: {m}")))?;
        }
        rig.validate(&self.rig)?;
        match self.displays.is_empty() {
            true => Ok(rig),
            false => rig.subset(&self.displays, &self.rig),
        }
    }
}

/// `--viewer`: a spot, or `fit`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ViewerSpot {
    /// x,y,z in meters.
    At([f32; 3]),
    /// Back from the scene's bounds until every eye sees them ([`framing::fit_viewer`]).
    Fit,
}

fn parse_viewer(s: &str) -> std::result::Result<ViewerSpot, String> {
    match s {
        "fit" => Ok(ViewerSpot::Fit),
        _ => parse_vec3(s).map(ViewerSpot::At),
    }
}

fn parse_exposure(s: &str) -> std::result::Result<Exposure, String> {
    match s {
        "auto" => Ok(Exposure::Auto),
        _ => match s.parse::<f32>() {
            Ok(ev) if ev.is_finite() => Ok(Exposure::Ev100(ev)),
            _ => Err(format!("{s:?}: `auto` or an EV100 (a finite number)")),
        },
    }
}

fn parse_lights(s: &str) -> std::result::Result<(u32, u64), String> {
    let (n, seed) = s.split_once(':').unwrap_or((s, "1"));
    let n = n.parse().map_err(|e| format!("{n:?}: {e}"))?;
    let seed = seed.parse().map_err(|e| format!("{seed:?}: {e}"))?;
    Ok((n, seed))
}

impl SceneArgs {
    /// The scene `--scene` names, with `--lights`' lights.
    pub fn load_scene(&self) -> Result<crate::scene::Scene> {
        let mut scene = crate::scene_spec::load(&self.scene)?;
        if let Some((n, seed)) = self.lights {
            crate::procedural::scatter_lights(&mut scene, n, seed);
        }
        Ok(scene)
    }

    /// Where `--viewer` and `--camera` put the viewer, or (neither given) the scene
    /// file's first camera, else `fit`; a generated scene, or any scene on a rig with
    /// a display fixed in the room, keeps the rig's spot.
    fn place_viewer(&self, rig: &mut Rig, scene: &Scene) -> std::result::Result<(), String> {
        // A room-fixed rig (a CAVE) stands where it is built; only a head moves.
        let framed = crate::scene_spec::is_file(&self.scene) && framing::moves_with_head(rig);
        let turned = self.yaw.is_some() || self.pitch.is_some();
        let camera = match (self.camera, self.viewer) {
            (Some(n), _) => Some(n),
            (None, None) if framed && !turned && !scene.cameras.is_empty() => Some(0),
            _ => None,
        };
        if let Some(n) = camera {
            let Some(c) = scene.cameras.get(n) else {
                let have = scene.cameras.len();
                return Err(format!("--camera {n}: the scene has {have} camera(s)"));
            };
            return framing::view_through(rig, c).map_err(|m| format!("camera {n}: {m}"));
        }
        match self.viewer {
            Some(ViewerSpot::At(p)) => rig.viewer.position = p,
            Some(ViewerSpot::Fit) => self.fit(rig, scene)?,
            None if framed => self.fit(rig, scene)?,
            None => {}
        }
        Ok(())
    }

    /// `fit`, looking down by [`framing::FIT_ELEVATION_DEG`] unless `--pitch` says.
    fn fit(&self, rig: &mut Rig, scene: &Scene) -> std::result::Result<(), String> {
        if self.pitch.is_none() {
            rig.viewer.pitch_deg = -framing::FIT_ELEVATION_DEG;
        }
        let bounds = scene.bounds().ok_or("--viewer fit: the scene is empty")?;
        framing::fit_viewer(rig, bounds).map(|_| ())
    }
}

fn parse_vec3(s: &str) -> std::result::Result<[f32; 3], String> {
    parse_finite(s, "three finite numbers x,y,z")
}

pub(crate) fn parse_pair(s: &str) -> std::result::Result<[f32; 2], String> {
    parse_finite(s, "two finite numbers yaw,pitch")
}

/// `N` comma-separated finite numbers; `expected` says what they are in the error.
fn parse_finite<const N: usize>(s: &str, expected: &str) -> std::result::Result<[f32; N], String> {
    let parts: Vec<f32> = s
        .split(',')
        .map(|p| p.trim().parse::<f32>().map_err(|e| format!("{p:?}: {e}")))
        .collect::<std::result::Result<_, _>>()?;
    match <[f32; N]>::try_from(parts) {
        Ok(v) if v.iter().all(|x| x.is_finite()) => Ok(v),
        _ => Err(format!("{s:?}: expected {expected}")),
    }
}

pub fn run() -> Result<()> {
    match Cli::parse().command {
        None => render::render(&render::RenderArgs::parse_from(["render"])),
        Some(Command::Info(InfoArgs { scene: Some(scene) })) => scene_info(&scene),
        Some(Command::Info(_)) => info(),
        Some(Command::Cull(args)) => cull::cull(&args),
        Some(Command::Render(args)) => render::render(&args),
        Some(Command::Stress(args)) => stress::stress(&args),
        Some(Command::Profile(args)) => profile::profile(&args),
        Some(Command::Diff(args)) => diff::diff(&args),
        #[cfg(feature = "cluster")]
        Some(Command::Cluster(args)) => cluster::cluster(&args),
    }
}

fn info() -> Result<()> {
    let gpu = Gpu::headless()?;
    println!("adapter: {}", gpu.adapter_line());
    let features = gpu.device.features();
    println!("tier: {}", Tier::of(features).name());
    for (feature, name, without) in OPTIONAL_FEATURES {
        if features.contains(feature) {
            println!("  {name:40} yes");
        } else {
            println!("  {name:40} no  (costs: {without})");
        }
    }
    let info = gpu.device.adapter_info();
    let (low, high) = (info.subgroup_min_size, info.subgroup_max_size);
    match crate::shaders::subgroup_tier(&gpu.device) {
        true => println!("GPU cull's workgroup scan: subgroup operations (subgroups of {low})"),
        false => println!(
            "GPU cull's workgroup scan: workgroup memory (subgroups {low} to {high}, or none)"
        ),
    }
    println!(
        "coarse cull with --coarse-cull auto, GPU culling on this adapter: off with the rig \
         cull (it reads each sphere once for the rig); with --rig-cull off \
         (sphere tests expected with it / without):"
    );
    let apart = RendererOptions {
        rig_cull: false,
        ..Default::default()
    };
    for preset in crate::rig::PRESETS {
        let resolved = Rig::preset(preset)?.resolve()?;
        let expected = resolved.expected_coarse_tests();
        let on = apart.coarse_for(&resolved, Some(&gpu.device));
        let gains = apart.coarse_for(&resolved, None);
        let why = match (on, gains) {
            (false, true) => "; a software adapter: indirect validation costs more",
            _ => "",
        };
        println!(
            "  {preset:40} {}  ({expected:.2}{why})",
            if on { "on " } else { "off" }
        );
    }
    println!(
        "occlusion with --occlusion auto (GPU culling, instanced or single-sampled \
         multiview, displays of one or two views, no far layer): on for a display from a \
         triangle per pixel of it, the scene's instances at their finest level:"
    );
    for preset in crate::rig::PRESETS {
        let rig = Rig::preset(preset)?;
        let pixels = |d: &crate::rig::Display| {
            let [w, h] = d.resolution;
            w as u64 * h as u64 * d.views().min(2) as u64
        };
        let from: Vec<String> = (rig.displays.iter())
            .map(|d| match d.views() {
                1 | 2 => format!("{} from {:.1}M", d.name, pixels(d) as f64 / 1e6),
                _ => format!("{} never (foveated)", d.name),
            })
            .collect();
        println!("  {preset:40} {}", from.join(", "));
    }
    Ok(())
}

/// `info --scene`: a glTF file's extensions (required ones marked) and whether each is
/// read, then what the scene loads as (no adapter is opened).
fn scene_info(spec: &str) -> Result<()> {
    println!("scene: {spec}");
    let gltf = [".gltf", ".glb"]
        .iter()
        .any(|e| spec.to_lowercase().ends_with(e));
    if gltf {
        let uses = crate::gltf_import::extension_uses(Path::new(spec))?;
        if uses.is_empty() {
            println!("  extensions: none");
        }
        for u in uses {
            let what = match (u.read, u.required) {
                (true, _) => "read",
                (false, false) => "not read: drawn without it",
                (false, true) => "not read, and required: the file is refused",
            };
            let name = format!("{}{}", u.name, if u.required { " (required)" } else { "" });
            println!("  extension {name:48} {what}");
        }
    }
    let scene = crate::scene_spec::load(spec)?;
    let triangles: u64 = (scene.instances.iter())
        .map(|i| scene.meshes[i.mesh as usize].index_count as u64 / 3)
        .sum();
    println!(
        "  loads: {} instances of {} meshes ({} triangles at the finest level), {} materials, {} textures, {} skins, {} morphs, {} lights",
        scene.instances.len(),
        scene.meshes.len(),
        triangles,
        scene.materials.len(),
        scene.textures.len(),
        scene.skins.skins.len(),
        scene.morphs.morphs.len(),
        scene.lights.len(),
    );
    for (n, camera) in scene.cameras.iter().enumerate() {
        println!("  camera {n}: {}", camera.describe());
    }
    Ok(())
}

pub fn write_json(path: &Path, value: &impl Serialize) -> Result<()> {
    let text = serde_json::to_string(value).expect("plain data always serializes");
    std::fs::write(path, text).map_err(|e| Error::io(path, e))
}
