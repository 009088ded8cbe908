//! The frame-level coarse cull: its frame test keeps every sphere that any display's or
//! eye's plane test keeps (tried adversarially at frustum corners, where plane tests
//! keep spheres outside the frustum), a block passes the frame's and a display's tests
//! whenever that display keeps one of its members, the draw buffers with and without it
//! are byte-identical, GPU and CPU, over every preset, random rigs and every mode, and
//! on a spatially coherent scene each display tests a fraction of the instances.

mod support;

use glam::{DVec3, Vec3, Vec4};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use stereocull::cull::coarse::{BLOCK, block_of};
use stereocull::cull::{CoarseCull, CullOutput};
use stereocull::device::Gpu;
use stereocull::frustum::{View, sphere_in_planes};
use stereocull::renderer::{CoarseMode, CullMode, RendererOptions, StereoMode};
use stereocull::rig::Rig;
use stereocull::scene::Scene;
use support::frustum_only;

/// Every view whose planes the culls test: each display's combined view, or with
/// `per_eye` each eye's (multi-camera).
fn views(rig: &Rig, per_eye: bool) -> Vec<View> {
    let resolved = rig.resolve().unwrap();
    let displays = resolved.displays.iter();
    match per_eye {
        false => displays.map(|d| d.combined).collect(),
        true => displays.flat_map(|d| d.eyes.iter().copied()).collect(),
    }
}

/// A sphere near a corner of `view`, from 1 mm to 100 m, its center up to two radii
/// from the corner: where the plane test keeps spheres the frustum does not hold.
fn sphere_at_a_corner(view: &View, rng: &mut rand_pcg::Pcg64) -> Vec4 {
    let corner = view.corners()[rng.random_range(0..8)];
    let radius = 10f64.powf(rng.random_range(-3.0..2.0));
    let direction = DVec3::new(
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
    )
    .normalize_or(DVec3::X);
    let center = corner + direction * radius * rng.random_range(0.0..2.0);
    center.as_vec3().extend(radius as f32)
}

/// How many spheres near the corners some view (with `per_eye`, some eye) keeps and the
/// coarse test drops.
fn dropped(rig: &Rig, (coarse, per_eye): (&CoarseCull, bool), seed: u64) -> (u32, u32) {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    let views = views(rig, per_eye);
    let (mut kept, mut lost) = (0, 0);
    for _ in 0..400 {
        let view = &views[rng.random_range(0..views.len())];
        let s = sphere_at_a_corner(view, &mut rng);
        if views
            .iter()
            .any(|v| sphere_in_planes(&v.frustum().planes, s))
        {
            kept += 1;
            lost += u32::from(!coarse.test(s));
        }
    }
    (kept, lost)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn the_coarse_test_keeps_what_any_display_or_eye_keeps(
        rig in support::rig_strategy(),
        seed in any::<u64>(),
    ) {
        for per_eye in [false, true] {
            let coarse = rig.resolve().unwrap().coarse_cull(per_eye);
            let (kept, lost) = dropped(&rig, (&coarse, per_eye), seed);
            prop_assert!(kept > 0);
            prop_assert_eq!(lost, 0, "per eye {}: {} of {} kept spheres dropped; {:?}", per_eye, lost, kept, coarse);
        }
    }
}

/// A block of 1 to 64 spheres around a corner of `view`, `far` meters out along a
/// random direction (rounding grows with distance from the origin), as columns.
fn block_at_a_corner(view: &View, far: f32, rng: &mut rand_pcg::Pcg64) -> [Vec<f32>; 4] {
    let count = rng.random_range(1..=BLOCK as usize);
    let spread = 10f32.powf(rng.random_range(-2.0..1.5));
    let mut columns: [Vec<f32>; 4] = Default::default();
    for _ in 0..count {
        let s = sphere_at_a_corner(view, rng);
        let jitter = Vec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        ) * spread;
        let c = s.truncate() + jitter * rng.random_range(0.0..1.0f32) * far.min(1.0);
        let r = s.w * rng.random_range(0.01..1.0f32);
        for (column, v) in columns.iter_mut().zip([c.x, c.y, c.z, -r]) {
            column.push(v);
        }
    }
    columns
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Blocks of spheres near the views' corners: whenever a view keeps a member, the
    /// block passes the frame test and that view's block test.
    #[test]
    fn a_block_passes_where_a_view_keeps_a_member(
        rig in support::rig_strategy(),
        seed in any::<u64>(),
    ) {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
        for per_eye in [false, true] {
            let frame = rig.resolve().unwrap().coarse_cull(per_eye);
            let views = views(&rig, per_eye);
            let tests: Vec<CoarseCull> =
                views.iter().map(|v| CoarseCull::around(v.frustum().planes)).collect();
            let mut kept = 0;
            for _ in 0..100 {
                let view = &views[rng.random_range(0..views.len())];
                let columns = block_at_a_corner(view, rng.random_range(0.0..4.0), &mut rng);
                let [x, y, z, r] = &columns;
                let block = block_of([x, y, z, r]);
                for (v, test) in views.iter().zip(&tests) {
                    let planes = v.frustum().planes;
                    let member = (0..x.len())
                        .any(|i| sphere_in_planes(&planes, Vec4::new(x[i], y[i], z[i], -r[i])));
                    if member {
                        kept += 1;
                        prop_assert!(frame.test(block.sphere), "frame test dropped {:?}", block);
                        prop_assert!(test.test_block(&block), "block test dropped {:?}", block);
                    }
                }
            }
            prop_assert!(kept > 0);
        }
    }
}

