//! `stereocull profile`: every stereo mode and cull mode at several instance counts, on
//! one adapter in one run, so that the ratios between them mean something.

use std::path::PathBuf;

use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};

use super::edits::EditArgs;
use super::profile_measure::{Config, measure};
use super::profile_report::{
    price_edits, price_occlusion, print_glass, print_occlusion, print_table, write_csv,
};
use super::{Switch, chart, write_json};
use crate::device::{Gpu, list_counts};
use crate::error::{Error, Result};
use crate::procedural;
use crate::profiling::{GpuTimer, write_trace};
use crate::renderer::{
    CoarseMode, CullMode, OcclusionMode, PosingMode, RendererOptions, StereoMode,
};
use crate::rig::Rig;

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

pub fn profile(args: &ProfileArgs) -> Result<()> {
    let gpu = Gpu::headless()?;
    let rigs = args
        .rig
        .iter()
        .map(|spec| {
            let mut rig = Rig::load(spec)?;
            for d in &mut rig.displays {
                d.resolution = [args.width, args.height];
                if let (Some(f), Some([yaw, pitch])) = (&mut d.foveation, args.gaze) {
                    f.gaze = Some(crate::rig::Gaze::both(yaw, pitch));
                }
            }
            rig.validate(spec)?;
            Ok((spec.as_str(), rig))
        })
        .collect::<Result<Vec<_>>>()?;
    let counts = gpu.sample_counts(RendererOptions::default().color_format);
    if !counts.contains(&args.msaa) {
        return Err(Error::Unsupported(format!(
            "--msaa {}: this adapter renders at {} samples per pixel",
            args.msaa,
            list_counts(&counts)
        )));
    }
    let configs = configurations(&gpu, args);
    let most_displays = rigs
        .iter()
        .map(|(_, r)| r.displays.len())
        .max()
        .unwrap_or(1) as u32;
    let mut timer = GpuTimer::new(&gpu.device, &gpu.queue, 4 * most_displays);
    if timer.is_none() {
        println!("GPU timings unavailable: the adapter has no TIMESTAMP_QUERY; CPU timings only");
    }
    let variants = args.glass.len()
        * args.moving.len()
        * args.coarse_cull.len()
        * args.rig_cull.len()
        * args.far_layer.len()
        * args.inset_cull.len()
        * args.occlusion.len()
        * args.posing.len();
    let total = (rigs.len() * args.instances.len() * configs.len() * variants) as u64
        * (args.frames + args.warmup) as u64;
    let bar = ProgressBar::new(total);
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} frames {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let mut rows = Vec::new();
    for (&n, &glass) in (args.instances.iter()).flat_map(|n| args.glass.iter().map(move |g| (n, g)))
    {
        let mut scene = match (args.city, args.rooms, args.crowd) {
            (true, _, _) => procedural::city(n, 1),
            (_, true, _) => procedural::rooms(n, 1),
            (_, _, true) => crate::crowd::scene(n, 1),
            _ => procedural::scene(n, args.meshes, 1),
        };
        if args.textured {
            procedural::texture(&mut scene);
        }
        procedural::glaze(&mut scene, glass);
        for (spec, rig) in &rigs {
            let variants: Vec<_> = args
                .moving
                .iter()
                .flat_map(|m| args.coarse_cull.iter().map(move |c| (*m, *c)))
                .flat_map(|(m, c)| args.rig_cull.iter().map(move |r| (m, (c, r.on()))))
                .flat_map(|(m, c)| args.far_layer.iter().map(move |f| (m, c, f.on())))
                .flat_map(|v| args.inset_cull.iter().map(move |i| (v, i.on())))
                .filter(|(_, inset)| !inset || rig.displays.iter().any(|d| d.views() == 4))
                .flat_map(|v| args.occlusion.iter().map(move |o| (v, *o)))
                .flat_map(|v| args.posing.iter().map(move |p| (v, *p)))
                .collect();
            for (
                &(mode, cull),
                &((((moving, (coarse, rig_cull), far), inset), occlusion), posing),
            ) in configs
                .iter()
                .flat_map(|c| variants.iter().map(move |v| (c, v)))
            {
                bar.set_message(format!(
                    "{spec} {n} {} {cull:?} {moving} % moving",
                    mode.name()
                ));
                let refused = crate::renderer::check_rig(
                    rig,
                    &RendererOptions {
                        mode,
                        ..Default::default()
                    },
                    gpu.device.limits().max_multiview_view_count,
                );
                if let Err(e) = refused {
                    println!("skipped {} on {spec}: {e}", mode.name());
                    continue;
                }
                let posing = posing.resolve(cull);
                if posing == PosingMode::Gpu && cull == CullMode::Cpu {
                    println!(
                        "skipped {} with a CPU cull: posing on the GPU needs the GPU cull",
                        mode.name()
                    );
                    continue;
                }
                let config = Config {
                    spec,
                    rig,
                    mode,
                    cull,
                    coarse,
                    rig_cull,
                    far,
                    inset,
                    occlusion,
                    posing,
                    edits: EditArgs {
                        moving,
                        churn: args.churn,
                    },
                    glass,
                };
                rows.push(measure(&gpu, &scene, &config, args, timer.as_mut(), &bar)?);
            }
        }
    }
    bar.finish_and_clear();
    price_edits(&mut rows);
    price_occlusion(&mut rows);
    print_table(&rows);
    print_occlusion(&rows);
    print_glass(&rows);
    std::fs::create_dir_all(&args.out).map_err(|e| Error::io(&args.out, e))?;
    write_csv(&args.out.join("profile.csv"), &rows)?;
    write_json(&args.out.join("profile.json"), &rows)?;
    let chart = args.out.join("profile.svg");
    std::fs::write(&chart, chart::chart_svg(&rows)).map_err(|e| Error::io(&chart, e))?;
    if let Some(path) = &args.trace {
        let frames = rows
            .iter()
            .map(|r| {
                let cull = r.cull_name();
                let label = format!("{} {} {cull} {}", r.rig, r.mode.name(), r.instances);
                (label, r.trace.clone())
            })
            .collect();
        write_trace(path, frames)?;
        println!("wrote {}", path.display());
    }
    println!(
        "wrote {}/profile.csv, profile.json, profile.svg",
        args.out.display()
    );
    Ok(())
}

/// The requested (mode, cull) pairs this adapter can run; says why it skips any.
fn configurations(gpu: &Gpu, args: &ProfileArgs) -> Vec<(StereoMode, CullMode)> {
    let multiview = gpu.device.features().contains(wgpu::Features::MULTIVIEW);
    let mut out = Vec::new();
    for &mode in &args.modes {
        for &cull in &args.cull {
            if mode.per_instance() && cull == CullMode::Gpu {
                println!(
                    "skipped {} with GPU culling: it records a draw per visible instance, so it culls on the CPU",
                    mode.name()
                );
            } else if mode == StereoMode::Multiview && !multiview {
                println!("skipped multiview: the adapter has no MULTIVIEW");
            } else {
                out.push((mode, cull));
            }
        }
    }
    out.dedup();
    out
}
