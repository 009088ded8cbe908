//! The CPU reference culler on hand-made cases, and against a naive loop on random
//! scenes (fixed seeds).

mod support;

use glam::{Vec3, Vec4Swizzles};
use stereocull::bins::{Bin, BinKind, mesh_material};
use stereocull::cull::{BinDraws, CullJob, CullOutput, cpu};
use stereocull::frustum::sphere_in_planes;
use stereocull::procedural;
use stereocull::records::{CullLayout, DrawArgs};
use stereocull::rig::Rig;
use stereocull::scene::Scene;
use support::cubes;

/// Three cube meshes of half-size 0.5 (bounding radius sqrt(3)/2).
fn scene_with(instances: &[(Vec3, u32)]) -> Scene {
    cubes(instances, 3)
}

fn cull(scene: &Scene, rig: &Rig, display: usize) -> CullOutput {
    support::reference_culls(scene, rig).remove(display)
}

/// The viewer of `hmd` stands at (0, 1.6, 2) looking down -Z.
fn hmd() -> Rig {
    Rig::preset("hmd").unwrap()
}

#[test]
fn nothing_visible_gives_no_draws_and_zeroed_args() {
    let behind: Vec<_> = (0..10)
        .map(|i| (Vec3::new(i as f32, 1.6, 10.0), i % 3))
        .collect();
    let out = cull(&scene_with(&behind), &hmd(), 0);
    assert!(out.visible.is_empty());
    assert_eq!(out.draw_count, 0);
    assert_eq!(out.draws, vec![DrawArgs::default(); 3]);
}

#[test]
fn everything_visible_gives_doubled_counts_grouped_by_mesh() {
    // Ids 0..6 alternate meshes 2, 0, 1, 2, 0, 1; all 5 m in front of the viewer.
    let front: Vec<_> = (0..6)
        .map(|i| (Vec3::new(i as f32 * 0.5 - 1.0, 1.6, -3.0), [2, 0, 1][i % 3]))
        .collect();
    let scene = scene_with(&front);
    let out = cull(&scene, &hmd(), 0);
    assert_eq!(
        out.visible,
        [1, 4, 2, 5, 0, 3],
        "grouped by mesh, ascending ids within"
    );
    assert_eq!(out.draw_count, 3);
    for (m, d) in out.draws.iter().enumerate() {
        assert_eq!(d.instance_count, 4, "2 views x 2 instances");
        assert_eq!(d.first_instance, 4 * m as u32);
        assert_eq!(d.index_count, 36);
        assert_eq!(d.first_index, scene.meshes[m].first_index);
        assert_eq!(d.base_vertex, scene.meshes[m].base_vertex);
    }
}

#[test]
fn empty_meshes_are_skipped_and_draws_packed_at_the_front() {
    let out = cull(&scene_with(&[(Vec3::new(0.0, 1.6, -3.0), 2)]), &hmd(), 0);
    assert_eq!(out.draw_count, 1);
    assert_eq!(out.draws[0].first_index, 72, "mesh 2 comes first");
    assert_eq!(&out.draws[1..], &[DrawArgs::default(); 2]);
}

#[test]
fn spheres_straddling_a_plane_are_visible_and_those_beyond_are_not() {
    let rig = hmd();
    let job = rig.cull_jobs().unwrap().remove(0);
    let radius = 3f32.sqrt() * 0.5;
    // A point on the left plane, 4 m ahead.
    let left = job.planes[0];
    let ahead = Vec3::new(0.0, 1.6, -2.0);
    let on_plane = ahead - left.xyz() * (left.xyz().dot(ahead) + left.w);
    let outward = -left.xyz();
    let cases = [
        (on_plane + outward * (0.5 * radius), true),
        (on_plane + outward * (0.999 * radius), true),
        (on_plane + outward * (1.01 * radius), false),
        (on_plane + outward * (2.0 * radius), false),
        (on_plane - outward * (0.5 * radius), true),
    ];
    let scene = scene_with(&cases.map(|(p, _)| (p, 0)));
    let out = cull(&scene, &rig, 0);
    let want: Vec<u32> = (0..cases.len() as u32)
        .filter(|&i| cases[i as usize].1)
        .collect();
    assert_eq!(out.visible, want);
}

#[test]
fn mono_displays_do_not_double() {
    let rig = Rig::preset("hmd-peripheral").unwrap();
    // 45 degrees to the left of the viewer (0, 1.6, 2), 3 m away.
    let p = Vec3::new(-2.12, 1.6, 2.0 - 2.12);
    let scene = scene_with(&[(p, 1), (p, 1), (p, 0)]);
    let side = cull(&scene, &rig, 1);
    assert_eq!(rig.displays[1].name, "peripheral-left");
    assert_eq!(side.visible, [2, 0, 1]);
    assert_eq!(
        (side.draws[0].instance_count, side.draws[0].first_instance),
        (1, 0)
    );
    assert_eq!(
        (side.draws[1].instance_count, side.draws[1].first_instance),
        (2, 1)
    );
    let right = cull(&scene, &rig, 2);
    assert!(right.visible.is_empty(), "the right panel looks away");
}

