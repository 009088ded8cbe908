//! Unchanged pixels kept with content the time poses ([`stereocull::keep`]): node
//! animations, skins and morph targets, posed on the CPU or on the GPU. The GPU marks
//! the tiles their spheres cover before and after the frame's pose
//! (`wgsl/keep_mark.wgsl`), so a GPU-posed instance, which the CPU never sees move,
//! still has its tiles redrawn. Every kept frame must equal the frame drawn whole.
//!
//! Exact comparisons: as in `tests/keep.rs`, both images come from one host's pipelines
//! drawing the same draws in the same order (the kept frame's a subset, per tile the
//! same fragments), and a kept pixel is the last frame's, which the full redraw draws
//! again from the same inputs.

mod support;

use stereocull::device::Gpu;
use stereocull::renderer::{
    CullMode, KeepUnchanged, OcclusionMode, PosingMode, RendererOptions, WholeRedraw,
};
use stereocull::rig::Rig;
use stereocull::scene::Scene;
use stereocull::scene_spec;
use support::keep::Run;
use support::{Tolerance, assert_images_match, gpu, sized};

fn options(cull: CullMode, posing: PosingMode, keep: KeepUnchanged) -> RendererOptions {
    RendererOptions {
        cull,
        posing,
        occlusion: OcclusionMode::Off,
        keep_unchanged: keep,
        ..Default::default()
    }
}

fn load(spec: &str) -> Scene {
    scene_spec::load(spec).unwrap()
}

/// Four frames with the head still and the time running: the first drawn whole, the
/// rest kept, each equal to the frame drawn whole, and each redrawing part of the
/// tiles but some.
fn assert_kept_frames(gpu: &Gpu, label: &str, scene: &Scene, rig: &Rig, options: RendererOptions) {
    let whole_options = RendererOptions {
        keep_unchanged: KeepUnchanged::Off,
        ..options.clone()
    };
    let mut kept = Run::new(gpu, scene, rig, options);
    let mut whole = Run::new(gpu, scene, rig, whole_options);
    let tiles: u32 = (rig.displays.iter())
        .map(|d| (2 * d.resolution[0]).div_ceil(16) * d.resolution[1].div_ceil(16))
        .sum();
    for f in 0..4 {
        let time = 0.4 + 0.15 * f as f32;
        let (stats, got) = kept.frame(gpu, rig, time);
        let (_, want) = whole.frame(gpu, rig, time);
        let name = format!("{label}-{f}");
        for (d, (got, want)) in got.iter().zip(&want).enumerate() {
            // Exact on any CPU: one host's pipelines draw both, the kept frame's draws a
            // subset of the full frame's in the same order (the module's note).
            assert_images_match(&format!("{name}-{d}"), got, want, Tolerance::EXACT);
        }
        let expected = (f == 0).then_some(WholeRedraw::FirstFrame);
        assert_eq!(stats.whole_redraw, expected, "{name}");
        let diagnostics = kept.renderer.diagnostics(&gpu.device, &gpu.queue);
        let changed = diagnostics.tiles_changed().unwrap();
        assert!(
            f == 0 || (changed > 0 && changed < tiles),
            "{name}: {changed} of {tiles} tiles changed"
        );
    }
}

/// A node animation (BoxAnimated), a skin (SimpleSkin) and a walking crowd (skins and
/// node animations) keep their unchanged pixels: posed on the CPU with either cull, and
/// posed on the GPU, where only the GPU's marks know what moved.
#[test]
fn posed_content_keeps_unchanged_pixels() {
    let gpu = gpu();
    let sample = |name, ext| load(support::gltf_sample(name, ext).to_str().unwrap());
    let scenes = [
        ("box", sample("BoxAnimated", "glb"), [1.5, 1.0, 9.0], "hmd"),
        ("skin", sample("SimpleSkin", "gltf"), [0.5, 1.0, 5.0], "hmd"),
        ("crowd", load("crowd:40:4"), [0.0, 1.6, 0.0], "hmd"),
        ("crowd", load("crowd:40:4"), [0.0, 1.6, 0.0], "cave"),
    ];
    let ways = [
        (CullMode::Gpu, PosingMode::Gpu),
        (CullMode::Gpu, PosingMode::Cpu),
        (CullMode::Cpu, PosingMode::Cpu),
    ];
    for (name, scene, viewer, preset) in scenes {
        let mut rig = sized(preset, 96, 80);
        rig.viewer.position = viewer;
        for (cull, posing) in ways {
            let label = format!("keep-{name}-{preset}-{cull:?}-{posing:?}");
            let options = options(cull, posing, KeepUnchanged::On);
            assert_kept_frames(&gpu, &label, &scene, &rig, options);
        }
    }
}

/// Morph targets played by their animations keep their unchanged pixels (the grid of
/// `support::morph`, with either cull), also on a copy of a grid that no node poses:
/// only its morph moves it.
#[test]
fn morph_targets_keep_unchanged_pixels() {
    let gpu = gpu();
    let mut scene = support::morph::morph_scene();
    let mut copy = scene.instances[0];
    copy.world_from_local.translation += glam::Vec3A::new(-1.4, 0.0, 0.0);
    scene.instances.push(copy);
    assert!(scene.posing.instances.iter().all(|n| n.instance != 2));
    let mut rig = sized("hmd", 96, 80);
    rig.viewer.position = [-1.2, 0.5, 3.0];
    for cull in [CullMode::Gpu, CullMode::Cpu] {
        let options = options(cull, PosingMode::Cpu, KeepUnchanged::On);
        assert_kept_frames(&gpu, &format!("keep-morph-{cull:?}"), &scene, &rig, options);
    }
}

/// Weights set by hand move every instance of the mesh: the next frame is drawn whole.
#[test]
fn morph_weights_set_by_hand_redraw_whole() {
    let gpu = gpu();
    let scene = support::morph::morph_scene();
    let rig = sized("hmd", 96, 80);
    let options = options(CullMode::Gpu, PosingMode::Cpu, KeepUnchanged::On);
    let mut run = Run::new(&gpu, &scene, &rig, options);
    run.frame(&gpu, &rig, 0.0);
    let weights = vec![0.5; scene.morphs.morphs[0].defaults.len()];
    run.renderer.set_morph_weights(0, &weights).unwrap();
    let (stats, _) = run.frame(&gpu, &rig, 0.0);
    assert_eq!(stats.whole_redraw, Some(WholeRedraw::Scene));
}
