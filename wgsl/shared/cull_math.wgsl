// A block's box (center c.xyz, half extents e) against a slot's test. The CPU twin
// is CoarseCull::test_block.
fn block_test(t: CoarseTest, c: vec4<f32>, e: vec3<f32>) -> bool {
    let slack = t.slack * (abs(c.x) + abs(c.y) + abs(c.z));
    for (var i = 0u; i < 6u; i++) {
        let p = t.planes[i];
        let reach = (abs(p.x) * e.x + abs(p.y) * e.y + abs(p.z) * e.z) * t.inflation;
        if (p.x * c.x + p.y * c.y + p.z * c.z + p.w < -(reach + slack)) {
            return false;
        }
    }
    return true;
}

// The box from `low` to `high` (of a group of spheres) grown for rounding, as the
// coarse cull bounds a block: the sphere through its corners and its half extents.
// What block_test takes.
struct Bound {
    sphere: vec4<f32>,
    extent: vec3<f32>,
}

// Reads the `count` spheres of the span from `first` into `spheres`; returns their
// grown box (the rig's passes: each sphere read once for the rig).
fn read_span(first: u32, count: u32, spheres: ptr<function, array<vec4<f32>, SPAN>>) -> Bound {
    var low = vec3(3.0e38);
    var high = vec3(-3.0e38);
    for (var i = 0u; i < count; i++) {
        let s = spheres_at(first + i);
        (*spheres)[i] = s;
        low = min(low, s.xyz - s.w);
        high = max(high, s.xyz + s.w);
    }
    return grown_bound(low, high);
}

fn grown_bound(low: vec3<f32>, high: vec3<f32>) -> Bound {
    let center = (low + high) * 0.5;
    let magnitude = abs(center.x) + abs(center.y) + abs(center.z);
    let extent = (high - low) * 0.5 * BLOCK_GROWTH + magnitude * BLOCK_SLACK;
    return Bound(vec4(center, length(extent) * BLOCK_GROWTH), extent);
}

// Whether the display's far split (src/far_layer.rs) keeps sphere s: with split_keep 2
// the far ones (entirely beyond split_distance from the display's apex), with 1 the
// rest, with 0 every sphere. The CPU twin is Split::keeps: same operations, same order.
fn in_split(s: vec4<f32>) -> bool {
    return in_split_of(display.split_keep, display.split_distance, display.position, s);
}

// in_split for any split (a rig member's): `keep` and `distance` from `apex`.
// Compiled out without TEST_SPLIT (a renderer without the far layer).
fn in_split_of(keep: u32, distance: f32, apex: vec3<f32>, s: vec4<f32>) -> bool {
    if (!TEST_SPLIT || keep == 0u) {
        return true;
    }
    let d = s.xyz - apex;
    let d2 = d.x * d.x + d.y * d.y + d.z * d.z;
    let reach = distance + s.w;
    return (d2 >= reach * reach) == (keep == 2u);
}

// Whether a view whose flags (a context's `hidden`) say it culls by the hidden area of
// display slot `slot` has s hidden there. Compiled out without TEST_HIDDEN (a renderer
// without the lens mask): see CullTests in src/shaders/cull_passes.rs.
fn hides(flags: u32, slot: u32, s: vec4<f32>) -> bool {
    if (!TEST_HIDDEN) {
        return false;
    }
    return (flags & CULL_HIDDEN) != 0u && hidden_in_views(slot, s);
}

// Whether display slot `slot`'s hidden area (src/cull/hidden.rs) hides sphere s in
// every masked view: some region of each holds it whole. The CPU twin is
// HiddenArea::hides: the plane arithmetic of sphere_in_planes, compared with the radius.
fn hidden_in_views(slot: u32, s: vec4<f32>) -> bool {
    let views = hidden[slot].count;
    for (var v = 0u; v < views; v++) {
        if (!hidden_in_view(slot, v, s)) {
            return false;
        }
    }
    return views > 0u;
}

fn hidden_in_view(slot: u32, v: u32, s: vec4<f32>) -> bool {
    for (var r = 0u; r < hidden[slot].views[v].count; r++) {
        var inside = true;
        for (var i = 0u; i < 3u; i++) {
            let p = hidden[slot].views[v].regions[r].planes[i];
            inside = inside && p.x * s.x + p.y * s.y + p.z * s.z + p.w >= s.w;
        }
        if (inside) {
            return true;
        }
    }
    return false;
}

// The member of the rig cull whose scratch and outputs the functions below address
// (RIG: the rig passes set it); 0 in a single view's passes, which write their own
// outputs from their start.
var<private> member: u32;

