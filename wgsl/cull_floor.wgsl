// The floor the cull is measured against (`profile`): the least any frustum cull could
// do, one read of every sphere, its plane test and one flag written per instance. It
// writes the display scratch (`entries`), which the next display cull overwrites.
// Bindings (all cull passes share them): CULL_BINDINGS in src/shaders/bindings.rs.

@compute @workgroup_size(WORKGROUP_SIZE)
fn floor(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let k = (wid.y * groups.x + wid.x) * WORKGROUP_SIZE + local;
    if (k < params.instance_count) {
        entries[k] = select(0u, 1u, sphere_in_planes(display.planes, spheres_at(k)));
    }
}

// The rig's floor (RIG): one read of every sphere for the whole rig, each member's
// plane tests (skipped for a span whose box fails the member's block test) and its
// mask of the span (RIG_ENTRIES); a span per invocation, members outside, as the rig's
// cull walks them.
@compute @workgroup_size(WORKGROUP_SIZE)
fn floor_rig(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let n = params.instance_count;
    let span = (wid.y * groups.x + wid.x) * WORKGROUP_SIZE + local;
    let first = span * SPAN;
    let count = select(0u, min(SPAN, n - first), first < n);
    var spheres: array<vec4<f32>, SPAN>;
    let bound = read_span(first, count, &spheres);
    for (var b = 0u; b < rig.members; b++) {
        let view = rig.views[b];
        // A loop, not a branch: a SIMD CPU adapter (lavapipe) runs both sides of a
        // branch under a mask, but leaves a loop once no lane has an iteration left.
        let tested = select(0u, count, block_test(view.block, bound.sphere, bound.extent));
        var mask = 0u;
        for (var i = 0u; i < tested; i++) {
            mask |= select(0u, 1u << (2u * i), sphere_in_planes(view.planes, spheres[i]));
        }
        if (count > 0u) {
            entries[rig_mask_index(b, span)] = mask;
        }
    }
}
