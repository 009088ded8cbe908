// Edits into place, once per frame with edits, before any cull, three entry points in
// dispatch order (src/scatter.rs): places of the cull order filled or vacated, moved
// instances, whole records. A moves edit (14 words after the 4-word header) is a slot,
// the instance's new transform rows and its world bounding sphere's radius, computed
// on the CPU; the center is computed here exactly as the CPU does (transform_center in
// src/scene.rs: same products, sums left to right, no fma), so that the GPU and the CPU
// culler test the very same sphere.
// Bindings: SCATTER_BINDINGS in src/shaders/bindings.rs.

const HEADER: u32 = 4u;
const MOVE_WORDS: u32 = 14u;
const RECORD_WORDS: u32 = 17u;
const PLACE_WORDS: u32 = 2u;
const SCATTER_GROUP: u32 = 64u;
// A vacant place's slot, and a removed instance's move (see src/places.rs).
const VACANT: u32 = 0xffffffffu;

// This invocation's edit, from the 4-word header: edit count, spheres too (GPU
// culling), workgroups along x; at or past the count when it has none.
fn edit_index(wid: vec3<u32>, local: u32) -> u32 {
    return (wid.y * edits[2] + wid.x) * SCATTER_GROUP + local;
}

fn edit_vec4(at: u32) -> vec4<f32> {
    return bitcast<vec4<f32>>(vec4(edits[at], edits[at + 1u], edits[at + 2u], edits[at + 3u]));
}

@compute @workgroup_size(SCATTER_GROUP)
fn scatter(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    let i = edit_index(wid, local);
    if (i >= edits[0]) {
        return;
    }
    let at = HEADER + i * MOVE_WORDS;
    let slot = edits[at];
    if (slot == VACANT) {
        return;
    }
    var record = instances_at(slot);
    let rows = array(edit_vec4(at + 1u), edit_vec4(at + 5u), edit_vec4(at + 9u));
    record.world_from_local = rows;
    instances_set(slot, record);
    if (edits[1] != 0u) {
        let l = mesh_bounds[record.mesh].xyz;
        var center: vec3<f32>;
        for (var r = 0u; r < 3u; r++) {
            let m = rows[r];
            center[r] = m.x * l.x + m.y * l.y + m.z * l.z + m.w;
        }
        spheres_set(positions[slot], vec4(center, bitcast<f32>(edits[at + 13u])));
    }
}

// The records scatter (dispatched after the moves): each edit is a slot and its whole
// 64-byte record (records.wgsl's InstanceRecord, word for word).
@compute @workgroup_size(SCATTER_GROUP)
fn scatter_records(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    let i = edit_index(wid, local);
    if (i >= edits[0]) {
        return;
    }
    let at = HEADER + i * RECORD_WORDS;
    let rows = array(edit_vec4(at + 1u), edit_vec4(at + 5u), edit_vec4(at + 9u));
    let spin = bitcast<f32>(edits[at + 15u]);
    let bob = bitcast<f32>(edits[at + 16u]);
    instances_set(edits[at], InstanceRecord(rows, edits[at + 13u], edits[at + 14u], spin, bob));
}

// The places scatter (dispatched first): each edit is a place and the slot now there,
// or VACANT; a vacant place's sphere is CullLayout::VACANT_SPHERE (a radius of minus
// infinity fails every plane test). Only the GPU culler has these buffers.
@compute @workgroup_size(SCATTER_GROUP)
fn scatter_places(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    let i = edit_index(wid, local);
    if (i >= edits[0] || edits[1] == 0u) {
        return;
    }
    let place = edits[HEADER + i * PLACE_WORDS];
    let slot = edits[HEADER + i * PLACE_WORDS + 1u];
    order[place] = slot;
    if (slot == VACANT) {
        spheres_set(place, vec4(0.0, 0.0, 0.0, bitcast<f32>(0xff800000u)));
    } else {
        positions[slot] = place;
    }
}