fn sum_index(i: u32) -> u32 {
    return member * params.member_sums + i;
}

fn visible_index(i: u32) -> u32 {
    if (RIG) {
        return rig.views[member].visible_at + i;
    }
    return i;
}

fn draw_index(i: u32) -> u32 {
    if (RIG) {
        return rig.views[member].draws_at + i;
    }
    return i;
}

fn count_index(i: u32) -> u32 {
    if (RIG) {
        return rig.views[member].counts_at + i;
    }
    return i;
}

// The cull contract's V of the view culled.
fn instances_per_object() -> u32 {
    if (RIG) {
        return rig.views[member].instances_per_object;
    }
    return display.instances_per_object;
}

// The level of detail of cull position k, whose sphere is s, from the viewer's position
// (the frame context, never an eye's: both eyes and every display draw the same level).
// The CPU twin is records::lod_level: same operations, same order.
fn lod_level(k: u32, s: vec4<f32>) -> u32 {
    if (params.lod_levels == 1u) {
        return 0u;
    }
    let d = s.xyz - frame.viewer_position;
    let d2 = d.x * d.x + d.y * d.y + d.z * d.z;
    let r2 = s.w * s.w;
    let first = mesh_of[k] * MAX_LODS;
    var level = 0u;
    for (var l = 1u; l < MAX_LODS; l++) {
        if (d2 > lods[first + l].error_sq * frame.lod_scale * r2) {
            level += 1u;
        }
    }
    return level;
}

// Blocks of BLOCK cull positions, the coarse cull's unit (the last may be short).
fn block_count() -> u32 {
    return (params.instance_count + BLOCK - 1u) / BLOCK;
}

// What a display's passes run over (cull_count, cull_position, mesh_range): every cull
// position (over_everything.wgsl) or its coarse blocks' (over_candidates.wgsl).

var<workgroup> uniform_count: u32;

// cull_count(), as a value the whole workgroup agrees on (loops with barriers need it).
fn workgroup_cull_count(local: u32) -> u32 {
    if (local == 0u) {
        uniform_count = cull_count();
    }
    return workgroupUniformLoad(&uniform_count);
}

// A display's scratch, per position the passes run over: its entry, one word whatever
// the number of levels: bit 31 visible, bits 28-29 its level, and for each level a 7-bit
// field (level 0 lowest) counting that level's visible positions before it in its span
// of SPAN positions. Then `span_sums`: per level, each span's prefix within its group
// of WORKGROUP_SIZE spans (both from the cull pass, a span per invocation, a group per
// workgroup); after them (group_slot), per level, each group's total, turned into its
// prefix among all the visible instances, finer levels first (the draws pass).
const ENTRY_VISIBLE: u32 = 0x80000000u;
const ENTRY_LEVEL_SHIFT: u32 = 28u;

fn span_count(n: u32) -> u32 {
    return (n + SPAN - 1u) / SPAN;
}

fn group_count(spans: u32) -> u32 {
    return (spans + WORKGROUP_SIZE - 1u) / WORKGROUP_SIZE;
}

// Where group g's total (then prefix) of `level` lies in span_sums.
fn group_slot(n: u32, level: u32, g: u32) -> u32 {
    let spans = span_count(n);
    return params.lod_levels * spans + level * group_count(spans) + g;
}

// Visible entries of `level` before position `pos` of the n run over, plus every finer
// level's (pos may be n, which gives `total`). After the draws pass's group prefixes.
fn flagged_before(level: u32, pos: u32, n: u32, total: u32) -> u32 {
    if (pos >= n) {
        return total;
    }
    return span_before(level, pos / SPAN, n) + within_span(level, pos);
}

// flagged_before the first position of span `span`: its group's prefix and its own.
fn span_before(level: u32, span: u32, n: u32) -> u32 {
    return span_sums[sum_index(group_slot(n, level, span / WORKGROUP_SIZE))] + span_sums[sum_index(level * span_count(n) + span)];
}

// The rig's entries (RIG_ENTRIES): per span of SPAN positions, at `entries[span]` a
// word of the positions' levels (position i's in bits 2i and 2i + 1) and at
// rig_mask_index(b, span) member b's mask (bit 2i: it keeps position i). A span's
// words for the whole rig, where a member's own cull writes a word per position.
fn rig_mask_index(b: u32, span: u32) -> u32 {
    return (1u + b) * (params.position_room / SPAN) + span;
}

