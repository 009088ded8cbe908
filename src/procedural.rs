//! Procedural scenes: built-in shapes scattered around the viewer at real scale,
//! deterministic from a seed. Stress tests and profiles use them at any size.

use glam::{Affine3A, Quat, Vec3, Vec4};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;

use crate::lights::Light;
use crate::scene::{AlphaMode, Animation, Instance, Material, Scene, Texture};
use crate::shapes::{self, Shape};

/// `n` instances of `mesh_count` built-in meshes scattered in a ball around the
/// origin (where every preset's viewer stands), at real scale: objects of 0.1 m to
/// 1.5 m, spread so that density stays near a few per cubic meter at any `n`. Ids
/// follow a Hilbert curve through the ball, as an engine that inserts in spatial order
/// would give them: neighbours in the cull order are neighbours in space, which the
/// coarse cull's blocks ([`crate::cull::coarse`]) need.
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
                material: None,
                animation: Animation::NONE,
            }
        })
        .collect();
    let offset = |i: &Instance| (Vec3::from(i.world_from_local.translation) - center) / radius;
    scene.instances.sort_by_cached_key(|i| hilbert(offset(i)));
    scene
}

/// The position of `p` (in the cube `[-1, 1]^3`) along a Hilbert curve of 10 bits per
/// axis.
fn hilbert(p: Vec3) -> u32 {
    hilbert_index(
        p.to_array()
            .map(|v| ((v * 0.5 + 0.5).clamp(0.0, 1.0) * 1023.0) as u32),
        10,
    )
}

/// The position of grid cell `x` (`bits` per axis, at most 10) along a Hilbert curve,
/// by Skilling's transpose ("Programming the Hilbert curve", 2004): unlike a Morton
/// curve it never jumps, so any run of it stays compact.
fn hilbert_index(mut x: [u32; 3], bits: u32) -> u32 {
    let mut q = 1 << (bits - 1);
    while q > 1 {
        let low = q - 1;
        for i in 0..3 {
            if x[i] & q != 0 {
                x[0] ^= low;
            } else {
                let t = (x[0] ^ x[i]) & low;
                x[0] ^= t;
                x[i] ^= t;
            }
        }
        q >>= 1;
    }
    x[1] ^= x[0];
    x[2] ^= x[1];
    let mut t = 0;
    let mut q = 1 << (bits - 1);
    while q > 1 {
        if x[2] & q != 0 {
            t ^= q - 1;
        }
        q >>= 1;
    }
    let spread = |v: u32| {
        let mut v = v ^ t;
        v = (v | (v << 16)) & 0x0300_00ff;
        v = (v | (v << 8)) & 0x0300_f00f;
        v = (v | (v << 4)) & 0x030c_30c3;
        (v | (v << 2)) & 0x0924_9249
    };
    (spread(x[0]) << 2) | (spread(x[1]) << 1) | spread(x[2])
}

/// A city around a room: a tenth of `n` instances are objects of the procedural scene
/// within 8 m of the viewer's standing point, the rest buildings (facades of 6 x 16
/// windows, 772 triangles; 8 to 30 m wide, 10 to 120 m tall, on the ground) from 200 m
/// to 2 km away: most of what a viewer sees is far enough that both eyes see it alike.
pub fn city(n: u32, seed: u64) -> Scene {
    let room = n / 10;
    let mut scene = scene(room, 8, seed);
    // Pulled in from the procedural ball to 8 m.
    let center = Vec3::new(0.0, 1.5, 0.0);
    let shrink = (8.0 / (4.0 + (room as f32).cbrt() * 0.8)).min(1.0);
    for inst in &mut scene.instances {
        let t = Vec3::from(inst.world_from_local.translation);
        inst.world_from_local.translation = (center + (t - center) * shrink).into();
    }
    let building = shapes::building(6, 16);
    let mesh = scene.add_mesh(
        "building".to_string(),
        &building.vertices,
        &building.indices,
    );
    let mut rng = Pcg64Mcg::seed_from_u64(seed ^ 0xc17);
    scene.instances.extend((room..n).map(|_| {
        let angle = rng.random_range(0.0..std::f32::consts::TAU);
        let distance = rng.random_range(200.0f32..2000.0);
        let size = Vec3::new(
            rng.random_range(8.0..30.0),
            rng.random_range(10.0..120.0),
            rng.random_range(8.0..30.0),
        );
        let at = Vec3::new(angle.cos() * distance, size.y * 0.5, angle.sin() * distance);
        let grey = rng.random_range(0.35..0.8);
        Instance {
            world_from_local: Affine3A::from_scale_rotation_translation(size, Quat::IDENTITY, at),
            mesh,
            color: Vec4::new(grey, grey * 0.95, grey * 0.9, 1.0),
            material: None,
            animation: Animation::NONE,
        }
    }));
    scene
}

/// Rooms' side, height, walls' thickness, and their doorways' width and height, in
/// meters: a house's proportions.
const ROOM: f32 = 6.0;
const ROOM_HEIGHT: f32 = 3.0;
const WALL: f32 = 0.15;
const DOOR: [f32; 2] = [1.0, 2.2];

