//! The one test harness every GPU and culling test shares: a headless device, rigs and
//! scenes of test size, the CPU reference cull, rendering, and one image comparison
//! with a stated tolerance that writes the images on failure.
//!
//! Each test binary uses part of it.
#![allow(dead_code)]

pub mod glb;
pub mod keep;
pub mod ktx2;
pub mod morph;
pub mod room;

use std::path::PathBuf;

use glam::{Affine3A, DVec3, DVec4, Quat, Vec3, Vec4};
use image::{Rgba, RgbaImage};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use stereocull::cull::{CullOutput, cpu};
use stereocull::device::Gpu;
use stereocull::procedural;
use stereocull::readback::read_rgba8;
use stereocull::records::CullLayout;
use stereocull::renderer::{
    CullMode, DisplayTarget, OcclusionMode, Renderer, RendererOptions, StereoMode,
};
use stereocull::rig::{Mount, Rig};
use stereocull::scene::{Animation, Instance, Scene};
use stereocull::shapes;

/// A headless device with every optional feature the adapter has. Never skips: no
/// adapter is a failure that says what to install.
pub fn gpu() -> Gpu {
    gpu_with(wgpu::Features::all())
}

/// As [`gpu`], with optional features limited to `allowed` (to test fallbacks).
pub fn gpu_with(allowed: wgpu::Features) -> Gpu {
    gpu_on(None, allowed)
}

/// As [`gpu_with`], on `backends` (else as `WGPU_BACKEND` says).
pub fn gpu_on(backends: Option<wgpu::Backends>, allowed: wgpu::Features) -> Gpu {
    let gpu = Gpu::headless_on(backends, allowed).unwrap_or_else(|e| {
        panic!("{e}: install mesa-vulkan-drivers (lavapipe), and libegl1 libgl1-mesa-dri for GL")
    });
    eprintln!("adapter: {}", gpu.adapter_line());
    gpu
}

/// A preset with every display at `width x height` pixels per eye.
pub fn sized(preset: &str, width: u32, height: u32) -> Rig {
    let mut rig = Rig::preset(preset).unwrap();
    for d in &mut rig.displays {
        d.resolution = [width, height];
    }
    rig
}

/// `meshes` cube meshes of half-size 0.5 (bounding radius sqrt(3)/2), and one unscaled
/// instance per `(position, mesh)`.
pub fn cubes(instances: &[(Vec3, u32)], meshes: u32) -> Scene {
    let mut s = Scene::default();
    for k in 0..meshes {
        let c = shapes::cuboid(Vec3::splat(0.5));
        s.add_mesh(format!("cube{k}"), &c.vertices, &c.indices);
    }
    s.instances = instances
        .iter()
        .map(|&(p, mesh)| Instance {
            world_from_local: Affine3A::from_translation(p),
            mesh,
            color: Vec4::ONE,
            material: None,
            animation: Animation::NONE,
        })
        .collect();
    s
}

/// Options that cull by the frustum alone: for the tests that hold the GPU's buffers
/// to the CPU reference of the frustum cull (with occlusion, `auto` by default, a
/// display's cull is two phases: `tests/occlusion.rs` holds those to their CPU twin).
pub fn frustum_only() -> RendererOptions {
    RendererOptions {
        occlusion: OcclusionMode::Off,
        ..Default::default()
    }
}

/// The CPU reference cull of every display of `rig`, as the `instanced` mode culls.
pub fn reference_culls(scene: &Scene, rig: &Rig) -> Vec<CullOutput> {
    cpu::cull_many(&CullLayout::new(scene), &rig.cull_jobs().unwrap())
}

/// The cull each mode runs: the classic modes draw per instance from a CPU cull; the
/// indirect modes cull on the GPU.
pub fn cull_for(mode: StereoMode) -> CullMode {
    if mode.per_instance() {
        CullMode::Cpu
    } else {
        CullMode::Gpu
    }
}

