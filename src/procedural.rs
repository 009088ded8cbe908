//! Procedural scenes: built-in shapes scattered around the viewer at real scale,
//! deterministic from a seed. Stress tests and profiles use them at any size.

use glam::{Affine3A, Quat, Vec3, Vec4};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;

use crate::scene::{Animation, Instance, Scene};
use crate::shapes::{self, Shape};

/// `n` instances of `mesh_count` built-in meshes scattered in a ball around the
/// origin (where every preset's viewer stands), at real scale: objects of 0.1 m to
/// 1.5 m, spread so that density stays near a few per cubic meter at any `n`.
pub fn scene(n: u32, mesh_count: u32, seed: u64) -> Scene {
    let mut scene = Scene::default();
    for k in 0..mesh_count.max(1) {
        let Shape { vertices, indices } = shapes::family(k);
        scene.add_mesh(format!("shape{k}"), &vertices, &indices);
    }
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let radius = 4.0 + (n as f32).cbrt() * 0.8;
    let center = Vec3::new(0.0, 1.5, 0.0);
    scene.instances = (0..n)
        .map(|_| {
            let offset = random_in_shell(&mut rng, 1.0, radius);
            let rotation = Quat::from_euler(
                glam::EulerRot::YXZ,
                rng.random_range(0.0..std::f32::consts::TAU),
                rng.random_range(-0.5..0.5),
                0.0,
            );
            let scale = rng.random_range(0.25..1.5);
            Instance {
                world_from_local: Affine3A::from_scale_rotation_translation(
                    Vec3::splat(scale),
                    rotation,
                    center + offset,
                ),
                mesh: rng.random_range(0..scene.meshes.len() as u32),
                color: Vec4::new(rng.random(), rng.random(), rng.random(), 1.0),
                animation: Animation::NONE,
            }
        })
        .collect();
    scene
}

fn random_in_shell(rng: &mut Pcg64Mcg, inner: f32, outer: f32) -> Vec3 {
    loop {
        let p = Vec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        ) * outer;
        let d = p.length();
        if (inner..=outer).contains(&d) {
            return p;
        }
    }
}
