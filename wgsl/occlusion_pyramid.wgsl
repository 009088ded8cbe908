// Each eye's depth pyramid of a display (src/occlusion/mod.rs is the CPU twin; its
// module documentation says what a texel holds), two levels per dispatch:
// `reduce_depth` reads the eye's viewport of the display's depth target into level 0
// and level 1; `reduce_level` level `level.index` - 1 into level `level.index` and the
// one after. The z of the dispatch is the eye: no reduction crosses the seam.
// Composed after occlusion.wgsl's layout helpers, the contexts and these bindings:
//   display: DisplayContext (uniform), level: PyramidLevel (uniform, dynamic offset),
//   pyramid: array<f32> (read_write), depth: the depth target, read by
//   depth_texel(pixel, eye) (src/shaders/mod.rs: a layer per eye in multiview; under
//   MSAA every sample, the farthest kept).

struct PyramidLevel {
    index: u32,
}


// Each workgroup's texels of the level it writes, for the next level.
var<workgroup> tile: array<f32, 64>;

@compute @workgroup_size(8, 8, 1)
fn reduce_depth(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(local_invocation_id) local: vec3<u32>,
    @builtin(workgroup_id) group: vec3<u32>,
) {
    let size = level_size(0u);
    let e = id.z;
    var d = 0.0;
    if (all(id.xy < size)) {
        let origin = eye_origin(e);
        let last = eye_size() - 1u;
        let at = 2u * id.xy;
        d = farthest4(
            depth_texel(origin + min(at, last), e),
            depth_texel(origin + min(at + vec2(1u, 0u), last), e),
            depth_texel(origin + min(at + vec2(0u, 1u), last), e),
            depth_texel(origin + min(at + vec2(1u, 1u), last), e),
        );
        pyramid[level_offset(e, 0u, pyramid_levels()) + id.y * size.x + id.x] = d;
    }
    next_level(0u, e, local.xy, group.xy, d);
}

// Level `level.index` (an even level from 2 on) from the one before it.
@compute @workgroup_size(8, 8, 1)
fn reduce_level(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(local_invocation_id) local: vec3<u32>,
    @builtin(workgroup_id) group: vec3<u32>,
) {
    let l = level.index;
    let size = level_size(l);
    let e = id.z;
    var d = 0.0;
    if (all(id.xy < size)) {
        let levels = pyramid_levels();
        let src = level_size(l - 1u);
        let base = level_offset(e, l - 1u, levels);
        let last = src - 1u;
        let at = 2u * id.xy;
        let a = min(at, last);
        let b = min(at + vec2(1u), last);
        d = farthest4(
            pyramid[base + a.y * src.x + a.x],
            pyramid[base + a.y * src.x + b.x],
            pyramid[base + b.y * src.x + a.x],
            pyramid[base + b.y * src.x + b.x],
        );
        pyramid[level_offset(e, l, levels) + id.y * size.x + id.x] = d;
    }
    next_level(l, e, local.xy, group.xy, d);
}

// Level l + 1 of the workgroup's 4 x 4 texels from its 8 x 8 of level l (`d`, each
// invocation's): two levels per dispatch. A texel of l + 1 that exists reads only
// texels of l inside this workgroup's tile, clamped at the level's edge as above.
fn next_level(l: u32, e: u32, local: vec2<u32>, group: vec2<u32>, d: f32) {
    tile[local.y * 8u + local.x] = d;
    workgroupBarrier();
    let levels = pyramid_levels();
    let size = level_size(l + 1u);
    let at = group * 4u + local;
    if (l + 1u >= levels || any(local >= vec2(4u)) || any(at >= size)) {
        return;
    }
    let last = level_size(l) - 1u - group * 8u;
    let a = min(2u * local, last);
    let b = min(2u * local + 1u, last);
    let farthest = farthest4(
        tile[a.y * 8u + a.x],
        tile[a.y * 8u + b.x],
        tile[b.y * 8u + a.x],
        tile[b.y * 8u + b.x],
    );
    pyramid[level_offset(e, l + 1u, levels) + at.y * size.x + at.x] = farthest;
}
