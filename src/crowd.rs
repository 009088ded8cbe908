//! `crowd:N[:SEED]`: N walking figures around the viewer, the stress case of posing and
//! skinning. Each figure is a skeleton of [`JOINTS`] joints (pelvis, spine, neck, head,
//! arms, legs) at human scale, a skinned mesh of one box per bone (each box moved by
//! its own joint), and a walk cycle played at its own phase and pace, in place, facing
//! its own way. Deterministic from the seed.

use std::f32::consts::{PI, TAU};

use glam::{Affine3A, Quat, Vec3, Vec4};
use rand::{Rng, SeedableRng};

use crate::pose::{Channel, Clip, Interpolation, PoseNode, Property, Trs};
use crate::scene::{Animation, Instance, Scene, Vertex};
use crate::skin::{Skin, SkinVertex};

/// One joint of the figure and the bone box it moves.
struct Bone {
    /// An earlier joint.
    parent: Option<usize>,
    /// From the parent in meters (the pelvis's: from the ground).
    offset: [f32; 3],
    /// The box's half-size.
    half: [f32; 3],
    /// The box hangs from the joint along `-y` (-1), or rises along `+y` (1: the
    /// spine and head).
    along: f32,
}

/// The figure's joints, parents first (indices: the walk's channels name them).
const SKELETON: [Bone; 17] = [
    // 0: pelvis
    Bone {
        parent: None,
        offset: [0.0, 0.95, 0.0],
        half: [0.16, 0.08, 0.1],
        along: 1.0,
    },
    // 1: spine
    Bone {
        parent: Some(0),
        offset: [0.0, 0.08, 0.0],
        half: [0.15, 0.14, 0.09],
        along: 1.0,
    },
    // 2: chest
    Bone {
        parent: Some(1),
        offset: [0.0, 0.28, 0.0],
        half: [0.18, 0.14, 0.1],
        along: 1.0,
    },
    // 3: neck
    Bone {
        parent: Some(2),
        offset: [0.0, 0.28, 0.0],
        half: [0.05, 0.05, 0.05],
        along: 1.0,
    },
    // 4: head
    Bone {
        parent: Some(3),
        offset: [0.0, 0.08, 0.0],
        half: [0.09, 0.11, 0.1],
        along: 1.0,
    },
    // 5: left shoulder
    Bone {
        parent: Some(2),
        offset: [0.23, 0.22, 0.0],
        half: [0.05, 0.15, 0.05],
        along: -1.0,
    },
    // 6: left elbow
    Bone {
        parent: Some(5),
        offset: [0.0, -0.3, 0.0],
        half: [0.04, 0.14, 0.04],
        along: -1.0,
    },
    // 7: left wrist
    Bone {
        parent: Some(6),
        offset: [0.0, -0.28, 0.0],
        half: [0.04, 0.08, 0.02],
        along: -1.0,
    },
    // 8: right shoulder
    Bone {
        parent: Some(2),
        offset: [-0.23, 0.22, 0.0],
        half: [0.05, 0.15, 0.05],
        along: -1.0,
    },
    // 9: right elbow
    Bone {
        parent: Some(8),
        offset: [0.0, -0.3, 0.0],
        half: [0.04, 0.14, 0.04],
        along: -1.0,
    },
    // 10: right wrist
    Bone {
        parent: Some(9),
        offset: [0.0, -0.28, 0.0],
        half: [0.04, 0.08, 0.02],
        along: -1.0,
    },
    // 11: left hip
    Bone {
        parent: Some(0),
        offset: [0.1, -0.05, 0.0],
        half: [0.07, 0.21, 0.07],
        along: -1.0,
    },
    // 12: left knee
    Bone {
        parent: Some(11),
        offset: [0.0, -0.43, 0.0],
        half: [0.05, 0.2, 0.05],
        along: -1.0,
    },
    // 13: left ankle
    Bone {
        parent: Some(12),
        offset: [0.0, -0.42, 0.0],
        half: [0.05, 0.03, 0.11],
        along: -1.0,
    },
    // 14: right hip
    Bone {
        parent: Some(0),
        offset: [-0.1, -0.05, 0.0],
        half: [0.07, 0.21, 0.07],
        along: -1.0,
    },
    // 15: right knee
    Bone {
        parent: Some(14),
        offset: [0.0, -0.43, 0.0],
        half: [0.05, 0.2, 0.05],
        along: -1.0,
    },
    // 16: right ankle
    Bone {
        parent: Some(15),
        offset: [0.0, -0.42, 0.0],
        half: [0.05, 0.03, 0.11],
        along: -1.0,
    },
];

