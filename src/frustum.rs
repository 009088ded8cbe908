//! Perspective views, frustum planes and the combined (display, frame) frustum.
//!
//! Conventions: right-handed, +Y up, a view looks down its own -Z, clip depth 0..1 (wgpu).
//! Planes are `Vec4(n, d)` with `dot(n, p) + d >= 0` inside, `n` unit length.
//!
//! Views are posed and their frusta built in f64, then rounded once (outwards) to the
//! f32 planes the culler tests: a viewer kilometers from the origin has no f32 eye
//! position to spare, and at a grazing angle one f32 ulp of the eye tilts a side plane
//! by meters at a few kilometers' distance.

use glam::{DAffine3, DMat3, DQuat, DVec3, Mat4, Vec3, Vec4, Vec4Swizzles};
use serde::{Deserialize, Serialize};

/// Field of view as tangents of the half-angles from the view axis to each edge.
/// Asymmetric and off-axis frusta are just unequal tangents; a tangent may be
/// negative when the axis lies outside the window (a far-off CAVE wall).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Fov {
    /// Tangent of the half-angle to the left edge.
    pub left: f32,
    /// Tangent of the half-angle to the right edge.
    pub right: f32,
    /// Tangent of the half-angle to the top edge.
    pub up: f32,
    /// Tangent of the half-angle to the bottom edge.
    pub down: f32,
}

impl Fov {
    /// The same window seen mirrored left-right (the other eye of a symmetric headset).
    pub fn mirrored(self) -> Fov {
        Fov {
            left: self.right,
            right: self.left,
            ..self
        }
    }

    /// Left, right, up, down in f64, for building frusta.
    pub fn tangents(&self) -> [f64; 4] {
        [self.left, self.right, self.up, self.down].map(f64::from)
    }

    /// A window that has area and stays in front of the eye (each tangent finite, so
    /// every half-angle is below 90 degrees and the whole angle below 180).
    pub fn is_valid(&self) -> bool {
        let t = [self.left, self.right, self.up, self.down];
        t.iter().all(|v| v.is_finite()) && self.left + self.right > 0.0 && self.up + self.down > 0.0
    }
}

/// One center of projection: an eye, or the apex of a combined frustum.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    /// Rigid pose (rotation and translation only), in f64; its translation is the apex.
    pub world_from_view: DAffine3,
    /// The window through which the view looks.
    pub fov: Fov,
    /// Near plane distance in meters.
    pub near: f32,
    /// Far plane distance in meters.
    pub far: f32,
}

impl View {
    /// The apex, rounded to f32 (what shaders get).
    pub fn position(&self) -> Vec3 {
        self.world_from_view.translation.as_vec3()
    }

    /// World to view space, rounded to f32.
    pub fn view_from_world(&self) -> Mat4 {
        self.view_from_world_f64().as_mat4()
    }

    fn view_from_world_f64(&self) -> glam::DMat4 {
        glam::DMat4::from(self.world_from_view.inverse())
    }

    /// View to world space, rounded to f32.
    pub fn world_from_view_f32(&self) -> Mat4 {
        glam::DMat4::from(self.world_from_view).as_mat4()
    }

    /// Off-axis perspective projection with depth 0 at `near` and 1 at `far`.
    pub fn clip_from_view(&self) -> Mat4 {
        let Fov {
            left: l,
            right: r,
            up: u,
            down: d,
        } = self.fov;
        let (n, f) = (self.near, self.far);
        Mat4::from_cols(
            Vec4::new(2.0 / (l + r), 0.0, 0.0, 0.0),
            Vec4::new(0.0, 2.0 / (u + d), 0.0, 0.0),
            Vec4::new((r - l) / (l + r), (u - d) / (u + d), f / (n - f), -1.0),
            Vec4::new(0.0, 0.0, n * f / (n - f), 0.0),
        )
    }

    /// Composed in f64 and rounded once: the vertex stage then needs one product per
    /// vertex instead of two, and loses nothing to an f32 view translation.
    pub fn clip_from_world(&self) -> Mat4 {
        self.clip_from_world_f64().as_mat4()
    }

