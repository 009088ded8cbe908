// The changed tiles of a kept frame, built on the GPU (src/cull/tile_marks.rs): each
// listed slot's world sphere marks the tiles it may cover in each eye of each display,
// once before the frame's scatter and pose (the sphere as last drawn) and once after
// (the sphere now). The CPU twin is TileMask::mark over the same spheres, in
// src/cull/tiles.rs: the same projection (sphere_pixels.wgsl), the same bits.

// One display's eyes, frustum and tile words: mirrored by TileDisplay in
// src/cull/tile_marks.rs (encase).
struct TileDisplay {
    eyes: RigOcclusion,
    planes: array<vec4<f32>, 6>,
    // Its tiles' first word in `tiles`.
    base: u32,
}

// The slots whose tiles change, each with the phases that mark it: MARK_BEFORE where
// the slot held an instance as last drawn, MARK_AFTER where it holds one now.
struct Marks {
    count: u32,
    list: array<u32>,
}

@compute @workgroup_size(MARK_GROUP)
fn mark(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    // Rows of groups (dispatch_size in src/shaders/bindings.rs), a display each in z.
    let i = (wid.x + wid.y * groups.x) * MARK_GROUP + local;
    if (i >= marks.count) {
        return;
    }
    let entry = marks.list[i];
    if ((entry & phase) == 0u) {
        return;
    }
    let s = spheres_at(positions[entry & MARK_SLOT]);
    let d = tile_displays[wid.z];
    if (!sphere_in_planes(d.planes, s)) {
        return;
    }
    let size = vec2<u32>(d.eyes.resolution);
    let eyes = min(d.eyes.views, 2u);
    let cols = (size.x * eyes + TILE - 1u) / TILE;
    for (var e = 0u; e < eyes; e++) {
        let t = eye_tiles(s, d.eyes.view_from_world[e], d.eyes.clip_from_view[e], size, e);
        for (var y = t.y; y <= t.w && t.x <= t.z; y++) {
            for (var x = t.x; x <= t.z; x++) {
                let i = y * cols + x;
                atomicOr(&tiles[d.base + i / 32u], 1u << (i % 32u));
            }
        }
    }
}