/// A renderer made with `options` that has submitted one frame of `scene` seen by `rig`
/// at time 0 (into targets of its own).
pub fn one_frame(gpu: &Gpu, scene: &Scene, rig: &Rig, options: RendererOptions) -> Renderer {
    let mut renderer = Renderer::new(&gpu.device, scene, rig, options).unwrap();
    let targets = renderer.create_targets(&gpu.device);
    renderer
        .submit_frame(&gpu.device, &gpu.queue, rig, 0.0, &targets)
        .unwrap();
    renderer
}

/// `renderer`'s next frame of `rig` at time 0 into `targets`, display 0's color read
/// back: for tests that change a renderer between frames.
pub fn next_frame(
    gpu: &Gpu,
    renderer: &mut Renderer,
    rig: &Rig,
    targets: &[DisplayTarget],
) -> RgbaImage {
    renderer
        .submit_frame(&gpu.device, &gpu.queue, rig, 0.0, targets)
        .unwrap();
    read_rgba8(&gpu.device, &gpu.queue, &targets[0].color).unwrap()
}

/// Every display's cull buffers of `renderer`'s last frame, read back.
pub fn read_culls(gpu: &Gpu, renderer: &Renderer, rig: &Rig) -> Vec<CullOutput> {
    (0..rig.displays.len())
        .map(|d| {
            renderer
                .diagnostics(&gpu.device, &gpu.queue)
                .cull(d)
                .unwrap()
        })
        .collect()
}

/// Asserts that a cull's buffers read back are the reference's, byte for byte.
pub fn assert_same_cull(what: &str, got: &CullOutput, want: &CullOutput) {
    assert_eq!(got.draw_count, want.draw_count, "{what}: draw_count");
    assert_eq!(got.draws, want.draws, "{what}: draws");
    assert_eq!(got.bins, want.bins, "{what}: bins");
    assert!(got.visible == want.visible, "{what}: visible lists differ");
}

/// One frame of `scene` seen by `rig` at time 0, every display read back.
pub fn render(
    gpu: &Gpu,
    scene: &Scene,
    rig: &Rig,
    options: RendererOptions,
) -> stereocull::Result<Vec<RgbaImage>> {
    render_at(gpu, scene, rig, options, 0.0)
}

/// [`render`] at `time` seconds (animated instances move with it).
pub fn render_at(
    gpu: &Gpu,
    scene: &Scene,
    rig: &Rig,
    options: RendererOptions,
    time: f32,
) -> stereocull::Result<Vec<RgbaImage>> {
    let mut renderer = Renderer::new(&gpu.device, scene, rig, options)?;
    let targets = renderer.create_targets(&gpu.device);
    renderer.submit_frame(&gpu.device, &gpu.queue, rig, time, &targets)?;
    targets
        .iter()
        .map(|t| read_rgba8(&gpu.device, &gpu.queue, &t.color))
        .collect()
}

/// A two-frame submission's frame against the frame drawn alone.
/// Each frame's views fill a quarter of a four-view target instead of half of a
/// double-wide one, so the draw places their clip positions by other constants
/// (`x * 0.25 - 0.75 w` against `x * 0.5 - 0.5 w` for the left eye) and clips them by
/// four planes instead of one: the same triangles, but a clip position's last bit can
/// differ, flipping the coverage of a pixel that an edge passes within a rounding step
/// of its center (and its neighbour's depth test with it). Colors are computed from the
/// same pixel and depth, so only edge pixels differ: at most 0.3 % of them, as for the
/// foveated views' outer pair (`tests/foveated.rs`, the same placement).
/// Content posed apart (`tests/frames_posed.rs`) is posed and skinned by the same
/// passes from the same joint matrices and records (copied, not recomputed): nothing
/// else differs.
pub const PLACED: Tolerance = Tolerance {
    levels: 0,
    share: 0.003,
};

