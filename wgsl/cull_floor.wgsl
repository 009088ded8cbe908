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

// The rig's floor (RIG): one read of every sphere for the whole rig, each member's plane
// test and flag, into the member's scratch.
@compute @workgroup_size(WORKGROUP_SIZE)
fn floor_rig(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let k = (wid.y * groups.x + wid.x) * WORKGROUP_SIZE + local;
    if (k < params.instance_count) {
        let s = spheres_at(k);
        for (var b = 0u; b < rig.members; b++) {
            entries[b * params.member_entries + k] = select(0u, 1u, sphere_in_planes(rig.views[b].planes, s));
        }
    }
}
