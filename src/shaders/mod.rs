//! WGSL composition, in one place: every pipeline's source is its file in `wgsl/` after
//! the shared includes, the constants injected from Rust, and the binding declarations
//! generated from the one binding list per pipeline family ([`CULL_BINDINGS`],
//! [`DRAW_BINDINGS`]), from which the bind-group layouts are built too.

/// Invocations per cull workgroup (the cull pass: a span of [`SPAN`] positions each),
/// and the scans' shared array holds one entry per invocation. 256 is the largest size
/// every WebGPU adapter must support.
pub const WORKGROUP_SIZE: u32 = 256;

/// Cull positions per span, the unit of the cull's first prefix sums, walked in order by
/// one invocation of the cull pass: its count per level (at most `SPAN - 1` before a
/// position) fits the 7-bit fields of a cull entry, four levels to a word
/// (`wgsl/shared/cull_math.wgsl`). 16: on lavapipe the workgroup scan's barriers cost
/// more than the sphere tests, so they come once per 16 positions; on a GPU 16 spheres
/// per invocation still leave 65,536 invocations at 1M instances.
pub const SPAN: u32 = 16;
const _: () = assert!(SPAN <= 128 && crate::scene::MAX_LODS <= 4);
// The rig cull scans two (member, level) counts to a word: a workgroup's total must fit
// 16 bits (`scan_rig_fields` in wgsl/cull.wgsl).
const _: () = assert!(WORKGROUP_SIZE * SPAN < 1 << 16);

/// Members of one set of rig dispatches ([`crate::cull::rig`]); larger rigs cull in
/// groups of this many. Each member costs the rig's cull pass a running count per
/// invocation: 16 keeps them in registers.
pub const MAX_RIG_VIEWS: usize = 16;

/// Regions of one view's hidden area ([`crate::cull::hidden`]): the window's outside
/// (six flipped frustum planes) and the visibility mask's triangles.
pub const MAX_HIDDEN_REGIONS: usize = 6 + MAX_MASK_TRIANGLES;

/// Pixels on a side of the tiles a kept frame redraws ([`crate::cull::tiles`]).
pub const TILE: u32 = 16;

/// Pixels a sphere's projected bounds grow by each way in the tiles' test, for the
/// rounding of the projection (as occlusion's, `crate::contexts::BOUNDS_GROWTH_PX`).
pub const TILE_MARGIN_PX: f32 = 1.0;

/// A slot listed for the tile marking pass ([`crate::keep::marks`]): it held an
/// instance as last drawn (its sphere then marks).
pub const MARK_BEFORE: u32 = 1 << 31;
/// A listed slot's flag: it holds an instance now (its sphere now marks).
pub const MARK_AFTER: u32 = 1 << 30;
/// The slot's bits of a listed entry.
pub const MARK_SLOT: u32 = MARK_AFTER - 1;
/// Invocations per workgroup of the tile marking pass.
pub const MARK_GROUP: u32 = 64;
/// Invocations (words of tiles) per workgroup of the tile listing pass.
pub const LIST_GROUP: u32 = 64;

/// Views a display's hidden area holds ([`crate::cull::hidden`]): a stereo pair, or two
/// frames' pairs in one submission ([`crate::renderer::frames`]).
pub const MAX_HIDDEN_VIEWS: usize = 4;

/// Cull positions per block of the frame's coarse cull ([`crate::cull::coarse`]): the
/// CPU culler's 64 lanes.
pub const BLOCK: u32 = 64;

/// How much a coarse block's half extents (and the radius through its corners) grow
/// over what its members reach: room for the rounding of its center, extents and
/// radius, and for the members' own plane tests, which err with their `|center|` where
/// the block's test allows for the block's. The extents also grow by [`BLOCK_SLACK`]
/// per unit of `|center|_1`: the box's faces come from rounded sums `center +- radius`.
pub const BLOCK_GROWTH: f32 = 1.0 + 1.0 / 4096.0;

/// See [`BLOCK_GROWTH`]: sixteen units of roundoff.
pub const BLOCK_SLACK: f32 = 1.0 / 1048576.0;

