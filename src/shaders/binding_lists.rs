//! Every pipeline's bind groups as binding lists: the cull passes, the draw pipelines
//! (the instances, the materials, the shadow map), the scatter of edits, the frame's
//! posing and skinning, the composites and the occlusion pyramids. Each list makes its
//! WGSL declarations and its layout (`bindings.rs`), so the two cannot disagree.

use super::bindings::{Access, Binding, TextureKind};
use super::windows::Windowed;

const fn binding(
    name: &'static str,
    access: Access,
    wgsl_type: &'static str,
    stages: wgpu::ShaderStages,
) -> Binding {
    Binding {
        name,
        access,
        wgsl_type,
        stages,
        windowed: None,
    }
}

const fn windowed(
    name: &'static str,
    access: Access,
    wgsl_type: &'static str,
    stages: wgpu::ShaderStages,
    which: Windowed,
) -> Binding {
    Binding {
        windowed: Some(which),
        ..binding(name, access, wgsl_type, stages)
    }
}

const fn texture(name: &'static str, kind: TextureKind, stages: wgpu::ShaderStages) -> Binding {
    binding(name, Access::Texture(kind), kind.wgsl_type(), stages)
}

const fn sampler(
    name: &'static str,
    ty: wgpu::SamplerBindingType,
    stages: wgpu::ShaderStages,
) -> Binding {
    let wgsl_type = match ty {
        wgpu::SamplerBindingType::Comparison => "sampler_comparison",
        _ => "sampler",
    };
    binding(name, Access::Sampler(ty), wgsl_type, stages)
}

const COMPUTE: wgpu::ShaderStages = wgpu::ShaderStages::COMPUTE;
const FRAGMENT: wgpu::ShaderStages = wgpu::ShaderStages::FRAGMENT;
const FILTERABLE: wgpu::TextureSampleType = wgpu::TextureSampleType::Float { filterable: true };

/// Every cull pass's bindings: the frame context, per display its context and outputs,
/// the scene data uploaded once, scratch shared by all displays, and the frame's coarse
/// cull results.
pub const CULL_BINDINGS: [Binding; 16] = [
    binding("frame", Access::Uniform, "FrameContext", COMPUTE),
    binding("display", Access::Uniform, "DisplayContext", COMPUTE),
    binding("params", Access::Uniform, "CullParams", COMPUTE),
    // The rig passes' members (src/cull/rig.rs): their planes, splits and where their
    // outputs start in the shared targets.
    binding("rig", Access::Uniform, "RigCull", COMPUTE),
    // Instance id at each cull position.
    binding("order", Access::StorageRead, "array<u32>", COMPUTE),
    binding("meshes", Access::StorageRead, "array<MeshRecord>", COMPUTE),
    // MAX_LODS levels per mesh.
    binding("lods", Access::StorageRead, "array<LodRecord>", COMPUTE),
    // Mesh of each cull position.
    binding("mesh_of", Access::StorageRead, "array<u32>", COMPUTE),
    // Per position culled: its entry (visible bit, level, per level its prefix in its
    // span; see ENTRY_VISIBLE in wgsl/shared/cull_math.wgsl).
    binding("entries", Access::StorageReadWrite, "array<u32>", COMPUTE),
    // Per level, each span's count then prefix in its group; then each group's total
    // then prefix.
    binding("span_sums", Access::StorageReadWrite, "array<u32>", COMPUTE),
    binding("visible", Access::StorageReadWrite, "array<u32>", COMPUTE),
    binding(
        "draws",
        Access::StorageReadWrite,
        "array<DrawArgs>",
        COMPUTE,
    ),
    // Per view: the draw count (what multi_draw_indexed_indirect_count reads), the
    // visible total, then each material bin's draw count.
    binding("counts", Access::StorageReadWrite, "array<u32>", COMPUTE),
    // Occlusion (wgsl/shared/occlusion.wgsl): per display slot, a word per span of
    // places whose low SPAN bits say which places that display drew last frame; then,
    // per display slot from params.pyramid_offset, params.pyramid_stride words apart,
    // its eyes' depth pyramids (src/occlusion.rs, f32 bits). One binding: GL has 16
    // storage buffers a stage.
    binding("occlusion", Access::StorageReadWrite, "array<u32>", COMPUTE),
    // Per display slot, the lens's hidden area as planes (src/cull/hidden.rs): what
    // a display's cull drops where its `hidden` is 1.
    binding("hidden", Access::StorageRead, "array<HiddenArea>", COMPUTE),
    // World bounding spheres in cull order.
    windowed(
        "spheres",
        Access::StorageRead,
        "array<vec4<f32>>",
        COMPUTE,
        Windowed::Spheres,
    ),
];

