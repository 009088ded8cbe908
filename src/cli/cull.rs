//! `stereocull cull`: every display's culls of a scene (the CPU's, or the GPU's read
//! back from rendered frames) written as JSON, the cull contract's buffers per display.

use std::path::PathBuf;

use clap::Args;
use serde::Serialize;

use super::{SceneArgs, edits, write_json};
use crate::bins::{BinKind, Bins};
use crate::cull::{CullOutput, cpu};
use crate::device::Gpu;
use crate::error::Result;
use crate::live::LiveScene;
use crate::records::CullLayout;
use crate::renderer::{CullMode, CullView, FramePlan, OcclusionMode, Renderer, RendererOptions};
use crate::rig::Rig;
use crate::scene::Scene;

#[derive(Args)]
pub(super) struct CullArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Write the per-display visible lists and draws here as JSON.
    #[arg(long)]
    dump_visible: PathBuf,
    /// Cull on the CPU (the reference) or on the GPU (buffers read back).
    #[arg(long, value_enum, default_value = "cpu")]
    cull: CullMode,
    /// Frames of edits (`--moving`, `--churn`) before the dump, which shows the last.
    #[arg(long, default_value_t = 1)]
    frames: u32,
    #[command(flatten)]
    edits: edits::EditArgs,
}

/// One display's entry in the `--dump-visible` file.
#[derive(Serialize)]
pub struct DisplayDump {
    pub name: String,
    pub views: u32,
    pub visible: Vec<u32>,
    pub draws: Vec<DrawDump>,
    pub draw_count: u32,
}

#[derive(Serialize)]
pub struct DrawDump {
    /// The material bin (`bins::Bins::kinds` index) whose range holds the draw.
    pub bin: u32,
    /// The bin is blended: a draw per instance, back to front.
    pub blended: bool,
    pub mesh: u32,
    pub index_count: u32,
    pub instance_count: u32,
    pub first_index: u32,
    pub base_vertex: i32,
    pub first_instance: u32,
}

pub fn display_dump(name: &str, views: u32, out: &CullOutput, scene: &Scene) -> DisplayDump {
    let meshes = out.draw_meshes(views, |id| scene.instances[id as usize].mesh);
    let bins = Bins::of(scene);
    DisplayDump {
        name: name.into(),
        views,
        visible: out.visible.clone(),
        draws: out
            .packed_draws()
            .zip(meshes)
            .map(|(d, mesh)| DrawDump {
                bin: bins.of_mesh[mesh as usize],
                blended: bins.kinds[bins.of_mesh[mesh as usize] as usize].alpha == BinKind::Blend,
                mesh,
                index_count: d.index_count,
                instance_count: d.instance_count,
                first_index: d.first_index,
                base_vertex: d.base_vertex,
                first_instance: d.first_instance,
            })
            .collect(),
        draw_count: out.draw_count,
    }
}

pub(super) fn cull(args: &CullArgs) -> Result<()> {
    let scene = args.scene.load_scene()?;
    let rig = args.scene.load_rig(&scene)?;
    let mut live = LiveScene::new(scene);
    let mut driver = edits::EditDriver::new(&live, &args.edits)?;
    let options = args.scene.options();
    let culls = match (args.cull, options.occlusion) {
        // Occlusion culls what frames drew: on the CPU too, the renderer's frames (their
        // pyramids read back halfway).
        (CullMode::Gpu, _) | (CullMode::Cpu, OcclusionMode::On) => {
            let options = RendererOptions {
                cull: args.cull,
                ..options.clone()
            };
            rendered_cull(&rig, options, &mut live, &mut driver, args.frames)?
        }
        (CullMode::Cpu, _) => {
            for frame in 0..args.frames {
                driver.apply(&mut live, frame)?;
            }
            cpu_cull(&rig, &options, live.scene())?
        }
    };
    let scene = live.scene();
    let views = |d: &crate::rig::Display| match (options.inset_cull, d.views()) {
        (true, 4) => 2,
        (_, views) => views,
    };
    let near = rig
        .displays
        .iter()
        .zip(&culls.near)
        .map(|(d, out)| display_dump(&d.name, views(d), out, scene));
    // With the far layer, each stereo display's far cull follows as `<name>.far`; with
    // the inset cull, each foveated display's inset cull as `<name>.inset`; with
    // occlusion, `<name>` is the early phase and `<name>.late` the late one.
    let extra = |list: &[Option<CullOutput>], tag: &str, v: Option<u32>| {
        let dumps = rig.displays.iter().zip(list).filter_map(|(d, out)| {
            Some(display_dump(
                &format!("{}.{tag}", d.name),
                v.unwrap_or_else(|| views(d)),
                out.as_ref()?,
                scene,
            ))
        });
        dumps.collect::<Vec<_>>()
    };
    let displays: Vec<_> = near
        .chain(extra(&culls.far, "far", Some(1)))
        .chain(extra(&culls.inset, "inset", Some(2)))
        .chain(extra(&culls.late, "late", None))
        .collect();
    write_json(
        &args.dump_visible,
        &serde_json::json!({ "displays": displays }),
    )
}

