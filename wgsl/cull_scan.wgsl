// Pass 2 of 4 per display: per level (y) and group of WORKGROUP_SIZE spans (x), turn the
// spans' counts into prefixes within the group and write the group's total, so that no
// single workgroup walks every span (the draws pass then scans only the group totals).
// No atomics and no workgroup waits on another: wgpu promises no forward progress
// between workgroups, so a chained (decoupled look-back) scan could hang.
// Bindings (all cull passes share them): CULL_BINDINGS in src/shaders/bindings.rs.

@compute @workgroup_size(WORKGROUP_SIZE)
fn scan_spans(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let n = workgroup_cull_count(local);
    let spans = span_count(n);
    let group = wid.x;
    let level = wid.y;
    if (group >= group_count(spans)) {
        return;
    }
    let s = group * WORKGROUP_SIZE + local;
    var count = 0u;
    if (s < spans) {
        count = span_sums[level * spans + s];
    }
    let scan = workgroup_exclusive_scan(local, count);
    if (s < spans) {
        span_sums[level * spans + s] = scan.x;
    }
    if (local == 0u) {
        span_sums[group_slot(n, level, group)] = scan.y;
    }
}
