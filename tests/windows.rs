//! Past one binding: instance records and spheres larger than a storage binding are
//! bound as windows of one buffer. With a binding limit of 80 KiB (records in five
//! windows, spheres in two), culls keep the contract byte for byte, images are those of
//! whole bindings, and moved instances (the scatter writes through the windows) too.

mod support;

use glam::{Affine3A, Quat, Vec3};
use image::RgbaImage;
use rand::{Rng, SeedableRng};
use stereocull::live::LiveScene;
use stereocull::readback::read_rgba8;
use stereocull::renderer::{CullMode, Renderer, RendererOptions};
use stereocull::rig::Rig;
use stereocull::scene::Scene;
use stereocull::shaders::{Window, Windows};
use stereocull::{cull, scene_spec};
use support::{Tolerance, assert_images_match, frustum_only};

const LIMIT: u64 = 80 << 10;

fn options(windowed: bool) -> RendererOptions {
    RendererOptions {
        binding_limit: windowed.then_some(LIMIT),
        ..frustum_only()
    }
}

#[test]
fn a_small_binding_limit_splits_records_and_spheres() {
    let w = Windows::new(5000, LIMIT);
    assert_eq!(
        w.instances,
        Window {
            count: 5,
            shift: 10
        }
    );
    assert_eq!(
        w.spheres,
        Window {
            count: 2,
            shift: 12
        }
    );
}

/// GPU culls through windows equal the CPU reference on every preset, with and without
/// levels of detail and the coarse cull.
#[test]
fn windowed_culls_keep_the_contract() {
    let gpu = support::gpu();
    let scene = scene_spec::load("procedural:5000:9").unwrap();
    for preset in support::PRESETS {
        let rig = support::sized(preset, 32, 32);
        for lod in [false, true] {
            // With four levels the cull flags (16 bytes an instance) must fit a binding.
            let limit = if lod { 96 << 10 } else { LIMIT };
            let options = RendererOptions {
                lod,
                binding_limit: Some(limit),
                ..frustum_only()
            };
            let renderer = support::one_frame(&gpu, &scene, &rig, options);
            let resolved = rig.resolve().unwrap();
            let frame = cull::cpu::FrameCull {
                lod: stereocull::renderer::frame_lod(
                    &rig,
                    &resolved,
                    renderer.options().lod_levels(),
                ),
                coarse: None,
            };
            let layout = stereocull::records::CullLayout::new(&scene);
            let want = cull::cpu::cull_frame(&layout, &rig.cull_jobs().unwrap(), &frame);
            let got = support::read_culls(&gpu, &renderer, &rig);
            assert_eq!(got, want, "{preset} lod {lod}");
        }
    }
}

fn images(
    gpu: &stereocull::device::Gpu,
    renderer: &mut Renderer,
    (rig, scene): (&Rig, &mut Option<&mut LiveScene>),
) -> Vec<RgbaImage> {
    if let Some(live) = scene {
        renderer.sync(&gpu.device, &gpu.queue, live).unwrap();
    }
    let targets = renderer.create_targets(&gpu.device);
    renderer
        .submit_frame(&gpu.device, &gpu.queue, rig, 0.5, &targets)
        .unwrap();
    targets
        .iter()
        .map(|t| read_rgba8(&gpu.device, &gpu.queue, &t.color).unwrap())
        .collect()
}

/// The same frames, windowed and whole: the default scene with shadows and the far
/// layer, and a procedural scene whose instances move (the scatter writes records and
/// spheres through the windows), GPU and CPU culled.
#[test]
fn windowed_bindings_draw_what_whole_ones_draw() {
    let gpu = support::gpu();
    let rig = support::sized("hmd", 96, 96);
    let room = scene_spec::load("default").unwrap();
    // The room's 41 instances: records in three windows of 16.
    let features = |windowed: bool| RendererOptions {
        shadows: true,
        far_layer: true,
        far_threshold_px: 4.0,
        binding_limit: windowed.then_some(1024),
        ..frustum_only()
    };
    let [whole, windowed] = [false, true].map(|w| {
        let mut renderer = Renderer::new(&gpu.device, &room, &rig, features(w)).unwrap();
        images(&gpu, &mut renderer, (&rig, &mut None))
    });
    // Exact: the windowed shaders differ only in which binding a record or sphere is
    // loaded from; every expression after the load is the same, so LLVM contracts it the
    // same way (exact on AMD EPYC and on Intel Xeon).
    assert_images_match("windows-room", &windowed[0], &whole[0], Tolerance::EXACT);

    let scene: Scene = scene_spec::load("procedural:5000:9").unwrap();
    for cull in [CullMode::Gpu, CullMode::Cpu] {
        let [whole, windowed] = [false, true].map(|w| {
            let mut live = LiveScene::new(scene.clone());
            let options = RendererOptions { cull, ..options(w) };
            let mut renderer = Renderer::new(&gpu.device, live.scene(), &rig, options).unwrap();
            let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(5);
            for handle in live.handles().into_iter().step_by(7) {
                let at = Vec3::new(
                    rng.random_range(-3.0..3.0),
                    1.6,
                    rng.random_range(-6.0..0.0),
                );
                let moved = Affine3A::from_rotation_translation(Quat::IDENTITY, at);
                live.set_transform(handle, moved).unwrap();
            }
            images(&gpu, &mut renderer, (&rig, &mut Some(&mut live)))
        });
        let name = format!("windows-moved-{cull:?}");
        // Exact for the reason above.
        assert_images_match(&name, &windowed[0], &whole[0], Tolerance::EXACT);
    }
}