    /// The inverse of [`View::clip_from_world`]: the pose times
    /// [`View::view_from_clip`]'s f64 form, composed in f64 and rounded once.
    pub fn world_from_clip(&self) -> Mat4 {
        self.world_from_clip_f64().as_mat4()
    }

    /// The pose times [`View::view_from_clip`]'s columns, term by term: the pose is
    /// rigid and the inverse sparse, so this is a fifth of a full product.
    fn world_from_clip_f64(&self) -> glam::DMat4 {
        let [x, y, z, w] = self.view_from_clip_columns();
        let pose = self.world_from_view;
        let [rx, ry, rz] = [
            pose.matrix3.x_axis,
            pose.matrix3.y_axis,
            pose.matrix3.z_axis,
        ];
        let t = pose.translation;
        glam::DMat4::from_cols(
            (rx * x.x).extend(0.0),
            (ry * y.y).extend(0.0),
            (t * z.w).extend(z.w),
            (rx * w.x + ry * w.y + rz * w.z + t * w.w).extend(w.w),
        )
    }

    /// The inverse of [`View::clip_from_view`] (of the f32 matrix, in f64, rounded once).
    pub fn view_from_clip(&self) -> Mat4 {
        glam::DMat4::from_cols_array_2d(&self.view_from_clip_columns().map(|c| c.to_array()))
            .as_mat4()
    }

    /// A perspective's inverse in closed form, by columns (a general 4x4 inverse costs
    /// five times as much, and a latch makes one for every view): with `x' = sx x + a z`,
    /// `y' = sy y + b z`, `z' = c z + d`, `w' = -z`, the view point is
    /// `((x' + a w') / sx, (y' + b w') / sy, -w', (z' + c w') / d)`.
    fn view_from_clip_columns(&self) -> [glam::DVec4; 4] {
        let p = self.clip_from_view().as_dmat4();
        let (sx, sy, d) = (p.x_axis.x, p.y_axis.y, p.w_axis.z);
        let (a, b, c) = (p.z_axis.x, p.z_axis.y, p.z_axis.z);
        [
            glam::DVec4::new(1.0 / sx, 0.0, 0.0, 0.0),
            glam::DVec4::new(0.0, 1.0 / sy, 0.0, 0.0),
            glam::DVec4::new(0.0, 0.0, 0.0, 1.0 / d),
            glam::DVec4::new(a / sx, b / sy, -1.0, c / d),
        ]
    }

    /// [`View::view_from_world`], [`View::clip_from_world`] and
    /// [`View::world_from_clip`] together, bit for bit, with the f64 products they share
    /// made once: a context needs all three for every view of every frame.
    pub fn world_matrices(&self) -> [Mat4; 3] {
        let view_from_world = self.view_from_world_f64();
        let clip_from_world = self.clip_from(view_from_world);
        [
            view_from_world.as_mat4(),
            clip_from_world.as_mat4(),
            self.world_from_clip_f64().as_mat4(),
        ]
    }

    fn clip_from_world_f64(&self) -> glam::DMat4 {
        self.clip_from(self.view_from_world_f64())
    }

    /// World to clip in f64, from the view's `view_from_world`.
    fn clip_from(&self, view_from_world: glam::DMat4) -> glam::DMat4 {
        self.clip_from_view().as_dmat4() * view_from_world
    }

    /// The six planes, built from the pose and tangents rather than extracted from
    /// the projection matrix: extraction loses about a meter at 1 km in f32 when
    /// far / near is 2e4. Built in f64, then pushed out by [`ROUNDING_SLACK`] of their
    /// magnitude and rounded to f32.
    pub fn frustum(&self) -> Frustum {
        let [l, r, u, d] = self.fov.tangents();
        let (near, far) = (self.near as f64, self.far as f64);
        let in_view = [
            (DVec3::new(1.0, 0.0, -l), 0.0),
            (DVec3::new(-1.0, 0.0, -r), 0.0),
            (DVec3::new(0.0, 1.0, -d), 0.0),
            (DVec3::new(0.0, -1.0, -u), 0.0),
            (DVec3::NEG_Z, -near),
            (DVec3::Z, far),
        ];
        let apex = self.world_from_view.translation;
        let magnitude = apex.abs().element_sum();
        let slack = ROUNDING_SLACK as f64;
        Frustum {
            planes: in_view.map(|(n, dist)| {
                let n = self.world_from_view.transform_vector3(n.normalize());
                let w = dist - n.dot(apex) + slack * (magnitude + dist.abs());
                n.as_vec3().extend(w as f32)
            }),
        }
    }

