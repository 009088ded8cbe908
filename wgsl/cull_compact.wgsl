// Pass 4 of 4 per display: every visible instance writes its id to its slot (its
// level's group prefix + its span's prefix + its own prefix within the span, one read
// of its entry). Slots ascend with cull position within a (level, mesh) group, so each
// draw's ids are contiguous and ascending.
// Bindings (all cull passes share them): CULL_BINDINGS in src/shaders/bindings.rs.

@compute @workgroup_size(WORKGROUP_SIZE)
fn compact(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let n = cull_count();
    let j = (wid.y * groups.x + wid.x) * WORKGROUP_SIZE + local;
    if (j >= n) {
        return;
    }
    place(j, n);
}

// The rig's compact pass (RIG): a span per invocation, as the rig's cull walks them;
// for each member, the span's kept positions in order, each placed after the kept
// positions of its level before it (the span's prefix per level, read once, then a
// count per level). The slots are `place`'s; a position per invocation read each
// member's two words and its span's prefix again for every position, which cost the
// rig's cull at 1M on `cave` about as much as its cull pass.
@compute @workgroup_size(WORKGROUP_SIZE)
fn compact_rig(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let n = params.instance_count;
    let span = (wid.y * groups.x + wid.x) * WORKGROUP_SIZE + local;
    let first = span * SPAN;
    if (first >= n) {
        return;
    }
    let levels = entries[span];
    for (var b = 0u; b < rig.members; b++) {
        member = b;
        // Bit 2i set where the member keeps position i of the span.
        var kept = entries[rig_mask_index(b, span)];
        // The prefixes are read only where the member keeps some position (a loop
        // no lane enters is skipped: see `place`).
        let reads = select(0u, params.lod_levels, kept != 0u);
        var next: array<u32, MAX_LODS>;
        for (var l = 0u; l < reads; l++) {
            next[l] = span_before(l, span, n);
        }
        // A loop, not a branch per position: it ends when no lane has a kept position
        // left.
        while (kept != 0u) {
            let bit = firstTrailingBit(kept);
            let level = (levels >> bit) & 3u;
            visible[visible_index(next[level])] = order[first + bit / 2u];
            next[level] += 1u;
            kept &= kept - 1u;
        }
    }
}

// Writes position j's id to its slot of the list of `member`, if visible there.
// A loop of at most one turn, not a branch: a SIMD CPU adapter (lavapipe) runs a
// branch's body under a mask for every lane, but skips a loop no lane enters.
fn place(j: u32, n: u32) {
    let entry = entry_of(j);
    let turns = select(0u, 1u, (entry & ENTRY_VISIBLE) != 0u);
    for (var t = 0u; t < turns; t++) {
        let level = (entry >> ENTRY_LEVEL_SHIFT) & 3u;
        visible[visible_index(flagged_before(level, j, n, 0u))] = order[cull_position(j)];
    }
}
