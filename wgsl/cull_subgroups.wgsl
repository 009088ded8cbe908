// The cull pass's subgroup tier (Features::SUBGROUP, an adapter with one subgroup
// size): the same spans and the same entries and sums as `cull` (cull.wgsl, composed
// before this file), its workgroup scan done by subgroupInclusiveAdd and one pass over
// the subgroups' totals: two barriers and a few reads where the workgroup-memory scan
// takes three barriers and up to 30 reads.
// The workgroup's spans are ordered by (subgroup, lane), not by local index, so no
// assumption about how local indices map onto subgroups enters the order; it needs
// full subgroups of one size, which a fixed subgroup size dividing WORKGROUP_SIZE gives
// (src/cull/gpu.rs chooses the tier).

// One total per subgroup: at most WORKGROUP_SIZE / 4, 4 the smallest subgroup wgpu has.
var<workgroup> subgroup_sums: array<vec4<u32>, WORKGROUP_SIZE / 4u>;

@compute @workgroup_size(WORKGROUP_SIZE)
fn cull_subgroups(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
    @builtin(subgroup_id) subgroup: u32,
    @builtin(num_subgroups) subgroups: u32,
    @builtin(subgroup_invocation_id) lane: u32,
    @builtin(subgroup_size) size: u32,
) {
    let n = workgroup_cull_count(local);
    let group = wid.y * groups.x + wid.x;
    let index = subgroup * size + lane;
    let counts = cull_span(group * WORKGROUP_SIZE + index, n);
    let inclusive = subgroupInclusiveAdd(counts);
    if (lane == size - 1u) {
        subgroup_sums[subgroup] = inclusive;
    }
    workgroupBarrier();
    var before = inclusive - counts;
    var total = vec4(0u);
    for (var s = 0u; s < subgroups; s++) {
        let sum = subgroup_sums[s];
        before += select(vec4(0u), sum, vec4(s < subgroup));
        total += sum;
    }
    write_span_sums(group, index, n, Scan4(before, total));
}