/// How far two images may differ: a pixel differs when a channel differs by more
/// than `levels`; at most `share` of the pixels may differ.
#[derive(Clone, Copy, Debug)]
pub struct Tolerance {
    pub levels: u8,
    pub share: f64,
}

impl Tolerance {
    /// The same compiled shaders on the same inputs: llvmpipe is deterministic, so the
    /// same pipeline drawing the same draws in the same order writes the same bytes on
    /// any CPU. For comparisons where only the culler, the draw call's form (count or
    /// fixed) or the pass that hosts the draw differ.
    pub const EXACT: Tolerance = Tolerance {
        levels: 0,
        share: 0.0,
    };

    /// Two shaders that compute the same values with differently written code (a
    /// material hook that restates the built-in shading, the caller's own pipeline):
    /// LLVM may contract `a * b + c` into one FMA in one expression tree and not in the
    /// other, and whether it does depends on the host (llvmpipe compiles for its vector
    /// width). A color's last bit then rounds one level apart, and a clip position's last
    /// bit can flip the coverage of a pixel on an edge. So: one level anywhere, and at
    /// most 0.1 % of the pixels (edge pixels) beyond it. Seen on an Intel Xeon, exact on
    /// AMD EPYC: 1 and 2 pixels of 24,000, each one level off (`stereocull diff`).
    pub const RECOMPILED: Tolerance = Tolerance {
        levels: 1,
        share: 0.001,
    };
}

/// The variable that relocates the shared glTF samples.
pub const SAMPLES_VAR: &str = "STEREOCULL_GLTF_SAMPLES";

/// A scene loaded from a file `name` holding `bytes`, as the CLI loads one.
pub fn load_bytes(name: &str, bytes: &[u8]) -> Scene {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    std::fs::write(&path, bytes).unwrap();
    stereocull::scene_spec::load(path.to_str().unwrap()).unwrap()
}

/// `<samples>/<name>/<name>.<ext>` in the shared Khronos samples: `../shared/gltf-samples/`
/// beside the clone, or where [`SAMPLES_VAR`] says. A missing directory fails with one
/// message that says where the samples come from.
pub fn gltf_sample(name: &str, ext: &str) -> PathBuf {
    let root = std::env::var_os(SAMPLES_VAR).map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/gltf-samples"),
        PathBuf::from,
    );
    assert!(
        root.is_dir(),
        "the shared glTF samples are not at {}: set {SAMPLES_VAR} to their directory \
         (Khronos glTF sample models; see the README's Test section for where to get them)",
        root.display()
    );
    let path = root.join(name).join(format!("{name}.{ext}"));
    assert!(
        path.is_file(),
        "{} is missing from the samples",
        path.display()
    );
    path
}

/// Compares `actual` with `reference`; on failure writes `<name>-actual.png`,
/// `-reference.png` and `-difference.png` under `target/test-images/` and panics naming
/// them. Returns the number of differing pixels.
pub fn assert_images_match(
    name: &str,
    actual: &RgbaImage,
    reference: &RgbaImage,
    tolerance: Tolerance,
) -> usize {
    assert_eq!(actual.dimensions(), reference.dimensions(), "{name}: sizes");
    let mut diff = RgbaImage::new(actual.width(), actual.height());
    let mut count = 0;
    for (x, y, a) in actual.enumerate_pixels() {
        let b = reference.get_pixel(x, y);
        let d = (0..3).map(|c| a[c].abs_diff(b[c])).max().unwrap_or(0);
        count += usize::from(d > tolerance.levels);
        let shade = d.saturating_mul(8);
        diff.put_pixel(x, y, Rgba([shade, shade, shade, 255]));
    }
    let share = count as f64 / (actual.width() * actual.height()) as f64;
    eprintln!(
        "{name}: {count} pixels differ by more than {} levels",
        tolerance.levels
    );
    if share > tolerance.share {
        let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/test-images");
        std::fs::create_dir_all(&dir).unwrap();
        for (suffix, image) in [
            ("actual", actual),
            ("reference", reference),
            ("difference", &diff),
        ] {
            image
                .save(dir.join(format!("{name}-{suffix}.png")))
                .unwrap();
        }
        panic!(
            "{name}: {count} pixels differ ({:.4} %, allowed {:.4} %); images in {}",
            100.0 * share,
            100.0 * tolerance.share,
            dir.display()
        );
    }
    count
}

