//! CPU culling throughput in instances x displays per second (criterion's "elem"): one
//! display (`hmd`) and five culled in one pass (`cave`), on all cores and on one; and
//! `hmd-peripheral`'s three displays with and without the coarse cull's blocks.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use stereocull::cull::cpu;
use stereocull::cull::{FrameCull, FrameLod};
use stereocull::procedural;
use stereocull::records::CullLayout;
use stereocull::rig::Rig;

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

criterion_group!(benches, cull, coarse);
criterion_main!(benches);