/// An occluder-heavy interior: `n` props (the procedural scene's shapes, 0.15 to 0.6 m,
/// on the floor or up to 2 m high) spread over a square grid of rooms 6 m a side and
/// 3 m high (each with a floor and a ceiling), about 24 to a room, the viewer's
/// standing point in the middle room. Every
/// wall between two rooms has a doorway at a random place along it; the outer walls are
/// whole. From inside a room most props of the others are behind a wall, and the
/// doorways let some be seen, some by one eye only. Ids follow a Hilbert curve, as in
/// [`scene`].
pub fn rooms(n: u32, seed: u64) -> Scene {
    let mut scene = scene(0, 8, seed);
    let c = shapes::cuboid(Vec3::splat(0.5));
    let wall_mesh = scene.add_mesh("wall".to_string(), &c.vertices, &c.indices);
    let side = ((n as f32 / 24.0).sqrt().ceil() as u32).max(1) | 1;
    let half = side as f32 * ROOM * 0.5;
    let mut rng = Pcg64Mcg::seed_from_u64(seed ^ 0x2007);
    let mut walls = Vec::new();
    for line in 0..=side {
        let at = line as f32 * ROOM - half;
        let outer = line == 0 || line == side;
        for cell in 0..side {
            let from = cell as f32 * ROOM - half;
            let door = (!outer).then(|| rng.random_range(DOOR[0]..ROOM - DOOR[0]));
            for (start, length, bottom, top) in wall_pieces(door) {
                let mid = from + start + length * 0.5;
                let size = Vec3::new(length, top - bottom, WALL);
                let y = (bottom + top) * 0.5;
                walls.push((Vec3::new(mid, y, at), size, false));
                walls.push((Vec3::new(at, y, mid), size, true));
            }
        }
    }
    let mut add = |at: Vec3, size: Vec3, turned: bool, mesh: u32, color: Vec4| {
        let rotation = match turned {
            true => Quat::from_rotation_y(std::f32::consts::FRAC_PI_2),
            false => Quat::IDENTITY,
        };
        scene.instances.push(Instance {
            world_from_local: Affine3A::from_scale_rotation_translation(size, rotation, at),
            mesh,
            color,
            material: None,
            animation: Animation::NONE,
        });
    };
    let plaster = Vec4::new(0.85, 0.82, 0.76, 1.0);
    for (at, size, turned) in walls {
        add(at, size, turned, wall_mesh, plaster);
    }
    let cells = side * side;
    let (floor, ceiling) = (
        Vec4::new(0.45, 0.36, 0.28, 1.0),
        Vec4::new(0.93, 0.93, 0.9, 1.0),
    );
    for cell in 0..cells {
        let corner = Vec3::new(
            (cell % side) as f32 * ROOM - half,
            0.0,
            (cell / side) as f32 * ROOM - half,
        );
        let slab = Vec3::new(ROOM, WALL, ROOM);
        let middle = corner + Vec3::new(ROOM * 0.5, 0.0, ROOM * 0.5);
        add(
            middle - Vec3::Y * (WALL * 0.5),
            slab,
            false,
            wall_mesh,
            floor,
        );
        add(
            middle + Vec3::Y * (ROOM_HEIGHT + WALL * 0.5),
            slab,
            false,
            wall_mesh,
            ceiling,
        );
        let props = n * (cell + 1) / cells - n * cell / cells;
        for _ in 0..props {
            let margin = 0.5;
            let at = corner
                + Vec3::new(
                    rng.random_range(margin..ROOM - margin),
                    rng.random_range(0.3..2.0),
                    rng.random_range(margin..ROOM - margin),
                );
            let size = Vec3::splat(rng.random_range(0.15..0.6));
            let mesh = rng.random_range(0..wall_mesh);
            let color = Vec4::new(rng.random(), rng.random(), rng.random(), 1.0);
            add(at, size, false, mesh, color);
        }
    }
    let offset = |i: &Instance| Vec3::from(i.world_from_local.translation) / half.max(1.0);
    scene.instances.sort_by_cached_key(|i| hilbert(offset(i)));
    scene.lights = (0..cells)
        .map(|cell| {
            let (x, z) = ((cell % side) as f32 + 0.5, (cell / side) as f32 + 0.5);
            let at = Vec3::new(x * ROOM - half, ROOM_HEIGHT - 0.8, z * ROOM - half);
            Light::point(at, Vec3::new(1.0, 0.85, 0.65), LAMP_CANDELA, Some(ROOM))
        })
        .collect();
    scene
}

/// A room's ceiling lamp: a warm point light reaching a room's width.
const LAMP_CANDELA: f32 = 3.0;