/// The frame's coarse cull (src/cull/coarse.rs), per slot and block of BLOCK cull
/// positions: the listed blocks ascending, per slot the listed positions' count and
/// each mesh's (start, count) among them, as `access` binds them.
const fn coarse_lists(access: Access) -> [Binding; 3] {
    [
        binding("block_list", access, "array<u32>", COMPUTE),
        binding("candidate_count", access, "array<u32>", COMPUTE),
        binding("candidate_ranges", access, "array<vec2<u32>>", COMPUTE),
    ]
}

/// The display passes' group 1 over the coarse cull's candidates: its lists, read only.
/// A display pass binds none of the coarse passes' writes (nor, without the coarse cull,
/// any of this group).
pub const CANDIDATE_BINDINGS: [Binding; 3] = coarse_lists(Access::StorageRead);

/// The frame-level coarse passes' group 1: what they write (the lists, each block's mark
/// and the display passes' indirect dispatches, which nothing else binds: a buffer read
/// as dispatch arguments may not be bound for writing in the same dispatch) and the
/// slots' block tests.
pub const COARSE_BINDINGS: [Binding; 6] = {
    let [list, count, ranges] = coarse_lists(Access::StorageReadWrite);
    [
        binding(
            "coarse_args",
            Access::StorageReadWrite,
            "array<u32>",
            COMPUTE,
        ),
        // Per slot and block: its mark (kept bit, then listed blocks before it).
        binding(
            "block_marks",
            Access::StorageReadWrite,
            "array<u32>",
            COMPUTE,
        ),
        list,
        count,
        ranges,
        binding(
            "block_tests",
            Access::StorageRead,
            "array<CoarseTest>",
            COMPUTE,
        ),
    ]
};

/// Every draw pipeline's bindings.
pub const DRAW_BINDINGS: [Binding; 4] = [
    binding(
        "frame",
        Access::Uniform,
        "FrameContext",
        wgpu::ShaderStages::VERTEX_FRAGMENT,
    ),
    binding(
        "display",
        Access::Uniform,
        "DisplayContext",
        wgpu::ShaderStages::VERTEX_FRAGMENT,
    ),
    binding(
        "visible",
        Access::StorageRead,
        "array<u32>",
        wgpu::ShaderStages::VERTEX,
    ),
    windowed(
        "instances",
        Access::StorageRead,
        "array<InstanceRecord>",
        wgpu::ShaderStages::VERTEX_FRAGMENT,
        Windowed::Instances,
    ),
];

/// Group 3 of the draw pipelines with motion vectors (`wgsl/shared/motion.wgsl`): the
/// instance records as the previous frame drew them; of the first-pose pipelines
/// (`wgsl/draw_first_pose.wgsl`), as the first frame of two draws them (its fragments
/// read their color).
pub const MOTION_BINDINGS: [Binding; 1] = [windowed(
    "previous_instances",
    Access::StorageRead,
    "array<InstanceRecord>",
    wgpu::ShaderStages::VERTEX_FRAGMENT,
    Windowed::Instances,
)];

