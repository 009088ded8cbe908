//! Levels of detail chosen on the GPU from the viewer: the expected level near, middle
//! and far; the same level in both eyes and every display (binocular rivalry otherwise),
//! checked through the draws; GPU and CPU byte-identical with LOD on.

mod support;

use std::collections::HashMap;

use glam::{Affine3A, Quat, Vec3, Vec4};
use stereocull::cull::CullOutput;
use stereocull::cull::FrameLod;
use stereocull::cull::cpu;
use stereocull::device::Gpu;
use stereocull::records::CullLayout;
use stereocull::renderer::{RendererOptions, StereoMode, frame_lod};
use stereocull::rig::Rig;
use stereocull::scene::{Animation, Instance, MAX_LODS, Scene};
use stereocull::{procedural, shapes};
use support::{frustum_only, gpu};

/// One frame culled by a renderer with LOD on; every display's cull read back.
fn culls(gpu: &Gpu, scene: &Scene, rig: &Rig, mode: StereoMode) -> Vec<Vec<CullOutput>> {
    let options = RendererOptions {
        lod: true,
        mode,
        cull: support::cull_for(mode),
        ..frustum_only()
    };
    let renderer = support::one_frame(gpu, scene, rig, options);
    support::read_culls(gpu, &renderer, rig)
        .into_iter()
        .map(|out| vec![out])
        .collect()
}

fn lod_of(rig: &Rig) -> FrameLod {
    frame_lod(rig, &rig.resolve().unwrap(), MAX_LODS as u32)
}

/// Instance id -> the first index of the draw that draws it (which names its level).
fn drawn_ranges(out: &CullOutput, views: u32) -> HashMap<u32, u32> {
    let mut map = HashMap::new();
    for d in &out.draws[..out.draw_count as usize] {
        let first = (d.first_instance / views) as usize;
        for &id in &out.visible[first..first + (d.instance_count / views) as usize] {
            map.insert(id, d.first_index);
        }
    }
    map
}

/// A dense sphere (so that it has every level) at distances straight ahead of the hmd
/// viewer chosen from its levels' own thresholds: each instance must be drawn with the
/// level its distance calls for, by the GPU and by the CPU reference.
#[test]
fn near_middle_and_far_instances_take_the_expected_levels() {
    let gpu = gpu();
    let mut scene = Scene::default();
    let s = shapes::sphere(0.5, 64, 32);
    scene.add_mesh("dense sphere", &s.vertices, &s.indices);
    let mesh = scene.meshes[0].clone();
    assert!(
        mesh.lods.len() >= 2,
        "near, middle and far levels: {:?}",
        mesh.lods
    );
    let rig = Rig::preset("hmd").unwrap();
    let lod = lod_of(&rig);
    let viewer = lod.viewer;
    // Where level l begins: d * d > error^2 * lod_scale * r * r.
    let radius = scene.world_sphere(&Instance {
        world_from_local: Affine3A::IDENTITY,
        mesh: 0,
        color: Vec4::ONE,
        material: None,
        animation: Animation::NONE,
    });
    let begins: Vec<f32> = mesh
        .lods
        .iter()
        .map(|l| l.error * lod.lod_scale.sqrt() * radius.w)
        .collect();
    let mut distances = vec![0.5 * begins[0]];
    for w in begins.windows(2) {
        distances.push(0.5 * (w[0] + w[1]));
    }
    distances.push(begins[begins.len() - 1] * 1.5);
    assert!(
        distances.iter().all(|&d| d < 900.0),
        "inside the far plane: {distances:?}"
    );
    scene.instances = distances
        .iter()
        .map(|&d| Instance {
            world_from_local: Affine3A::from_translation(viewer - Vec3::Z * d),
            mesh: 0,
            color: Vec4::ONE,
            material: None,
            animation: Animation::NONE,
        })
        .collect();
    let want: Vec<u32> = std::iter::once(mesh.first_index)
        .chain(mesh.lods.iter().map(|l| l.first_index))
        .collect();
    let reference = cpu::cull_many_lod(&CullLayout::new(&scene), &rig.cull_jobs().unwrap(), &lod);
    for (what, out) in [
        (
            "gpu",
            &culls(&gpu, &scene, &rig, StereoMode::Instanced)[0][0],
        ),
        ("cpu", &reference[0]),
    ] {
        let ranges = drawn_ranges(out, 2);
        for (id, first) in want.iter().enumerate() {
            assert_eq!(
                ranges.get(&(id as u32)),
                Some(first),
                "{what}: instance {id} at {} m",
                distances[id]
            );
        }
    }
}