const CONTEXTS: &str = include_str!("../../wgsl/shared/contexts.wgsl");
const RECORDS: &str = include_str!("../../wgsl/shared/records.wgsl");
const CULL_MATH: &str = include_str!("../../wgsl/shared/cull_math.wgsl");
const PYRAMID: &str = include_str!("../../wgsl/shared/pyramid.wgsl");
const OCCLUSION: &str = include_str!("../../wgsl/shared/occlusion.wgsl");
const KEEP: &str = include_str!("../../wgsl/shared/keep.wgsl");
const SPHERE_PIXELS: &str = include_str!("../../wgsl/shared/sphere_pixels.wgsl");
const CULL_SUBGROUPS: &str = concat!(
    include_str!("../../wgsl/cull.wgsl"),
    include_str!("../../wgsl/cull_subgroups.wgsl")
);
const DRAW_CLIP_DISTANCES: &str = include_str!("../../wgsl/shared/draw_clip_distances.wgsl");
const DRAW_NO_CLIP_DISTANCES: &str = include_str!("../../wgsl/shared/draw_no_clip_distances.wgsl");
const DRAW_CLIP_RECT: &str = include_str!("../../wgsl/shared/draw_clip_rect.wgsl");
const DECODE: &str = include_str!("../../wgsl/shared/decode.wgsl");
const DRAW_COMMON: &str = include_str!("../../wgsl/shared/draw_common.wgsl");
const BASE_COLOR: &str = include_str!("../../wgsl/shared/base_color.wgsl");
const PBR: &str = include_str!("../../wgsl/shared/pbr.wgsl");
const TONEMAP: &str = include_str!("../../wgsl/shared/tonemap.wgsl");
const DRAW: &str = include_str!("../../wgsl/draw.wgsl");
const DRAW_MULTIVIEW: &str = include_str!("../../wgsl/draw_multiview.wgsl");
const DRAW_MOTION: &str = include_str!("../../wgsl/draw_motion.wgsl");
const DRAW_FIRST_POSE: &str = include_str!("../../wgsl/draw_first_pose.wgsl");
const MOTION: &str = include_str!("../../wgsl/shared/motion.wgsl");

mod binding_lists;
mod bindings;
mod cull_passes;
mod draw_key;
mod hooks;
mod screen;
mod windows;

pub use binding_lists::{
    CANDIDATE_BINDINGS, COARSE_BINDINGS, CULL_BINDINGS, DEPTH_RESOLVE_BINDINGS, DRAW_BINDINGS,
    FAR_COMPOSITE_BINDINGS, FOVEATED_COMPOSITE_BINDINGS, KEEP_LIST_BINDINGS, KEEP_TILES_BINDINGS,
    LIGHT_CLUSTER_BINDINGS, MARK_TILES_BINDINGS, MATERIAL_BINDINGS, MORPH_BINDINGS,
    MOTION_BINDINGS, POSE_BINDINGS, PYRAMID_SET_DEPTHS, PYRAMID_SET_SLICES, SCATTER_BINDINGS,
    SHADOW_MAP_BINDINGS, SKIN_BINDINGS, VISIBILITY_MASK_BINDINGS, pyramid_bindings,
};
pub use bindings::{
    Access, Binding, Bound, TextureKind, bind_group, bind_group_layout, declarations,
};
pub(crate) use bindings::{compute_pipeline, dispatch_size, pipeline_layout};
pub use cull_passes::{
    CullKey, CullPass, CullTests, PYRAMID_LEVELS_PER_DISPATCH, PYRAMID_SIDE, Phase, pyramid_source,
    subgroup_tier,
};
pub use draw_key::DrawKey;
pub use hooks::{Shaders, check_shading};
pub use screen::{
    MAX_MASK_TRIANGLES, depth_resolve_source, far_composite_source, foveated_composite_source,
    keep_list_source, keep_tiles_source, visibility_mask_source,
};
pub(crate) use screen::{ScreenTargets, depth_write, screen_pipeline};
pub use windows::{Window, Windowed, Windows};

