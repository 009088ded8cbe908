//! `stereocull profile`: every stereo mode and cull mode at several instance counts, on
//! one adapter in one run, so that the ratios between them mean something.

use indicatif::{ProgressBar, ProgressStyle};

use super::edits::EditArgs;
pub use super::profile_args::ProfileArgs;
use super::profile_measure::{Config, measure};
use super::profile_ratios::{print_frames, print_keep};
use super::profile_report::{
    price_edits, price_occlusion, print_glass, print_occlusion, print_table, write_csv,
};
use super::{chart, write_json};
use crate::device::{Gpu, list_counts};
use crate::error::{Error, Result};
use crate::keep::KeepUnchanged;
use crate::procedural;
use crate::profiling::{GpuTimer, write_trace};
use crate::renderer::{CullMode, PosingMode, RendererOptions, StereoMode};
use crate::rig::Rig;

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
        * args.posing.len()
        * args.frames_per_submit.len()
        * args.keep_unchanged.len();
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
                .flat_map(|v| args.frames_per_submit.iter().map(move |f| (v, *f)))
                .flat_map(|v| args.keep_unchanged.iter().map(move |k| (v, *k)))
                .collect();
            for (
                &(mode, cull),
                &(
                    (((((moving, (coarse, rig_cull), far), inset), occlusion), posing), frames),
                    keep,
                ),
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
                if frames == 2 && mode != StereoMode::Instanced {
                    println!(
                        "skipped {} with two frames per submission: instanced only",
                        mode.name()
                    );
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
                    frames,
                    keep,
                };
                match measure(&gpu, &scene, &config, args, timer.as_mut(), &bar) {
                    // What can never keep pixels is refused with `on`: said, not run.
                    Err(Error::Unsupported(why)) if keep == KeepUnchanged::On => {
                        println!("skipped {} with --keep-unchanged on: {why}", mode.name());
                    }
                    row => rows.push(row?),
                }
            }
        }
    }
    bar.finish_and_clear();
    price_edits(&mut rows);
    price_occlusion(&mut rows);
    print_table(&rows);
    print_occlusion(&rows);
    print_glass(&rows);
    print_frames(&rows);
    print_keep(&rows);
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