// Bit 2i set where position i of a span's `levels` word has level `level`.
fn level_match(levels: u32, level: u32) -> u32 {
    let x = levels ^ (level * 0x55555555u);
    return ~(x | (x >> 1u)) & 0x55555555u;
}

// Visible entries of `level` before `pos` within its span, for the member addressed.
fn within_span(level: u32, pos: u32) -> u32 {
    if (RIG) {
        let span = pos / SPAN;
        let kept = entries[rig_mask_index(member, span)] & level_match(entries[span], level);
        return countOneBits(kept & ((1u << (2u * (pos % SPAN))) - 1u));
    }
    return (entries[pos] >> (7u * level)) & 0x7fu;
}

// Position j's entry for the member addressed: its visible bit and level (the span
// fields only without RIG).
fn entry_of(j: u32) -> u32 {
    if (RIG) {
        let span = j / SPAN;
        let shift = 2u * (j % SPAN);
        let kept = (entries[rig_mask_index(member, span)] >> shift) & 1u;
        let level = (entries[span] >> shift) & 3u;
        return select(0u, ENTRY_VISIBLE | (level << ENTRY_LEVEL_SHIFT), kept != 0u);
    }
    return entries[j];
}

// Turns `groups` group totals from span_sums[first] on into prefixes starting at
// `carry`, in one workgroup; returns carry plus their total. The draws pass's over
// its cull's workgroups, the coarse lists' over their workgroups of blocks.
fn prefix_groups(first: u32, groups: u32, carry_in: u32, local: u32) -> u32 {
    var carry = carry_in;
    for (var base = 0u; base < groups; base += WORKGROUP_SIZE) {
        let g = base + local;
        var sum = 0u;
        if (g < groups) {
            sum = span_sums[sum_index(first + g)];
        }
        let scan = workgroup_exclusive_scan(local, sum);
        if (g < groups) {
            span_sums[sum_index(first + g)] = carry + scan.x;
        }
        carry += scan.y;
    }
    return carry;
}

var<workgroup> scan_scratch: array<vec4<u32>, WORKGROUP_SIZE>;

// Invocations per chunk of the scans: WORKGROUP_SIZE / SCAN_CHUNK chunk sums.
const SCAN_CHUNK: u32 = 16u;
var<workgroup> chunk_sums: array<vec4<u32>, WORKGROUP_SIZE / SCAN_CHUNK>;

struct Scan4 {
    before: vec4<u32>,
    total: vec4<u32>,
}

// Exclusive prefix sums of four values at once over the workgroup (the cull's four
// levels of detail in one pass). The first invocation of each chunk turns the chunk's
// values into prefixes within it; then each invocation adds the chunk sums before its
// chunk to its own prefix (a loop of constant bound: every lane reads the same sum).
// Three barriers, where a Hillis-Steele scan takes two per doubling, and at most 17
// reads an invocation (lavapipe runs an invocation's reads as gathers: the scan that
// summed the values before it in its chunk, up to 30 reads, cost the rig cull's three
// scans on `cave` at 1M more than its sphere tests).
fn workgroup_exclusive_scan4(local: u32, value: vec4<u32>) -> Scan4 {
    scan_scratch[local] = value;
    workgroupBarrier();
    // A loop that only the chunks' first invocations enter, not a branch: a SIMD CPU
    // adapter (lavapipe) skips a loop no lane enters.
    let chunk_turns = select(0u, SCAN_CHUNK, local < WORKGROUP_SIZE / SCAN_CHUNK);
    var sum = vec4(0u);
    for (var i = 0u; i < chunk_turns; i++) {
        let at = local * SCAN_CHUNK + i;
        let v = scan_scratch[at];
        scan_scratch[at] = sum;
        sum += v;
    }
    if (local < WORKGROUP_SIZE / SCAN_CHUNK) {
        chunk_sums[local] = sum;
    }
    workgroupBarrier();
    let chunk = local / SCAN_CHUNK;
    var before = scan_scratch[local];
    var total = vec4(0u);
    for (var c = 0u; c < WORKGROUP_SIZE / SCAN_CHUNK; c++) {
        let sum = chunk_sums[c];
        before += select(vec4(0u), sum, vec4(c < chunk));
        total += sum;
    }
    workgroupBarrier();
    return Scan4(before, total);
}

// Exclusive prefix sum of `value` over the workgroup: (exclusive prefix, total).
fn workgroup_exclusive_scan(local: u32, value: u32) -> vec2<u32> {
    let scan = workgroup_exclusive_scan4(local, vec4(value, 0u, 0u, 0u));
    return vec2(scan.before.x, scan.total.x);
}
