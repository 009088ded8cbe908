//! Optional features forced off (the pipeline falls back or says clearly what it cannot
//! do) and hostile transforms (dropped and counted, the rest untouched).

mod support;

use glam::{Affine3A, Vec3};
use image::RgbaImage;
use stereocull::Error;
use stereocull::device::Gpu;
use stereocull::profiling::GpuTimer;
use stereocull::readback::read_rgba8;
use stereocull::renderer::{CullMode, Renderer, RendererOptions, StereoMode};
use stereocull::rig::Rig;
use stereocull::{procedural, scene_spec};
use support::{Tolerance, assert_images_match, frustum_only};

fn gpu_without(missing: wgpu::Features) -> Gpu {
    let gpu = support::gpu_with(wgpu::Features::all() - missing);
    assert!(!gpu.device.features().intersects(missing));
    gpu
}

fn rig() -> Rig {
    support::sized("hmd", 160, 120)
}

fn render(gpu: &Gpu, mode: StereoMode, cull: CullMode) -> Result<RgbaImage, Error> {
    let scene = scene_spec::load("default")?;
    let options = RendererOptions {
        mode,
        cull,
        ..frustum_only()
    };
    Ok(support::render(gpu, &scene, &rig(), options.clone())?.remove(0))
}

/// The image tests' tolerance (see `tests/images.rs`): channels within 2 levels, at most
/// 0.05 % of pixels beyond.
const EDGES: Tolerance = Tolerance {
    levels: 2,
    share: 0.0005,
};

fn full() -> RgbaImage {
    render(
        &gpu_without(wgpu::Features::empty()),
        StereoMode::Instanced,
        CullMode::Gpu,
    )
    .unwrap()
}

/// Clipping at the seam splits triangles, so the rasterizer sees different edges and a
/// pixel or two near the seam change coverage (measured: 2 of 38,400 pixels, by 79 levels);
/// same tolerance as the image tests (2 levels, 0.05 % beyond).
#[test]
fn without_clip_distances_the_discard_fallback_gives_the_same_image() {
    let gpu = gpu_without(wgpu::Features::CLIP_DISTANCES);
    let image = render(&gpu, StereoMode::Instanced, CullMode::Gpu).unwrap();
    assert_images_match("discard-fallback", &image, &full(), EDGES);
}

#[test]
fn without_indirect_count_the_fixed_count_draw_gives_the_same_image() {
    let gpu = gpu_without(wgpu::Features::MULTI_DRAW_INDIRECT_COUNT);
    let image = render(&gpu, StereoMode::Instanced, CullMode::Gpu).unwrap();
    // Exact on any CPU: the same pipeline draws the same draws; the zeroed tail draws none.
    assert_images_match("fixed-count", &image, &full(), Tolerance::EXACT);
}

#[test]
fn without_first_instance_the_indirect_modes_say_so_and_the_classic_ones_still_draw() {
    let gpu = gpu_without(wgpu::Features::INDIRECT_FIRST_INSTANCE);
    let msg = render(&gpu, StereoMode::Instanced, CullMode::Gpu)
        .unwrap_err()
        .to_string();
    assert!(msg.contains("INDIRECT_FIRST_INSTANCE"), "{msg}");
    let image = render(&gpu, StereoMode::MultiPass, CullMode::Cpu).unwrap();
    // Viewport versus clip-space remap: channels within 2 levels, as in tests/images.rs.
    let within_two_levels = Tolerance {
        levels: 2,
        share: 0.0,
    };
    assert_images_match("no-first-instance", &image, &full(), within_two_levels);
}

#[test]
fn without_multiview_that_mode_is_unavailable_with_a_clear_error() {
    let gpu = gpu_without(wgpu::Features::MULTIVIEW);
    let msg = render(&gpu, StereoMode::Multiview, CullMode::Gpu)
        .unwrap_err()
        .to_string();
    assert!(msg.contains("multiview is unavailable"), "{msg}");
}

/// MSAA counts: without adapter-specific format features only WebGPU's 1x and 4x exist,
/// and the error names them; multiview MSAA needs multisampled arrays; a count the
/// adapter lacks is a typed error even where the renderer cannot know the adapter.
#[test]
fn unsupported_msaa_is_a_clear_error() {
    let msaa = |gpu: &Gpu, mode, sample_count| {
        let options = RendererOptions {
            mode,
            sample_count,
            ..frustum_only()
        };
        let scene = scene_spec::load("default").unwrap();
        Renderer::new(&gpu.device, &scene, &rig(), options).err()
    };
    let webgpu = gpu_without(wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES);
    assert_eq!(webgpu.sample_counts(frustum_only().color_format), [1, 4]);
    let msg = msaa(&webgpu, StereoMode::Instanced, 8)
        .expect("8x accepted")
        .to_string();
    assert!(msg.contains("8x MSAA") && msg.contains("has 1, 4"), "{msg}");
    assert!(msaa(&webgpu, StereoMode::Instanced, 4).is_none());
    let flat = gpu_without(wgpu::Features::MULTISAMPLE_ARRAY);
    let msg = msaa(&flat, StereoMode::Multiview, 4)
        .expect("accepted")
        .to_string();
    assert!(msg.contains("MULTISAMPLE_ARRAY"), "{msg}");
    let full = gpu_without(wgpu::Features::empty());
    let lacking = [2, 8, 16]
        .into_iter()
        .find(|n| !full.sample_counts(frustum_only().color_format).contains(n));
    if let Some(n) = lacking {
        let err = msaa(&full, StereoMode::Instanced, n).expect("a count the adapter lacks");
        assert!(matches!(err, Error::Wgpu(_)), "{n}x: {err}");
    }
}

