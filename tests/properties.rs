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
use stereocull::rig::{Mount, Rig, Screen};
use stereocull::scene::Scene;

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
        rig in support::rig_strategy(),
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
        let job = rig.cull_jobs().unwrap().remove(d);
        let out = cpu::cull(&CullLayout::new(&scene), &job);
        prop_assert_eq!(out.visible, vec![0], "display {} eye {} point {} sphere {}", d, e, p, s);
    }
}

fn gpu() -> &'static Gpu {
    static GPU: OnceLock<Gpu> = OnceLock::new();
    GPU.get_or_init(support::gpu)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn gpu_culling_equals_cpu_with_extreme_coordinates(
        rig in support::rig_strategy(),
        n in 1u32..5000,
        meshes in 1u32..40,
        seed in any::<u64>(),
    ) {
        let gpu = gpu();
        let scene = support::extreme_scene(&rig, n, meshes, seed);
        let renderer = support::one_frame(gpu, &scene, &rig, support::frustum_only());
        let got = support::read_culls(gpu, &renderer, &rig);
        for (d, (got, want)) in got.into_iter().zip(support::reference_culls(&scene, &rig)).enumerate() {
            prop_assert_eq!(got, want, "display {}", d);
        }
    }
}

/// A CAVE wall seen at a grazing angle (the eye a few centimeters to half a meter from
/// its plane) by a viewer kilometers from the origin. The truth is each eye's frustum
/// computed here in f64 straight from the rig's numbers: rays from the exact eye
/// through the wall's edges, which lie in its side planes, from viewers beside or in
/// front of the wall and half of them turned so that both eyes share a side plane.
/// Spheres of 5 cm around points of those rays, 1 m to 6 km away, touch the frustum
/// and must all be kept. (Rounding the eye positions to f32, as the f32 rig did, makes
/// this test fail: one ulp at 5 km tilts a side plane past the spheres.)
#[test]
fn grazing_walls_far_from_the_origin_keep_what_an_eye_sees() {
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(9);
    let (mut checked, mut worst) = (0, f64::MAX);
    for case in 0..300 {
        let heading = rng.random_range(0.0..std::f64::consts::TAU);
        let distance = rng.random_range(4000.0..6000.0);
        let origin = DVec3::new(heading.cos() * distance, 0.0, heading.sin() * distance);
        let corner = |x: f64, y: f64, z: f64| (origin + DVec3::new(x, y, z)).as_vec3().into();
        let wall = Screen {
            lower_left: corner(-1.5, 0.0, -1.5),
            lower_right: corner(1.5, 0.0, -1.5),
            upper_left: corner(-1.5, 3.0, -1.5),
        };
        let mut rig = support::sized("cave", 32, 32);
        rig.displays.truncate(1);
        rig.displays[0].mount = Mount::Screen(wall);
        rig.far = 1.0e4;
        let grazing = rng.random_range(0.02..0.5);
        rig.viewer.position = corner(
            rng.random_range(-8.0..8.0),
            rng.random_range(0.3..2.7),
            -1.5 + grazing,
        );
        rig.viewer.yaw_deg = rng.random_range(-180.0..180.0);
        if rng.random_bool(0.5) {
            // Eyes in line with a vertical edge: both eyes' side planes through it then
            // coincide, and the display frustum has no margin from the other eye there.
            let viewer = DVec3::from(rig.viewer.position.map(f64::from));
            let edge = if rng.random_bool(0.5) { -1.5 } else { 1.5 };
            let to_edge = origin + DVec3::new(edge, 0.0, -1.5) - viewer;
            let yaw = f64::atan2(-to_edge.z, to_edge.x).to_degrees();
            rig.viewer.yaw_deg = (yaw + rng.random_range(-0.02..0.02)) as f32;
        }
        if rig.resolve().is_err() {
            continue; // an eye on or behind the wall
        }
        let mut points = Vec::new();
        for eye in exact_eyes(&rig) {
            for _ in 0..20 {
                let (u, v) = on_an_edge(&mut rng);
                let on_wall = point_on_wall(&wall, u, v);
                let ray = (on_wall - eye).normalize();
                let depth_per_meter = ray.dot(exact_normal(&wall));
                let reach = 10f64.powf(rng.random_range(0.0..3.78));
                // Between the near and far planes, which are depths along the normal.
                let depth = (reach * depth_per_meter).clamp(0.1, 0.99e4);
                points.push(eye + ray * (depth / depth_per_meter));
            }
        }
        let planes = rig.cull_jobs().unwrap()[0].planes;
        let inside = |p: &DVec3| {
            let distance = |pl: &glam::Vec4| pl.truncate().as_dvec3().dot(*p) + pl.w as f64;
            planes.iter().map(distance).fold(f64::MAX, f64::min)
        };
        worst = points.iter().map(inside).fold(worst, f64::min);
        let scene = spheres_at(&points, 0.05);
        let out = cpu::cull(&CullLayout::new(&scene), &rig.cull_jobs().unwrap()[0]);
        let kept: Vec<u32> = (0..points.len() as u32).collect();
        assert_eq!(
            out.visible, kept,
            "case {case}: viewer {:?}, {} m from the wall plane",
            rig.viewer.position, grazing
        );
        checked += points.len();
    }
    eprintln!(
        "{checked} points on the eye frusta; nearest to leaving the display frustum: {worst:.4} m inside"
    );
    assert!(checked > 5000, "{checked} points");
}

