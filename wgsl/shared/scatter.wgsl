// Edits into place, once per frame with edits, before any cull: three pipelines in
// dispatch order (src/scatter.rs), each its own module declaring `Edits` as the header
// and one kind's records: places of the cull order filled or vacated
// (scatter_places.wgsl), moved instances (scatter_moves.wgsl), whole records
// (scatter_records.wgsl). The records mirror src/records.rs (EditHeader, PlaceEdit,
// MoveEdit, RecordEdit; tests/shaders.rs compares their layouts); rows are scalar
// arrays so that the records pack as the CPU writes them (a vec4 would align to 16).
// Bindings: SCATTER_BINDINGS in src/shaders/bindings.rs.

const SCATTER_GROUP: u32 = 64u;
// A vacant place's slot, and a removed instance's move (see src/places.rs).
const VACANT: u32 = 0xffffffffu;

struct EditHeader {
    count: u32,
    // 1 under GPU culling: the spheres, order and positions are the culler's.
    spheres_too: u32,
    // Workgroups along x; y spreads past the device's limit per dimension.
    groups_x: u32,
    // Occlusion: visibility words per display slot and the slots (zeros without).
    visibility_words: u32,
    visibility_slots: u32,
    // How a moved sphere is written (scatter_moves.wgsl's `written`).
    grow: u32,
    unused: array<u32, 2>,
}

struct PlaceEdit {
    place: u32,
    slot: u32,
}

struct MoveEdit {
    slot: u32,
    rows: array<f32, 12>,
    radius: f32,
}

struct RecordEdit {
    slot: u32,
    rows: array<f32, 12>,
    color: u32,
    mesh: u32,
    spin: f32,
    bob: f32,
    material: u32,
    generation: u32,
}

// This invocation's edit; at or past the header's count when it has none.
fn edit_index(wid: vec3<u32>, local: u32) -> u32 {
    return (wid.y * edits.header.groups_x + wid.x) * SCATTER_GROUP + local;
}

// The three rows of a 3x4 affine transform, from an edit's scalars.
fn edit_rows(r: array<f32, 12>) -> array<vec4<f32>, 3> {
    return array(
        vec4(r[0], r[1], r[2], r[3]),
        vec4(r[4], r[5], r[6], r[7]),
        vec4(r[8], r[9], r[10], r[11]),
    );
}