    /// The 8 corners in world space: near lower-left, lower-right, upper-right,
    /// upper-left, then the far ones in the same order (corner `i` and `i + 4` span
    /// one lateral edge).
    pub fn corners(&self) -> [DVec3; 8] {
        let window = self.window();
        std::array::from_fn(|i| {
            let dist = if i < 4 { self.near } else { self.far } as f64;
            self.world_from_view.transform_point3(window[i % 4] * dist)
        })
    }

    /// The directions of the four lateral edges in view space (lower-left,
    /// lower-right, upper-right, upper-left), at unit depth.
    fn window(&self) -> [DVec3; 4] {
        let [l, r, u, d] = self.fov.tangents();
        [(-l, -d), (r, -d), (r, u), (-l, u)].map(|(x, y)| DVec3::new(x, y, -1.0))
    }
}

/// Six planes: left, right, bottom, top, near, far.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frustum {
    /// Inside when `dot(n, p) + d >= 0` for every plane.
    pub planes: [Vec4; 6],
}

impl Frustum {
    /// Whether point `p` is inside every plane.
    pub fn contains_point(&self, p: Vec3) -> bool {
        self.planes.iter().all(|pl| pl.xyz().dot(p) + pl.w >= 0.0)
    }
}

/// Relative slack (16 units in the last place of f32) by which planes are pushed out
/// and sphere radii grown ([`crate::scene::Scene::world_sphere`]): the plane test sums
/// four products of magnitude |center| and |plane.w|, so its rounding error is a few
/// ulps of those. With this slack no rounding, even a million meters from the origin,
/// can cull a sphere that meets the true frustum (tests/properties.rs).
pub const ROUNDING_SLACK: f32 = 1.0 / (1u32 << 20) as f32;

/// Conservative sphere test, `s` = (center, radius): the CPU twin of `sphere_in_planes`
/// in `wgsl/shared/cull_math.wgsl`. The operation order is the contract: same products,
/// same sums, left to right, no fused multiply-add, so CPU and GPU decide identically.
#[inline]
pub fn sphere_in_planes(planes: &[Vec4; 6], s: Vec4) -> bool {
    planes
        .iter()
        .all(|p| plane_distance(p.to_array(), [s.x, s.y, s.z]) >= -s.w)
}

/// `p`'s signed distance of `c` (scaled by the normal's length) in the order every plane
/// test uses: `p.x * c.x + p.y * c.y + p.z * c.z + p.w`, products summed left to right,
/// no fused multiply-add. The one Rust spelling of it: [`sphere_in_planes`], the CPU
/// culler's lanes and the coarse test all call it, and WGSL's twins
/// (`wgsl/shared/cull_math.wgsl`, `cull_coarse.wgsl`) are written in the same order.
#[inline(always)]
pub fn plane_distance(p: [f32; 4], c: [f32; 3]) -> f32 {
    p[0] * c[0] + p[1] * c[1] + p[2] * c[2] + p[3]
}

/// How far (meters) every side of a combined frustum is pushed out beyond the exact
/// bound, so that rounding can never make it smaller than the views it must contain.
const ENCLOSING_SLACK: f64 = 1e-5;

