// Every eye's depth pyramid of a set of displays (src/occlusion/mod.rs is the CPU
// twin; its module documentation says what a texel holds), six levels per dispatch:
// `reduce_depth` reads each eye's viewport of its display's depth target into levels
// 0 to 5; `reduce_level` level `level.index` - 1 into level `level.index` and the five
// after it. The z of the dispatch is the slice (a display's eye: eyes.slices), so no
// reduction crosses an eye's seam or a display's edge; the x and y cover the set's
// largest eye, and a workgroup past its own eye's level returns at once.
// Each dispatch costs the CPU a flush of its bindings and a barrier in wgpu, more
// than its GPU work at these sizes, so a dispatch does as many levels as one
// workgroup's tile allows: a 16 x 16 workgroup owns a 32 x 32 tile of its first level
// (each invocation a 2 x 2 block of it) and reduces it to one texel; and one set of
// dispatches reduces up to SET_DEPTHS displays' depth targets.
// Composed after pyramid.wgsl's layout helpers, the constants LEVELS_PER_DISPATCH (6:
// 32 x 32 texels of the first level down to 1 x 1), SIDE (16, invocations per
// workgroup side) and SET_DEPTHS, and the bindings of pyramid_bindings
// (src/shaders/binding_lists.rs: the set, each dispatch's level, the pyramids, the
// set's depth targets), the type DepthTarget of each, read_depth(target, pixel, slice)
// (a layer per eye in multiview; under MSAA every sample, the farthest kept) and
// depth_texels(pixel, slice), which calls block_texels with the slice's target
// (src/shaders/cull_passes.rs).

struct PyramidLevel {
    index: u32,
}

// One eye of a display in the set (PyramidSlice in src/occlusion/pyramid.rs): where
// its view starts in its display's depth target (side by side; 0 for a layer), its
// pixels, where its display's pyramids start in `pyramid` (words), which eye it is
// (its pyramid's place, and its layer in multiview) and which of the set's depth
// targets it reads.
struct PyramidSlice {
    origin: vec2<u32>,
    size: vec2<u32>,
    base: u32,
    eye: u32,
    depth: u32,
}

// The set's eyes: the first `count` of `slices`.
struct PyramidSet {
    slices: array<PyramidSlice, MAX_SLICES>,
    count: u32,
}

// Texels of the level being reduced within the workgroup, one per invocation.
var<workgroup> tile: array<f32, SIDE * SIDE>;

@compute @workgroup_size(SIDE, SIDE, 1)
fn reduce_depth(
    @builtin(local_invocation_id) local: vec3<u32>,
    @builtin(workgroup_id) group: vec3<u32>,
) {
    let s = eyes.slices[group.z];
    if (skipped(0u, s, group.xy)) {
        return;
    }
    // This invocation's 2 x 2 texels of level 0, from its display's depth target.
    let p = group.xy * (2u * SIDE) + 2u * local.xy;
    reduce(0u, s, vec4(local.xy, group.xy), depth_texels(2u * p, s));
}

// Levels `level.index` (a multiple of LEVELS_PER_DISPATCH) on, from the one before.
@compute @workgroup_size(SIDE, SIDE, 1)
fn reduce_level(
    @builtin(local_invocation_id) local: vec3<u32>,
    @builtin(workgroup_id) group: vec3<u32>,
) {
    let s = eyes.slices[group.z];
    if (skipped(level.index, s, group.xy)) {
        return;
    }
    reduce(level.index, s, vec4(local.xy, group.xy), vec4(0.0));
}

// Whether workgroup `group` has nothing of slice `s` from level `first` on: its tile
// lies past the level (the slice is smaller than the set's largest), or the slice has
// no level `first`. The same for every invocation of the workgroup.
fn skipped(first: u32, s: PyramidSlice, group: vec2<u32>) -> bool {
    let levels = pyramid_levels(s.size);
    return first >= levels || any(group * (2u * SIDE) >= level_size(s.size, first));
}

