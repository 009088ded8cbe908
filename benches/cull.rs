//! CPU culling throughput in instances x displays per second (criterion's "elem"): one
//! display (`hmd`) and five culled in one pass (`cave`), on all cores and on one; and
//! `hmd-peripheral`'s three displays with and without the coarse cull's blocks.
//!
//! Then the GPU cull over its floor kernel (`gpu_cull`): a procedural scene with LOD on,
//! `hmd` and `cave`, the rig cull and the per-display culls, each timed by the wall clock
//! in rounds that alternate it with the floor (`Diagnostics::cull_against_floor`), as
//! `profile`'s `cull_over_floor` does. On lavapipe the wall clock is the cost.
//!
//! `cargo bench --bench cull` (`-- gpu_cull` for the GPU part alone); under
//! `cargo test` one short round of each on a small scene.

use criterion::{Criterion, Throughput};
use stereocull::cull::cpu;
use stereocull::cull::{FrameCull, FrameLod};
use stereocull::device::Gpu;
use stereocull::procedural;
use stereocull::records::CullLayout;
use stereocull::renderer::{DisplayTarget, OcclusionMode, Renderer, RendererOptions, WallCulls};
use stereocull::rig::Rig;
use stereocull::shaders::subgroup_tier;

fn cull(c: &mut Criterion) {
    let single = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");
    let mut group = c.benchmark_group("cpu_cull");
    for preset in ["hmd", "cave"] {
        let rig = Rig::preset(preset).expect("preset");
        let displays = rig.cull_jobs().expect("display frusta");
        for n in [100_000u32, 1_000_000] {
            let layout = CullLayout::new(&procedural::scene(n, 64, 1));
            group.throughput(Throughput::Elements(n as u64 * displays.len() as u64));
            group.bench_function(format!("{preset}/{n}/all_cores"), |b| {
                b.iter(|| cpu::cull_many(&layout, &displays))
            });
            group.bench_function(format!("{preset}/{n}/one_core"), |b| {
                b.iter(|| single.install(|| cpu::cull_many(&layout, &displays)))
            });
        }
    }
    group.finish();
}

fn coarse(c: &mut Criterion) {
    let mut group = c.benchmark_group("cpu_coarse_cull");
    let rig = Rig::preset("hmd-peripheral").expect("preset");
    let displays = rig.cull_jobs().expect("display frusta");
    let test = rig.resolve().expect("resolves").coarse_cull(false);
    let n = 1_000_000u32;
    let layout = CullLayout::new(&procedural::scene(n, 8, 1));
    group.throughput(Throughput::Elements(n as u64 * displays.len() as u64));
    for (name, coarse) in [("on", Some(test)), ("off", None)] {
        let frame = FrameCull {
            lod: FrameLod::OFF,
            coarse,
        };
        group.bench_function(format!("hmd-peripheral/{n}/{name}"), |b| {
            b.iter(|| cpu::cull_frame(&layout, &displays, &frame))
        });
    }
    group.finish();
}

/// The GPU cull over its floor: per rig and path, the floor's and the whole cull's wall
/// milliseconds and their ratio, and each display's own cull over the floor. `profile`'s
/// scene (`procedural:N`, 8 meshes, LOD on) at 16 x 16 pixels an eye, so that the one
/// frame drawn first (which builds the bind groups the rounds reuse) costs little.
fn gpu_cull(benching: bool, filter: Option<&str>) {
    let gpu = Gpu::headless().expect("no adapter: install mesa-vulkan-drivers (lavapipe)");
    println!("adapter: {}", gpu.adapter_line());
    let tier = match subgroup_tier(&gpu.device) {
        true => "subgroup operations",
        false => "workgroup memory",
    };
    println!("the display cull pass's scan: {tier}");
    let (n, rounds) = match benching {
        true => (1_000_000, 15),
        false => (20_000, 1),
    };
    let scene = procedural::scene(n, 8, 1);
    println!("gpu_cull: procedural:{n}, 8 meshes, LOD on, {rounds} rounds, wall-clock medians");
    for preset in ["hmd", "cave"] {
        let mut rig = Rig::preset(preset).expect("preset");
        for d in &mut rig.displays {
            d.resolution = [16, 16];
        }
        for rig_cull in [true, false] {
            let name = format!("gpu_cull/{preset}/{}", path_name(rig_cull));
            if filter.is_some_and(|f| !name.contains(f)) {
                continue;
            }
            let options = RendererOptions {
                lod: true,
                rig_cull,
                cull_floor: true,
                occlusion: OcclusionMode::Off,
                ..Default::default()
            };
            let wall = timed(&gpu, &scene, &rig, options, rounds);
            report(&name, &rig, &wall);
        }
    }
}

/// One frame drawn, then the cull against its floor in `rounds` rounds.
fn timed(
    gpu: &Gpu,
    scene: &stereocull::scene::Scene,
    rig: &Rig,
    options: RendererOptions,
    rounds: u32,
) -> WallCulls {
    let mut renderer = Renderer::new(&gpu.device, scene, rig, options).expect("renderer");
    let targets = renderer.create_targets(&gpu.device);
    renderer.prepare(&gpu.queue, rig, 0.0).expect("prepare");
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    let views: Vec<_> = targets.iter().map(DisplayTarget::views).collect();
    renderer.encode(&mut encoder, &views, None).expect("encode");
    gpu.queue.submit([encoder.finish()]);
    let diagnostics = renderer.diagnostics(&gpu.device, &gpu.queue);
    // A round first, untimed: llvmpipe compiles a pipeline at its first dispatch.
    diagnostics.cull_against_floor(1).expect("warm-up");
    (diagnostics.cull_against_floor(rounds).expect("timed"))
        .expect("a GPU cull with its floor kernel")
}

fn path_name(rig_cull: bool) -> &'static str {
    match rig_cull {
        true => "rig",
        false => "per_display",
    }
}

fn report(name: &str, rig: &Rig, wall: &WallCulls) {
    println!(
        "{name}: floor {:.1} ms, whole cull {:.1} ms, cull over floor {:.2}",
        wall.floor_ms,
        wall.rig_ms,
        wall.rig_ms / wall.floor_ms
    );
    let names = rig.displays.iter().map(|d| d.name.as_str());
    for (name, ms) in names.zip(&wall.views_ms) {
        let ratio = ms / wall.floor_ms;
        println!("  {name}: {ms:.1} ms alone, over floor {ratio:.2}");
    }
}

fn main() {
    let benching = std::env::args().any(|a| a == "--bench");
    // criterion's filter, the first argument that is no flag: the GPU part runs the
    // configurations whose names hold it (`gpu_cull`: all of them, `gpu_cull/hmd`: one
    // rig's), none of criterion's names holds `gpu_cull`.
    let filter = std::env::args().skip(1).find(|a| !a.starts_with('-'));
    let mut c = Criterion::default().configure_from_args();
    cull(&mut c);
    coarse(&mut c);
    c.final_summary();
    gpu_cull(benching, filter.as_deref());
}
