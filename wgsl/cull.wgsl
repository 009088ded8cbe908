// Pass 1 of 3 per display: each invocation walks one span of SPAN cull positions in
// order (or the positions of the blocks the frame's coarse cull listed for this
// display), tests each world sphere against the display frustum (never per eye),
// chooses its level of detail from the viewer and writes its entry (one word, whatever
// the number of levels: see ENTRY_VISIBLE in cull_math.wgsl). Each sphere is read once.
// The workgroup then scans its spans' per-level counts: each span's prefix within the
// workgroup and the workgroup's totals go to span_sums for the draws pass.
// A span per invocation, not a position: the workgroup scan's barriers then come once
// per SPAN positions (on lavapipe they cost more than the sphere tests themselves).
// Bindings (all cull passes share them): CULL_BINDINGS in src/shaders/bindings.rs.

@compute @workgroup_size(WORKGROUP_SIZE)
fn cull(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let n = workgroup_cull_count(local);
    let group = wid.y * groups.x + wid.x;
    let counts = cull_span(group * WORKGROUP_SIZE + local, n);
    write_span_sums(group, local, n, workgroup_exclusive_scan4(local, counts));
}

// The rig's cull (RIG): the same spans and sums as `cull` for every member at once,
// each member's in its own scratch, its entries compressed (RIG_ENTRIES in
// cull_math.wgsl: per span a word of levels for the rig and a mask per member). Each
// sphere is read once and its level chosen once (the frame's, whatever the member) for
// the whole rig; each member's planes and split (and in the early occlusion phase what
// its display drew last frame) then decide what it keeps, as the member's own `cull`
// would (same operations). Members outside, positions inside: a
// member's record is loaded once per span (on lavapipe a load at a member's index is a
// gather per lane), and its sphere tests skipped for a span whose box fails its block
// test (the coarse cull's guarantee, per span: a sphere the member keeps makes the
// span's box pass). Built in the late occlusion phase (OCCLUSION 2) it culls every
// member's late phase: what its display did not draw last frame unless its pyramids
// hide it, recording what they do not hide, as each display's own late cull does.
@compute @workgroup_size(WORKGROUP_SIZE)
fn cull_rig(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let n = params.instance_count;
    let group = wid.y * groups.x + wid.x;
    let span = group * WORKGROUP_SIZE + local;
    let first = span * SPAN;
    let count = select(0u, min(SPAN, n - first), first < n);
    var spheres: array<vec4<f32>, SPAN>;
    let bound = read_span(first, count, &spheres);
    // Each position's level (bits 2i, 2i + 1), chosen when a member first keeps it.
    var levels = 0u;
    var chosen = 0u;
    for (var b = 0u; b < rig.members; b++) {
        let view = rig.views[b];
        // The member's eyes: what the late phase (OCCLUSION 2) tests the pyramids with,
        // and a kept frame its changed tiles.
        let late = rig.occlusion[b];
        let base = pyramid_base(view.cull_slot);
        // A loop, not a branch: a SIMD CPU adapter (lavapipe) runs both sides of a
        // branch under a mask, but leaves a loop once no lane has an iteration left.
        let tested = select(0u, count, block_test(view.block, bound.sphere, bound.extent));
        var mask = 0u;
        // The late phase: which of the span's positions the pyramids do not hide.
        var unhidden = 0u;
        for (var i = 0u; i < tested; i++) {
            let s = spheres[i];
            let framed = sphere_in_planes(view.planes, s) && in_split_of(view.split_keep, view.split_distance, view.position, s);
            var kept: bool;
            if (OCCLUSION == 2u) {
                // The display's own late cull (cull_entry, occlusion_entry), in order.
                let shown = framed && !hides(view.hidden, view.cull_slot, s) && !occluded_for(s, late, base);
                unhidden |= select(0u, 1u << i, shown && !blended(first + i));
                kept = shown && !drawn_by(view.cull_slot, first + i);
            } else {
                // The hidden area and the tiles last: their tests cost several frustums'.
                kept = framed && member_saw(view, first + i) && !hides(view.hidden, view.cull_slot, s) && !untouched(view.hidden, view.cull_slot, late.view_from_world, late.clip_from_view, late.resolution, late.views, s);
            }
            if (kept) {
                if (((chosen >> i) & 1u) == 0u) {
                    levels |= lod_level(first + i, s) << (2u * i);
                    chosen |= 1u << i;
                }
                mask |= 1u << (2u * i);
            }
        }
        if (count > 0u) {
            entries[rig_mask_index(b, span)] = mask;
            // The span's word, which this invocation alone writes (as cull_span does).
            if (OCCLUSION == 2u) {
                occlusion[view.cull_slot * params.visibility_words + span] = unhidden;
            }
        }
    }
    if (count > 0u) {
        entries[span] = levels;
    }
    scan_rig(group, local, n, levels);
}