/// The growth of radii is what makes the guarantee: without it the same corner spheres
/// are dropped (so the test above can fail), and with it the frame frustum still
/// narrows (it is no `EVERYTHING`).
#[test]
fn without_grown_radii_corner_spheres_are_dropped() {
    let rig = Rig::preset("hmd-peripheral").unwrap();
    let coarse = rig.resolve().unwrap().coarse_cull(false);
    assert_ne!(coarse, CoarseCull::EVERYTHING);
    eprintln!("hmd-peripheral: radii grow by {}", coarse.inflation);
    assert!(
        (1.0..3.0).contains(&coarse.inflation),
        "{}",
        coarse.inflation
    );
    let bare = CoarseCull {
        inflation: 1.0,
        slack: 0.0,
        ..coarse
    };
    let lost: u32 = (0..8)
        .map(|seed| dropped(&rig, (&bare, false), seed).1)
        .sum();
    assert!(
        lost > 0,
        "no corner sphere separates the bare frame frustum"
    );
    let behind = Vec3::new(0.0, 1.6, 40.0).extend(0.5);
    assert!(
        !coarse.test(behind),
        "a sphere behind the viewer is no candidate"
    );
}

#[test]
fn auto_runs_the_coarse_cull_where_it_pays() {
    let gpu = support::gpu();
    // Without the rig cull, as GPU culling without it and CPU culling decide.
    let auto = |cull| RendererOptions {
        cull,
        rig_cull: false,
        ..frustum_only()
    };
    let on = |preset: &str, cull, device| {
        let resolved = Rig::preset(preset).unwrap().resolve().unwrap();
        auto(cull).coarse_for(&resolved, device)
    };
    for cull in [CullMode::Gpu, CullMode::Cpu] {
        assert!(on("hmd-peripheral", cull, None));
        assert!(on("cave", cull, None));
        assert!(
            !on("hmd", cull, None),
            "one display: the coarse cull would only add tests"
        );
    }
    // The rig cull reads each sphere once for the rig: the GPU needs no coarse cull.
    let resolved = Rig::preset("cave").unwrap().resolve().unwrap();
    let rig_culled = RendererOptions {
        rig_cull: true,
        ..auto(CullMode::Gpu)
    };
    assert!(!rig_culled.coarse_for(&resolved, None));
    let cpu = RendererOptions {
        cull: CullMode::Cpu,
        ..rig_culled
    };
    assert!(cpu.coarse_for(&resolved, None), "the CPU culls as before");
    let software = gpu.device.adapter_info().device_type == wgpu::DeviceType::Cpu;
    assert_eq!(
        on("cave", CullMode::Gpu, Some(&gpu.device)),
        !software,
        "GPU culling on a software adapter: indirect validation costs more"
    );
    assert!(on("cave", CullMode::Cpu, Some(&gpu.device)));
    for (preset, range) in [
        ("hmd-peripheral", 0.3..0.8),
        ("cave", 0.2..0.8),
        ("hmd", 1.0..1.5),
    ] {
        let ratio = Rig::preset(preset)
            .unwrap()
            .resolve()
            .unwrap()
            .expected_coarse_tests();
        assert!(range.contains(&ratio), "{preset}: {ratio}");
    }
}

fn culls(
    scene: &Scene,
    rig: &Rig,
    options: RendererOptions,
) -> (Vec<CullOutput>, Option<Vec<u32>>) {
    culls_on(&support::gpu(), scene, rig, options)
}

fn culls_on(
    gpu: &Gpu,
    scene: &Scene,
    rig: &Rig,
    options: RendererOptions,
) -> (Vec<CullOutput>, Option<Vec<u32>>) {
    let renderer = support::one_frame(gpu, scene, rig, options);
    let outputs = support::read_culls(gpu, &renderer, rig);
    let candidates = renderer
        .diagnostics(&gpu.device, &gpu.queue)
        .candidates()
        .unwrap();
    (outputs, candidates)
}