/// A frame's culls per display: its own, its far layer's and its insets'.
struct Culls {
    near: Vec<CullOutput>,
    far: Vec<Option<CullOutput>>,
    inset: Vec<Option<CullOutput>>,
    /// With occlusion (GPU culling), each display's late phase; `near` is then its
    /// early phase.
    late: Vec<Option<CullOutput>>,
}

/// Every display's cull and, with the far layer, each stereo display's far cull (with
/// the inset cull, each foveated display's inset cull): the renderer's CPU cull of the
/// frame's plan.
fn cpu_cull(rig: &Rig, options: &RendererOptions, scene: &Scene) -> Result<Culls> {
    let resolved = rig.resolve()?;
    let coarse = options.coarse_for(&resolved, None);
    let plan = FramePlan::of(rig, resolved, options, coarse, 0.0)?;
    let layout = CullLayout::new(scene);
    let outputs = cpu::cull_frame(&layout, &plan.jobs(), &plan.cull);
    let inset_culls = plan.inset_culls();
    let apart: Vec<_> = inset_culls.iter().map(|c| c.job.clone()).collect();
    let insets = cpu::cull_many_lod(&layout, &apart, &plan.cull.lod);
    let n = rig.displays.len();
    let (mut near, mut far, mut inset) = (vec![None; n], vec![None; n], vec![None; n]);
    let planned = plan.culls().into_iter().chain(inset_culls);
    for (cull, out) in planned.zip(outputs.into_iter().chain(insets)) {
        match cull.view {
            CullView::Display(i) => near[i] = Some(out),
            CullView::Far(i) => far[i] = Some(out),
            CullView::Inset(i) => inset[i] = Some(out),
            CullView::Eye(..) | CullView::Late(_) | CullView::Light => {}
        }
    }
    let near = near.into_iter().map(Option::unwrap_or_default).collect();
    let late = vec![None; n];
    Ok(Culls {
        near,
        far,
        inset,
        late,
    })
}

/// `frames` frames culled as `options` say, each after its edits are synced; the last
/// frame's cull buffers (and far layers', insets' and late phases' culls) read back.
fn rendered_cull(
    rig: &Rig,
    options: RendererOptions,
    live: &mut LiveScene,
    driver: &mut edits::EditDriver,
    frames: u32,
) -> Result<Culls> {
    let gpu = Gpu::headless()?;
    let mut renderer = Renderer::new(&gpu.device, live.scene(), rig, options)?;
    let targets = renderer.create_targets(&gpu.device);
    for frame in 0..frames {
        driver.apply(live, frame)?;
        renderer.sync(&gpu.device, &gpu.queue, live)?;
        renderer.submit_frame(&gpu.device, &gpu.queue, rig, 0.0, &targets)?;
    }
    let displays = 0..rig.displays.len();
    let diagnostics = renderer.diagnostics(&gpu.device, &gpu.queue);
    Ok(Culls {
        near: displays
            .clone()
            .map(|i| diagnostics.cull(i))
            .collect::<Result<_>>()?,
        far: displays
            .clone()
            .map(|i| diagnostics.far_cull(i))
            .collect::<Result<_>>()?,
        inset: displays
            .clone()
            .map(|i| diagnostics.inset_cull(i))
            .collect::<Result<_>>()?,
        late: displays
            .map(|i| diagnostics.late_cull(i))
            .collect::<Result<_>>()?,
    })
}
