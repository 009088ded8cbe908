//! Property tests (proptest): culling never drops an instance that an eye can see, and
//! the GPU culler equals the CPU reference byte for byte, with coordinates from a tenth of
//! a millimeter to a million meters.

mod support;

use std::sync::OnceLock;

use glam::{Affine3A, DVec3, Quat, Vec3, Vec4Swizzles};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use stereocull::cull::cpu;
use stereocull::device::Gpu;
use stereocull::procedural;
use stereocull::records::CullLayout;
use stereocull::renderer::{Renderer, RendererOptions};
use stereocull::rig::{Mount, Rig};
use stereocull::scene::Scene;

const PRESETS: [&str; 3] = ["hmd", "cave", "hmd-peripheral"];

/// A preset moved anywhere within a million meters, looking anywhere, with a far plane
/// of a kilometer or of two thousand kilometers. A CAVE moves with its viewer (its walls
/// are world-fixed), who stays within half a meter of its center.
fn rig_strategy() -> impl Strategy<Value = Rig> {
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

/// A point of display `d`'s eye `e` frustum, from window coordinates in [0, 1] and a
/// depth fraction (log-spaced from near to far), computed in f64.
fn point_in_eye(rig: &Rig, d: usize, e: usize, window: (f64, f64), depth: f64) -> DVec3 {
    let view = rig.resolve().unwrap().displays[d].eyes[e];
    let f = view.fov;
    let lerp = |a: f32, b: f32, t: f64| a as f64 + (b as f64 - a as f64) * t;
    let z = view.near as f64 * (view.far as f64 / view.near as f64).powf(depth);
    let local = DVec3::new(
        lerp(-f.left, f.right, window.0) * z,
        lerp(-f.down, f.up, window.1) * z,
        -z,
    );
    view.world_from_view.transform_point3(local)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    /// A sphere holding a point of any eye's frustum is always visible to that display.
    #[test]
    fn no_instance_an_eye_sees_is_culled(
        rig in rig_strategy(),
        display in any::<prop::sample::Index>(),
        eye in 0usize..2,
        window in (0.0f64..=1.0, 0.0f64..=1.0),
        depth in 0.0f64..=1.0,
        radius_exp in -4.0f32..2.0,
        offset in (-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0, 0.0f32..0.99),
    ) {
        let d = display.index(rig.displays.len());
        let e = eye.min(rig.displays[d].views() as usize - 1);
        let p = point_in_eye(&rig, d, e, window, depth);
        let radius = 10f32.powf(radius_exp);
        let direction = Vec3::new(offset.0, offset.1, offset.2).normalize_or(Vec3::X);
        let center = p.as_vec3() + direction * (offset.3 * radius);
        let mut scene = procedural::scene(1, 1, 7);
        let bounds = scene.meshes[0].bounds;
        let scale = radius / bounds.w;
        scene.instances[0].world_from_local = Affine3A::from_scale_rotation_translation(
            Vec3::splat(scale),
            Quat::IDENTITY,
            center - bounds.xyz() * scale,
        );
        // The sphere the culler gets, in f64: only a case whose rounding still holds the
        // point says anything.
        let s = scene.world_sphere(&scene.instances[0]);
        prop_assume!(s.xyz().as_dvec3().distance(p) <= s.w as f64);
        let job = rig.cull_jobs().unwrap()[d];
        let out = cpu::cull(&CullLayout::new(&scene), &job);
        prop_assert_eq!(out.visible, vec![0], "display {} eye {} point {} sphere {}", d, e, p, s);
    }
}

fn gpu() -> &'static Gpu {
    static GPU: OnceLock<Gpu> = OnceLock::new();
    GPU.get_or_init(support::gpu)
}

/// `n` instances of `meshes` meshes around the viewer, at distances from 10 cm to two
/// thousand kilometers and sizes from a tenth of a millimeter to a hundred meters.
fn extreme_scene(rig: &Rig, n: u32, meshes: u32, seed: u64) -> Scene {
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

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn gpu_culling_equals_cpu_with_extreme_coordinates(
        rig in rig_strategy(),
        n in 1u32..5000,
        meshes in 1u32..40,
        seed in any::<u64>(),
    ) {
        let gpu = gpu();
        let scene = extreme_scene(&rig, n, meshes, seed);
        let mut renderer = Renderer::new(&gpu.device, &scene, &rig, RendererOptions::default()).unwrap();
        let targets = renderer.create_targets(&gpu.device);
        renderer.submit_frame(&gpu.device, &gpu.queue, &rig, &targets).unwrap();
        for (d, want) in support::reference_culls(&scene, &rig).into_iter().enumerate() {
            let got = renderer.read_cull(&gpu.device, &gpu.queue, d).unwrap();
            prop_assert_eq!(got, want, "display {}", d);
        }
    }
}
