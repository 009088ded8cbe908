// Keeping unchanged pixels (src/cull/tiles.rs is the CPU twin: same operations, same
// order): a display's cull keeps only what touches one of its changed tiles, TILE x
// TILE pixels of its target, a bit each (row-major, the target's width in tiles per
// row) from params.tile_offset + slot * params.tile_stride in `occlusion`. Composed
// after occlusion.wgsl, whose projection helpers it shares.

// `display.hidden`'s bits: the hidden area culls (1), the changed tiles cull (2).
const CULL_HIDDEN: u32 = 1u;
const CULL_TILES: u32 = 2u;

// Whether a kept frame's changed tiles leave sphere s out of the display the pass culls
// for (untouched, tested with its eyes).
fn untouched_in_display(s: vec4<f32>) -> bool {
    let views = array(display.eye[0].view_from_world, display.eye[1].view_from_world);
    let clips = array(display.eye[0].clip_from_view, display.eye[1].clip_from_view);
    return untouched(display.hidden, display.cull_slot, views, clips, display.resolution, display.views, s);
}

// Whether a view whose flags (a context's `hidden`) say its frame keeps pixels has
// sphere s cover none of display slot `slot`'s changed tiles in its first `count` eyes.
// Compiled out without TEST_TILES (a renderer that keeps no pixels): see CullTests in
// src/shaders/cull_passes.rs.
fn untouched(flags: u32, slot: u32, views: array<mat4x4<f32>, 2>, clips: array<mat4x4<f32>, 2>, resolution: vec2<f32>, count: u32, s: vec4<f32>) -> bool {
    if (!TEST_TILES) {
        return false;
    }
    return (flags & CULL_TILES) != 0u && !touches_changed_tiles(slot, views, clips, resolution, count, s);
}

// Whether sphere s may cover a changed tile of display slot `slot`, in one of its first
// `views` eyes (side by side, each `resolution` pixels).
fn touches_changed_tiles(slot: u32, views: array<mat4x4<f32>, 2>, clips: array<mat4x4<f32>, 2>, resolution: vec2<f32>, count: u32, s: vec4<f32>) -> bool {
    let size = vec2<u32>(resolution);
    let eyes = min(count, 2u);
    let cols = (size.x * eyes + TILE - 1u) / TILE;
    let base = params.tile_offset + slot * params.tile_stride;
    for (var e = 0u; e < eyes; e++) {
        let t = eye_tiles(s, views[e], clips[e], size, e);
        for (var y = t.y; y <= t.w && t.x <= t.z; y++) {
            for (var x = t.x; x <= t.z; x++) {
                let i = y * cols + x;
                if (((occlusion[base + i / 32u] >> (i % 32u)) & 1u) != 0u) {
                    return true;
                }
            }
        }
    }
    return false;
}