/// Random scenes on every preset and on random rigs: with the coarse cull forced on, the
/// GPU's and the CPU's draw buffers equal the CPU reference without it, in the indirect
/// modes and (CPU culls per eye) multi-camera, with and without levels of detail.
#[test]
fn draw_buffers_are_the_same_with_and_without_the_coarse_cull() {
    let rigs = support::presets_and_random_rigs(4);
    for (i, rig) in rigs.iter().enumerate() {
        let scene = support::extreme_scene(rig, 3000 + 500 * i as u32, 9, i as u64);
        for (mode, cull, lod) in [
            (StereoMode::Instanced, CullMode::Gpu, false),
            (StereoMode::Instanced, CullMode::Gpu, true),
            (StereoMode::Instanced, CullMode::Cpu, false),
            (StereoMode::MultiCamera, CullMode::Cpu, false),
        ] {
            let options = |coarse_cull| RendererOptions {
                mode,
                cull,
                lod,
                coarse_cull,
                ..frustum_only()
            };
            let (with, candidates) = culls(&scene, rig, options(CoarseMode::On));
            let (without, none) = culls(&scene, rig, options(CoarseMode::Off));
            let case = format!("rig {i} {mode:?} {cull:?} lod {lod}");
            assert_eq!(with, without, "{case}");
            assert_eq!(none, None, "{case}");
            if cull == CullMode::Gpu {
                let n = scene.instances.len() as u32;
                let c = candidates.unwrap_or_else(|| panic!("{case}: no candidate count"));
                assert_eq!(c.len(), with.len(), "{case}: a count per display");
                for (c, out) in c.iter().zip(&with) {
                    let visible = out.visible.len() as u32;
                    let most = n.next_multiple_of(BLOCK);
                    assert!((visible..=most).contains(c), "{case}: {c} candidates");
                    assert_eq!(c % BLOCK, 0, "{case}: whole blocks");
                }
                eprintln!("{case}: {c:?} candidates of {n}");
            }
        }
    }
}

/// Each display's candidates and the frame's sphere tests for `scene` on
/// `hmd-peripheral` with the coarse cull on.
fn listed(scene: &Scene) -> (Vec<u32>, u64) {
    let rig = Rig::preset("hmd-peripheral").unwrap();
    let options = RendererOptions {
        coarse_cull: CoarseMode::On,
        ..frustum_only()
    };
    let gpu = support::gpu();
    let renderer = support::one_frame(&gpu, scene, &rig, options);
    let candidates = renderer
        .diagnostics(&gpu.device, &gpu.queue)
        .candidates()
        .unwrap();
    let tests = renderer
        .diagnostics(&gpu.device, &gpu.queue)
        .sphere_tests()
        .unwrap();
    (candidates.unwrap(), tests.unwrap())
}

/// The procedural scenes' ids follow a Hilbert curve, so each block is compact and
/// each display lists a fraction of them: the frame tests fewer spheres than without
/// the coarse cull. The same instances shuffled make every block span the scene, and
/// nearly everything is listed (still exact: see the byte-identity test above).
#[test]
fn blocks_of_a_coherent_scene_narrow_each_display() {
    let n = 20_000;
    let mut scene = stereocull::procedural::scene(n, 8, 1);
    let (candidates, tests) = listed(&scene);
    eprintln!("coherent: {candidates:?} candidates of {n}, {tests} sphere tests");
    assert!(candidates.iter().all(|&c| c < n * 7 / 10), "{candidates:?}");
    assert!(tests < 3 * n as u64, "{tests}: no fewer than without");

    let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
    for i in (1..scene.instances.len()).rev() {
        scene.instances.swap(i, rng.random_range(0..=i));
    }
    let (candidates, tests) = listed(&scene);
    eprintln!("shuffled: {candidates:?} candidates of {n}, {tests} sphere tests");
    assert!(candidates.iter().all(|&c| c > n * 9 / 10), "{candidates:?}");
    assert!(tests > 3 * n as u64, "{tests}");
}

/// The coarse lists' prefix sums at their edges (issue 24: the coarse cull through the
/// display cull's tree): a block, a workgroup of blocks (256 blocks, 16,384 positions)
/// and one past each, and three workgroups, on `cave` (five slots) and
/// `hmd-peripheral`, with LOD off and on: with the coarse cull on, the
/// GPU's buffers equal its own without it and (LOD off) the CPU reference; on these
/// coherent scenes some display lists a fraction of the positions, so the lists have
/// gaps.
#[test]
fn coarse_lists_match_at_their_edges() {
    let gpu = support::gpu();
    let group = BLOCK * 256;
    let edges = [1, BLOCK, BLOCK + 1, group, group + 1, 40_003];
    let cases = ["cave", "hmd-peripheral"].into_iter().flat_map(|rig| {
        edges
            .iter()
            .flat_map(move |&n| [(rig, n, false), (rig, n, true)])
    });
    for (rig, n, lod) in cases {
        let rig = support::sized(rig, 64, 64);
        let scene = stereocull::procedural::scene(n, 6, n as u64 + 5);
        let options = |coarse_cull| RendererOptions {
            lod,
            coarse_cull,
            ..frustum_only()
        };
        let (got, candidates) = culls_on(&gpu, &scene, &rig, options(CoarseMode::On));
        let (want, _) = culls_on(&gpu, &scene, &rig, options(CoarseMode::Off));
        let case = format!("n={n} lod={lod}");
        assert_eq!(got, want, "{case}");
        if !lod {
            assert_eq!(got, support::reference_culls(&scene, &rig), "{case}");
        }
        let candidates = candidates.unwrap_or_else(|| panic!("{case}: no candidates"));
        eprintln!("{case}: {candidates:?} candidates");
        if n >= group {
            assert!(candidates.iter().any(|&c| c < n * 9 / 10), "{case}");
        }
    }
}
