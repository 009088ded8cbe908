//! Unchanged pixels kept ([`stereocull::keep`]): over frames that hold the head still
//! and then move it, with instances moving, inserted, removed, recolored and animated,
//! every frame a renderer keeping unchanged pixels draws equals the frame one drawing
//! whole draws; GPU and CPU culls agree; a tile whose only instance left is redrawn.
//!
//! Exact comparisons: a kept pixel is the last frame's, which the full redraw draws
//! again from the same inputs; a redrawn tile is drawn by the same pipelines from the
//! same draws (a subset, in the same order), so each of its pixels sees the same
//! fragments in the same order and llvmpipe, deterministic, writes the same bytes.

mod support;

use glam::{Vec3, Vec4};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use stereocull::error::Error;
use stereocull::live::LiveScene;
use stereocull::renderer::{
    CullMode, KeepUnchanged, OcclusionMode, Renderer, RendererOptions, WholeRedraw,
};
use stereocull::scene::{Animation, Instance, Scene};
use stereocull::scene_spec;
use support::keep::Run;
use support::{Tolerance, assert_images_match, gpu, sized};

fn options(cull: CullMode, keep: KeepUnchanged) -> RendererOptions {
    RendererOptions {
        cull,
        occlusion: OcclusionMode::Off,
        keep_unchanged: keep,
        ..Default::default()
    }
}

/// A procedural scene, every 300th instance spinning or bobbing.
fn scene() -> Scene {
    let mut scene = scene_spec::load("procedural:3000:4").unwrap();
    let mut rng = Pcg64Mcg::seed_from_u64(7);
    for instance in scene.instances.iter_mut().step_by(300) {
        instance.animation = Animation {
            spin: rng.random_range(0.5..3.0),
            bob: rng.random_range(0.0..0.2),
        };
    }
    scene
}

/// Frame `frame`'s edits, the same in every run (a fixed seed per frame): a third of 1 % of the
/// instances moved, some recolored, and some removed (odd frames) and inserted again
/// elsewhere (even frames: `removed` holds them in between).
fn edit(live: &mut LiveScene, frame: u64, removed: &mut Vec<Instance>) {
    let mut rng = Pcg64Mcg::seed_from_u64(100 + frame);
    let handles = live.handles();
    let n = handles.len();
    for _ in 0..n / 300 {
        let h = handles[rng.random_range(0..n)];
        let mut moved = live.get(h).unwrap().world_from_local;
        moved.translation += glam::Vec3A::new(rng.random_range(-0.3..0.3), 0.0, 0.2);
        live.set_transform(h, moved).unwrap();
    }
    for _ in 0..3 {
        let h = handles[rng.random_range(0..n)];
        let color = Vec4::new(rng.random(), rng.random(), rng.random(), 1.0);
        live.set_color(h, color).unwrap();
    }
    // Inserted where removed instances left their meshes' places: no layout again.
    match frame % 2 {
        1 => {
            for _ in 0..4 {
                // A handle drawn twice is already gone.
                if let Ok(instance) = live.remove(handles[rng.random_range(0..n)]) {
                    removed.push(instance);
                }
            }
        }
        _ => {
            for mut instance in removed.drain(..) {
                instance.world_from_local.translation += glam::Vec3A::new(0.0, 0.5, 0.0);
                live.insert(instance).unwrap();
            }
        }
    }
}

