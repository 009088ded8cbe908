// The frame level, before any display's cull (src/cull/coarse.rs): the cull order is
// cut into blocks of BLOCK positions; each block's sphere is tested once against the
// frame frustum and, when it passes, against each display's frustum (its slot); each
// display's passes then run over the positions of its own blocks, dispatched
// indirectly from their count. Two entry points, in dispatch order: coarse_blocks (one
// invocation per cull position) and coarse_lists (one workgroup per slot).
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

// Bit 31 of a block mark: the block is kept.
const KEPT_BIT: u32 = 0x80000000u;

var<workgroup> low: array<vec3<f32>, WORKGROUP_SIZE>;
var<workgroup> high: array<vec3<f32>, WORKGROUP_SIZE>;

// The twin of block_of in src/cull/coarse.rs (each holds its members on its own; they
// need not agree bit for bit): the box of the members' spheres, reduced over the
// block's invocations, grown, and the sphere through its corners.
@compute @workgroup_size(WORKGROUP_SIZE)
fn coarse_blocks(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let k = (wid.y * groups.x + wid.x) * WORKGROUP_SIZE + local;
    low[local] = vec3(3.0e38);
    high[local] = vec3(-3.0e38);
    if (k < params.instance_count) {
        let s = spheres_at(k);
        low[local] = s.xyz - s.w;
        high[local] = s.xyz + s.w;
    }
    workgroupBarrier();
    let lane = local % BLOCK;
    for (var step = BLOCK / 2u; step > 0u; step >>= 1u) {
        if (lane < step) {
            low[local] = min(low[local], low[local + step]);
            high[local] = max(high[local], high[local + step]);
        }
        workgroupBarrier();
    }
    let block = k / BLOCK;
    let blocks = block_count();
    if (lane != 0u || block >= blocks) {
        return;
    }
    let center = (low[local] + high[local]) * 0.5;
    let magnitude = abs(center.x) + abs(center.y) + abs(center.z);
    let extent = (high[local] - low[local]) * 0.5 * BLOCK_GROWTH + magnitude * BLOCK_SLACK;
    let sphere = vec4(center, length(extent) * BLOCK_GROWTH);
    let in_frame = grown_test(frame.coarse_planes, frame.coarse_inflation, frame.coarse_slack, sphere);
    for (var slot = 0u; slot < arrayLength(&block_tests); slot++) {
        let kept = in_frame && block_test(block_tests[slot], sphere, extent);
        block_marks[slot * blocks + block] = select(0u, KEPT_BIT, kept);
    }
}

// Per slot, one workgroup: its blocks' marks become (blocks kept before) | kept bit,
// the kept blocks are listed in ascending order, each mesh's range among the listed
// positions is found, and the display passes' count and indirect dispatch written.
@compute @workgroup_size(WORKGROUP_SIZE)
fn coarse_lists(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let slot = wid.x;
    let blocks = block_count();
    let first = slot * blocks;
    var listed = 0u;
    for (var base = 0u; base < blocks; base += WORKGROUP_SIZE) {
        let b = base + local;
        var kept = 0u;
        if (b < blocks) {
            kept = block_marks[first + b] >> 31u;
        }
        let scan = workgroup_exclusive_scan(local, kept);
        if (b < blocks) {
            block_marks[first + b] = (listed + scan.x) | (kept << 31u);
            if (kept == 1u) {
                block_list[first + listed + scan.x] = b;
            }
        }
        listed += scan.y;
    }
    storageBarrier();
    for (var m = local; m < params.mesh_count; m += WORKGROUP_SIZE) {
        let mesh = meshes[m];
        let start = listed_before(first, mesh.cull_start, listed);
        let end = listed_before(first, mesh.cull_start + mesh.cull_count, listed);
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

// Writes a dispatch of `needed` workgroups at coarse_args[at].
fn grid(at: u32, needed: u32) {
    let x = min(needed, params.max_groups);
    coarse_args[at] = x;
    coarse_args[at + 1u] = select(0u, (needed + x - 1u) / x, x > 0u);
    coarse_args[at + 2u] = 1u;
}

// Listed positions before cull position `pos` of the slot whose marks start at `first`.
fn listed_before(first: u32, pos: u32, listed: u32) -> u32 {
    if (pos >= params.instance_count) {
        return listed * BLOCK;
    }
    let mark = block_marks[first + pos / BLOCK];
    let within = select(0u, pos % BLOCK, (mark & KEPT_BIT) != 0u);
    return (mark & ~KEPT_BIT) * BLOCK + within;
}