/// What the contract says, written as plainly as possible: visible ids by mesh, then
/// one draw per mesh with visible instances, in its material bin's range (bins in
/// alpha-mode order, each as long as its meshes); in a blended bin's range (as long as
/// its meshes' instances) one draw per visible instance, farthest first, ties by id.
fn naive(scene: &Scene, job: &CullJob) -> CullOutput {
    let (planes, views) = (&job.planes, job.instances_per_object);
    let mut per_mesh = vec![Vec::new(); scene.meshes.len()];
    for (id, inst) in scene.instances.iter().enumerate() {
        let s = scene.world_sphere(inst);
        if sphere_in_planes(planes, s) {
            per_mesh[inst.mesh as usize].push(id as u32);
        }
    }
    let kind = |m: usize| {
        let material = scene.materials.get(mesh_material(scene, m) as usize);
        material.map_or(Bin::default(), |m| Bin {
            alpha: BinKind::of(m.alpha),
            second_uv: m.second_uv != Default::default(),
            shading: m.shading,
        })
    };
    let mut visible = Vec::new();
    let mut mesh_draws = Vec::new();
    let mut blended = Vec::new();
    for (m, (mesh, ids)) in scene.meshes.iter().zip(per_mesh).enumerate() {
        if kind(m).alpha == BinKind::Blend {
            for id in ids {
                let key = cpu::sort_key(
                    scene.world_sphere(&scene.instances[id as usize]),
                    job.sort_origin,
                );
                let draw = DrawArgs {
                    index_count: mesh.index_count,
                    instance_count: views,
                    first_index: mesh.first_index,
                    base_vertex: mesh.base_vertex,
                    first_instance: views * visible.len() as u32,
                };
                blended.push((kind(m), key, id, draw));
                visible.push(id);
            }
            continue;
        }
        if !ids.is_empty() {
            let draw = DrawArgs {
                index_count: mesh.index_count,
                instance_count: views * ids.len() as u32,
                first_index: mesh.first_index,
                base_vertex: mesh.base_vertex,
                first_instance: views * visible.len() as u32,
            };
            mesh_draws.push((kind(m), draw));
            visible.extend(ids);
        }
    }
    blended.sort_by_key(|&(_, key, id, _)| (key, id));
    let mut kinds: Vec<Bin> = (0..scene.meshes.len()).map(kind).collect();
    kinds.sort();
    kinds.dedup();
    if kinds.is_empty() {
        kinds.push(Bin::default());
    }
    let mut draws = Vec::new();
    let mut bins = Vec::new();
    for k in kinds {
        let members = (0..scene.meshes.len()).filter(|&m| kind(m) == k);
        let capacity = match k.alpha {
            BinKind::Blend => (members.map(|m| {
                scene
                    .instances
                    .iter()
                    .filter(|i| i.mesh == m as u32)
                    .count()
            }))
            .sum(),
            _ => members.count(),
        };
        let first = draws.len();
        draws.extend(mesh_draws.iter().filter(|d| d.0 == k).map(|d| d.1));
        draws.extend(blended.iter().filter(|d| d.0 == k).map(|d| d.3));
        let count = draws.len() - first;
        draws.resize(first + capacity, DrawArgs::default());
        bins.push(BinDraws {
            first: first as u32,
            count: count as u32,
        });
    }
    CullOutput {
        visible,
        draws,
        draw_count: bins.iter().map(|b| b.count).sum(),
        bins,
    }
}

#[test]
fn matches_the_naive_contract_on_random_scenes() {
    let cases = [(1, 1, 1), (63, 5, 2), (50_001, 40, 3), (70_000, 300, 4)];
    for (k, (n, meshes, seed)) in cases.into_iter().enumerate() {
        let scene = procedural::scene(n, meshes, seed);
        // Half the cases spread their meshes over every material bin.
        let scene = match k % 2 {
            0 => scene,
            _ => support::with_random_bins(scene, seed),
        };
        for preset in ["hmd", "cave", "hmd-peripheral"] {
            let rig = Rig::preset(preset).unwrap();
            for (d, job) in rig.cull_jobs().unwrap().iter().enumerate() {
                let got = cpu::cull(&CullLayout::new(&scene), job);
                let want = naive(&scene, job);
                assert_eq!(got, want, "n={n} meshes={meshes} {preset} display {d}");
            }
        }
    }
}