#[test]
fn every_kept_frame_is_the_frame_drawn_whole() {
    let gpu = gpu();
    let scene = scene();
    let still = sized("hmd", 192, 160);
    let mut turned = still.clone();
    turned.viewer.yaw_deg += 3.0;
    // Still, then a turn and back, then still again: the two frames after the turn
    // are drawn whole while the bounds the turn did not track are taken again.
    let rigs = [
        &still, &still, &still, &still, &turned, &still, &still, &still, &still, &still,
    ];
    for cull in [CullMode::Gpu, CullMode::Cpu] {
        let mut kept = Run::new(&gpu, &scene, &still, options(cull, KeepUnchanged::On));
        let mut whole = Run::new(&gpu, &scene, &still, options(cull, KeepUnchanged::Off));
        let mut kept_frames = 0;
        let mut removed = [Vec::new(), Vec::new()];
        for (f, rig) in rigs.iter().enumerate() {
            let time = 0.5 + f as f32 / 90.0;
            if f > 0 {
                edit(&mut kept.live, f as u64, &mut removed[0]);
                edit(&mut whole.live, f as u64, &mut removed[1]);
            }
            let (stats, got) = kept.frame(&gpu, rig, time);
            let (_, want) = whole.frame(&gpu, rig, time);
            let name = format!("keep-{cull:?}-{f}");
            // Exact on any CPU: both images come from the same compiled pipelines on
            // this host, drawing the same draws in the same order (the module's note).
            assert_images_match(&name, &got[0], &want[0], Tolerance::EXACT);
            let expected = match f {
                0 => Some(WholeRedraw::FirstFrame),
                4 | 5 => Some(WholeRedraw::Pose),
                6 | 7 => Some(WholeRedraw::Settling),
                _ => None,
            };
            assert_eq!(stats.whole_redraw, expected, "{name}");
            if expected.is_none() {
                kept_frames += 1;
                let tiles = (192 * 2 / 16) * (160 / 16);
                let diagnostics = kept.renderer.diagnostics(&gpu.device, &gpu.queue);
                let changed = diagnostics.tiles_changed().unwrap();
                assert!(
                    changed > 0 && changed < tiles,
                    "{name}: {changed} of {tiles} tiles changed"
                );
                // The CPU counts the tiles it marks; the GPU's are read back.
                let counted = if cull == CullMode::Cpu { changed } else { 0 };
                assert_eq!(stats.tiles_changed, counted, "{name}");
                // The target is whole tiles: 256 pixels each.
                let pixels = diagnostics.pixels_redrawn().unwrap();
                assert_eq!(pixels, 256 * u64::from(changed), "{name}");
            } else {
                let diagnostics = kept.renderer.diagnostics(&gpu.device, &gpu.queue);
                let pixels = diagnostics.pixels_redrawn().unwrap();
                assert_eq!(pixels, 2 * 192 * 160, "{name}: every view's pixels");
            }
        }
        assert_eq!(kept_frames, 5);
    }
}

/// The GPU cull and the CPU cull of a kept frame keep the same instances: those that
/// touch a changed tile. The tiles the GPU marks (`wgsl/keep_mark.wgsl`) are the bits
/// its CPU twin marks, frame after frame.
#[test]
fn the_gpu_and_cpu_culls_of_a_kept_frame_are_the_same_bytes() {
    let gpu = gpu();
    let scene = scene();
    for preset in ["hmd", "cave"] {
        let rig = sized(preset, 192, 160);
        let mut runs = [CullMode::Gpu, CullMode::Cpu]
            .map(|c| Run::new(&gpu, &scene, &rig, options(c, KeepUnchanged::On)));
        let mut removed = [Vec::new(), Vec::new()];
        for f in 0..3 {
            for (run, removed) in runs.iter_mut().zip(&mut removed) {
                if f > 0 {
                    edit(&mut run.live, f, removed);
                }
                let (stats, _) = run.frame(&gpu, &rig, 1.0 + f as f32 / 90.0);
                assert_eq!(stats.whole_redraw.is_none(), f > 0, "{preset} frame {f}");
            }
            for d in (0..rig.displays.len()).filter(|_| f > 0) {
                let [marked_on_gpu, marked_on_cpu] = runs.each_ref().map(|r| {
                    let diagnostics = r.renderer.diagnostics(&gpu.device, &gpu.queue);
                    diagnostics.changed_tiles(d).unwrap().unwrap()
                });
                let name = format!("{preset} frame {f} display {d}");
                assert_eq!(marked_on_gpu, marked_on_cpu, "{name}: tiles marked");
                assert!(marked_on_gpu.iter().any(|&w| w != 0), "{name}: none marked");
            }
        }
        let [on_gpu, on_cpu] = runs.map(|r| support::read_culls(&gpu, &r.renderer, &rig));
        let mut whole = Run::new(
            &gpu,
            &scene,
            &rig,
            options(CullMode::Gpu, KeepUnchanged::Off),
        );
        whole.frame(&gpu, &rig, 1.0);
        let whole = support::read_culls(&gpu, &whole.renderer, &rig);
        for (d, (got, want)) in on_gpu.iter().zip(&on_cpu).enumerate() {
            support::assert_same_cull(&format!("{preset} display {d}"), got, want);
            assert!(
                got.visible.len() < whole[d].visible.len(),
                "{preset} display {d}: the kept frame's cull kept {} of {}",
                got.visible.len(),
                whole[d].visible.len()
            );
        }
    }
}