/// `n` point lights scattered over `scene`'s instances (seeded): each somewhere over the
/// box of their positions, 0.5 to 2.8 m above its floor, of 1 to 6 candela reaching 3 to
/// 6 m, warm to cool white.
pub fn scatter_lights(scene: &mut Scene, n: u32, seed: u64) {
    let centers = scene
        .instances
        .iter()
        .map(|i| Vec3::from(i.world_from_local.translation));
    let (lo, hi) = centers.fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), c| (lo.min(c), hi.max(c)),
    );
    let (lo, hi) = if lo.x <= hi.x {
        (lo, hi)
    } else {
        (Vec3::splat(-10.0), Vec3::splat(10.0))
    };
    let mut rng = Pcg64Mcg::seed_from_u64(seed ^ 0x11647);
    for _ in 0..n {
        let at = Vec3::new(
            rng.random_range(lo.x..=hi.x),
            lo.y + rng.random_range(0.5..2.8),
            rng.random_range(lo.z..=hi.z),
        );
        let warmth: f32 = rng.random();
        let color = Vec3::new(1.0, 0.8 + 0.2 * warmth, 0.6 + 0.4 * warmth);
        let range = rng.random_range(3.0..6.0);
        scene.lights.push(Light::point(
            at,
            color,
            rng.random_range(1.0..6.0),
            Some(range),
        ));
    }
}

/// The pieces of one room's wall along its length ([`ROOM`]): `(start, length, bottom,
/// top)`, whole, or around a doorway centered `door` along it.
fn wall_pieces(door: Option<f32>) -> Vec<(f32, f32, f32, f32)> {
    let Some(center) = door else {
        return vec![(0.0, ROOM, 0.0, ROOM_HEIGHT)];
    };
    let (left, right) = (center - DOOR[0] * 0.5, center + DOOR[0] * 0.5);
    vec![
        (0.0, left, 0.0, ROOM_HEIGHT),
        (right, ROOM - right, 0.0, ROOM_HEIGHT),
        (left, DOOR[0], DOOR[1], ROOM_HEIGHT),
    ]
}

/// Gives every mesh of `scene` one base color texture (a generated 256 x 256 pattern of
/// colored tiles and stripes, so that filtering and mipmaps have work to do).
pub fn texture(scene: &mut Scene) {
    let image = image::RgbaImage::from_fn(256, 256, |x, y| {
        let tile = ((x / 32) + (y / 32)) % 2;
        let stripe = u8::from((x + y) % 16 < 3);
        let base = if tile == 0 {
            [230, 200, 120]
        } else {
            [90, 140, 210]
        };
        image::Rgba([
            base[0] - 60 * stripe,
            base[1] - 60 * stripe,
            base[2] - 60 * stripe,
            255,
        ])
    });
    scene.textures = vec![Texture {
        name: "procedural tiles".into(),
        image,
        encoding: Default::default(),
        basis: None,
    }];
    scene.materials = vec![Material {
        name: "tiled".into(),
        base_color_texture: Some(0),
        ..Default::default()
    }];
    for v in &mut scene.vertices {
        v.material = 0;
    }
}

/// Makes `percent` % of `scene`'s meshes (the first ones, at least one for any
/// positive share) glass: a blended material like the scene's first (or plain), and
/// their instances half transparent. For profiling the blended bins' sort.
pub fn glaze(scene: &mut Scene, percent: f64) {
    let meshes = scene.meshes.len();
    let glazed = ((meshes as f64 * percent / 100.0).round() as usize)
        .clamp(usize::from(percent > 0.0), meshes);
    if glazed == 0 {
        return;
    }
    let base = scene.materials.first().cloned().unwrap_or_default();
    if scene.materials.is_empty() {
        scene.materials.push(base.clone());
    }
    scene.materials.push(Material {
        name: "glass".into(),
        alpha: AlphaMode::Blend,
        ..base
    });
    let glass = scene.materials.len() as u32 - 1;
    for m in 0..glazed {
        let mesh = scene.meshes[m].clone();
        let first = mesh.first_index as usize;
        for &i in &scene.indices[first..first + mesh.index_count as usize] {
            scene.vertices[(i as i32 + mesh.base_vertex) as usize].material = glass;
        }
    }
    for inst in scene
        .instances
        .iter_mut()
        .filter(|i| (i.mesh as usize) < glazed)
    {
        inst.color.w = 0.5;
    }
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

#[cfg(test)]
mod tests {
    use super::hilbert_index;

    /// Every cell of an 8^3 grid gets its own index, and cells one index apart share a
    /// face: the curve visits all of them without a jump.
    #[test]
    fn the_hilbert_curve_visits_every_cell_by_steps_to_a_neighbour() {
        let mut cells = vec![None; 512];
        for x in 0..8 {
            for y in 0..8 {
                for z in 0..8 {
                    let index = hilbert_index([x, y, z], 3) as usize;
                    assert!(cells[index].is_none(), "index {index} twice");
                    cells[index] = Some([x as i32, y as i32, z as i32]);
                }
            }
        }
        let cells: Vec<[i32; 3]> = cells.into_iter().map(|c| c.expect("every index")).collect();
        for pair in cells.windows(2) {
            let step: i32 = (0..3).map(|i| (pair[0][i] - pair[1][i]).abs()).sum();
            assert_eq!(step, 1, "{:?} to {:?}", pair[0], pair[1]);
        }
    }
}
