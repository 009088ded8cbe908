// A world sphere against a view: the frustum's planes, its center and radius in the
// view, its depth and its projected pixels. Pure functions, shared by the cull passes
// (occlusion, the changed tiles) and the tile marking pass; each has its CPU twin in
// src/frustum.rs, src/sphere_projection.rs or src/cull/tiles.rs (same operations, same
// order).

const DEPTH_SLACK: f32 = 1.0 / 262144.0;

// The CPU twin is frustum::sphere_in_planes. Same products, same sums, left to right,
// no fma: CPU and GPU reach identical decisions, which the byte-for-byte tests need.
fn sphere_in_planes(planes: array<vec4<f32>, 6>, s: vec4<f32>) -> bool {
    for (var i = 0u; i < 6u; i++) {
        let p = planes[i];
        if (p.x * s.x + p.y * s.y + p.z * s.z + p.w < -s.w) {
            return false;
        }
    }
    return true;
}

fn view_center(s: vec4<f32>, m: mat4x4<f32>) -> vec3<f32> {
    return vec3(
        m[0].x * s.x + m[1].x * s.y + m[2].x * s.z + m[3].x,
        m[0].y * s.x + m[1].y * s.y + m[2].y * s.z + m[3].y,
        m[0].z * s.x + m[1].z * s.y + m[2].z * s.z + m[3].z,
    );
}

// The radius grown for the rounding of c (grown_radius in src/occlusion/mod.rs: the
// same sum, left to right).
fn grown_radius(s: vec4<f32>, m: mat4x4<f32>, c: vec3<f32>) -> f32 {
    let t = m[3];
    let magnitude = abs(c.x) + abs(c.y) + abs(c.z) + abs(s.x) + abs(s.y) + abs(s.z) + abs(t.x) + abs(t.y) + abs(t.z) + s.w;
    return s.w + magnitude * DEPTH_SLACK;
}

// Depth-buffer value at view distance d > 0.
fn depth_at(d: f32, clip: mat4x4<f32>) -> f32 {
    return (clip[2].z * -d + clip[3].z) / d;
}

// Slopes (a / z) of the two tangents from the eye to the circle of radius r about
// (a, z), least first.
fn tangent_slopes(a: f32, z: f32, r: f32) -> vec2<f32> {
    let t = sqrt(a * a + z * z - r * r);
    let lo = (a * t - z * r) / (z * t + a * r);
    let hi = (a * t + z * r) / (z * t - a * r);
    return vec2(lo, hi);
}

// Whether both tangents from the eye to the circle of radius r about (a, z) lie ahead.
fn bounded(a: f32, z: f32, r: f32) -> bool {
    return sqrt(a * a + z * z - r * r) * z > abs(a) * r;
}

// The first and last pixels (x0, y0, x1, y1) of one eye's view of `size` that sphere s
// may cover: its projected bounds grown by TILE_MARGIN_PX, or the whole view where it
// reaches the near plane; x0 > x1 outside the view or behind the eye.
fn eye_pixels(s: vec4<f32>, view: mat4x4<f32>, clip: mat4x4<f32>, size: vec2<u32>) -> vec4<u32> {
    let c = view_center(s, view);
    let r = grown_radius(s, view, c);
    // Wholly behind the eye: it sees none of it.
    if (c.z - r >= 0.0) {
        return vec4(1u, 0u, 0u, 0u);
    }
    let near = -c.z - r;
    let whole = vec4(0u, 0u, size.x - 1u, size.y - 1u);
    if (!(near > 0.0) || depth_at(near, clip) < 0.0) {
        return whole;
    }
    // A sphere reaching past 90 degrees off the view's axis has a tangent behind the
    // eye: its projection is unbounded on that side.
    if (!(bounded(c.x, -c.z, r) && bounded(c.y, -c.z, r))) {
        return whole;
    }
    return sphere_rect(c, r, clip, size, TILE_MARGIN_PX);
}

// The pixels (first x, y, last x, y) of a view of `size` that the sphere about c (in
// the view) of radius r covers, wholly ahead of the eye with both tangents: its
// projected bounds grown by `margin` pixels each way, clamped to the view; x0 > x1
// where they miss it. The tiles' and occlusion's rectangle (their CPU twins:
// cull::tiles::pixels_of and occlusion::occluded_in_eye, the same operations).
fn sphere_rect(c: vec3<f32>, r: f32, clip: mat4x4<f32>, size: vec2<u32>, margin: f32) -> vec4<u32> {
    let xs = tangent_slopes(c.x, -c.z, r);
    let ys = tangent_slopes(c.y, -c.z, r);
    let x0 = clip[0].x * xs.x - clip[2].x;
    let y0 = clip[1].y * ys.x - clip[2].y;
    let x1 = clip[0].x * xs.y - clip[2].x;
    let y1 = clip[1].y * ys.y - clip[2].y;
    let w = f32(size.x);
    let h = f32(size.y);
    let px0 = (x0 * 0.5 + 0.5) * w - margin;
    let px1 = (x1 * 0.5 + 0.5) * w + margin;
    let py0 = (0.5 - y1 * 0.5) * h - margin;
    let py1 = (0.5 - y0 * 0.5) * h + margin;
    if (px1 < 0.0 || py1 < 0.0 || px0 >= w || py0 >= h) {
        return vec4(1u, 0u, 0u, 0u);
    }
    // Clamped as floats: a conversion of a value out of range is not defined.
    let last = vec2(w - 1.0, h - 1.0);
    let lo = vec2<u32>(clamp(vec2(px0, py0), vec2(0.0), last));
    let hi = vec2<u32>(clamp(vec2(px1, py1), vec2(0.0), last));
    return vec4(lo, hi);
}

// The tiles (first x, y, last x, y) of a target whose views of `size` lie side by side
// that sphere s may cover in view e: eye_pixels' in tiles (TileMask::tiles_of in
// src/cull/tiles.rs); x0 > x1 where none.
fn eye_tiles(s: vec4<f32>, view: mat4x4<f32>, clip: mat4x4<f32>, size: vec2<u32>, e: u32) -> vec4<u32> {
    let p = eye_pixels(s, view, clip, size);
    if (p.x > p.z) {
        return p;
    }
    let x = vec2(e * size.x, 0u);
    return vec4((p.xy + x) / TILE, (p.zw + x) / TILE);
}