/// The scatter pass's bindings (`wgsl/scatter_*.wgsl`): the frame's edits, and where
/// they go.
pub const SCATTER_BINDINGS: [Binding; 7] = [
    // The header and one kind's edits (`Edits` in each wgsl/scatter_*.wgsl).
    binding("edits", Access::StorageRead, "Edits", COMPUTE),
    // Cull position of each slot (the places scatter writes, the moves read).
    binding("positions", Access::StorageReadWrite, "array<u32>", COMPUTE),
    // Slot at each cull position.
    binding("order", Access::StorageReadWrite, "array<u32>", COMPUTE),
    // The GPU culler's occlusion words (CULL_BINDINGS' `occlusion`): places filled or
    // vacated lose their visibility bits.
    binding(
        "visibility",
        Access::StorageReadWrite,
        "array<atomic<u32>>",
        COMPUTE,
    ),
    // Each mesh's local bounding sphere (center, radius): where a moved sphere's
    // center comes from.
    binding(
        "mesh_bounds",
        Access::StorageRead,
        "array<vec4<f32>>",
        COMPUTE,
    ),
    windowed(
        "instances",
        Access::StorageReadWrite,
        "array<InstanceRecord>",
        COMPUTE,
        Windowed::Instances,
    ),
    // World bounding spheres in cull order (the GPU culler's; a stand-in otherwise).
    windowed(
        "spheres",
        Access::StorageReadWrite,
        "array<vec4<f32>>",
        COMPUTE,
        Windowed::Spheres,
    ),
];

/// Group 1 of the draw pipelines (and the shadow's cutouts): the materials' textures,
/// their sampler and records (`crate::materials`).
pub const MATERIAL_BINDINGS: [Binding; 4] = [
    texture(
        "color_textures",
        TextureKind {
            dimension: wgpu::TextureViewDimension::D2Array,
            ..TextureKind::d2(FILTERABLE)
        },
        FRAGMENT,
    ),
    sampler(
        "texture_sampler",
        wgpu::SamplerBindingType::Filtering,
        FRAGMENT,
    ),
    binding(
        "materials",
        Access::StorageRead,
        "array<MaterialRecord>",
        FRAGMENT,
    ),
    texture(
        "data_textures",
        TextureKind {
            dimension: wgpu::TextureViewDimension::D2Array,
            ..TextureKind::d2(FILTERABLE)
        },
        FRAGMENT,
    ),
];

/// Group 2 of the built-in draw pipelines: the frame's shadow map and its comparison
/// sampler (`light_reaching` in `wgsl/shared/draw_common.wgsl`).
pub const SHADOW_MAP_BINDINGS: [Binding; 5] = [
    texture(
        "shadow_map",
        TextureKind::d2(wgpu::TextureSampleType::Depth),
        FRAGMENT,
    ),
    sampler(
        "shadow_sampler",
        wgpu::SamplerBindingType::Comparison,
        FRAGMENT,
    ),
    // The punctual lights (crate::lights), each display's view of its clusters and
    // their records.
    binding(
        "lights",
        Access::StorageRead,
        "array<LightRecord>",
        FRAGMENT,
    ),
    binding("light_views", Access::StorageRead, "array<u32>", FRAGMENT),
    binding(
        "light_clusters",
        Access::StorageRead,
        "array<u32>",
        FRAGMENT,
    ),
];

/// The light cluster pass (`wgsl/light_clusters.wgsl`): the lights, the views (the
/// count, the slices' depths and each display's matrices, from the CPU) and the
/// cluster records it sets bits of.
pub const LIGHT_CLUSTER_BINDINGS: [Binding; 3] = [
    binding("lights", Access::StorageRead, "array<LightRecord>", COMPUTE),
    binding("light_views", Access::StorageRead, "array<u32>", COMPUTE),
    binding(
        "light_clusters",
        Access::StorageReadWrite,
        "array<atomic<u32>>",
        COMPUTE,
    ),
];

/// The far layer's composite (`wgsl/far_composite.wgsl`): the display's and the far
/// layer's contexts, the far layer's color and depth.
pub const FAR_COMPOSITE_BINDINGS: [Binding; 5] = [
    binding("display", Access::Uniform, "DisplayContext", FRAGMENT),
    binding("far", Access::Uniform, "DisplayContext", FRAGMENT),
    texture("far_color", TextureKind::d2(FILTERABLE), FRAGMENT),
    texture(
        "far_depth",
        TextureKind::d2(wgpu::TextureSampleType::Depth),
        FRAGMENT,
    ),
    sampler("far_sampler", wgpu::SamplerBindingType::Filtering, FRAGMENT),
];