/// The smallest-apex perspective view, oriented by `orientation`, that contains every
/// given view's frustum. `origin` (the viewer) is where the corners are measured from,
/// so that combined frusta keep millimeters near eyes far from the world origin.
///
/// The chapter's Figure 1.2, generalised to asymmetric, canted and off-axis views: each
/// side takes the widest lateral-edge tangent of the inputs, then the apex is placed
/// (behind the eyes) so that every side plane contains every input corner; near and far
/// take the nearest and farthest input corners. For two parallel eyes this is exactly the
/// chapter's construction (right plane = left eye's right plane moved to the right eye).
/// `None` when the inputs span 180 degrees or more (no single frustum holds them: a CAVE).
///
/// Each view is carried into the basis as one rotation and offset, not corner by corner:
/// a latch builds every display's on the submit's path.
pub fn enclosing_view(orientation: DQuat, origin: DVec3, views: &[View]) -> Option<View> {
    let to_basis = DMat3::from_quat(orientation.inverse());
    // A view in the basis: its apex, and its four lateral edges' directions at unit
    // depth (a corner is the apex plus a direction times its depth).
    let in_basis = |v: &View| {
        let rotation = to_basis * v.world_from_view.matrix3;
        let apex = to_basis * (v.world_from_view.translation - origin);
        (apex, v.window().map(|w| rotation * w))
    };
    let fov = widest_fov(views.iter().map(|v| in_basis(v).1))?;
    let [left, right, up, down] = fov.tangents();
    // One pass over the corners for the four side reaches and the depth range.
    let mut reach = [f64::MIN; 4];
    let (mut z_nearest, mut z_farthest) = (f64::MIN, f64::MAX);
    for v in views {
        let (apex, edges) = in_basis(v);
        for dist in [v.near, v.far].map(f64::from) {
            for e in edges {
                let p = apex + e * dist;
                let sides = [
                    p.x + right * p.z,
                    -p.x + left * p.z,
                    p.y + up * p.z,
                    -p.y + down * p.z,
                ];
                for (r, s) in reach.iter_mut().zip(sides) {
                    *r = wider(*r, s);
                }
                z_nearest = wider(z_nearest, p.z);
                z_farthest = -wider(-z_farthest, -p.z);
            }
        }
    }
    let [c_right, c_left, c_up, c_down] = reach.map(|r| r + ENCLOSING_SLACK);
    let apex_z = f64::max(
        (c_right + c_left) / (left + right),
        (c_up + c_down) / (up + down),
    );
    // Any x in [c_right - r z, l z - c_left] works; the middle keeps slack on both sides.
    let apex_x = 0.5 * ((c_right - right * apex_z) + (left * apex_z - c_left));
    let apex_y = 0.5 * ((c_up - up * apex_z) + (down * apex_z - c_down));
    let near = round_down(apex_z - z_nearest);
    let far = round_up(apex_z - z_farthest + ENCLOSING_SLACK);
    if !(near > 0.0 && far > near && apex_z.is_finite()) {
        return None;
    }
    Some(View {
        world_from_view: DAffine3::from_rotation_translation(
            orientation,
            origin + orientation * DVec3::new(apex_x, apex_y, apex_z),
        ),
        fov,
        near,
        far,
    })
}

/// Widest tangent per side over all lateral edges (each view's edge directions in the
/// basis), rounded outwards to f32.
fn widest_fov(views: impl Iterator<Item = [DVec3; 4]>) -> Option<Fov> {
    let mut widest = [f64::MIN; 4];
    for edges in views {
        for e in edges {
            let depth = -e.z;
            // An edge at 89.9 degrees or more from the axis: no finite tangent holds it.
            if depth <= 1e-3 * e.length() {
                return None;
            }
            let [right, left, up, down] = &mut widest;
            *right = wider(*right, e.x / depth);
            *left = wider(*left, -e.x / depth);
            *up = wider(*up, e.y / depth);
            *down = wider(*down, -e.y / depth);
        }
    }
    let [right, left, up, down] = widest.map(round_up);
    let fov = Fov {
        left,
        right,
        up,
        down,
    };
    fov.is_valid().then_some(fov)
}

/// The larger of `a` and `b`, both finite (the rig is validated): one instruction,
/// where `f64::max`'s NaN rule costs several in the corner loops.
#[inline(always)]
fn wider(a: f64, b: f64) -> f64 {
    if b > a { b } else { a }
}