// Texel `p` of level `l` of slice `s` (l > 0) from what it covers one level finer:
// the farthest of 2 x 2, clamped at that level's edge.
fn texel(l: u32, p: vec2<u32>, s: PyramidSlice, levels: u32) -> f32 {
    let at = 2u * p;
    let src = level_size(s.size, l - 1u);
    let base = s.base + level_offset(s.size, s.eye, l - 1u, levels);
    let a = min(at, src - 1u);
    let b = min(at + 1u, src - 1u);
    return farthest4(
        pyramid[base + a.y * src.x + a.x],
        pyramid[base + a.y * src.x + b.x],
        pyramid[base + b.y * src.x + a.x],
        pyramid[base + b.y * src.x + b.x],
    );
}

// The 2 x 2 texels of level 0 (x = k & 1, y = k >> 1 in component k) whose pixels start
// at `at` of slice `s`'s view in `depth`: each the farthest of its 2 x 2 pixels,
// clamped at the view's edge as the reference clamps.
fn block_texels(depth: DepthTarget, at: vec2<u32>, s: PyramidSlice) -> vec4<f32> {
    var texels = vec4(0.0);
    for (var k = 0u; k < 4u; k++) {
        let q = at + 2u * vec2(k & 1u, k >> 1u);
        texels[k] = farthest4(
            view_pixel(depth, q, s),
            view_pixel(depth, q + vec2(1u, 0u), s),
            view_pixel(depth, q + vec2(0u, 1u), s),
            view_pixel(depth, q + vec2(1u, 1u), s),
        );
    }
    return texels;
}

// Pixel q of slice `s`'s view, clamped at its edge.
fn view_pixel(depth: DepthTarget, q: vec2<u32>, s: PyramidSlice) -> f32 {
    return read_depth(depth, s.origin + min(q, s.size - 1u), s);
}

// The workgroup's tile of level `first` and the five levels after it (`ids`: the
// invocation's local and workgroup ids; `texels`: with `first` 0, its 2 x 2 of level 0).
// Texels past a level's edge are reduced too, and never written: reduced from clamped
// reads of texels that exist, each is the farthest of a part of what the edge texel
// beside it covers, so reading it beside that texel (where the reference reads the
// edge twice) changes nothing.
fn reduce(first: u32, s: PyramidSlice, ids: vec4<u32>, texels: vec4<f32>) {
    let local = ids.xy;
    let group = ids.zw;
    let eye = s.size;
    let levels = pyramid_levels(eye);
    let size = level_size(eye, first);
    let base = s.base + level_offset(eye, s.eye, first, levels);
    // This invocation's 2 x 2 block of level `first`.
    let p = group * (2u * SIDE) + 2u * local;
    var d = 0.0;
    for (var k = 0u; k < 4u; k++) {
        let q = p + vec2(k & 1u, k >> 1u);
        var t: f32;
        if (first == 0u) {
            t = texels[k];
        } else {
            t = texel(first, q, s, levels);
        }
        if (all(q < size)) {
            pyramid[base + q.y * size.x + q.x] = t;
        }
        d = max(d, t);
    }
    var span = SIDE;
    for (var n = 1u; n < LEVELS_PER_DISPATCH && first + n < levels; n++) {
        let l = first + n;
        let here = level_size(eye, l);
        let at = group * span + local;
        if (all(local < vec2(span)) && all(at < here)) {
            pyramid[s.base + level_offset(eye, s.eye, l, levels) + at.y * here.x + at.x] = d;
        }
        workgroupBarrier();
        tile[local.y * SIDE + local.x] = d;
        workgroupBarrier();
        let half = span / 2u;
        if (all(local < vec2(half))) {
            let i = 2u * local;
            let j = i + 1u;
            d = farthest4(
                tile[i.y * SIDE + i.x],
                tile[i.y * SIDE + j.x],
                tile[j.y * SIDE + i.x],
                tile[j.y * SIDE + j.x],
            );
        }
        span = half;
    }
}

// Under MSAA (read_depth's), a pixel's farthest of its SAMPLES samples.
fn farthest_sample(depth: texture_depth_multisampled_2d, p: vec2<u32>) -> f32 {
    var d = 0.0;
    for (var i = 0; i < SAMPLES; i++) {
        d = max(d, textureLoad(depth, p, i));
    }
    return d;
}
