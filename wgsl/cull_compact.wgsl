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

// The rig's compact pass (RIG): each position placed in every member's list.
@compute @workgroup_size(WORKGROUP_SIZE)
fn compact_rig(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let n = params.instance_count;
    let j = (wid.y * groups.x + wid.x) * WORKGROUP_SIZE + local;
    if (j >= n) {
        return;
    }
    for (var b = 0u; b < rig.members; b++) {
        member = b;
        place(j, n);
    }
}

// Writes position j's id to its slot of the list of `member`, if visible there.
// A loop of at most one turn, not a branch: a SIMD CPU adapter (lavapipe) runs a
// branch's body under a mask for every lane, but skips a loop no lane enters (in the
// rig's compact pass, most members see few of a SIMD group's positions).
fn place(j: u32, n: u32) {
    let entry = entry_of(j);
    let turns = select(0u, 1u, (entry & ENTRY_VISIBLE) != 0u);
    for (var t = 0u; t < turns; t++) {
        let level = (entry >> ENTRY_LEVEL_SHIFT) & 3u;
        visible[visible_index(flagged_before(level, j, n, 0u))] = order[cull_position(j)];
    }
}
