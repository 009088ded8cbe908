// The frame level, before any display's cull (src/cull/coarse.rs): the cull order is
// cut into blocks of BLOCK positions; each block's sphere is tested once against the
// frame frustum and, when it passes, against each display's frustum (its slot); each
// display's passes then run over the positions of its own blocks, dispatched
// indirectly from their count. Three entry points, in dispatch order, the display
// cull's tree of prefix sums again: coarse_blocks (a block per invocation; each
// workgroup's blocks' prefixes and totals per slot), coarse_lists (one workgroup per
// slot, over the workgroup totals only) and coarse_place (a block per invocation: each
// kept block into its slot's list).
// Bindings: CULL_BINDINGS in group 0, COARSE_BINDINGS in group 1 (src/shaders/bindings.rs).

// The CPU twin is CoarseCull::test: same operations, same order, no fma.
fn grown_test(planes: array<vec4<f32>, 6>, inflation: f32, slack: f32, s: vec4<f32>) -> bool {
    let reach = s.w * inflation + slack * (abs(s.x) + abs(s.y) + abs(s.z));
    for (var i = 0u; i < 6u; i++) {
        let p = planes[i];
        if (p.x * s.x + p.y * s.y + p.z * s.z + p.w < -reach) {
            return false;
        }
    }
    return true;
}

// Bit 31 of a block mark: the block is kept. The rest: kept blocks of the slot
// before it in its group of WORKGROUP_SIZE blocks (kept_before adds the group's prefix).
const KEPT_BIT: u32 = 0x80000000u;

// Where a slot's group totals (then prefixes) lie in span_sums, the display culls'
// scratch, free until the first display cull (after every frame pass).
fn group_sums(slot: u32) -> u32 {
    return slot * group_count(block_count());
}

// Kept blocks of `slot` before `block`, whose mark is `mark` (after coarse_lists turned
// the group totals into prefixes).
fn kept_before(slot: u32, block: u32, mark: u32) -> u32 {
    return span_sums[group_sums(slot) + block / WORKGROUP_SIZE] + (mark & ~KEPT_BIT);
}

// The twin of block_of in src/cull/coarse.rs (each holds its members on its own; they
// need not agree bit for bit): the box of the members' spheres, grown, and the sphere
// through its corners; then per slot, the block's mark and its group's total.
@compute @workgroup_size(WORKGROUP_SIZE)
fn coarse_blocks(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let group = wid.y * groups.x + wid.x;
    let block = group * WORKGROUP_SIZE + local;
    let blocks = block_count();
    var low = vec3(3.0e38);
    var high = vec3(-3.0e38);
    for (var k = block * BLOCK; k < min(block * BLOCK + BLOCK, params.instance_count); k++) {
        let s = spheres_at(k);
        low = min(low, s.xyz - s.w);
        high = max(high, s.xyz + s.w);
    }
    let bound = grown_bound(low, high);
    let in_frame = block < blocks
        && grown_test(frame.coarse_planes, frame.coarse_inflation, frame.coarse_slack, bound.sphere);
    for (var slot = 0u; slot < arrayLength(&block_tests); slot++) {
        let kept = in_frame && block_test(block_tests[slot], bound.sphere, bound.extent);
        let scan = workgroup_exclusive_scan(local, select(0u, 1u, kept));
        if (block < blocks) {
            block_marks[slot * blocks + block] = scan.x | select(0u, KEPT_BIT, kept);
        }
        if (local == 0u && group < group_count(blocks)) {
            span_sums[group_sums(slot) + group] = scan.y;
        }
    }
}

// Per slot, one workgroup: its group totals become prefixes, each mesh's range among
// the listed positions is found, and the display passes' count and indirect dispatches
// written. It walks group totals (one per WORKGROUP_SIZE blocks), never every block.
@compute @workgroup_size(WORKGROUP_SIZE)
fn coarse_lists(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let slot = wid.x;
    let listed = prefix_groups(group_sums(slot), group_count(block_count()), 0u, local);
    storageBarrier();
    for (var m = local; m < params.mesh_count; m += WORKGROUP_SIZE) {
        let mesh = meshes[m];
        let start = listed_before(slot, mesh.cull_start, listed);
        let end = listed_before(slot, mesh.cull_start + mesh.cull_count, listed);
        candidate_ranges[slot * params.mesh_count + m] = vec2(start, end - start);
    }
    if (local == 0u) {
        let count = listed * BLOCK;
        candidate_count[slot] = count;
        // The display passes' grids, x within the device's limit, y the rest: the
        // cull pass's over spans, then the compact pass's over positions.
        grid(slot * 6u, group_count(span_count(count)));
        grid(slot * 6u + 3u, (count + WORKGROUP_SIZE - 1u) / WORKGROUP_SIZE);
    }
}

// Per slot (y) and group of WORKGROUP_SIZE blocks (x), a block per invocation: a kept
// block goes into its slot's list at its place (its group's prefix and its own).
@compute @workgroup_size(WORKGROUP_SIZE)
fn coarse_place(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let slot = wid.y;
    let blocks = block_count();
    let block = wid.x * WORKGROUP_SIZE + local;
    if (block >= blocks) {
        return;
    }
    let mark = block_marks[slot * blocks + block];
    if ((mark & KEPT_BIT) != 0u) {
        block_list[slot * blocks + kept_before(slot, block, mark)] = block;
    }
}

// Writes a dispatch of `needed` workgroups at coarse_args[at].
fn grid(at: u32, needed: u32) {
    let x = min(needed, params.max_groups);
    coarse_args[at] = x;
    coarse_args[at + 1u] = select(0u, (needed + x - 1u) / x, x > 0u);
    coarse_args[at + 2u] = 1u;
}

// Listed positions of `slot` before cull position `pos` (after its group prefixes).
fn listed_before(slot: u32, pos: u32, listed: u32) -> u32 {
    if (pos >= params.instance_count) {
        return listed * BLOCK;
    }
    let block = pos / BLOCK;
    let mark = block_marks[slot * block_count() + block];
    let within = select(0u, pos % BLOCK, (mark & KEPT_BIT) != 0u);
    return kept_before(slot, block, mark) * BLOCK + within;
}