/// Random scenes with LOD on, every preset: the GPU's buffers equal the CPU reference's.
#[test]
fn gpu_matches_cpu_with_lod_on_every_preset() {
    let gpu = gpu();
    for (n, meshes, seed) in [(3000, 8, 1), (40_000, 16, 2)] {
        let scene = procedural::scene(n, meshes, seed);
        for preset in ["hmd", "cave", "hmd-peripheral"] {
            let rig = support::sized(preset, 64, 64);
            let reference = cpu::cull_many_lod(
                &CullLayout::new(&scene),
                &rig.cull_jobs().unwrap(),
                &lod_of(&rig),
            );
            let got = culls(&gpu, &scene, &rig, StereoMode::Instanced);
            for (d, (got, want)) in got.iter().zip(&reference).enumerate() {
                assert!(got[0] == *want, "n={n} {preset} display {d} differs");
            }
            let levels = reference.iter().map(|o| o.draw_count).max().unwrap();
            assert!(
                levels > meshes,
                "{preset}: some coarser levels drawn ({levels} draws)"
            );
        }
    }
}

/// Binocular rivalry is ruled out through the draws: in multi-camera (each eye culled
/// alone) an instance both eyes see is drawn at one level, and in `cave` an instance
/// several walls see is drawn at one level on all of them.
#[test]
fn both_eyes_and_every_display_draw_an_instance_at_one_level() {
    let gpu = gpu();
    let mut scene = procedural::scene(20_000, 8, 5);
    for (k, inst) in scene.instances.iter_mut().enumerate() {
        let turn = Quat::from_rotation_y(k as f32);
        inst.world_from_local *= Affine3A::from_quat(turn);
    }
    let rig = support::sized("hmd", 64, 64);
    let lod = lod_of(&rig);
    let layout = CullLayout::new(&scene);
    let eyes: Vec<_> = rig.resolve().unwrap().displays[0]
        .eyes
        .iter()
        .map(|e| stereocull::cull::CullJob {
            planes: e.frustum().planes,
            instances_per_object: 1,
            split: None,
            hidden: None,
            tiles: None,
            sort_origin: e.position(),
        })
        .collect();
    let per_eye = cpu::cull_many_lod(&layout, &eyes, &lod);
    let (left, right) = (drawn_ranges(&per_eye[0], 1), drawn_ranges(&per_eye[1], 1));
    let both: Vec<_> = left.keys().filter(|id| right.contains_key(id)).collect();
    assert!(both.len() > 1000, "{} seen by both eyes", both.len());
    for id in both {
        assert_eq!(
            left[id], right[id],
            "instance {id}: the eyes draw different levels"
        );
    }
    let cave = support::sized("cave", 32, 32);
    let walls = culls(&gpu, &scene, &cave, StereoMode::Instanced);
    let mut level_of: HashMap<u32, u32> = HashMap::new();
    let mut shared = 0;
    for out in &walls {
        for (id, first) in drawn_ranges(&out[0], 2) {
            if let Some(seen) = level_of.insert(id, first) {
                assert_eq!(seen, first, "instance {id}: walls draw different levels");
                shared += 1;
            }
        }
    }
    assert!(shared > 100, "{shared} instances on two walls");
}

/// A surface listed in both windings (an open tube, a glTF `doubleSided` primitive) is
/// simplified one side at a time: every level is again both windings of one side, and
/// keeps the tube's area (welded, the two sides close the tube's rims, which then
/// collapsed freely: a 16-sided tube fell to four triangles of a flat strip).
#[test]
fn a_two_sided_tube_keeps_both_windings_and_its_shape_at_every_level() {
    let mut scene = Scene::default();
    let tube = shapes::cylinder(0.2, 0.8, 32);
    scene.add_mesh("tube", &tube.vertices, &tube.indices);
    let mesh = &scene.meshes[0];
    assert!(
        !mesh.lods.is_empty(),
        "a 128-triangle tube has coarser levels"
    );
    let area = |first: u32, count: u32| -> f32 {
        let indices = &scene.indices[first as usize..(first + count) as usize];
        let at =
            |i: u32| Vec3::from(scene.vertices[(mesh.base_vertex as u32 + i) as usize].position);
        indices
            .chunks_exact(3)
            .map(|t| 0.5 * (at(t[1]) - at(t[0])).cross(at(t[2]) - at(t[0])).length())
            .sum()
    };
    let full = area(mesh.first_index, mesh.index_count);
    for lod in &mesh.lods {
        let indices = &scene.indices[lod.first_index as usize..][..lod.index_count as usize];
        let (front, back) = indices.split_at(indices.len() / 2);
        assert_eq!(
            stereocull::scene::both_windings(front),
            indices,
            "level of {} indices is not one side in both windings",
            lod.index_count
        );
        assert!(back.len() < tube.indices.len() / 2, "coarser than the tube");
        let kept = area(lod.first_index, lod.index_count) / full;
        assert!(
            (0.85..=1.0001).contains(&kept),
            "level of {} indices keeps {kept} of the tube's area",
            lod.index_count
        );
    }
}
