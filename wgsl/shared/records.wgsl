// Storage records and the cull's uniforms, each mirrored in Rust: InstanceRecord,
// MeshRecord, LodRecord and DrawArgs by src/records.rs (bytemuck), MaterialRecord by
// src/materials.rs, CullParams by src/cull/gpu.rs and CoarseTest by src/cull/coarse.rs
// (encase). tests/shaders.rs compares offsets and sizes member by member.

struct InstanceRecord {
    // Rows of the 3x4 affine world_from_local: world = rows * vec4(local, 1).
    world_from_local: array<vec4<f32>, 3>,
    // RGBA8 unorm (unpack4x8unorm), linear.
    color: u32,
    mesh: u32,
    // Animation from the frame's time: radians per second about local +Y, and meters
    // of bob along world +Y (see vertex() in draw_common.wgsl).
    spin: f32,
    bob: f32,
    // The instance's own material in place of its mesh's (same bin), or 0xffffffff:
    // the mesh's (the vertices'). WGSL pads the record to 80 bytes.
    material: u32,
    // The slot's generation: a record whose previous frame's has another is a newcomer
    // (wgsl/shared/motion.wgsl).
    generation: u32,
}

struct MeshRecord {
    first_index: u32,
    index_count: u32,
    base_vertex: i32,
    // This mesh's range in the cull order (instances grouped by mesh, ids ascending).
    cull_start: u32,
    cull_count: u32,
    // Its material's bin: which range of the draws its draws go to.
    bin: u32,
}

// MAX_LODS per mesh, level 0 the mesh itself; mirrored by LodRecord in src/records.rs.
struct LodRecord {
    first_index: u32,
    index_count: u32,
    // Squared error relative to the bounding radius; infinite for levels a mesh lacks.
    error_sq: f32,
}

// Mirrored by MaterialRecord in src/materials.rs (bytemuck): glTF's metallic-roughness
// material. Layers are of color_textures (base color, emissive: sRGB) or data_textures
// (the rest: linear), 0xffffffff (UNTEXTURED) where a slot has no texture.
struct MaterialRecord {
    // Times the emissive strength.
    emissive: vec3<f32>,
    base_color_layer: u32,
    // KHR_texture_transform, for every texture: uv' = uv_transform * vec3(uv, 1).
    uv_transform: mat3x2<f32>,
    // Base color alpha below this is a hole (alphaMode MASK); 0 for every other mode.
    alpha_cutoff: f32,
    // Roughness in green, metalness in blue.
    metallic_roughness_layer: u32,
    normal_layer: u32,
    // Occlusion in red.
    occlusion_layer: u32,
    emissive_layer: u32,
    metallic: f32,
    roughness: f32,
    normal_scale: f32,
    occlusion_strength: f32,
    // A bit per texture slot that reads the vertex's second coordinates (uv1): base
    // color 1, metallic-roughness 2, normal 4, occlusion 8, emissive 16.
    second_uv: u32,
}

// Written whole by the draws pass every frame: see DrawArgs in src/records.rs.
struct DrawArgs {
    index_count: u32,
    // views * visible instances of the mesh (doubled for stereo).
    instance_count: u32,
    first_index: u32,
    base_vertex: i32,
    // views * offset of the mesh's first visible instance in `visible`.
    first_instance: u32,
}

