// Moved instances: the new transform's rows into the instance record and, under GPU
// culling, the world sphere at the slot's cull position. The radius comes computed on
// the CPU; the center is computed here exactly as the CPU does (transform_center in
// src/scene/mod.rs: same products, sums left to right, no fma), so that the GPU and the
// CPU culler test the very same sphere.

struct Edits {
    header: EditHeader,
    list: array<MoveEdit>,
}

@compute @workgroup_size(SCATTER_GROUP)
fn scatter(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    let i = edit_index(wid, local);
    if (i >= edits.header.count) {
        return;
    }
    let edit = edits.list[i];
    if (edit.slot == VACANT) {
        return;
    }
    var record = instances_at(edit.slot);
    let rows = edit_rows(edit.rows);
    record.world_from_local = rows;
    instances_set(edit.slot, record);
    if (edits.header.spheres_too != 0u) {
        let l = mesh_bounds[record.mesh].xyz;
        var center: vec3<f32>;
        for (var r = 0u; r < 3u; r++) {
            let m = rows[r];
            center[r] = m.x * l.x + m.y * l.y + m.z * l.z + m.w;
        }
        let at = positions[edit.slot];
        // A second frame's move: the first frame's center, with a radius that holds
        // both poses (computed on the CPU, as is every radius).
        let kept = spheres_at(at).xyz;
        spheres_set(at, vec4(select(center, kept, edits.header.grow != 0u), edit.radius));
    }
}
