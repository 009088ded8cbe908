// The CPU twin is frustum::sphere_in_planes. Same products, same sums, left to right,
// no fma: CPU and GPU reach identical decisions, which the byte-for-byte tests need.
fn sphere_in_planes(planes: array<vec4<f32>, 6>, s: vec4<f32>) -> bool {
    for (var i = 0u; i < 6u; i++) {
        let p = planes[i];
        if (p.x * s.x + p.y * s.y + p.z * s.z + p.w < -s.w) {
            return false;
        }
    }
    return true;
}

// Whether the display's far split (src/far_layer.rs) keeps sphere s: with split_keep 2
// the far ones (entirely beyond split_distance from the display's apex), with 1 the
// rest, with 0 every sphere. The CPU twin is Split::keeps: same operations, same order.
fn in_split(s: vec4<f32>) -> bool {
    if (display.split_keep == 0u) {
        return true;
    }
    let d = s.xyz - display.position;
    let d2 = d.x * d.x + d.y * d.y + d.z * d.z;
    let reach = display.split_distance + s.w;
    return (d2 >= reach * reach) == (display.split_keep == 2u);
}

// The level of detail of cull position k's sphere, from the viewer's position (the
// frame context, never an eye's: both eyes and every display draw the same level). The
// CPU twin is records::lod_level: same operations, same order.
fn lod_level(k: u32) -> u32 {
    if (params.lod_levels == 1u) {
        return 0u;
    }
    let s = spheres_at(k);
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

// What a display's passes run over: every cull position, or, after the frame's coarse
// cull (COARSE), the positions of the blocks listed for its slot, ascending (the last
// block's may run past the instances: cull_position then passes instance_count).
fn cull_count() -> u32 {
    if (COARSE) {
        return candidate_count[display.cull_slot];
    }
    return params.instance_count;
}

fn cull_position(j: u32) -> u32 {
    if (COARSE) {
        let listed = block_list[display.cull_slot * block_count() + j / BLOCK];
        return listed * BLOCK + j % BLOCK;
    }
    return j;
}

// Mesh m's (start, count) among what the passes run over.
fn mesh_range(m: u32) -> vec2<u32> {
    if (COARSE) {
        return candidate_ranges[display.cull_slot * params.mesh_count + m];
    }
    return vec2(meshes[m].cull_start, meshes[m].cull_count);
}

var<workgroup> uniform_count: u32;

// cull_count(), as a value the whole workgroup agrees on (loops with barriers need it).
fn workgroup_cull_count(local: u32) -> u32 {
    if (local == 0u) {
        uniform_count = cull_count();
    }
    return workgroupUniformLoad(&uniform_count);
}

// Flagged entries of `level` before position `pos` of the n run over, plus every finer
// level's (pos may be n, which gives `total`). Block sums must hold block prefixes.
fn flagged_before(level: u32, pos: u32, n: u32, total: u32) -> u32 {
    if (pos >= n) {
        return total;
    }
    let blocks = (n + WORKGROUP_SIZE - 1u) / WORKGROUP_SIZE;
    return block_sums[level * blocks + pos / WORKGROUP_SIZE] + (local_prefix[level * n + pos] & ~VISIBLE_BIT);
}

// Turns `blocks` block sums from block_sums[first] on into block prefixes starting at
// `carry`, in one workgroup; returns carry plus their total.
fn prefix_blocks(first: u32, blocks: u32, carry_in: u32, local: u32) -> u32 {
    var carry = carry_in;
    for (var base = 0u; base < blocks; base += WORKGROUP_SIZE) {
        let b = base + local;
        var sum = 0u;
        if (b < blocks) {
            sum = block_sums[first + b];
        }
        let scan = workgroup_exclusive_scan(local, sum);
        if (b < blocks) {
            block_sums[first + b] = carry + scan.x;
        }
        carry += scan.y;
    }
    return carry;
}

// Bit 31 of a local_prefix entry is the instance's visibility flag; the low bits are
// its exclusive prefix within its workgroup (< WORKGROUP_SIZE).
const VISIBLE_BIT: u32 = 0x80000000u;

var<workgroup> scan_scratch: array<u32, WORKGROUP_SIZE>;

// Exclusive prefix sum of `value` over the workgroup (Hillis-Steele); every
// invocation must call it. Returns (exclusive prefix, workgroup total).
fn workgroup_exclusive_scan(local: u32, value: u32) -> vec2<u32> {
    scan_scratch[local] = value;
    workgroupBarrier();
    for (var offset = 1u; offset < WORKGROUP_SIZE; offset <<= 1u) {
        var add = 0u;
        if (local >= offset) {
            add = scan_scratch[local - offset];
        }
        workgroupBarrier();
        scan_scratch[local] += add;
        workgroupBarrier();
    }
    let inclusive = scan_scratch[local];
    let total = scan_scratch[WORKGROUP_SIZE - 1u];
    workgroupBarrier();
    return vec2(inclusive - value, total);
}