/// The smallest f32 not below `x`.
pub(crate) fn round_up(x: f64) -> f32 {
    let r = x as f32;
    if (r as f64) < x { r.next_up() } else { r }
}

/// The largest f32 not above `x`.
fn round_down(x: f64) -> f32 {
    let r = x as f32;
    if (r as f64) > x { r.next_down() } else { r }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn eye(x: f64) -> View {
        View {
            world_from_view: DAffine3::from_translation(DVec3::new(x, 0.0, 0.0)),
            fov: Fov {
                left: 1.0,
                right: 0.8,
                up: 0.9,
                down: 1.1,
            },
            near: 0.1,
            far: 50.0,
        }
    }

    #[test]
    fn projection_maps_corners_to_ndc_corners() {
        let v = eye(0.3);
        let m = v.clip_from_world();
        let ndc = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
        for (i, c) in v.corners().iter().enumerate() {
            let p = m.project_point3(c.as_vec3());
            let (x, y) = ndc[i % 4];
            let z = if i < 4 { 0.0 } else { 1.0 };
            assert!(
                (p - Vec3::new(x, y, z)).abs().max_element() < 1e-4,
                "{i}: {p}"
            );
        }
    }

    #[test]
    fn world_matrices_are_the_three_made_apart() {
        let mut v = eye(0.3);
        v.world_from_view = DAffine3::from_rotation_translation(
            DQuat::from_euler(glam::EulerRot::YXZ, 0.7, -0.2, 0.05),
            DVec3::new(12.5, 1.7, -30.25),
        );
        let expected = [
            v.view_from_world(),
            v.clip_from_world(),
            v.world_from_clip(),
        ];
        assert_eq!(v.world_matrices(), expected);
        assert_ne!(expected[1], Mat4::IDENTITY);
    }

    /// The closed-form inverses against the general inverse of the f64 products, on
    /// random poses and windows (off-axis, far from the origin).
    #[test]
    fn closed_form_inverses_match_the_general_inverse() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(42);
        for _ in 0..200 {
            let mut tangent = || rng.random_range(-0.3..1.5_f32);
            let fov = Fov {
                left: tangent(),
                right: tangent() + 0.4,
                up: tangent(),
                down: tangent() + 0.4,
            };
            let angles = [(); 3].map(|_| rng.random_range(-3.0..3.0));
            let at = [(); 3].map(|_| rng.random_range(-2e3..2e3));
            let v = View {
                world_from_view: DAffine3::from_rotation_translation(
                    DQuat::from_euler(glam::EulerRot::YXZ, angles[0], angles[1], angles[2]),
                    DVec3::from(at),
                ),
                fov,
                near: rng.random_range(0.01..1.0),
                far: rng.random_range(10.0..1e4),
            };
            let close = |closed: Mat4, general: Mat4, tolerance: f32| {
                let scale = general
                    .abs()
                    .to_cols_array()
                    .into_iter()
                    .fold(1.0, f32::max);
                assert!(
                    closed.abs_diff_eq(general, tolerance * scale),
                    "{closed} vs {general}"
                );
            };
            let general = v.clip_from_view().as_dmat4().inverse();
            close(v.view_from_clip(), general.as_mat4(), 1e-6);
            let general = v.clip_from_world_f64().inverse();
            close(v.world_from_clip(), general.as_mat4(), 1e-6);
        }
    }

    #[test]
    fn parallel_eyes_give_the_chapters_construction() {
        let (l, r) = (eye(-0.032), eye(0.032));
        let d = enclosing_view(DQuat::IDENTITY, DVec3::ZERO, &[l, r]).unwrap();
        // The apex lies behind the eyes where the two outer planes meet.
        let expected_z = 0.064 / (1.0 + 0.8);
        assert!(
            (d.position().z - expected_z).abs() < 1e-4,
            "{}",
            d.position()
        );
        let (a, b) = (d.fov, l.fov);
        let diff = [
            a.left - b.left,
            a.right - b.right,
            a.up - b.up,
            a.down - b.down,
        ];
        assert!(diff.iter().all(|x| x.abs() < 1e-5), "{a:?} vs {b:?}");
    }
}
