// Places of the cull order filled or vacated (dispatched first): each edit is a place
// and the slot now there, or VACANT, and with occlusion the place's visibility bits
// cleared (wgsl/shared/occlusion.wgsl); a vacant place's sphere is
// CullLayout::VACANT_SPHERE (a radius of minus infinity fails every plane test). Only
// the GPU culler has these buffers.

struct Edits {
    header: EditHeader,
    list: array<PlaceEdit>,
}

@compute @workgroup_size(SCATTER_GROUP)
fn scatter(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    let i = edit_index(wid, local);
    if (i >= edits.header.count || edits.header.spheres_too == 0u) {
        return;
    }
    let e = edits.list[i];
    // Whoever now holds the place was not drawn last frame: its bit goes, in every
    // display's words (neighbouring places share a word: atomically).
    let bit = ~(1u << (e.place % VISIBILITY_SPAN));
    for (var d = 0u; d < edits.header.visibility_slots; d++) {
        atomicAnd(&visibility[d * edits.header.visibility_words + e.place / VISIBILITY_SPAN], bit);
    }
    order[e.place] = e.slot;
    if (e.slot == VACANT) {
        spheres_set(e.place, vec4(0.0, 0.0, 0.0, bitcast<f32>(0xff800000u)));
    } else {
        positions[e.slot] = e.place;
    }
}