/// What a scatter's edits carry; each edit's first word is its key (a place, or a
/// slot), at most one edit per key.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EditKind {
    /// Place and slot ([`crate::records::PlaceEdit`]).
    Places,
    /// Slot, transform rows, world sphere radius ([`crate::records::MoveEdit`]).
    Moves,
    /// Slot and the whole record ([`crate::records::RecordEdit`]).
    Records,
}

/// The scatter pass's source for `kind`'s edits: one module per kind, each
/// declaring its own `Edits`.
pub fn scatter_source(windows: &Windows, kind: EditKind) -> String {
    use crate::records::EditHeader;
    let bindings = declarations(&SCATTER_BINDINGS, 0, windows);
    let body = match kind {
        EditKind::Places => include_str!("../../wgsl/scatter_places.wgsl"),
        EditKind::Moves => include_str!("../../wgsl/scatter_moves.wgsl"),
        EditKind::Records => include_str!("../../wgsl/scatter_records.wgsl"),
    };
    let shared = include_str!("../../wgsl/shared/scatter.wgsl");
    let rig = MAX_RIG_VIEWS;
    let grow = format!(
        "const GROWN_GIVEN: u32 = {}u;\nconst GROWN_MEASURED: u32 = {}u;\nconst GROWN_SLACK: f32 = {:?};\n",
        EditHeader::GROWN_GIVEN,
        EditHeader::GROWN_MEASURED,
        crate::records::GROWN_SLACK,
    );
    let span = format!(
        "const VISIBILITY_SPAN: u32 = {SPAN}u;\nconst MAX_RIG_VIEWS: u32 = {rig}u;\n{grow}{}",
        hidden_constant()
    );
    [&span, RECORDS, &bindings, shared, body].concat()
}

/// The marking pass of a kept frame's changed tiles ([`crate::keep::marks`]) for
/// spheres bound in `windows`.
pub fn keep_mark_source(windows: &Windows) -> String {
    let bindings = declarations(&MARK_TILES_BINDINGS, 0, windows);
    let marks =
        format!("const MARK_GROUP: u32 = {MARK_GROUP}u;\nconst MARK_SLOT: u32 = {MARK_SLOT}u;\n");
    let body = include_str!("../../wgsl/keep_mark.wgsl");
    [
        &constants(),
        &marks,
        RECORDS,
        &bindings,
        SPHERE_PIXELS,
        body,
    ]
    .concat()
}

/// The shading function of [`crate::scene::Shading::Unlit`] materials: the base color alone.
pub const UNLIT: &str = "fn material(s: Surface) -> vec4<f32> { return base_color(s); }\n";

/// The stereo decode for a pipeline of the caller's own that draws the cull outputs
/// (`Renderer::draw_display_with_own_pipeline`): the contexts and records, group 0's
/// bindings ([`DRAW_BINDINGS`]), `const VIEWS` (`views`: 2 for one draw covering both
/// eyes, else 1) and `decode_instance`, `decode` and their `Decoded`
/// (`wgsl/shared/decode.wgsl`). Append entry points and compile.
pub fn decode_source(views: u32) -> String {
    decode_source_with(views, &Windows::WHOLE)
}

/// [`decode_source`] for instance records bound in `windows` (scenes past one binding:
/// `Renderer::decode_source` gives the renderer's).
pub fn decode_source_with(views: u32, windows: &Windows) -> String {
    let views = format!("const VIEWS: u32 = {views}u;\n");
    let bindings = declarations(&DRAW_BINDINGS, 0, windows);
    [&constants(), &views, CONTEXTS, RECORDS, &bindings, DECODE].concat()
}

fn constants() -> String {
    let lods = crate::scene::MAX_LODS;
    let rig = MAX_RIG_VIEWS;
    format!(
        "\nconst WORKGROUP_SIZE: u32 = {WORKGROUP_SIZE}u;\nconst MAX_LODS: u32 = {lods}u;\n\
         const MAX_RIG_VIEWS: u32 = {rig}u;\n\
         const BLOCK: u32 = {BLOCK}u;\nconst SPAN: u32 = {SPAN}u;\nconst BLOCK_GROWTH: f32 = {BLOCK_GROWTH:?};\n\
         const BLOCK_SLACK: f32 = {BLOCK_SLACK:?};\n{}",
        hidden_constant()
    )
}

