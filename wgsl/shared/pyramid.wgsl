// The layout of a display's depth pyramids in `pyramid` (PyramidShape in
// src/occlusion.rs): per eye its levels finest first, level l ceil(size / 2^(l+1))
// texels, each the farthest depth of the pixels it covers; `size` is one eye's view
// in pixels (its display's resolution).

fn level_size(size: vec2<u32>, l: u32) -> vec2<u32> {
    let shift = l + 1u;
    let half = (1u << shift) - 1u;
    return (size + vec2(half)) >> vec2(shift);
}

fn pyramid_levels(size: vec2<u32>) -> u32 {
    var l = 0u;
    while (any(level_size(size, l) != vec2(1u))) {
        l++;
    }
    return l + 1u;
}

// Where level l of eye e starts.
fn level_offset(size: vec2<u32>, e: u32, l: u32, levels: u32) -> u32 {
    var eye_len = 0u;
    var before = 0u;
    for (var k = 0u; k < levels; k++) {
        let here = level_size(size, k);
        if (k == l) {
            before = eye_len;
        }
        eye_len += here.x * here.y;
    }
    return e * eye_len + before;
}

fn farthest4(a: f32, b: f32, c: f32, d: f32) -> f32 {
    return max(max(a, b), max(c, d));
}