pub const PRESETS: [&str; 3] = ["hmd", "cave", "hmd-peripheral"];

/// A preset moved anywhere within a million meters, looking anywhere, with a far plane
/// of a kilometer or of two thousand kilometers. A CAVE moves with its viewer (its walls
/// are world-fixed), who stays within half a meter of its center.
pub fn rig_strategy() -> impl Strategy<Value = Rig> {
    let coordinate = prop_oneof![-10.0f32..10.0, -1.0e6f32..1.0e6];
    (
        0..PRESETS.len(),
        [coordinate.clone(), coordinate.clone(), coordinate],
        [-0.5f32..0.5, -0.5f32..0.5, -0.5f32..0.5],
        -180.0f32..180.0,
        -80.0f32..80.0,
        0.0f32..0.08,
        prop_oneof![Just(1.0e3f32), Just(2.0e6f32)],
    )
        .prop_map(|(preset, moved, jitter, yaw, pitch, ipd, far)| {
            let mut rig = Rig::preset(PRESETS[preset]).unwrap();
            let moved = Vec3::from(moved);
            let home = Vec3::from(rig.viewer.position);
            rig.viewer.position = (home + moved + Vec3::from(jitter)).into();
            rig.viewer.yaw_deg = yaw;
            rig.viewer.pitch_deg = pitch;
            rig.viewer.ipd = ipd;
            rig.far = far;
            for d in &mut rig.displays {
                d.resolution = [64, 64];
                if let Mount::Screen(s) = &mut d.mount {
                    for corner in [&mut s.lower_left, &mut s.lower_right, &mut s.upper_left] {
                        *corner = (Vec3::from(*corner) + moved).into();
                    }
                }
            }
            rig
        })
}

/// `n` instances of `meshes` meshes around the viewer, at distances from 10 cm to two
/// thousand kilometers and sizes from a tenth of a millimeter to a hundred meters.
pub fn extreme_scene(rig: &Rig, n: u32, meshes: u32, seed: u64) -> Scene {
    let mut scene = procedural::scene(n, meshes, seed);
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    let around = Vec3::from(rig.viewer.position);
    for inst in &mut scene.instances {
        let direction = Vec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        )
        .normalize_or(Vec3::Z);
        let distance = 10f32.powf(rng.random_range(-1.0..6.3));
        let scale = 10f32.powf(rng.random_range(-4.0..2.0));
        let rotation = Quat::from_euler(
            glam::EulerRot::YXZ,
            rng.random(),
            rng.random(),
            rng.random(),
        );
        inst.world_from_local = Affine3A::from_scale_rotation_translation(
            Vec3::splat(scale),
            rotation,
            around + direction * distance,
        );
    }
    scene
}

/// Every preset at 64 x 64 pixels per eye, then `random` rigs from [`rig_strategy`]
/// (fixed seeds): the rigs the byte-equality tests run over.
pub fn presets_and_random_rigs(random: usize) -> Vec<Rig> {
    use proptest::strategy::ValueTree;
    let mut runner = proptest::test_runner::TestRunner::deterministic();
    let random = (0..random).map(|_| rig_strategy().new_tree(&mut runner).unwrap().current());
    PRESETS
        .iter()
        .map(|p| sized(p, 64, 64))
        .chain(random)
        .collect()
}

