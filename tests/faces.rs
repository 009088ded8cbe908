//! Back faces are culled: what a mesh's winding means, and the two ways to keep a surface
//! drawn (both windings; a reversed twin for mirroring transforms), checked in every mode.

mod support;

use glam::{Affine3A, Quat, Vec3};
use image::RgbaImage;
use stereocull::renderer::{RendererOptions, StereoMode};
use stereocull::scene::Scene;
use support::{Tolerance, assert_images_match, cubes, gpu, sized};

fn render_all_modes(scene: &Scene) -> Vec<RgbaImage> {
    let gpu = gpu();
    let rig = sized("hmd", 96, 80);
    StereoMode::ALL
        .into_iter()
        .map(|mode| {
            let options = RendererOptions {
                cull: support::cull_for(mode),
                mode,
                ..Default::default()
            };
            support::render(&gpu, scene, &rig, options)
                .unwrap()
                .remove(0)
        })
        .collect()
}

/// Pixels that differ from the same mode's image of an empty scene.
fn drawn_pixels(images: &[RgbaImage]) -> Vec<usize> {
    let empty = render_all_modes(&Scene::default());
    images
        .iter()
        .zip(&empty)
        .map(|(image, empty)| {
            image
                .pixels()
                .zip(empty.pixels())
                .filter(|(a, b)| a != b)
                .count()
        })
        .collect()
}

/// A unit cube around the viewer (the hmd stands at (0, 1.6, 2)): all of it faces away.
fn around_the_viewer(scene: &mut Scene) {
    scene.instances[0].world_from_local = Affine3A::from_scale_rotation_translation(
        Vec3::splat(3.0),
        Quat::IDENTITY,
        Vec3::new(0.0, 1.6, 2.0),
    );
}

#[test]
fn a_closed_mesh_seen_from_inside_is_not_drawn_unless_it_has_both_windings() {
    let mut scene = cubes(&[(Vec3::ZERO, 0)], 1);
    around_the_viewer(&mut scene);
    for (mode, drawn) in StereoMode::ALL
        .iter()
        .zip(drawn_pixels(&render_all_modes(&scene)))
    {
        // Multiview draws both faces (lavapipe drops front faces of view 1 when culling).
        if *mode != StereoMode::Multiview {
            assert_eq!(drawn, 0, "{}: back faces culled", mode.name());
        }
    }
    let shape = stereocull::shapes::cuboid(Vec3::splat(0.5));
    let both = stereocull::scene::both_windings(&shape.indices);
    let mut two_sided = Scene::default();
    two_sided.add_mesh("two-sided cube", &shape.vertices, &both);
    two_sided.instances = scene.instances.clone();
    let images = render_all_modes(&two_sided);
    for ((mode, drawn), image) in StereoMode::ALL
        .iter()
        .zip(drawn_pixels(&images))
        .zip(&images)
    {
        let all = (image.width() * image.height()) as usize;
        assert_eq!(drawn, all, "{}: walls all around", mode.name());
    }
}

/// A mirrored instance with its mesh's reversed twin looks like the unmirrored cube (a
/// cube is its own mirror image); with the plain mesh it shows its far inside walls.
#[test]
fn a_mirroring_transform_keeps_its_front_faces_with_the_reversed_twin() {
    let at = Vec3::new(0.3, 1.4, -1.0);
    let turned = Quat::from_rotation_y(0.6) * Quat::from_rotation_x(0.4);
    let place = |scale: Vec3| Affine3A::from_scale_rotation_translation(scale, turned, at);
    let mut plain = cubes(&[(Vec3::ZERO, 0)], 1);
    plain.instances[0].world_from_local = place(Vec3::ONE);
    let mut mirrored = plain.clone();
    mirrored.instances[0].world_from_local = place(Vec3::new(-1.0, 1.0, 1.0));
    let inside_out = render_all_modes(&mirrored);
    mirrored.instances[0].mesh = mirrored.add_mirrored_mesh(0);
    let reference = render_all_modes(&plain);
    let twin = render_all_modes(&mirrored);
    for (k, mode) in StereoMode::ALL.iter().enumerate() {
        let name = format!("mirrored-{}", mode.name());
        // The mirror splits each face along its other diagonal: edge pixels may round apart.
        let tolerance = Tolerance {
            levels: 2,
            share: 0.002,
        };
        assert_images_match(&name, &twin[k], &reference[k], tolerance);
        if *mode != StereoMode::Multiview {
            let differing = inside_out[k]
                .pixels()
                .zip(reference[k].pixels())
                .filter(|(a, b)| a != b)
                .count();
            assert!(
                differing > 200,
                "{name}: inside out differs in {differing} pixels"
            );
        }
    }
}