// Whether rig member `view` keeps position k by what its display drew last frame: in
// its early occlusion phase only what it drew. Compiled out without TEST_EARLY.
fn member_saw(view: RigView, k: u32) -> bool {
    if (!TEST_EARLY) {
        return true;
    }
    return view.early == 0u || drawn_by(view.cull_slot, k);
}

// `scan_rig(group, local, n, levels)` follows this file, composed from the pipeline's
// key (CullKey::rig_scans in src/shaders/cull_passes.rs): a call of scan_rig_fields per
// eight fields the key's members and levels have, in straight code.

// The workgroup's scan of the rig's (member, level) fields `base` to `base + 7`, each
// member's span counts from the mask it wrote in `entries`: a workgroup's total per
// field is at most WORKGROUP_SIZE * SPAN = 4096, so two fit a word. Field f is member
// f / levels's level f % levels. Three barriers per eight fields, where a scan per
// member would take three per member. The loops have a constant bound, so that they
// unroll into constant indices of `packed`.
fn scan_rig_fields(base: u32, group: u32, local: u32, n: u32, levels: u32) {
    let all = rig.members * params.lod_levels;
    let span = group * WORKGROUP_SIZE + local;
    let spanned = span * SPAN < n;
    var packed = vec4(0u);
    for (var i = 0u; i < 8u; i++) {
        let f = base + i;
        if (f >= all) {
            break;
        }
        let mask = select(0u, entries[rig_mask_index(f / params.lod_levels, span)], spanned);
        let count = countOneBits(mask & level_match(levels, f % params.lod_levels));
        packed[i / 2u] |= count << (16u * (i % 2u));
    }
    let scan = workgroup_exclusive_scan4(local, packed);
    for (var i = 0u; i < 8u; i++) {
        let f = base + i;
        if (f >= all) {
            break;
        }
        member = f / params.lod_levels;
        let half = 16u * (i % 2u);
        let before = (scan.before[i / 2u] >> half) & 0xffffu;
        let total = (scan.total[i / 2u] >> half) & 0xffffu;
        write_level_sums(vec2(group, local), n, f % params.lod_levels, vec2(before, total));
    }
}

// Walks span `span` of the n positions run over, writing each entry; returns the span's
// visible count per level.
fn cull_span(span: u32, n: u32) -> vec4<u32> {
    // Per level, the span's visible positions so far, in the entry's 7-bit fields.
    var fields = 0u;
    // The late occlusion phase: which of the span's positions the pyramids do not hide.
    var seen = 0u;
    let first = span * SPAN;
    for (var j = first; j < min(first + SPAN, n); j++) {
        let tested = cull_entry(j);
        let entry = tested & ~ENTRY_SEEN;
        seen |= select(0u, 1u << (j - first), tested != entry);
        entries[j] = fields | entry;
        if ((entry & ENTRY_VISIBLE) != 0u) {
            fields += 1u << (7u * ((entry >> ENTRY_LEVEL_SHIFT) & 3u));
        }
    }
    // A span's positions are SPAN consecutive places, aligned (a coarse block is a
    // whole number of spans): one word of bits, which this invocation alone writes.
    if (OCCLUSION == 2u && first < n) {
        occlusion[display.cull_slot * params.visibility_words + cull_position(first) / SPAN] = seen;
    }
    return (vec4(fields) >> vec4(0u, 7u, 14u, 21u)) & vec4(0x7fu);
}

// The span at `index` of workgroup `group`: its prefix within the workgroup per level,
// and (index 0) the workgroup's totals.
fn write_span_sums(group: u32, index: u32, n: u32, scan: Scan4) {
    for (var l = 0u; l < params.lod_levels; l++) {
        write_level_sums(vec2(group, index), n, l, vec2(scan.before[l], scan.total[l]));
    }
}

// write_span_sums for one level: `sums` the span's prefix and the workgroup's total.
fn write_level_sums(at: vec2<u32>, n: u32, level: u32, sums: vec2<u32>) {
    let spans = span_count(n);
    let group = at.x;
    let index = at.y;
    if (group >= group_count(spans)) {
        return;
    }
    let span = group * WORKGROUP_SIZE + index;
    if (span < spans) {
        span_sums[sum_index(level * spans + span)] = sums.x;
    }
    if (index == 0u) {
        span_sums[sum_index(group_slot(n, level, group))] = sums.y;
    }
}

// Cull position j's visible bit and level (no span fields yet), and in the late
// occlusion phase ENTRY_SEEN where the pyramids do not hide it.
fn cull_entry(j: u32) -> u32 {
    let k = cull_position(j);
    if (k >= params.instance_count) {
        return 0u;
    }
    let s = spheres_at(k);
    if (!(sphere_in_planes(display.planes, s) && in_split(s))) {
        return 0u;
    }
    if (hides(display.hidden, display.cull_slot, s)) {
        return 0u;
    }
    if (untouched_in_display(s)) {
        return 0u;
    }
    return occlusion_entry(k, s, ENTRY_VISIBLE | (lod_level(k, s) << ENTRY_LEVEL_SHIFT));
}