/// `scene` with its meshes spread over materials of every alpha mode (opaque, cutouts
/// at random cutoffs, blended) at random (fixed `seed`), so that its draws fall into
/// every material bin (with three meshes or more, every alpha mode). Each mesh's
/// vertices name its one material.
pub fn with_random_bins(mut scene: Scene, seed: u64) -> Scene {
    use stereocull::scene::{AlphaMode, Material};
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(seed);
    scene.materials = (0..5)
        .map(|k| Material {
            name: format!("material {k}"),
            alpha: match k % 3 {
                0 => AlphaMode::Opaque,
                1 => AlphaMode::Mask {
                    cutoff: rng.random_range(0.1..0.9),
                },
                _ => AlphaMode::Blend,
            },
            ..Default::default()
        })
        .collect();
    // Meshes that share vertices (a mirrored twin) share their material.
    let mut chosen = std::collections::HashMap::new();
    for m in 0..scene.meshes.len() {
        let mesh = scene.meshes[m].clone();
        let first = mesh.first_index as usize;
        let indices = &scene.indices[first..first + mesh.index_count as usize];
        // The first three meshes take one of each alpha mode, the rest at random.
        let next = chosen.len() as u32;
        let material = *chosen.entry(mesh.base_vertex).or_insert_with(|| {
            if next < 3 {
                next
            } else {
                rng.random_range(0..5)
            }
        });
        for &i in indices {
            scene.vertices[(i as i32 + mesh.base_vertex) as usize].material = material;
        }
    }
    scene
}

/// The plane z = 0 from -`half` to `half` in x and y, facing +z: one instance, untextured.
pub fn plane(half: f32) -> Scene {
    let mut scene = Scene::default();
    let corner = |x: f32, y: f32| stereocull::scene::Vertex::new(Vec3::new(x, y, 0.0), Vec3::Z);
    let vertices = [
        corner(-half, -half),
        corner(half, -half),
        corner(half, half),
        corner(-half, half),
    ];
    let mesh = scene.add_mesh("plane", &vertices, &[0, 1, 2, 0, 2, 3]);
    scene.instances.push(Instance {
        world_from_local: Affine3A::IDENTITY,
        mesh,
        color: Vec4::ONE,
        material: None,
        animation: Animation::NONE,
    });
    scene
}

/// Where the center of pixel (x, y) of eye `e` (its own half, `eye_w` x `eye_h`) of
/// display 0 sees the plane z = 0, and that eye's position.
pub fn on_plane(
    rig: &Rig,
    e: usize,
    (x, y): (u32, u32),
    (eye_w, eye_h): (u32, u32),
) -> (Vec3, Vec3) {
    let at = (x as f64 + 0.5, y as f64 + 0.5);
    let (p, eye) = on_plane_at(rig, e, at, (eye_w, eye_h));
    (p.as_vec3(), eye)
}

/// Where the point `(x, y)` (pixels from the top left corner of eye `e`'s view) of
/// display 0 sees the plane z = 0, in f64, and that eye's position.
pub fn on_plane_at(
    rig: &Rig,
    e: usize,
    (x, y): (f64, f64),
    (eye_w, eye_h): (u32, u32),
) -> (DVec3, Vec3) {
    let view = rig.resolve().unwrap().displays[0].eyes[e];
    let world_from_clip = view.world_from_clip().as_dmat4();
    let ndc = |z: f64| {
        let p = world_from_clip
            * DVec4::new(
                x / eye_w as f64 * 2.0 - 1.0,
                1.0 - y / eye_h as f64 * 2.0,
                z,
                1.0,
            );
        p.truncate() / p.w
    };
    let (a, b) = (ndc(0.25), ndc(0.75));
    let t = a.z / (a.z - b.z);
    (a + (b - a) * t, view.position())
}

/// Linear to 8-bit sRGB, as the target's format stores it.
pub fn srgb(l: f32) -> f32 {
    let l = l.clamp(0.0, 1.0);
    let s = if l <= 0.003_130_8 {
        12.92 * l
    } else {
        1.055 * l.powf(1.0 / 2.4) - 0.055
    };
    s * 255.0
}
