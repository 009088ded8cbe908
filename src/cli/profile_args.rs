//! What `stereocull profile` is asked: the configurations it measures side by side
//! (each list one dimension of them) and how long it runs them.

use std::path::PathBuf;

use clap::Args;

use super::Switch;
use crate::renderer::{CoarseMode, CullMode, OcclusionMode, StereoMode};

#[derive(Args)]
pub struct ProfileArgs {
    /// Instance counts (procedural scenes, seed 1).
    #[arg(long, value_delimiter = ',', default_value = "1000,10000,100000")]
    pub instances: Vec<u32>,
    /// Presets or rig files (several compare rigs in one run: stereo against mono,
    /// foveated against uniform).
    #[arg(long, value_delimiter = ',', default_value = "hmd")]
    pub rig: Vec<String>,
    /// Both eyes' gaze (yaw,pitch degrees) on the foveated rigs' displays: insets that
    /// follow it (smaller) instead of fixed foveation. Other rigs are unaffected.
    #[arg(long, value_parser = super::parse_pair, allow_hyphen_values = true)]
    pub gaze: Option<[f32; 2]>,
    #[arg(
        long,
        value_delimiter = ',',
        value_enum,
        default_value = "multi-camera,multi-pass,single-pass,instanced,multiview"
    )]
    pub modes: Vec<StereoMode>,
    #[arg(long, value_delimiter = ',', value_enum, default_value = "gpu,cpu")]
    pub cull: Vec<CullMode>,
    #[arg(long, default_value = "profile")]
    pub out: PathBuf,
    /// Timed frames per configuration, after the warm-up.
    #[arg(long, default_value_t = 10)]
    pub frames: u32,
    #[arg(long, default_value_t = 3)]
    pub warmup: u32,
    /// Per-eye resolution of every display (small keeps software rasterizers quick).
    #[arg(long, default_value_t = 128)]
    pub width: u32,
    #[arg(long, default_value_t = 128)]
    pub height: u32,
    /// Built-in meshes in the procedural scenes.
    #[arg(long, default_value_t = 8)]
    pub meshes: u32,
    /// MSAA samples per pixel (1: none).
    #[arg(long, default_value_t = 1)]
    pub msaa: u32,
    /// Give every mesh a base color texture (`procedural:N:M:1:textured`).
    #[arg(long)]
    pub textured: bool,
    /// Percents of the meshes made blended glass (`procedural:N:M:1:glassP`), one
    /// configuration each (`0,1,10` measures the blended sort against none in one run).
    #[arg(long, value_delimiter = ',', default_value = "0")]
    pub glass: Vec<f64>,
    /// Profile `city:N` scenes (a room and buildings 200 m to 2 km away) instead.
    #[arg(long)]
    pub city: bool,
    /// Profile `rooms:N` scenes (rooms with doorways, props inside: occluders) instead.
    #[arg(long, conflicts_with = "city")]
    pub rooms: bool,
    /// Profile `crowd:N` scenes (N skinned figures walking, posed and skinned every
    /// frame on the 90 Hz clock, posing timed as the frame's CPU work) instead.
    #[arg(long, conflicts_with_all = ["city", "rooms"])]
    pub crowd: bool,
    /// Occlusion culling, one configuration each (`on,off` compares them in one run).
    #[arg(long, value_delimiter = ',', value_enum, default_value = "auto")]
    pub occlusion: Vec<OcclusionMode>,
    /// Where animations are posed, one configuration each (`cpu,gpu` compares them;
    /// `gpu` runs with GPU culling only; auto: the GPU where the cull runs there).
    #[arg(long, value_delimiter = ',', value_enum, default_value = "auto")]
    pub posing: Vec<super::PosingArg>,
    /// Frames per submission, one configuration each (`1,2` compares dt multiview
    /// with a submission per frame; 2 runs `instanced` only).
    #[arg(long, value_delimiter = ',', default_value = "1")]
    pub frames_per_submit: Vec<u32>,
    /// Seconds between a submission's two frames.
    #[arg(long, default_value_t = crate::renderer::DEFAULT_DT)]
    pub dt: f32,
    /// Keeping unchanged pixels, one configuration each (`off,on` compares them): the
    /// profile's viewer holds still, so each frame after the first redraws only the
    /// tiles its moved instances (`--moving`) changed. What never keeps is skipped.
    #[arg(long, value_delimiter = ',', value_enum, default_value = "off")]
    pub keep_unchanged: Vec<crate::keep::KeepUnchanged>,
    /// Levels of detail chosen on the GPU from the viewer's position.
    #[arg(long, value_enum, default_value = "off")]
    pub lod: Switch,
    /// Percents of instances moved every frame, one configuration each (`0,1,10`
    /// measures what moves cost against the static scene in one run).
    #[arg(long, value_delimiter = ',', default_value = "0")]
    pub moving: Vec<f64>,
    /// Percent of instances removed and inserted again every frame.
    #[arg(long, default_value_t = 0.0)]
    pub churn: f64,
    /// The frame's shadow map, drawn once per frame.
    #[arg(long, value_enum, default_value = "off")]
    pub shadows: Switch,
    /// The far layer, one configuration each (`on,off` compares them).
    #[arg(long, value_delimiter = ',', value_enum, default_value = "off")]
    pub far_layer: Vec<Switch>,
    /// Foveated rigs' inset cull, one configuration each (`on,off` compares them; rigs
    /// without a foveated display run `off` only).
    #[arg(long, value_delimiter = ',', value_enum, default_value = "off")]
    pub inset_cull: Vec<Switch>,
    /// Pixels the eyes' images of a far instance may differ by.
    #[arg(long, default_value_t = crate::far_layer::FAR_THRESHOLD_PX)]
    pub far_threshold: f32,
    /// The lens's hidden area drawn and culled by (the rigs' masks; `instanced` and
    /// `multiview`): two runs compare it.
    #[arg(long, value_enum, default_value = "off")]
    pub visibility_mask: Switch,
    /// Each display's draw also writes motion vectors (`instanced`, without the far
    /// layer or foveation): two runs compare it.
    #[arg(long, value_enum, default_value = "off")]
    pub motion_vectors: Switch,
    /// The frame-level coarse cull, one configuration each (`on,off` compares them).
    #[arg(long, value_delimiter = ',', value_enum, default_value = "auto")]
    pub coarse_cull: Vec<CoarseMode>,
    /// GPU culling: the rig cull (every display's frustum cull in one set of
    /// dispatches), one configuration each (`on,off` compares it with a set per
    /// display).
    #[arg(long, value_delimiter = ',', value_enum, default_value = "on")]
    pub rig_cull: Vec<Switch>,
    /// Also write a Chrome trace (chrome://tracing, Perfetto) of the last timed frame of
    /// every configuration: per display a scope, per pass (`cull`, `draw`) one inside it.
    #[arg(long)]
    pub trace: Option<PathBuf>,
}
