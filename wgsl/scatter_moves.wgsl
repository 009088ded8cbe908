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
        spheres_set(at, written(spheres_at(at), center, edit.radius));
    }
}

// The sphere a move writes over `was`: its own (center, radius), or for a two-frame
// submission's second frame one about the first frame's center that holds both
// frames' spheres (src/renderer/second_frame.rs). Edits from the CPU bring that
// radius (GROWN_GIVEN: the CPU culler takes the same bytes); the pose pass's are grown
// here (GROWN_MEASURED: posing on the GPU has no CPU twin), as renderer::grown does.
// A place filled this frame (its sphere vacant, radius -inf) has no first frame's
// sphere: its own is written.
fn written(was: vec4<f32>, center: vec3<f32>, radius: f32) -> vec4<f32> {
    if (was.w < 0.0) {
        return vec4(center, radius);
    }
    switch edits.header.grow {
        case GROWN_GIVEN: {
            return vec4(was.xyz, radius);
        }
        case GROWN_MEASURED: {
            let reach = distance(was.xyz, center) + radius;
            return vec4(was.xyz, max(was.w, reach * (1.0 + GROWN_SLACK)));
        }
        default: {
            return vec4(center, radius);
        }
    }
}
