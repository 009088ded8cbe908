// Whole records (dispatched after the moves, so an inserted instance's record wins):
// each edit is a slot and its 80-byte instance record, member by member.

struct Edits {
    header: EditHeader,
    list: array<RecordEdit>,
}

@compute @workgroup_size(SCATTER_GROUP)
fn scatter(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    let i = edit_index(wid, local);
    if (i >= edits.header.count) {
        return;
    }
    let e = edits.list[i];
    instances_set(e.slot, InstanceRecord(edit_rows(e.rows), e.color, e.mesh, e.spin, e.bob, e.material, e.generation));
}
