// Pass 3 of 4 per display, one workgroup: per level of detail, finest first, turn the
// level's group totals into group prefixes (after every finer level's instances); then
// per material bin, in its own fixed range of the draws (its meshes times the levels,
// bins in order), build one draw per mesh of the bin with visible instances at a level,
// packed by level, then ascending mesh id; zero the rest of the range and write the
// counts (all draws, visible, then each bin's draws). It walks group totals (one per
// WORKGROUP_SIZE * SPAN positions), never every span, and the meshes once per bin and
// level. Deterministic: no atomics anywhere.
// Bindings (all cull passes share them): CULL_BINDINGS in src/shaders/bindings.rs.

@compute @workgroup_size(WORKGROUP_SIZE)
fn draws_main(@builtin(local_invocation_index) local: u32) {
    pack(local);
}

// The rig's draws pass (RIG): a workgroup per member, `draws_main` for each.
@compute @workgroup_size(WORKGROUP_SIZE)
fn draws_rig(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    member = wid.y;
    pack(local);
}

fn pack(local: u32) {
    let n = workgroup_cull_count(local);
    let groups = group_count(span_count(n));
    // Visible positions up to and including each level.
    var totals: array<u32, MAX_LODS>;
    var carry = 0u;
    for (var level = 0u; level < params.lod_levels; level++) {
        carry = prefix_groups(group_slot(n, level, 0u), groups, carry, local);
        totals[level] = carry;
        storageBarrier();
    }
    var first = 0u;
    var all = 0u;
    // Blended bins are the blend pass's (wgsl/cull_blend.wgsl).
    for (var bin = 0u; bin < min(params.bin_count, params.first_blend_bin); bin++) {
        var packed = 0u;
        var members = 0u;
        for (var level = 0u; level < params.lod_levels; level++) {
            let written = pack_draws(vec2(bin, level), n, totals[level], first + packed, local);
            packed += written.x;
            members = written.y;
            storageBarrier();
        }
        let end = first + members * params.lod_levels;
        for (var d = first + packed + local; d < end; d += WORKGROUP_SIZE) {
            draws[draw_index(d)] = DrawArgs(0u, 0u, 0u, 0, 0u);
        }
        if (local == 0u) {
            counts[count_index(2u + bin)] = packed;
        }
        first = end;
        all += packed;
    }
    if (local == 0u) {
        counts[count_index(0u)] = all;
        counts[count_index(1u)] = carry;
    }
}

// Writes the draws of `at` = (bin, level) from draws[packed] on, in ascending mesh id;
// returns how many, and how many meshes the bin has. `n` is what the passes ran over,
// `total` the visible count up to this level.
fn pack_draws(at: vec2<u32>, n: u32, total: u32, packed: u32, local: u32) -> vec2<u32> {
    var written = vec2(0u);
    for (var base = 0u; base < params.mesh_count; base += WORKGROUP_SIZE) {
        let m = base + local;
        var count = 0u;
        var offset = 0u;
        let member = m < params.mesh_count && meshes[m].bin == at.x;
        if (member) {
            let range = mesh_range(m);
            offset = flagged_before(at.y, range.x, n, total);
            count = flagged_before(at.y, range.x + range.y, n, total) - offset;
        }
        let scan = workgroup_exclusive_scan4(local, vec4(select(0u, 1u, count > 0u), select(0u, 1u, member), 0u, 0u));
        if (count > 0u) {
            let mesh = meshes[m];
            let lod = lods[m * MAX_LODS + at.y];
            draws[draw_index(packed + written.x + scan.before.x)] = DrawArgs(
                lod.index_count,
                instances_per_object() * count,
                lod.first_index,
                mesh.base_vertex,
                instances_per_object() * offset,
            );
        }
        written += scan.total.xy;
    }
    return written;
}
