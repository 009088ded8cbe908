// Keeping unchanged pixels (src/keep/tiles.rs is the CPU twin: same operations, same
// order): a display's cull keeps only what touches one of its changed tiles, TILE x
// TILE pixels of its target, a bit each (row-major, the target's width in tiles per
// row) from params.tile_offset + slot * params.tile_stride in `occlusion`. Composed
// after occlusion.wgsl, whose projection helpers it shares.

// `display.hidden`'s bits: the hidden area culls (1), the changed tiles cull (2).
const CULL_HIDDEN: u32 = 1u;
const CULL_TILES: u32 = 2u;

// Whether sphere s may cover a changed tile of the display the pass culls for.
fn touched_in_display(s: vec4<f32>) -> bool {
    let views = array(display.eye[0].view_from_world, display.eye[1].view_from_world);
    let clips = array(display.eye[0].clip_from_view, display.eye[1].clip_from_view);
    return touches_changed_tiles(display.cull_slot, views, clips, display.resolution, display.views, s);
}

// Whether sphere s may cover a changed tile of display slot `slot`, in one of its first
// `views` eyes (side by side, each `resolution` pixels).
fn touches_changed_tiles(slot: u32, views: array<mat4x4<f32>, 2>, clips: array<mat4x4<f32>, 2>, resolution: vec2<f32>, count: u32, s: vec4<f32>) -> bool {
    let size = vec2<u32>(resolution);
    let eyes = min(count, 2u);
    let cols = (size.x * eyes + TILE - 1u) / TILE;
    let base = params.tile_offset + slot * params.tile_stride;
    for (var e = 0u; e < eyes; e++) {
        let p = eye_pixels(s, views[e], clips[e], size);
        if (p.x > p.z) {
            continue;
        }
        let lo = (p.xy + vec2(e * size.x, 0u)) / TILE;
        let hi = (p.zw + vec2(e * size.x, 0u)) / TILE;
        for (var y = lo.y; y <= hi.y; y++) {
            for (var x = lo.x; x <= hi.x; x++) {
                let i = y * cols + x;
                if (((occlusion[base + i / 32u] >> (i % 32u)) & 1u) != 0u) {
                    return true;
                }
            }
        }
    }
    return false;
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
    let xs = tangent_slopes(c.x, -c.z, r);
    let ys = tangent_slopes(c.y, -c.z, r);
    let x0 = clip[0].x * xs.x - clip[2].x;
    let y0 = clip[1].y * ys.x - clip[2].y;
    let x1 = clip[0].x * xs.y - clip[2].x;
    let y1 = clip[1].y * ys.y - clip[2].y;
    let w = f32(size.x);
    let h = f32(size.y);
    let px0 = (x0 * 0.5 + 0.5) * w - TILE_MARGIN_PX;
    let px1 = (x1 * 0.5 + 0.5) * w + TILE_MARGIN_PX;
    let py0 = (0.5 - y1 * 0.5) * h - TILE_MARGIN_PX;
    let py1 = (0.5 - y0 * 0.5) * h + TILE_MARGIN_PX;
    if (px1 < 0.0 || py1 < 0.0 || px0 >= w || py0 >= h) {
        return vec4(1u, 0u, 0u, 0u);
    }
    let last = vec2(w - 1.0, h - 1.0);
    let lo = vec2<u32>(clamp(vec2(px0, py0), vec2(0.0), last));
    let hi = vec2<u32>(clamp(vec2(px1, py1), vec2(0.0), last));
    return vec4(lo, hi);
}