#[test]
fn without_timestamps_there_is_no_gpu_timer() {
    let gpu = gpu_without(wgpu::Features::TIMESTAMP_QUERY);
    assert!(GpuTimer::new(&gpu.device, &gpu.queue, 4).is_none());
}

#[test]
fn classic_modes_refuse_gpu_culling_with_a_reason() {
    let gpu = gpu_without(wgpu::Features::empty());
    let msg = render(&gpu, StereoMode::SinglePass, CullMode::Gpu)
        .unwrap_err()
        .to_string();
    assert!(msg.contains("--cull cpu"), "{msg}");
}

#[test]
fn non_finite_transforms_are_dropped_and_counted_and_the_rest_kept_in_order() {
    let mut scene = procedural::scene(50, 3, 7);
    let kept: Vec<Vec3> = scene
        .instances
        .iter()
        .enumerate()
        .filter(|(i, _)| i % 10 != 3)
        .map(|(_, inst)| inst.world_from_local.translation.into())
        .collect();
    for (i, inst) in scene.instances.iter_mut().enumerate() {
        if i % 10 == 3 {
            let bad = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY][i % 3];
            inst.world_from_local = Affine3A::from_translation(Vec3::new(bad, 0.0, 0.0));
        }
    }
    assert_eq!(scene.drop_non_finite_instances(), 5);
    let left: Vec<Vec3> = scene
        .instances
        .iter()
        .map(|i| i.world_from_local.translation.into())
        .collect();
    assert_eq!(left, kept);
}

#[test]
fn non_finite_animation_is_dropped_like_a_non_finite_transform() {
    let mut scene = procedural::scene(4, 2, 3);
    scene.instances[1].animation.spin = f32::NAN;
    scene.instances[2].animation.bob = f32::INFINITY;
    let kept = [scene.instances[0], scene.instances[3]];
    assert_eq!(scene.drop_non_finite_instances(), 2);
    assert_eq!(scene.instances, kept);
}

#[test]
fn zero_scale_instances_cull_and_draw_without_nan() {
    let mut scene = procedural::scene(20, 2, 3);
    scene.instances[0].world_from_local = Affine3A::from_scale(Vec3::ZERO);
    assert_eq!(
        scene.drop_non_finite_instances(),
        0,
        "zero scale is finite: kept"
    );
    let sphere = scene.world_sphere(&scene.instances[0]);
    assert!(sphere.is_finite() && sphere.w == 0.0, "{sphere}");
}

/// Instance records and spheres outgrow a binding in windows (tests/windows.rs); what
/// must still fit one binding, 4 bytes of cull flags per instance, stops up front with
/// the numbers (here under a 64 KiB binding limit, as a small device would have).
#[test]
fn more_instances_than_one_binding_holds_stop_up_front_with_the_numbers() {
    let gpu = gpu_without(wgpu::Features::empty());
    let max: u64 = 64 << 10;
    let mut scene = procedural::scene(1, 1, 1);
    let too_many = (max / 4 + 1) as usize;
    scene.instances = vec![scene.instances[0]; too_many];
    let options = RendererOptions {
        binding_limit: Some(max),
        ..frustum_only()
    };
    let err = Renderer::new(&gpu.device, &scene, &rig(), options)
        .err()
        .expect("accepted");
    let msg = err.to_string();
    assert!(matches!(err, Error::Limits(_)), "{msg}");
    assert!(
        msg.contains(&max.to_string()) && msg.contains(&too_many.to_string()),
        "{msg}"
    );
}