/// A foveated display's composite (`wgsl/foveated_composite.wgsl`): its parameters and
/// the display's target, read texel by texel.
pub const FOVEATED_COMPOSITE_BINDINGS: [Binding; 2] = [
    binding("params", Access::Uniform, "CompositeParams", FRAGMENT),
    texture(
        "source",
        TextureKind::d2(wgpu::TextureSampleType::Float { filterable: false }),
        FRAGMENT,
    ),
];

/// The lens's hidden area written to depth (`wgsl/visibility_mask.wgsl`): each view's
/// placed triangles.
pub const VISIBILITY_MASK_BINDINGS: [Binding; 1] = [binding(
    "mask",
    Access::Uniform,
    "MaskVertices",
    wgpu::ShaderStages::VERTEX,
)];

/// The compositor's depth resolve (`wgsl/depth_resolve.wgsl`): one layer of a
/// multisampled depth attachment.
pub const DEPTH_RESOLVE_BINDINGS: [Binding; 1] = [texture(
    "depth",
    TextureKind {
        multisampled: true,
        ..TextureKind::d2(wgpu::TextureSampleType::Depth)
    },
    FRAGMENT,
)];

/// The frame's skinning pass (`wgsl/skin.wgsl`).
pub const SKIN_BINDINGS: [Binding; 4] = [
    binding("rest", Access::StorageRead, "array<SkinVertex>", COMPUTE),
    // Each joint's matrix, three rows.
    binding(
        "joints",
        Access::StorageRead,
        "array<array<vec4<f32>, 3>>",
        COMPUTE,
    ),
    // The vertex buffer every later pass draws, as words (its Vertex layout).
    binding("vertices", Access::StorageReadWrite, "array<u32>", COMPUTE),
    binding("params", Access::Uniform, "SkinParams", COMPUTE),
];

/// The frame's morph pass (`wgsl/morph.wgsl`): the morphed vertices at rest, their
/// targets' offsets and the weights, and what it writes: the scene's vertices and the
/// skins' rest vertices (a skinned mesh is morphed before it is skinned), as words.
pub const MORPH_BINDINGS: [Binding; 6] = [
    binding("rest", Access::StorageRead, "array<MorphVertex>", COMPUTE),
    binding("deltas", Access::StorageRead, "array<MorphDelta>", COMPUTE),
    binding("weights", Access::StorageRead, "array<f32>", COMPUTE),
    binding("vertices", Access::StorageReadWrite, "array<u32>", COMPUTE),
    binding("skin_rest", Access::StorageReadWrite, "array<u32>", COMPUTE),
    binding("params", Access::Uniform, "MorphParams", COMPUTE),
];

/// The frame's pose pass (`wgsl/pose.wgsl`), one group for its three entry points:
/// the frame, the tables, each node's local and world rows, and what it writes for the
/// skins and the scatter of moves.
pub const POSE_BINDINGS: [Binding; 12] = [
    binding("frame", Access::Uniform, "FrameContext", COMPUTE),
    binding("nodes", Access::StorageRead, "array<PoseNode>", COMPUTE),
    binding(
        "channels",
        Access::StorageRead,
        "array<PoseChannel>",
        COMPUTE,
    ),
    binding("times", Access::StorageRead, "array<f32>", COMPUTE),
    binding("values", Access::StorageRead, "array<vec4<f32>>", COMPUTE),
    binding("locals", Access::StorageReadWrite, "array<Rows>", COMPUTE),
    binding("worlds", Access::StorageReadWrite, "array<Rows>", COMPUTE),
    binding("targets", Access::StorageRead, "array<PoseTarget>", COMPUTE),
    binding(
        "skin_joints",
        Access::StorageRead,
        "array<SkinJoint>",
        COMPUTE,
    ),
    binding(
        "joint_matrices",
        Access::StorageReadWrite,
        "array<Rows>",
        COMPUTE,
    ),
    binding("edits", Access::StorageReadWrite, "Edits", COMPUTE),
    binding("params", Access::Uniform, "PoseParams", COMPUTE),
];

