//! Built-in meshes for procedural scenes, in meters, centered on the origin.

use std::f32::consts::TAU;

use glam::Vec3;

use crate::scene::Vertex;

/// Indexed triangles, counter-clockwise when seen from outside.
pub struct Shape {
    /// Local space, meters.
    pub vertices: Vec<Vertex>,
    /// Three per triangle.
    pub indices: Vec<u32>,
}

/// Shape `k` of an endless family: box, sphere, cylinder, torus, each cycle with other
/// proportions and tessellation, so that any mesh count gives distinct meshes. The
/// curved ones are tessellated like an engine's props (96 to 1,610 triangles), finer
/// than a distant view needs, which is what levels of detail are for.
pub fn family(k: u32) -> Shape {
    let variant = (k / 4) as f32;
    let t = 1.0 + 0.15 * (variant % 7.0);
    match k % 4 {
        0 => cuboid(Vec3::new(0.5 * t, 0.5, 0.5 / t)),
        1 => sphere(0.3 * t, 24 + (k / 4) % 12, 16 + (k / 4) % 8),
        2 => cylinder(0.2 * t, 0.8, 24 + (k / 4) % 20),
        _ => torus(0.35, 0.1 * t, 32 + (k / 4) % 12, 12 + (k / 4) % 6),
    }
}

/// A box of half extents `half`, centered on the origin (12 triangles).
pub fn cuboid(half: Vec3) -> Shape {
    let mut s = Shape {
        vertices: Vec::new(),
        indices: Vec::new(),
    };
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let n = Vec3::AXES[axis] * sign;
            let u = Vec3::AXES[(axis + 1) % 3] * sign;
            let v = n.cross(u);
            let base = s.vertices.len() as u32;
            for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                s.vertices.push(Vertex {
                    uv: [0.5 + 0.5 * a, 0.5 - 0.5 * b],
                    ..Vertex::new((n + u * a + v * b) * half, n)
                });
            }
            s.indices.extend([0, 1, 2, 0, 2, 3].map(|i| base + i));
        }
    }
    s
}

/// A unit box (half-size 0.5) whose four sides are facades of `columns x floors`
/// quads (a window grid) under a flat roof: the city's buildings.
pub fn building(columns: u32, floors: u32) -> Shape {
    let mut out = Shape {
        vertices: Vec::new(),
        indices: Vec::new(),
    };
    let mut add = |s: Shape| {
        let base = out.vertices.len() as u32;
        out.vertices.extend(s.vertices);
        out.indices.extend(s.indices.iter().map(|i| base + i));
    };
    for n in [Vec3::X, Vec3::Z, Vec3::NEG_X, Vec3::NEG_Z] {
        // Counter-clockwise from outside: across x up = n.
        let across = Vec3::Y.cross(n);
        add(grid(columns, floors, |u, v| {
            (0.5 * n + across * (u - 0.5) + Vec3::Y * (v - 0.5), n)
        }));
    }
    for (n, down) in [(Vec3::Y, Vec3::NEG_Z), (Vec3::NEG_Y, Vec3::Z)] {
        add(grid(1, 1, |u, v| {
            (0.5 * n + Vec3::X * (u - 0.5) + down * (v - 0.5), n)
        }));
    }
    out
}

/// A grid of `(columns + 1) x (rows + 1)` vertices from `f(u, v)` (both in 0..=1, also
/// the texture coordinates) returning position and normal, stitched into quads.
fn grid(columns: u32, rows: u32, f: impl Fn(f32, f32) -> (Vec3, Vec3)) -> Shape {
    let mut vertices = Vec::new();
    for r in 0..=rows {
        for c in 0..=columns {
            let (u, v) = (c as f32 / columns as f32, r as f32 / rows as f32);
            let (p, n) = f(u, v);
            vertices.push(Vertex {
                uv: [u, 1.0 - v],
                ..Vertex::new(p, n)
            });
        }
    }
    let mut indices = Vec::new();
    let stride = columns + 1;
    for r in 0..rows {
        for c in 0..columns {
            let i = r * stride + c;
            indices.extend([i, i + 1, i + stride + 1, i, i + stride + 1, i + stride]);
        }
    }
    Shape { vertices, indices }
}

/// A UV sphere of `radius`, `segments` around and `rings` from pole to pole.
pub fn sphere(radius: f32, segments: u32, rings: u32) -> Shape {
    grid(segments, rings, |u, v| {
        let (theta, phi) = (u * TAU, (v - 0.5) * std::f32::consts::PI);
        let n = Vec3::new(phi.cos() * theta.sin(), phi.sin(), phi.cos() * theta.cos());
        (n * radius, n)
    })
}

/// An open tube, seen from inside too (both windings: back faces are culled): enough for
/// a stress scene, and its normals are smooth.
pub fn cylinder(radius: f32, height: f32, segments: u32) -> Shape {
    let tube = grid(segments, 1, |u, v| {
        let theta = u * TAU;
        let n = Vec3::new(theta.sin(), 0.0, theta.cos());
        (n * radius + Vec3::Y * (v - 0.5) * height, n)
    });
    Shape {
        indices: crate::scene::both_windings(&tube.indices),
        ..tube
    }
}

/// A torus about +Y: ring radius `major`, tube radius `minor`, tessellated `segments`
/// around and `sides` about the tube.
pub fn torus(major: f32, minor: f32, segments: u32, sides: u32) -> Shape {
    grid(segments, sides, |u, v| {
        let (theta, phi) = (u * TAU, v * TAU);
        let ring = Vec3::new(theta.sin(), 0.0, theta.cos());
        let n = ring * phi.cos() + Vec3::Y * phi.sin();
        (ring * major + n * minor, n)
    })
}