/// A device lost mid-run (here destroyed, as a driver reset would) ends the frame loop
/// with `Error::DeviceLost` and its reason; readbacks fail with a typed error instead of
/// hanging or panicking in wgpu's uncaptured-error handler.
#[test]
fn a_lost_device_is_reported_not_a_hang() {
    let gpu = gpu_without(wgpu::Features::empty());
    let scene = scene_spec::load("default").unwrap();
    let mut renderer = Renderer::new(&gpu.device, &scene, &rig(), Default::default()).unwrap();
    let targets = renderer.create_targets(&gpu.device);
    let started = std::time::Instant::now();
    let mut frames = 0;
    let error = loop {
        if frames == 3 {
            gpu.device.destroy();
        }
        let frame = renderer
            .submit_frame(&gpu.device, &gpu.queue, &rig(), 0.0, &targets)
            .and_then(|_| read_rgba8(&gpu.device, &gpu.queue, &targets[0].color))
            .and_then(|_| gpu.check_lost());
        match frame {
            Ok(()) => frames += 1,
            Err(e) => break e,
        }
        assert!(frames < 10, "frames went on after the device was destroyed");
    };
    assert_eq!(frames, 3);
    assert!(started.elapsed().as_secs() < 60);
    eprintln!("after the loss: {error}");
    assert!(matches!(error, Error::Readback(_)), "{error:?}");
    let lost = gpu.check_lost().unwrap_err();
    assert!(lost.to_string().contains("Destroyed"), "{lost}");
    let counts = renderer
        .diagnostics(&gpu.device, &gpu.queue)
        .visible_counts();
    assert!(counts.is_err(), "reading counts of a lost device");
}

#[test]
fn the_tier_names_what_runs_as_designed() {
    use stereocull::device::Tier;
    use wgpu::Features as F;
    let all = F::all();
    assert_eq!(Tier::of(all), Tier::Full);
    for fallback in [
        F::MULTI_DRAW_INDIRECT_COUNT,
        F::CLIP_DISTANCES,
        F::MULTIVIEW,
    ] {
        assert_eq!(Tier::of(all - fallback), Tier::GpuDriven, "{fallback:?}");
    }
    assert_eq!(Tier::of(all - F::INDIRECT_FIRST_INSTANCE), Tier::Classic);
    assert_eq!(Tier::of(F::empty()), Tier::Classic);
    // Profiling features change what is measured, not what is drawn.
    assert_eq!(Tier::of(all - F::TIMESTAMP_QUERY), Tier::Full);
}

/// Vertex and index buffers are not storage bindings: a mesh bigger than one binding
/// (lavapipe: 128 MiB) still fits one buffer and draws.
#[test]
fn vertices_past_the_binding_size_are_accepted_up_to_the_buffer_size() {
    let gpu = gpu_without(wgpu::Features::empty());
    let limits = gpu.device.limits();
    eprintln!(
        "binding {} bytes, buffer {} bytes",
        limits.max_storage_buffer_binding_size, limits.max_buffer_size
    );
    assert!(
        limits.max_buffer_size > limits.max_storage_buffer_binding_size,
        "assumes lavapipe: 128 MiB bindings, larger buffers"
    );
    let mut scene = procedural::scene(1, 1, 1);
    let vertices = (limits.max_storage_buffer_binding_size / 24 + 1) as usize;
    scene.vertices.resize(vertices, scene.vertices[0]);
    Renderer::new(&gpu.device, &scene, &rig(), frustum_only())
        .expect("a vertex buffer past the binding size fits one buffer");
}

/// Materials that do not fit the scene are typed errors when the renderer is made, in
/// every mode: a mesh naming a material the scene lacks, a mesh of two materials, a
/// material naming a texture it lacks, a cutout whose cutoff is not a number.
#[test]
fn materials_naming_what_the_scene_lacks_are_errors() {
    let gpu = support::gpu();
    let mut scene = procedural::scene(20, 2, 7);
    let mesh_1 = scene.meshes[1].base_vertex as usize;
    for v in &mut scene.vertices[mesh_1..] {
        v.material = 1;
    }
    let make = |scene: &stereocull::scene::Scene| {
        StereoMode::ALL.map(|mode| {
            let options = RendererOptions {
                mode,
                cull: support::cull_for(mode),
                ..frustum_only()
            };
            Renderer::new(&gpu.device, scene, &rig(), options).err()
        })
    };
    for err in make(&scene) {
        let msg = err.expect("a mesh naming material 1 of 1").to_string();
        assert!(msg.contains("mesh 1 ("), "{msg}");
        assert!(msg.contains("names material 1 of 1"), "{msg}");
    }
    scene.materials = vec![Default::default(); 2];
    scene.vertices[mesh_1 + 3].material = 0;
    for err in make(&scene) {
        let msg = err.expect("a mesh of two materials").to_string();
        assert!(
            msg.contains("mesh 1 (") && msg.contains("mixes materials 1 and 0"),
            "{msg}"
        );
    }
    scene.materials.clear();
    for v in &mut scene.vertices {
        v.material = 0;
    }
    scene.materials = vec![stereocull::scene::Material {
        name: "stone".into(),
        base_color_texture: Some(0),
        ..Default::default()
    }];
    for err in make(&scene) {
        let msg = err.expect("a material naming texture 0 of 0").to_string();
        assert!(msg.contains("\"stone\" names texture 0 of 0"), "{msg}");
    }
    scene.materials[0].base_color_texture = None;
    scene.materials[0].alpha = stereocull::scene::AlphaMode::Mask { cutoff: f32::NAN };
    for err in make(&scene) {
        let msg = err.expect("a cutoff that is not a number").to_string();
        assert!(msg.contains("\"stone\" has alpha cutoff NaN"), "{msg}");
    }
}