/// Joints per figure.
pub const JOINTS: usize = SKELETON.len();

/// One walk cycle, in seconds (at pace 1).
const CYCLE: f32 = 1.1;

/// Keys per cycle of every channel.
const KEYS: usize = 12;

/// N figures (deterministic from `seed`) standing on a disc around the origin, from 2 m
/// out, about one per 3 square meters; the viewer's presets stand near the origin.
pub fn scene(n: u32, seed: u64) -> Scene {
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(seed);
    let mut scene = Scene::default();
    let (vertices, indices, weights) = figure_mesh();
    for i in 0..n {
        // Area-uniform on the ring 2 m .. R, R growing with the crowd.
        let outer = (4.0 + 3.0 * n as f32 / PI).sqrt();
        let r = rng.random_range(4.0..outer * outer).sqrt();
        let angle = rng.random_range(0.0..TAU);
        let place = Trs {
            translation: Vec3::new(r * angle.cos(), 0.0, r * angle.sin()),
            rotation: Quat::from_rotation_y(rng.random_range(0.0..TAU)),
            scale: Vec3::splat(rng.random_range(0.9..1.1)),
        };
        let color = Vec4::new(rng.random(), rng.random(), rng.random(), 1.0);
        let phase = rng.random_range(0.0..CYCLE);
        let pace = rng.random_range(0.85..1.15);
        add_figure(
            &mut scene,
            (i, place, color),
            (phase, pace),
            (&vertices, &indices, &weights),
        );
    }
    scene.pose(0.0);
    scene
}

/// One figure: its nodes (a placement root above the skeleton), its own mesh and
/// instance, its skin and its walk.
fn add_figure(
    scene: &mut Scene,
    (i, place, color): (u32, Trs, Vec4),
    (phase, pace): (f32, f32),
    (vertices, indices, joint_of): (&[Vertex], &[u32], &[u16]),
) {
    let root = scene.posing.nodes.len() as u32;
    scene.posing.nodes.push(PoseNode {
        parent: None,
        root_from: Affine3A::IDENTITY,
        rest: place,
    });
    let rest_worlds = rest_worlds();
    for Bone { parent, offset, .. } in SKELETON {
        scene.posing.nodes.push(PoseNode {
            parent: Some(parent.map_or(root, |p| root + 1 + p as u32)),
            root_from: Affine3A::IDENTITY,
            rest: Trs {
                translation: Vec3::from(offset),
                rotation: Quat::IDENTITY,
                scale: Vec3::ONE,
            },
        });
    }
    let mesh = scene.add_mesh(format!("figure {i}"), vertices, indices);
    let base = scene.meshes[mesh as usize].base_vertex as u32;
    let joint_base = scene.skins.joint_matrices.len() as u32;
    scene.skins.joint_matrices.extend([[[0.0; 4]; 3]; JOINTS]);
    let first = scene.skins.vertices.len() as u32;
    for (k, (v, &j)) in vertices.iter().zip(joint_of).enumerate() {
        scene.skins.vertices.push(SkinVertex {
            position: v.position,
            normal: v.normal,
            tangent: v.tangent,
            joints: [j, 0, 0, 0],
            weights: [1.0, 0.0, 0.0, 0.0],
            joint_base,
            destination: base + k as u32,
        });
    }
    let inverse_binds: Vec<Affine3A> = rest_worlds.iter().map(|w| w.inverse()).collect();
    scene.skins.skins.push(Skin {
        instance: scene.instances.len() as u32,
        rest_sphere: scene.meshes[mesh as usize].bounds,
        joints: (0..JOINTS as u32).map(|j| root + 1 + j).collect(),
        joint_bounds: bone_bounds(),
        inverse_binds,
        vertices: first..scene.skins.vertices.len() as u32,
        joint_base,
    });
    scene.instances.push(Instance {
        world_from_local: Affine3A::IDENTITY,
        mesh,
        color,
        material: None,
        animation: Animation::NONE,
    });
    scene.posing.clips.push(walk(root + 1, phase, pace));
}

/// Each joint's world transform at rest (the skeleton alone, standing at the origin).
fn rest_worlds() -> Vec<Affine3A> {
    let mut worlds: Vec<Affine3A> = Vec::with_capacity(JOINTS);
    for Bone { parent, offset, .. } in SKELETON {
        let above = parent.map_or(Affine3A::IDENTITY, |p| worlds[p]);
        worlds.push(above * Affine3A::from_translation(Vec3::from(offset)));
    }
    worlds
}