/// An instance removed from a tile nothing else covers leaves the clear color there: a
/// keeper that forgot the instance's bounds before the change would keep it drawn.
/// With MSAA too: the tiles' clear covers every sample, the resolve the whole target.
#[test]
fn a_removed_instance_alone_in_its_tiles_is_cleared() {
    let gpu = gpu();
    let at = |x: f32| (Vec3::new(x, 1.6, -6.0), 0);
    let scene = support::cubes(&[at(-2.5), at(0.0), at(2.5)], 1);
    let rig = sized("hmd", 96, 80);
    for samples in [1, 4] {
        let options = |keep| RendererOptions {
            sample_count: samples,
            ..options(CullMode::Gpu, keep)
        };
        let mut kept = Run::new(&gpu, &scene, &rig, options(KeepUnchanged::On));
        let mut whole = Run::new(&gpu, &scene, &rig, options(KeepUnchanged::Off));
        let (_, before) = kept.frame(&gpu, &rig, 0.0);
        for run in [&mut kept, &mut whole] {
            let alone = run.live.handles()[2];
            run.live.remove(alone).unwrap();
        }
        let (stats, got) = kept.frame(&gpu, &rig, 0.0);
        let (_, want) = whole.frame(&gpu, &rig, 0.0);
        assert_eq!(stats.whole_redraw, None);
        let name = format!("keep-removed-x{samples}");
        // Exact on any CPU: one host's pipelines on both sides; the tiles' clear writes
        // the stored level of the clear color, which any rounding keeps.
        assert_images_match(&name, &got[0], &want[0], Tolerance::EXACT);
        assert_ne!(
            before[0], got[0],
            "{name}: the removed cube was drawn and is gone"
        );
    }
}

/// What never keeps is refused with `on` and drawn whole with `auto`, with its reason.
#[test]
fn what_cannot_keep_is_refused_or_drawn_whole_with_its_reason() {
    let gpu = gpu();
    let scene = scene_spec::load("procedural:200:4").unwrap();
    let hmd = sized("hmd", 32, 32);
    let with = |keep| RendererOptions {
        motion_vectors: true,
        ..options(CullMode::Gpu, keep)
    };
    match Renderer::new(&gpu.device, &scene, &hmd, with(KeepUnchanged::On)) {
        Err(Error::Unsupported(m)) => assert!(m.contains("motion"), "{m}"),
        other => panic!("not refused: {:?}", other.err()),
    }
    let auto = Run::new(&gpu, &scene, &hmd, with(KeepUnchanged::Auto));
    let mut auto = auto;
    for _ in 0..2 {
        let stats = (auto.renderer)
            .submit_frame(&gpu.device, &gpu.queue, &hmd, 0.0, &auto.targets)
            .unwrap();
        assert!(
            matches!(stats.whole_redraw, Some(WholeRedraw::Unsupported(m)) if m.contains("motion")),
            "{:?}",
            stats.whole_redraw
        );
    }
    // A light that changes lights pixels far from any instance, through a sync or
    // set directly.
    let mut run = Run::new(
        &gpu,
        &scene,
        &hmd,
        options(CullMode::Gpu, KeepUnchanged::On),
    );
    run.frame(&gpu, &hmd, 0.0);
    let lit = stereocull::lights::Light::point(Vec3::new(0.0, 3.0, -4.0), Vec3::ONE, 10.0, None);
    run.live.insert_light(lit).unwrap();
    let (stats, _) = run.frame(&gpu, &hmd, 0.0);
    assert_eq!(stats.whole_redraw, Some(WholeRedraw::Scene));
    let (stats, _) = run.frame(&gpu, &hmd, 0.0);
    assert_eq!(stats.whole_redraw, None);
    run.renderer.set_lights(&[lit]).unwrap();
    let (stats, _) = run.frame(&gpu, &hmd, 0.0);
    assert_eq!(stats.whole_redraw, Some(WholeRedraw::Scene));
    // A latch would move every kept pixel.
    run.renderer.prepare(&gpu.queue, &hmd, 0.0).unwrap();
    assert!(matches!(
        run.renderer.latch(&gpu.queue, &hmd),
        Err(Error::Unsupported(_))
    ));
}
