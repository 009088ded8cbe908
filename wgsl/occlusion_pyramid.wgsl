// Each eye's depth pyramid of a display (src/occlusion.rs is the CPU twin; its module
// documentation says what a texel holds). `reduce_depth` reads the eye's viewport of the
// display's depth target into level 0; `reduce_level` level `level.index` - 1 into
// level `level.index`. The z of the dispatch is the eye: no reduction crosses the seam.
// Composed after occlusion.wgsl's layout helpers, the contexts and these bindings:
//   display: DisplayContext (uniform), level: PyramidLevel (uniform, dynamic offset),
//   pyramid: array<f32> (read_write), depth: the depth target (DEPTH_TYPE; MSAA: every
//   sample, the farthest kept).

struct PyramidLevel {
    index: u32,
}

fn depth_texel(p: vec2<u32>) -> f32 {
    if (DEPTH_SAMPLES == 1u) {
        return textureLoad(depth, p, 0);
    }
    var d = 0.0;
    for (var i = 0; i < i32(DEPTH_SAMPLES); i++) {
        d = max(d, textureLoad(depth, p, i));
    }
    return d;
}

@compute @workgroup_size(8, 8, 1)
fn reduce_depth(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = level_size(0u);
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    let e = id.z;
    let origin = vec2<u32>(display.eye[e].viewport.xy);
    let last = eye_size() - 1u;
    let at = vec2(2u * id.x, 2u * id.y);
    let d = farthest4(
        depth_texel(origin + min(at, last)),
        depth_texel(origin + min(at + vec2(1u, 0u), last)),
        depth_texel(origin + min(at + vec2(0u, 1u), last)),
        depth_texel(origin + min(at + vec2(1u, 1u), last)),
    );
    pyramid[level_offset(e, 0u, pyramid_levels()) + id.y * size.x + id.x] = d;
}

@compute @workgroup_size(8, 8, 1)
fn reduce_level(@builtin(global_invocation_id) id: vec3<u32>) {
    let l = level.index;
    let size = level_size(l);
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    let levels = pyramid_levels();
    let e = id.z;
    let src = level_size(l - 1u);
    let base = level_offset(e, l - 1u, levels);
    let last = src - 1u;
    let at = vec2(2u * id.x, 2u * id.y);
    let a = min(at, last);
    let b = min(at + vec2(1u), last);
    let d = farthest4(
        pyramid[base + a.y * src.x + a.x],
        pyramid[base + a.y * src.x + b.x],
        pyramid[base + b.y * src.x + a.x],
        pyramid[base + b.y * src.x + b.x],
    );
    pyramid[level_offset(e, l, levels) + id.y * size.x + id.x] = d;
}