/// The figure's bones as boxes in its rest pose (the skin's bind space), each vertex's
/// one joint.
fn figure_mesh() -> (Vec<Vertex>, Vec<u32>, Vec<u16>) {
    let (mut vertices, mut indices, mut joints) = (Vec::new(), Vec::new(), Vec::new());
    for (j, (world, bone)) in rest_worlds().iter().zip(SKELETON).enumerate() {
        let (half, along) = (bone.half, bone.along);
        let half = Vec3::from(half);
        let center = world.transform_point3(Vec3::new(0.0, along * half.y, 0.0));
        let (corners, box_indices) = eight_corner_box(half);
        let first = vertices.len() as u32;
        vertices.extend(corners.iter().map(|&(p, n)| Vertex::new(center + p, n)));
        indices.extend(box_indices.iter().map(|i| first + i));
        joints.extend([j as u16; 8]);
    }
    (vertices, indices, joints)
}

/// Each bone's box as a sphere in its joint's bind space (what it moves).
fn bone_bounds() -> Vec<Vec4> {
    SKELETON
        .iter()
        .map(|bone| {
            let half = Vec3::from(bone.half);
            Vec3::new(0.0, bone.along * half.y, 0.0).extend(half.length() * (1.0 + 1e-5))
        })
        .collect()
}

/// A box of eight shared corners (normals along the diagonals: smooth at a crowd's
/// distances, and a third of a flat box's vertices), its twelve triangles counter-
/// clockwise seen from outside.
fn eight_corner_box(half: Vec3) -> ([(Vec3, Vec3); 8], [u32; 36]) {
    let corner = |i: u32| {
        let sign = Vec3::new(
            if i & 1 == 0 { -1.0 } else { 1.0 },
            if i & 2 == 0 { -1.0 } else { 1.0 },
            if i & 4 == 0 { -1.0 } else { 1.0 },
        );
        (sign * half, sign.normalize())
    };
    let corners = [0, 1, 2, 3, 4, 5, 6, 7].map(corner);
    #[rustfmt::skip]
    let indices = [
        0, 2, 3, 0, 3, 1, // -z
        4, 5, 7, 4, 7, 6, // +z
        0, 4, 6, 0, 6, 2, // -x
        1, 3, 7, 1, 7, 5, // +x
        0, 1, 5, 0, 5, 4, // -y
        2, 6, 7, 2, 7, 3, // +y
    ];
    (corners, indices)
}

/// The walk: hips, knees, shoulders and elbows swinging about the figure's x axis, the
/// pelvis bobbing twice a cycle; its joints from `first` (the pelvis), at `phase`
/// seconds into the cycle and `pace` times its speed.
fn walk(first: u32, phase: f32, pace: f32) -> Clip {
    let swing = |joint: usize, curve: fn(f32) -> f32| {
        let angles = (0..=KEYS).map(|k| curve(k as f32 / KEYS as f32));
        Channel {
            node: first + joint as u32,
            property: Property::Rotation,
            interpolation: Interpolation::Linear,
            times: key_times(),
            values: angles
                .map(|a| Vec4::from(Quat::from_rotation_x(a)))
                .collect(),
        }
    };
    let bob = Channel {
        node: first,
        property: Property::Translation,
        interpolation: Interpolation::Linear,
        times: key_times(),
        values: (0..=KEYS)
            .map(|k| {
                let u = k as f32 / KEYS as f32;
                Vec4::new(0.0, 0.95 + 0.025 * (2.0 * TAU * u).cos(), 0.0, 0.0)
            })
            .collect(),
    };
    Clip {
        name: "walk".into(),
        channels: vec![
            bob,
            swing(11, |u| 0.45 * (TAU * u).sin()),
            swing(14, |u| -0.45 * (TAU * u).sin()),
            swing(12, |u| 0.45 * (1.0 - (TAU * u).cos())),
            swing(15, |u| 0.45 * (1.0 + (TAU * u).cos())),
            swing(5, |u| -0.35 * (TAU * u).sin()),
            swing(8, |u| 0.35 * (TAU * u).sin()),
            swing(6, |u| -0.3 - 0.2 * (TAU * u).sin()),
            swing(9, |u| -0.3 + 0.2 * (TAU * u).sin()),
        ],
        offset: phase,
        speed: pace,
    }
}

fn key_times() -> Vec<f32> {
    (0..=KEYS).map(|k| CYCLE * k as f32 / KEYS as f32).collect()
}