/// Depth targets one set of pyramid dispatches reads (`wgsl/occlusion_pyramid.wgsl`):
/// a binding each (WebGPU has no array of textures without an optional feature, and
/// stages have 16 sampled textures at least). A rig of more displays with occlusion
/// reduces its pyramids in sets of this many.
pub const PYRAMID_SET_DEPTHS: usize = 8;
/// Eyes one set of pyramid dispatches reduces: two per display.
pub const PYRAMID_SET_SLICES: usize = 2 * PYRAMID_SET_DEPTHS;

/// The occlusion pyramids' pass (`wgsl/occlusion_pyramid.wgsl`) over a set of depth
/// targets of `samples` per pixel, their eyes side by side or (`layered`) a layer
/// each: the set's slices, each dispatch's level record (a dynamic offset), the
/// pyramids (every display's region), its `depths` depth targets (1 to
/// [`PYRAMID_SET_DEPTHS`]).
pub fn pyramid_bindings(samples: u32, layered: bool, depths: usize) -> Vec<Binding> {
    let depth = TextureKind {
        dimension: match layered {
            true => wgpu::TextureViewDimension::D2Array,
            false => wgpu::TextureViewDimension::D2,
        },
        multisampled: samples > 1,
        ..TextureKind::d2(wgpu::TextureSampleType::Depth)
    };
    const DEPTHS: [&str; PYRAMID_SET_DEPTHS] = [
        "depth0", "depth1", "depth2", "depth3", "depth4", "depth5", "depth6", "depth7",
    ];
    let fixed = [
        binding("eyes", Access::Uniform, "PyramidSet", COMPUTE),
        binding("level", Access::UniformDynamic, "PyramidLevel", COMPUTE),
        binding("pyramid", Access::StorageReadWrite, "array<f32>", COMPUTE),
    ];
    let depths = depths.clamp(1, PYRAMID_SET_DEPTHS);
    let textures = DEPTHS[..depths]
        .iter()
        .map(|name| texture(name, depth, COMPUTE));
    fixed.into_iter().chain(textures).collect()
}

// The binding lists of keeping unchanged pixels ([`crate::keep`]): the GPU's marking
// of the changed tiles, their listing and the tile pass that clears them.
/// A kept frame's changed tiles marked on the GPU (`wgsl/keep_mark.wgsl`).
pub const MARK_TILES_BINDINGS: [Binding; 6] = [
    // The listed slots, each with its phases' flags.
    binding("marks", Access::StorageRead, "Marks", COMPUTE),
    // The phase this dispatch marks: MARK_BEFORE or MARK_AFTER.
    binding("phase", Access::Uniform, "u32", COMPUTE),
    binding(
        "tile_displays",
        Access::StorageRead,
        "array<TileDisplay>",
        COMPUTE,
    ),
    // Cull position of each slot.
    binding("positions", Access::StorageRead, "array<u32>", COMPUTE),
    // The GPU culler's occlusion words (CULL_BINDINGS' `occlusion`): each display's
    // tiles.
    binding(
        "tiles",
        Access::StorageReadWrite,
        "array<atomic<u32>>",
        COMPUTE,
    ),
    windowed(
        "spheres",
        Access::StorageRead,
        "array<vec4<f32>>",
        COMPUTE,
        Windowed::Spheres,
    ),
];

/// A kept frame's changed tiles cleared (`wgsl/keep_tiles.wgsl`): the display's grid
/// of tiles and the changed ones' list.
pub const KEEP_TILES_BINDINGS: [Binding; 2] = [
    binding(
        "tiles",
        Access::StorageRead,
        "TileWords",
        wgpu::ShaderStages::VERTEX,
    ),
    binding(
        "list",
        Access::StorageRead,
        "array<u32>",
        wgpu::ShaderStages::VERTEX,
    ),
];

/// A kept frame's changed tiles listed (`wgsl/keep_list.wgsl`): the display's bits in,
/// the list and the tile pass's indirect draw out.
pub const KEEP_LIST_BINDINGS: [Binding; 3] = [
    binding("tiles", Access::StorageRead, "TileWords", COMPUTE),
    binding("list", Access::StorageReadWrite, "array<u32>", COMPUTE),
    binding("draw", Access::StorageReadWrite, "TileDraw", COMPUTE),
];