// Uniform; mirrored by CullParams in src/cull/gpu.rs (encase).
struct CullParams {
    instance_count: u32,
    mesh_count: u32,
    // The device's limit of workgroups per dimension: how the coarse pass splits each
    // display's dispatch over its blocks into x and y.
    max_groups: u32,
    // Levels of detail in use: 1 (LOD off) or MAX_LODS.
    lod_levels: u32,
    // Occlusion: words of visibility bits per display slot, where the pyramids start
    // in `occlusion`, and the words between two display slots' pyramids (each slot
    // has its own region, so that every display's are built before any late cull).
    visibility_words: u32,
    pyramid_offset: u32,
    pyramid_stride: u32,
    // Keeping unchanged pixels: where the changed tiles' bits start in `occlusion`, and
    // the words from one display slot's to the next's (wgsl/shared/keep.wgsl).
    tile_offset: u32,
    tile_stride: u32,
    // Material bins: each has its own range of the draws and word of the counts;
    // the first blended bin (0xffffffff: none; the later ones are blended too), whose
    // instances occlusion never marks drawn.
    bin_count: u32,
    first_blend_bin: u32,
    // Where the blended bins' ranges of the draws start (the blend pass's).
    blend_first: u32,
    // Cull positions of room (a multiple of SPAN): the rig cull's entries hold a word
    // per span of them for the rig's levels, then one per span per member (RIG_ENTRIES
    // in cull_math.wgsl).
    position_room: u32,
    // Words of `span_sums` per member of the rig cull (RigCull): each member's sums
    // start at its index times this.
    member_sums: u32,
}

// One member of the rig cull (src/cull/rig.rs, RigView): what its context holds for
// culling, and where its outputs start in the rig's shared targets (in elements).
struct RigView {
    planes: array<vec4<f32>, 6>,
    position: vec3<f32>,
    split_keep: u32,
    // Where its blended instances sort from (cull_blend.wgsl's sort_origin).
    sort_origin: vec3<f32>,
    split_distance: f32,
    instances_per_object: u32,
    visible_at: u32,
    draws_at: u32,
    counts_at: u32,
    // Its display's slot of visibility words, and 1 where it culls in the early
    // occlusion phase (keeping only what its display drew last frame), else 0.
    cull_slot: u32,
    early: u32,
    // 1 where the display's hidden area (`hidden` at cull_slot) culls too, else 0.
    hidden: u32,
    // Its planes grown for rounding, as the coarse cull tests a block against a
    // display: a span whose box fails it holds nothing the member keeps.
    block: CoarseTest,
}

// One region of a view's hidden area (src/cull/hidden.rs): a sphere is in it when it
// is inside all three planes by its radius (unused planes pass every sphere).
struct HiddenRegion {
    planes: array<vec4<f32>, 3>,
}

// One view's hidden area: the window's outside (six flipped frustum planes), then the
// visibility mask's triangles; the first `count` regions are in use.
struct HiddenView {
    regions: array<HiddenRegion, MAX_HIDDEN_REGIONS>,
    count: u32,
}

// A display slot's hidden area: a sphere every one of the first `count` views hides
// is dropped by the display's cull (0: none is).
struct HiddenArea {
    views: array<HiddenView, MAX_HIDDEN_VIEWS>,
    count: u32,
}

// What a member in the late occlusion phase tests against its display's pyramids
// (src/cull/rig.rs, RigOcclusion): its first two views' matrices (eye[0..2] of its
// context), one view's pixels, the margin and the display's views.
struct RigOcclusion {
    view_from_world: array<mat4x4<f32>, 2>,
    clip_from_view: array<mat4x4<f32>, 2>,
    resolution: vec2<f32>,
    margin_px: f32,
    views: u32,
}

// The views one set of rig dispatches culls: the first `members` of `views`; in the
// late phase each member's occlusion test in `occlusion` (apart from `views`, which
// the other phases load per member per span and never need it).
struct RigCull {
    views: array<RigView, MAX_RIG_VIEWS>,
    occlusion: array<RigOcclusion, MAX_RIG_VIEWS>,
    members: u32,
}

// One slot's block test of the coarse cull (src/cull/coarse.rs): a display's planes
// pushed out for rounding, radii grown by `inflation` plus `slack` per unit of
// |center|_1. Mirrored by CoarseCull (encase).
struct CoarseTest {
    planes: array<vec4<f32>, 6>,
    inflation: f32,
    slack: f32,
}