fn hidden_constant() -> String {
    format!(
        "const TILE: u32 = {TILE}u;\nconst TILE_MARGIN_PX: f32 = {TILE_MARGIN_PX:?};\n{}",
        hidden_views()
    )
}

fn hidden_views() -> String {
    format!(
        "const MAX_HIDDEN_REGIONS: u32 = {MAX_HIDDEN_REGIONS}u;\nconst MAX_HIDDEN_VIEWS: u32 = {MAX_HIDDEN_VIEWS}u;\n"
    )
}

/// The frame's shadow pass: depth only, the light as the display's eye 0
/// (`wgsl/shadow.wgsl` after the mono decode).
pub fn shadow_source(windows: &Windows) -> String {
    [
        &decode_source_with(1, windows),
        include_str!("../../wgsl/shadow.wgsl"),
    ]
    .concat()
}

/// The frame's shadow pass for cutout bins: [`shadow_source`]'s decode, the materials
/// (group 1) and a fragment stage that discards under the cutoff
/// (`wgsl/shadow_cutout.wgsl`).
pub fn shadow_cutout_source(windows: &Windows) -> String {
    [
        &decode_source_with(1, windows),
        &declarations(&MATERIAL_BINDINGS, 1, windows),
        // Its vertices carry both sets whatever the bin: one pipeline for every cutout.
        "const SECOND_UV: bool = true;\n",
        BASE_COLOR,
        include_str!("../../wgsl/shadow_cutout.wgsl"),
    ]
    .concat()
}

/// The frame's skinning pass (`wgsl/skin.wgsl`).
pub fn skin_source() -> String {
    let bindings = declarations(&SKIN_BINDINGS, 0, &Windows::WHOLE);
    [&bindings, include_str!("../../wgsl/skin.wgsl")].concat()
}

const LIGHT_RECORDS: &str = include_str!("../../wgsl/shared/light_records.wgsl");
const LIGHTS: &str = include_str!("../../wgsl/shared/lights.wgsl");

/// The clusters' shape and the clusters buffer's layout ([`crate::lights`]).
fn light_constants() -> String {
    use crate::lights::*;
    format!(
        "const CLUSTER_X: u32 = {CLUSTER_X}u;\nconst CLUSTER_Y: u32 = {CLUSTER_Y}u;\n\
         const CLUSTER_Z: u32 = {CLUSTER_Z}u;\nconst CLUSTERS: u32 = {CLUSTERS}u;\n\
         const CLUSTER_WORDS: u32 = {CLUSTER_WORDS}u;\nconst CLUSTER_NEAR: f32 = {CLUSTER_NEAR:?};\n\
         const CLUSTER_FAR: f32 = {CLUSTER_FAR:?};\nconst LIGHT_HEADER_WORDS: u32 = {HEADER_WORDS}u;\n\
         const LIGHT_DISPLAY_WORDS: u32 = {DISPLAY_WORDS}u;\n\
         const LIGHT_VIEW_WORDS: u32 = {VIEW_WORDS}u;\n\
         const CLUSTER_RECORD_WORDS: u32 = {CLUSTER_RECORD_WORDS}u;\n"
    )
}

/// Each display's light clusters (`wgsl/light_clusters.wgsl`).
pub fn light_clusters_source() -> String {
    let bindings = declarations(&LIGHT_CLUSTER_BINDINGS, 0, &Windows::WHOLE);
    let body = include_str!("../../wgsl/light_clusters.wgsl");
    [&light_constants(), &bindings, LIGHT_RECORDS, body].concat()
}

/// The frame's morph pass (`wgsl/morph.wgsl`).
pub fn morph_source() -> String {
    let bindings = declarations(&MORPH_BINDINGS, 0, &Windows::WHOLE);
    [&bindings, include_str!("../../wgsl/morph.wgsl")].concat()
}