/// Wall coordinates in [0, 1]^2 on one of its four edges: rays through them run in
/// the eye frustum's side planes, where a tilted plane shows.
fn on_an_edge(rng: &mut rand_pcg::Pcg64Mcg) -> (f64, f64) {
    let along = rng.random_range(0.0..=1.0);
    let side = f64::from(rng.random_range(0..2u8));
    match rng.random_range(0..2) {
        0 => (side, along),
        _ => (along, side),
    }
}

/// The eye centers in f64 from the rig's numbers: left then right.
fn exact_eyes(rig: &Rig) -> [DVec3; 2] {
    let v = &rig.viewer;
    let position = DVec3::from(v.position.map(f64::from));
    let turn = glam::DQuat::from_rotation_y((v.yaw_deg as f64).to_radians());
    let half = turn * DVec3::X * (0.5 * v.ipd as f64);
    [position - half, position + half]
}

fn point_on_wall(s: &Screen, u: f64, v: f64) -> DVec3 {
    let [a, b, c] =
        [s.lower_left, s.lower_right, s.upper_left].map(|p| DVec3::from(p.map(f64::from)));
    a + (b - a) * u + (c - a) * v
}

/// The wall's normal towards the viewer.
fn exact_normal(s: &Screen) -> DVec3 {
    let [a, b, c] =
        [s.lower_left, s.lower_right, s.upper_left].map(|p| DVec3::from(p.map(f64::from)));
    -(b - a).cross(c - a).normalize()
}

/// One instance per point: a sphere mesh scaled to `radius`, centered on the point.
fn spheres_at(points: &[DVec3], radius: f32) -> Scene {
    let mut scene = support::cubes(&[], 1);
    let bounds = scene.meshes[0].bounds;
    let scale = radius / bounds.w;
    scene.instances = points
        .iter()
        .map(|p| stereocull::scene::Instance {
            world_from_local: Affine3A::from_scale_rotation_translation(
                Vec3::splat(scale),
                Quat::IDENTITY,
                p.as_vec3() - bounds.xyz() * scale,
            ),
            mesh: 0,
            color: glam::Vec4::ONE,
            material: None,
            animation: stereocull::scene::Animation::NONE,
        })
        .collect();
    scene
}

/// Culling stays conservative for animated instances: every vertex of every pose (any
/// time) lies inside the world sphere the culler tests, for random shapes, transforms,
/// spins and bobs (fixed seed).
#[test]
fn animated_instances_stay_inside_their_culling_sphere() {
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(21);
    let mut scene = procedural::scene(300, 12, 5);
    // A mesh off its local origin orbits the spin axis instead of turning in place.
    let mut off_center = stereocull::shapes::family(4);
    for v in &mut off_center.vertices {
        v.position = (Vec3::from(v.position) + Vec3::new(1.5, 0.3, -0.8)).into();
    }
    let orbiting = scene.add_mesh("off-center", &off_center.vertices, &off_center.indices);
    for (k, inst) in scene.instances.iter_mut().enumerate() {
        inst.animation = stereocull::scene::Animation {
            spin: rng.random_range(-6.0..6.0),
            bob: rng.random_range(-2.0..2.0),
        };
        if k % 2 == 0 {
            inst.mesh = orbiting;
        }
    }
    let mut checked = 0;
    for inst in &scene.instances {
        let sphere = scene.world_sphere(inst);
        let mesh = &scene.meshes[inst.mesh as usize];
        let range = mesh.first_index as usize..(mesh.first_index + mesh.index_count) as usize;
        for _ in 0..20 {
            let t: f32 = rng.random_range(0.0..100.0);
            let a = inst.animation;
            let lift = Vec3::Y * a.bob * (std::f32::consts::PI * t).sin();
            let pose = Affine3A::from_translation(lift)
                * inst.world_from_local
                * Affine3A::from_rotation_y(a.spin * t);
            for &i in &scene.indices[range.clone()] {
                let v = scene.vertices[mesh.base_vertex as usize + i as usize];
                let p = pose.transform_point3(Vec3::from(v.position));
                let outside = p.distance(sphere.xyz()) - sphere.w;
                assert!(
                    outside <= 0.0,
                    "{p} is {outside} m outside {sphere} at t = {t}"
                );
                checked += 1;
            }
        }
    }
    assert!(checked > 100_000, "{checked} vertices");
}
