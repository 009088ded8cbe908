// Occlusion culling's late test (src/occlusion.rs is its CPU twin: same operations, same
// order, no fused multiply-add). OCCLUSION is 0 (frustum only), 1 (the early phase:
// keep what the display drew last frame), 2 (the late phase: keep what it did not
// draw and the depth pyramids do not hide; record what they do not hide, blended
// instances aside) or 3 (tested: a far layer's cull keeps what the pyramids do not
// hide, and records nothing).
// Composed after pyramid.wgsl, whose layout the pyramids have in `occlusion`, each
// display slot's in its own region from pyramid_base(slot) on (depths as bits:
// non-negative floats order as their bits).

const ENTRY_SEEN: u32 = 0x40000000u;
const DEPTH_MARGIN: f32 = 1.0 / 1048576.0;

// Whether the display drew cull position k last frame.
fn drawn_last_frame(k: u32) -> bool {
    return drawn_by(display.cull_slot, k);
}

// Whether the display of visibility slot `slot` drew cull position k last frame.
fn drawn_by(slot: u32, k: u32) -> bool {
    let word = occlusion[slot * params.visibility_words + k / SPAN];
    return ((word >> (k % SPAN)) & 1u) != 0u;
}

// Position k's entry `kept` (it passed the frustum) under the phase: the early phase
// keeps it if drawn last frame; the late phase if not, unless hidden, and marks it
// ENTRY_SEEN where not hidden (and not blended).
fn occlusion_entry(k: u32, s: vec4<f32>, kept: u32) -> u32 {
    if (OCCLUSION == 0u) {
        return kept;
    }
    if (OCCLUSION == 3u) {
        return select(kept, 0u, occluded(s));
    }
    let drawn = drawn_last_frame(k);
    if (OCCLUSION == 1u) {
        return select(0u, kept, drawn);
    }
    if (occluded(s)) {
        return 0u;
    }
    return select(kept, 0u, drawn) | select(ENTRY_SEEN, 0u, blended(k));
}

// Blended instances are never marked drawn: always drawn late, after every opaque
// surface the display draws, so that they blend over all of it.
fn blended(k: u32) -> bool {
    return meshes[mesh_of[k]].bin >= params.first_blend_bin;
}

// Where display slot `slot`'s pyramids start in `occlusion`.
fn pyramid_base(slot: u32) -> u32 {
    return params.pyramid_offset + slot * params.pyramid_stride;
}

// A display's pyramids as a view's test reads them: where they start, one view's
// pixels, and how far projected bounds grow each way.
struct Pyramids {
    base: u32,
    size: vec2<u32>,
    margin_px: f32,
}

// Hidden from every eye of the display: the stereo rule, with the test its context
// holds (as DisplayContext::rig_occlusion makes it for a rig member).
fn occluded(s: vec4<f32>) -> bool {
    let views = array(display.eye[0].view_from_world, display.eye[1].view_from_world);
    let clips = array(display.eye[0].clip_from_view, display.eye[1].clip_from_view);
    let test = RigOcclusion(views, clips, display.resolution, display.occlusion_margin_px, display.views);
    return occluded_for(s, test, pyramid_base(display.cull_slot));
}

// Hidden from every eye (of the first two) of a display whose test is `o` and whose
// slot's pyramids start at `base`: the stereo rule.
fn occluded_for(s: vec4<f32>, o: RigOcclusion, base: u32) -> bool {
    let at = Pyramids(base, vec2<u32>(o.resolution), o.margin_px);
    for (var e = 0u; e < min(o.views, 2u); e++) {
        if (!occluded_in_eye(s, o.view_from_world[e], o.clip_from_view[e], e, at)) {
            return false;
        }
    }
    return true;
}

fn pyramid_texel(i: u32) -> f32 {
    return bitcast<f32>(occlusion[i]);
}

// The finest level where pixels lo..=hi span at most two texels per axis.
fn pyramid_level(lo: vec2<u32>, hi: vec2<u32>, levels: u32) -> u32 {
    var l = 0u;
    loop {
        if (l + 1u >= levels) {
            break;
        }
        let span = (hi >> vec2(l + 1u)) - (lo >> vec2(l + 1u));
        if (span.x <= 1u && span.y <= 1u) {
            break;
        }
        l++;
    }
    return l;
}

// Whether eye e (of `view` and `clip`) of a display whose pyramids are `at` sees s
// behind them.
fn occluded_in_eye(s: vec4<f32>, view: mat4x4<f32>, clip: mat4x4<f32>, e: u32, at: Pyramids) -> bool {
    let c = view_center(s, view);
    let r = grown_radius(s, view, c);
    let near = -c.z - r;
    if (!(near > 0.0)) {
        return false;
    }
    let near_depth = depth_at(near, clip);
    if (near_depth < 0.0) {
        return false;
    }
    let p = sphere_rect(c, r, clip, at.size, at.margin_px);
    if (p.x > p.z) {
        return true;
    }
    let lo = p.xy;
    let hi = p.zw;
    let levels = pyramid_levels(at.size);
    let l = pyramid_level(lo, hi, levels);
    let a = lo >> vec2(l + 1u);
    let b = hi >> vec2(l + 1u);
    let base = at.base + level_offset(at.size, e, l, levels);
    let width = level_size(at.size, l).x;
    let farthest = farthest4(
        pyramid_texel(base + a.y * width + a.x),
        pyramid_texel(base + a.y * width + b.x),
        pyramid_texel(base + b.y * width + a.x),
        pyramid_texel(base + b.y * width + b.x),
    );
    return near_depth > farthest + DEPTH_MARGIN;
}