/// The frame's posing pass (`wgsl/pose.wgsl`, three entry points): the frame context
/// and the moves scatter's records come before it.
pub fn pose_source() -> String {
    let pose = format!(
        "const POSE_GROUP: u32 = {}u;\nconst MAX_DEPTH: u32 = {}u;\nconst ROUNDING_SLACK: f32 = {:?};\n",
        crate::pose_tables::POSE_GROUP,
        crate::pose_tables::MAX_DEPTH,
        crate::frustum::ROUNDING_SLACK,
    );
    let scatter = include_str!("../../wgsl/shared/scatter.wgsl");
    let body = include_str!("../../wgsl/pose.wgsl");
    let bindings = declarations(&POSE_BINDINGS, 0, &Windows::WHOLE);
    [&constants(), &pose, CONTEXTS, scatter, &bindings, body].concat()
}

/// Every shader variant the crate can build, with its label.
pub fn all_sources() -> Vec<(String, String)> {
    // Whole bindings, and every windowed array split in three (scenes past one binding).
    let split = Windows::new(5 << 20, 80 << 20);
    [Windows::WHOLE, split]
        .iter()
        .flat_map(|w| {
            let tag = if *w == Windows::WHOLE {
                ""
            } else {
                ".windowed"
            };
            let cull = CullPass::variants()
                .into_iter()
                .map(move |(p, c)| (p.label(c), p.source(CullKey::over(c), w)));
            let occlusion = (CullPass::occlusion_variants().into_iter()).map(move |(p, k)| {
                let label = k.phase.label(&p.label(k.over_candidates));
                (label, p.source(k, w))
            });
            let bare = (CullPass::bare_variants().into_iter()).map(move |(p, k)| {
                (
                    format!("{}.bare", p.label(k.over_candidates)),
                    p.source(k, w),
                )
            });
            let draw = (DrawKey::ALL.iter().flat_map(|k| k.alpha_variants()))
                .flat_map(|k| {
                    [
                        k,
                        DrawKey {
                            second_uv: true,
                            ..k
                        },
                    ]
                })
                .map(move |k| (k.label(), k.source_with(None, w)));
            let others = [
                (
                    "stereocull.scatter_places".into(),
                    scatter_source(w, EditKind::Places),
                ),
                (
                    "stereocull.scatter_moves".into(),
                    scatter_source(w, EditKind::Moves),
                ),
                (
                    "stereocull.scatter_records".into(),
                    scatter_source(w, EditKind::Records),
                ),
                ("stereocull.shadow".to_string(), shadow_source(w)),
                (
                    "stereocull.shadow.cutout".to_string(),
                    shadow_cutout_source(w),
                ),
                (
                    "stereocull.far_composite".to_string(),
                    far_composite_source(),
                ),
                (
                    "stereocull.foveated_composite".to_string(),
                    foveated_composite_source(),
                ),
                (
                    "stereocull.depth_resolve".to_string(),
                    depth_resolve_source(),
                ),
                (
                    "stereocull.visibility_mask".to_string(),
                    visibility_mask_source(false),
                ),
                (
                    "stereocull.visibility_mask.multiview".to_string(),
                    visibility_mask_source(true),
                ),
                ("stereocull.skin".to_string(), skin_source()),
                (
                    "stereocull.keep_tiles".to_string(),
                    keep_tiles_source(wgpu::TextureFormat::Rgba8UnormSrgb, wgpu::Color::BLACK),
                ),
                ("stereocull.keep_mark".to_string(), keep_mark_source(w)),
                ("stereocull.keep_list".to_string(), keep_list_source()),
                ("stereocull.morph".to_string(), morph_source()),
                (
                    "stereocull.light_clusters".to_string(),
                    light_clusters_source(),
                ),
                ("stereocull.pose".to_string(), pose_source()),
            ];
            let pyramids = [(1, false), (4, false), (1, true)]
                .into_iter()
                .flat_map(|v| [1, PYRAMID_SET_DEPTHS].map(|depths| (v, depths)))
                .map(|((samples, layered), depths)| {
                    let label =
                        format!("stereocull.occlusion_pyramid.x{samples}.{layered}.{depths}");
                    (label, pyramid_source(samples, layered, depths))
                });
            cull.chain(occlusion)
                .chain(bare)
                .chain(draw)
                .chain(others)
                .chain(pyramids)
                .map(move |(label, source)| (format!("{label}{tag}"), source))
                .collect::<Vec<_>>()
        })
        .collect()
}
