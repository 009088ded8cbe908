//! Shader checks that need no GPU: every variant validates with naga, and every struct
//! the GPU reads has the same layout in Rust and in WGSL (offsets read by naga).

use std::mem::{offset_of, size_of};

use glam::{Mat4, UVec2, Vec2, Vec3, Vec4};
use naga::{Module, TypeInner};
use stereocull::contexts::{DisplayContext, EyeContext, FrameContext};
use stereocull::cull::CoarseCull;
use stereocull::cull::gpu_buffers::CullParams;
use stereocull::cull::hidden::{HiddenArea, HiddenRegion, HiddenView, MAX_HIDDEN_REGIONS};
use stereocull::cull::rig::{MAX_RIG_VIEWS, RigCull, RigOcclusion, RigView};
use stereocull::draw::VERTEX_ATTRIBUTES;
use stereocull::keep::clear::TileGrid;
use stereocull::keep::marks::TileDisplay;
use stereocull::materials::MaterialRecord;
use stereocull::occlusion::pyramid::{PyramidSet, PyramidSlice};
use stereocull::records::{
    DrawArgs, EditHeader, InstanceRecord, LodRecord, MeshRecord, MoveEdit, PlaceEdit, RecordEdit,
};
use stereocull::records::{storage_bytes, uniform_bytes};
use stereocull::scene::Vertex;
use stereocull::shaders::{
    Access, Binding, CANDIDATE_BINDINGS, COARSE_BINDINGS, CULL_BINDINGS, CullKey, CullPass,
    DEPTH_RESOLVE_BINDINGS, DRAW_BINDINGS, DrawKey, EditKind, FAR_COMPOSITE_BINDINGS,
    FOVEATED_COMPOSITE_BINDINGS, KEEP_LIST_BINDINGS, KEEP_TILES_BINDINGS, MARK_TILES_BINDINGS,
    MATERIAL_BINDINGS, MOTION_BINDINGS, POSE_BINDINGS, PYRAMID_SET_DEPTHS, SCATTER_BINDINGS,
    SHADOW_MAP_BINDINGS, SKIN_BINDINGS, Window, Windows, all_sources, depth_resolve_source,
    far_composite_source, foveated_composite_source, keep_list_source, keep_mark_source,
    keep_tiles_source, pose_source, pyramid_bindings, pyramid_source, scatter_source,
    shadow_cutout_source, shadow_source, skin_source,
};

fn parse(label: &str, source: &str) -> Module {
    naga::front::wgsl::parse_str(source)
        .unwrap_or_else(|e| panic!("{label}: {}", e.emit_to_string(source)))
}

#[test]
fn every_shader_variant_validates() {
    let sources = all_sources();
    assert!(sources.len() >= 6, "variants: {}", sources.len());
    for (label, source) in sources {
        let module = parse(&label, &source);
        naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::all(),
        )
        .validate(&module)
        .unwrap_or_else(|e| panic!("{label}: {}", e.emit_to_string(&source)));
    }
}

/// (member name -> offset) and span of the WGSL struct `name`.
fn wgsl_struct(module: &Module, name: &str) -> (Vec<(String, u32)>, u32) {
    let ty = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no struct {name} in WGSL"))
        .1;
    match &ty.inner {
        TypeInner::Struct { members, span } => (
            members
                .iter()
                .map(|m| (m.name.clone().unwrap_or_default(), m.offset))
                .collect(),
            *span,
        ),
        other => panic!("{name} is not a struct: {other:?}"),
    }
}

fn module() -> Module {
    parse(
        "cull",
        &CullPass::Cull.source(CullKey::over(false), &Windows::WHOLE),
    )
}

#[test]
fn records_match_wgsl() {
    let module = module();
    let check = |name: &str, size: usize, rust: &[(&str, usize)]| {
        let (members, span) = wgsl_struct(&module, name);
        assert_eq!(span as usize, size, "{name} size");
        let names: Vec<&str> = members.iter().map(|(n, _)| n.as_str()).collect();
        let rust_names: Vec<&str> = rust.iter().map(|(n, _)| *n).collect();
        assert_eq!(names, rust_names, "{name} members");
        for ((member, offset), (_, rust_offset)) in members.iter().zip(rust) {
            assert_eq!(*offset as usize, *rust_offset, "{name}.{member} offset");
        }
    };
    check(
        "InstanceRecord",
        size_of::<InstanceRecord>(),
        &[
            (
                "world_from_local",
                offset_of!(InstanceRecord, world_from_local),
            ),
            ("color", offset_of!(InstanceRecord, color)),
            ("mesh", offset_of!(InstanceRecord, mesh)),
            ("spin", offset_of!(InstanceRecord, spin)),
            ("bob", offset_of!(InstanceRecord, bob)),
            ("material", offset_of!(InstanceRecord, material)),
            ("generation", offset_of!(InstanceRecord, generation)),
        ],
    );
    check(
        "MeshRecord",
        size_of::<MeshRecord>(),
        &[
            ("first_index", offset_of!(MeshRecord, first_index)),
            ("index_count", offset_of!(MeshRecord, index_count)),
            ("base_vertex", offset_of!(MeshRecord, base_vertex)),
            ("cull_start", offset_of!(MeshRecord, cull_start)),
            ("cull_count", offset_of!(MeshRecord, cull_count)),
            ("bin", offset_of!(MeshRecord, bin)),
        ],
    );
    check(
        "LodRecord",
        size_of::<LodRecord>(),
        &[
            ("first_index", offset_of!(LodRecord, first_index)),
            ("index_count", offset_of!(LodRecord, index_count)),
            ("error_sq", offset_of!(LodRecord, error_sq)),
        ],
    );
    check(
        "MaterialRecord",
        size_of::<MaterialRecord>(),
        &[
            ("emissive", offset_of!(MaterialRecord, emissive)),
            (
                "base_color_layer",
                offset_of!(MaterialRecord, base_color_layer),
            ),
            ("uv_transform", offset_of!(MaterialRecord, uv_transform)),
            ("alpha_cutoff", offset_of!(MaterialRecord, alpha_cutoff)),
            (
                "metallic_roughness_layer",
                offset_of!(MaterialRecord, metallic_roughness_layer),
            ),
            ("normal_layer", offset_of!(MaterialRecord, normal_layer)),
            (
                "occlusion_layer",
                offset_of!(MaterialRecord, occlusion_layer),
            ),
            ("emissive_layer", offset_of!(MaterialRecord, emissive_layer)),
            ("metallic", offset_of!(MaterialRecord, metallic)),
            ("roughness", offset_of!(MaterialRecord, roughness)),
            ("normal_scale", offset_of!(MaterialRecord, normal_scale)),
            (
                "occlusion_strength",
                offset_of!(MaterialRecord, occlusion_strength),
            ),
            ("second_uv", offset_of!(MaterialRecord, second_uv)),
        ],
    );
    check(
        "DrawArgs",
        size_of::<DrawArgs>(),
        &[
            ("index_count", offset_of!(DrawArgs, index_count)),
            ("instance_count", offset_of!(DrawArgs, instance_count)),
            ("first_index", offset_of!(DrawArgs, first_index)),
            ("base_vertex", offset_of!(DrawArgs, base_vertex)),
            ("first_instance", offset_of!(DrawArgs, first_instance)),
        ],
    );
    // wgpu reads indirect draws with exactly this layout.
    assert_eq!(
        size_of::<DrawArgs>(),
        size_of::<wgpu::util::DrawIndexedIndirectArgs>()
    );
    assert_eq!(size_of::<DrawArgs>(), 20);
    assert_eq!(size_of::<InstanceRecord>(), 80);
}

/// The scatter passes' edit records, each in the module of its kind, packed as the CPU
/// writes them: 32, 8, 56 and 76 bytes.
#[test]
fn edit_records_match_wgsl() {
    let check = |kind: EditKind, name: &str, size: usize, rust: &[(&str, usize)]| {
        let module = parse(name, &scatter_source(&Windows::WHOLE, kind));
        let (members, span) = wgsl_struct(&module, name);
        assert_eq!(span as usize, size, "{name} size");
        let found: Vec<(&str, usize)> = members
            .iter()
            .map(|(n, o)| (n.as_str(), *o as usize))
            .collect();
        assert_eq!(found, rust, "{name} members and offsets");
    };
    check(
        EditKind::Moves,
        "EditHeader",
        size_of::<EditHeader>(),
        &[
            ("count", offset_of!(EditHeader, count)),
            ("spheres_too", offset_of!(EditHeader, spheres_too)),
            ("groups_x", offset_of!(EditHeader, groups_x)),
            ("visibility_words", offset_of!(EditHeader, visibility_words)),
            ("visibility_slots", offset_of!(EditHeader, visibility_slots)),
            ("grow", offset_of!(EditHeader, grow)),
            ("unused", offset_of!(EditHeader, unused)),
        ],
    );
    check(
        EditKind::Places,
        "PlaceEdit",
        size_of::<PlaceEdit>(),
        &[
            ("place", offset_of!(PlaceEdit, place)),
            ("slot", offset_of!(PlaceEdit, slot)),
        ],
    );
    check(
        EditKind::Moves,
        "MoveEdit",
        size_of::<MoveEdit>(),
        &[
            ("slot", offset_of!(MoveEdit, slot)),
            ("rows", offset_of!(MoveEdit, rows)),
            ("radius", offset_of!(MoveEdit, radius)),
        ],
    );
    check(
        EditKind::Records,
        "RecordEdit",
        size_of::<RecordEdit>(),
        &[
            ("slot", offset_of!(RecordEdit, slot)),
            ("rows", offset_of!(RecordEdit, rows)),
            ("color", offset_of!(RecordEdit, color)),
            ("mesh", offset_of!(RecordEdit, mesh)),
            ("spin", offset_of!(RecordEdit, spin)),
            ("bob", offset_of!(RecordEdit, bob)),
            ("material", offset_of!(RecordEdit, material)),
            ("generation", offset_of!(RecordEdit, generation)),
        ],
    );
    // The byte counts the README and SyncStats quote.
    let sizes = [
        size_of::<PlaceEdit>(),
        size_of::<MoveEdit>(),
        size_of::<RecordEdit>(),
    ];
    assert_eq!(sizes, [8, 56, 76]);
    // Each kind's module lists its own records after the header.
    for (kind, record) in [
        (EditKind::Places, "PlaceEdit"),
        (EditKind::Moves, "MoveEdit"),
        (EditKind::Records, "RecordEdit"),
    ] {
        let module = parse("edits", &scatter_source(&Windows::WHOLE, kind));
        let (members, _) = wgsl_struct(&module, "Edits");
        assert_eq!(members[1], ("list".to_string(), 32), "{kind:?}");
        let list = module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some("Edits"));
        let Some((_, ty)) = list else {
            panic!("no Edits")
        };
        let TypeInner::Struct { members, .. } = &ty.inner else {
            panic!("Edits")
        };
        let TypeInner::Array { base, .. } = module.types[members[1].ty].inner else {
            panic!("{kind:?}: Edits.list is not an array")
        };
        assert_eq!(module.types[base].name.as_deref(), Some(record), "{kind:?}");
    }
}

/// A matrix whose every element differs from every other value used here.
fn distinct_mat(seed: f32) -> Mat4 {
    Mat4::from_cols_array(&std::array::from_fn(|i| seed + i as f32 * 0.01))
}

fn eye(seed: f32) -> EyeContext {
    EyeContext {
        view_from_world: distinct_mat(seed),
        world_from_view: distinct_mat(seed + 1.0),
        clip_from_view: distinct_mat(seed + 2.0),
        view_from_clip: distinct_mat(seed + 3.0),
        clip_from_world: distinct_mat(seed + 4.0),
        world_from_clip: distinct_mat(seed + 5.0),
        previous_clip_from_world: distinct_mat(seed + 6.0),
        position: Vec3::new(seed + 7.0, seed + 7.1, seed + 7.2),
        time_ahead: seed + 7.5,
        viewport: Vec4::new(seed + 8.0, seed + 8.1, seed + 8.2, seed + 8.3),
        placement: Vec4::new(seed + 9.0, seed + 9.1, seed + 9.2, seed + 9.3),
    }
}

fn f32_at(bytes: &[u8], offset: u32) -> f32 {
    let o = offset as usize;
    f32::from_le_bytes(bytes[o..o + 4].try_into().unwrap())
}

/// Checks that each WGSL member's first scalar, read at naga's offset from encase's
/// bytes, is the Rust field's first scalar, and that the sizes agree.
fn check_uniform(name: &str, bytes: &[u8], expected_first: &[(&str, f32)]) {
    let (members, span) = wgsl_struct(&module(), name);
    assert_eq!(bytes.len(), span as usize, "{name} size");
    let names: Vec<&str> = members.iter().map(|(n, _)| n.as_str()).collect();
    let rust_names: Vec<&str> = expected_first.iter().map(|(n, _)| *n).collect();
    assert_eq!(names, rust_names, "{name} members");
    for ((member, offset), (_, want)) in members.iter().zip(expected_first) {
        assert_eq!(f32_at(bytes, *offset), *want, "{name}.{member} at {offset}");
    }
}

#[test]
fn contexts_match_wgsl() {
    let e = eye(10.0);
    check_uniform(
        "EyeContext",
        &uniform_bytes(&e),
        &[
            ("view_from_world", 10.0),
            ("world_from_view", 11.0),
            ("clip_from_view", 12.0),
            ("view_from_clip", 13.0),
            ("clip_from_world", 14.0),
            ("world_from_clip", 15.0),
            ("previous_clip_from_world", 16.0),
            ("position", 17.0),
            ("time_ahead", 17.5),
            ("viewport", 18.0),
            ("placement", 19.0),
        ],
    );
    let d = DisplayContext {
        view_from_world: distinct_mat(1.0),
        world_from_view: distinct_mat(2.0),
        clip_from_view: distinct_mat(3.0),
        view_from_clip: distinct_mat(4.0),
        eye: [eye(10.0), eye(20.0), eye(30.0), eye(40.0)],
        position: Vec3::new(5.0, 5.1, 5.2),
        resolution: Vec2::new(6.0, 6.1),
        planes: std::array::from_fn(|i| Vec4::splat(7.0 + i as f32)),
        instances_per_object: 2,
        first_eye: 1,
        split_keep: 2,
        split_distance: 13.0,
        cull_slot: 3,
        views: 4,
        occlusion_margin_px: 14.5,
        hidden: 1,
    };
    let bytes = uniform_bytes(&d);
    check_uniform(
        "DisplayContext",
        &bytes,
        &[
            ("view_from_world", 1.0),
            ("world_from_view", 2.0),
            ("clip_from_view", 3.0),
            ("view_from_clip", 4.0),
            ("eye", 10.0),
            ("position", 5.0),
            ("resolution", 6.0),
            ("planes", 7.0),
            ("instances_per_object", f32::from_bits(2)),
            ("first_eye", f32::from_bits(1)),
            ("split_keep", f32::from_bits(2)),
            ("split_distance", 13.0),
            ("cull_slot", f32::from_bits(3)),
            ("views", f32::from_bits(4)),
            ("occlusion_margin_px", 14.5),
            ("hidden", f32::from_bits(1)),
        ],
    );
    // Each eye sits one EyeContext span after the one before (the fourth, a foveated
    // display's right inset, three), and the last plane five vec4s after the first.
    let (members, _) = wgsl_struct(&module(), "DisplayContext");
    let at = |n: &str| members.iter().find(|(m, _)| m == n).unwrap().1;
    let (_, eye_span) = wgsl_struct(&module(), "EyeContext");
    assert_eq!(f32_at(&bytes, at("eye") + eye_span), 20.0);
    assert_eq!(f32_at(&bytes, at("eye") + eye_span + 4 * 64), 24.0);
    assert_eq!(f32_at(&bytes, at("eye") + 3 * eye_span), 40.0);
    assert_eq!(f32_at(&bytes, at("planes") + 5 * 16), 12.0);

    let f = FrameContext {
        viewer_position: Vec3::new(1.0, 1.1, 1.2),
        time: 2.0,
        viewer_direction: Vec3::new(3.0, 3.1, 3.2),
        lod_scale: 4.0,
        coarse_planes: std::array::from_fn(|i| Vec4::splat(5.0 + i as f32)),
        coarse_inflation: 6.0,
        coarse_slack: 7.0,
        light_from_world: Mat4::from_cols_array(&[8.0; 16]),
        light_direction: Vec3::splat(9.0),
        shadows: 10,
        previous_time: 11.0,
        exposure: 12.0,
        tonemap: 13,
    };
    let bytes = uniform_bytes(&f);
    check_uniform(
        "FrameContext",
        &bytes,
        &[
            ("viewer_position", 1.0),
            ("time", 2.0),
            ("viewer_direction", 3.0),
            ("lod_scale", 4.0),
            ("coarse_planes", 5.0),
            ("coarse_inflation", 6.0),
            ("coarse_slack", 7.0),
            ("light_from_world", 8.0),
            ("light_direction", 9.0),
            ("shadows", f32::from_bits(10)),
            ("previous_time", 11.0),
            ("exposure", 12.0),
            ("tonemap", f32::from_bits(13)),
        ],
    );
    let (members, _) = wgsl_struct(&module(), "FrameContext");
    let planes = members
        .iter()
        .find(|(m, _)| m == "coarse_planes")
        .unwrap()
        .1;
    assert_eq!(f32_at(&bytes, planes + 5 * 16), 10.0);
    let test = CoarseCull {
        planes: std::array::from_fn(|i| Vec4::splat(1.0 + i as f32)),
        inflation: 7.0,
        slack: 8.0,
    };
    let bytes = storage_bytes(&[test, test]);
    let (_, span) = wgsl_struct(&module(), "CoarseTest");
    assert_eq!(bytes.len(), 2 * span as usize, "CoarseTest stride");
    check_uniform(
        "CoarseTest",
        &bytes[..span as usize],
        &[("planes", 1.0), ("inflation", 7.0), ("slack", 8.0)],
    );
    let (members, _) = wgsl_struct(&module(), "CoarseTest");
    assert_eq!(f32_at(&bytes, members[0].1 + 5 * 16), 6.0);
    let params = CullParams {
        instance_count: 3,
        mesh_count: 5,
        max_groups: 7,
        lod_levels: 4,
        visibility_words: 9,
        pyramid_offset: 128,
        pyramid_stride: 29,
        tile_offset: 31,
        tile_stride: 37,
        bin_count: 11,
        first_blend_bin: 13,
        blend_first: 17,
        position_room: 19,
        member_sums: 23,
    };
    check_uniform(
        "CullParams",
        &uniform_bytes(&params),
        &[
            ("instance_count", f32::from_bits(3)),
            ("mesh_count", f32::from_bits(5)),
            ("max_groups", f32::from_bits(7)),
            ("lod_levels", f32::from_bits(4)),
            ("visibility_words", f32::from_bits(9)),
            ("pyramid_offset", f32::from_bits(128)),
            ("pyramid_stride", f32::from_bits(29)),
            ("tile_offset", f32::from_bits(31)),
            ("tile_stride", f32::from_bits(37)),
            ("bin_count", f32::from_bits(11)),
            ("first_blend_bin", f32::from_bits(13)),
            ("blend_first", f32::from_bits(17)),
            ("position_room", f32::from_bits(19)),
            ("member_sums", f32::from_bits(23)),
        ],
    );
}

#[test]
fn rig_records_match_wgsl() {
    let view = |k: f32| RigView {
        planes: std::array::from_fn(|i| Vec4::splat(k + i as f32)),
        position: Vec3::splat(k + 10.0),
        split_keep: 2,
        sort_origin: Vec3::splat(k + 11.0),
        split_distance: k + 12.0,
        instances_per_object: 4,
        visible_at: 5,
        draws_at: 6,
        counts_at: 7,
        cull_slot: 8,
        early: 1,
        hidden: 9,
        block: CoarseCull {
            planes: std::array::from_fn(|i| Vec4::splat(k + 20.0 + i as f32)),
            inflation: k + 30.0,
            slack: k + 31.0,
        },
    };
    check_uniform(
        "RigView",
        &uniform_bytes(&view(1.0)),
        &[
            ("planes", 1.0),
            ("position", 11.0),
            ("split_keep", f32::from_bits(2)),
            ("sort_origin", 12.0),
            ("split_distance", 13.0),
            ("instances_per_object", f32::from_bits(4)),
            ("visible_at", f32::from_bits(5)),
            ("draws_at", f32::from_bits(6)),
            ("counts_at", f32::from_bits(7)),
            ("cull_slot", f32::from_bits(8)),
            ("early", f32::from_bits(1)),
            ("hidden", f32::from_bits(9)),
            ("block", 21.0),
        ],
    );
    let (members, _) = wgsl_struct(&module(), "RigView");
    let block = members.iter().find(|(m, _)| m == "block").unwrap().1;
    let (test, _) = wgsl_struct(&module(), "CoarseTest");
    let inflation = test.iter().find(|(m, _)| m == "inflation").unwrap().1;
    assert_eq!(f32_at(&uniform_bytes(&view(1.0)), block + inflation), 31.0);
    // Three members of MAX_RIG_VIEWS: the third's planes a whole RigView after the
    // second's, the count after every record.
    let views: Vec<RigView> = (0..3).map(|k| view(100.0 * k as f32)).collect();
    let test = |k: f32| RigOcclusion {
        view_from_world: [Mat4::from_cols_array(&[k; 16]), Mat4::IDENTITY],
        clip_from_view: [Mat4::IDENTITY, Mat4::from_cols_array(&[k + 1.0; 16])],
        resolution: Vec2::new(k + 2.0, k + 3.0),
        margin_px: k + 4.0,
        views: 2,
    };
    check_uniform(
        "RigOcclusion",
        &uniform_bytes(&test(1.0)),
        &[
            ("view_from_world", 1.0),
            ("clip_from_view", 1.0),
            ("resolution", 3.0),
            ("margin_px", 5.0),
            ("views", f32::from_bits(2)),
        ],
    );
    let mut set = RigCull::new(&views);
    set.occlusion[2] = test(700.0);
    let bytes = uniform_bytes(&set);
    check_uniform(
        "RigCull",
        &bytes,
        &[
            ("views", 0.0),
            ("occlusion", 1.0),
            ("members", f32::from_bits(3)),
        ],
    );
    let (_, span) = wgsl_struct(&module(), "RigView");
    assert_eq!(f32_at(&bytes, 2 * span + 5 * 16), 205.0);
    assert_eq!(f32_at(&bytes, (MAX_RIG_VIEWS as u32 - 1) * span), 0.0);
    // Where a member's record and test are written: naga's offsets.
    let (set_members, _) = wgsl_struct(&module(), "RigCull");
    let (tests, test_span) = wgsl_struct(&module(), "RigOcclusion");
    let occlusion = set_members
        .iter()
        .find(|(m, _)| m == "occlusion")
        .unwrap()
        .1;
    let margin = tests.iter().find(|(m, _)| m == "margin_px").unwrap().1;
    let (view_at, test_at) = RigCull::offsets(2);
    assert_eq!(
        (view_at, test_at),
        ((2 * span) as u64, (occlusion + 2 * test_span) as u64)
    );
    assert_eq!(f32_at(&bytes, test_at as u32 + margin), 704.0);
}

/// The tile marking pass's display records (encase) and list, and the tile pass's grid
/// (bytemuck), against naga's offsets in their own modules.
#[test]
fn tile_records_match_wgsl() {
    let mark = parse("keep_mark", &keep_mark_source(&Windows::WHOLE));
    let display = |k: f32| TileDisplay {
        eyes: RigOcclusion {
            view_from_world: [Mat4::from_cols_array(&[k; 16]), Mat4::IDENTITY],
            clip_from_view: [Mat4::IDENTITY, Mat4::IDENTITY],
            resolution: Vec2::new(k + 2.0, k + 3.0),
            margin_px: k + 4.0,
            views: 2,
        },
        planes: std::array::from_fn(|i| Vec4::splat(k + 10.0 + i as f32)),
        base: 77,
    };
    let bytes = storage_bytes(&[display(1.0), display(500.0)]);
    let (members, span) = wgsl_struct(&mark, "TileDisplay");
    assert_eq!(bytes.len(), 2 * span as usize, "TileDisplay stride");
    let names: Vec<&str> = members.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["eyes", "planes", "base"]);
    let at = |member: usize, record: u32| f32_at(&bytes, record * span + members[member].1);
    assert_eq!(
        (at(0, 0), at(1, 0), at(2, 0)),
        (1.0, 11.0, f32::from_bits(77))
    );
    assert_eq!((at(0, 1), at(1, 1)), (500.0, 510.0));
    let (marks, _) = wgsl_struct(&mark, "Marks");
    assert_eq!(marks, [("count".to_string(), 0), ("list".to_string(), 4)]);
    let clear = keep_tiles_source(wgpu::TextureFormat::Rgba8UnormSrgb, wgpu::Color::BLACK);
    let (members, _) = wgsl_struct(&parse("keep_tiles", &clear), "TileWords");
    let want = [
        ("cols", offset_of!(TileGrid, cols)),
        ("width", offset_of!(TileGrid, width)),
        ("height", offset_of!(TileGrid, height)),
        ("words", size_of::<TileGrid>()),
    ];
    let want: Vec<(String, u32)> = want.map(|(n, o)| (n.to_string(), o as u32)).into();
    assert_eq!(members, want);
    // The listing's count is the tile pass's indirect draw.
    let (members, span) = wgsl_struct(&parse("keep_list", &keep_list_source()), "TileDraw");
    use wgpu::util::DrawIndirectArgs as Args;
    let want = [
        ("vertex_count", offset_of!(Args, vertex_count)),
        ("instance_count", offset_of!(Args, instance_count)),
        ("first_vertex", offset_of!(Args, first_vertex)),
        ("first_instance", offset_of!(Args, first_instance)),
    ];
    let want: Vec<(String, u32)> = want.map(|(n, o)| (n.to_string(), o as u32)).into();
    assert_eq!((members, span as usize), (want, size_of::<Args>()));
}

#[test]
fn hidden_areas_match_wgsl() {
    let region = |k: f32| HiddenRegion {
        planes: std::array::from_fn(|i| Vec4::splat(k + i as f32)),
    };
    let view = |k: f32| HiddenView {
        regions: std::array::from_fn(|r| region(k + 10.0 * r as f32)),
        count: 7,
    };
    // Four views: a stereo pair, or two frames' pairs in one submission.
    let area = HiddenArea {
        views: [view(1.0), view(1000.0), view(2000.0), view(3000.0)],
        count: 4,
    };
    let bytes = storage_bytes(&[area, area]);
    let (_, span) = wgsl_struct(&module(), "HiddenArea");
    assert_eq!(bytes.len(), 2 * span as usize, "HiddenArea stride");
    check_uniform(
        "HiddenArea",
        &bytes[..span as usize],
        &[("views", 1.0), ("count", f32::from_bits(4))],
    );
    let (_, view_span) = wgsl_struct(&module(), "HiddenView");
    check_uniform(
        "HiddenView",
        &bytes[view_span as usize..2 * view_span as usize],
        &[("regions", 1000.0), ("count", f32::from_bits(7))],
    );
    check_uniform(
        "HiddenView",
        &bytes[3 * view_span as usize..4 * view_span as usize],
        &[("regions", 3000.0), ("count", f32::from_bits(7))],
    );
    // Region 3's third plane: three regions of three vec4s, then two.
    assert_eq!(f32_at(&bytes, (3 * 3 + 2) * 16), 33.0);
    let last = (MAX_HIDDEN_REGIONS as u32 - 1) * 3 * 16;
    assert_eq!(
        f32_at(&bytes, last),
        1.0 + 10.0 * (MAX_HIDDEN_REGIONS - 1) as f32
    );
}

/// Every pipeline the crate builds, with its source and its bind groups' lists in
/// group order.
fn pipelines_and_their_lists() -> Vec<(String, String, Vec<Vec<Binding>>)> {
    let whole = &Windows::WHOLE;
    let lists = |l: &[&[Binding]]| l.iter().map(|g| g.to_vec()).collect::<Vec<_>>();
    let cull_lists = |label: &str| {
        if label.starts_with("stereocull.coarse") {
            lists(&[&CULL_BINDINGS, &COARSE_BINDINGS])
        } else if label.contains(".candidates") {
            lists(&[&CULL_BINDINGS, &CANDIDATE_BINDINGS])
        } else {
            lists(&[&CULL_BINDINGS])
        }
    };
    let draw = lists(&[&DRAW_BINDINGS, &MATERIAL_BINDINGS, &SHADOW_MAP_BINDINGS]);
    let keyed = |(p, k): (CullPass, CullKey)| {
        let label = k.phase.label(&p.label(k.over_candidates));
        (label, p.source(k, whole))
    };
    let mut out: Vec<_> = (CullPass::variants().into_iter())
        .map(|(p, c)| (p.label(c), p.source(CullKey::over(c), whole)))
        .chain(CullPass::occlusion_variants().into_iter().map(keyed))
        .chain(
            (CullPass::bare_variants().into_iter().map(keyed))
                .map(|(label, source)| (format!("{label}.bare"), source)),
        )
        .map(|(label, source)| {
            let groups = cull_lists(&label);
            (label, source, groups)
        })
        .collect();
    let motion = lists(&[
        &DRAW_BINDINGS,
        &MATERIAL_BINDINGS,
        &SHADOW_MAP_BINDINGS,
        &MOTION_BINDINGS,
    ]);
    out.extend(
        (DrawKey::ALL.iter().flat_map(|k| k.alpha_variants())).map(|k| {
            let groups = if k.motion || k.first_pose {
                &motion
            } else {
                &draw
            };
            (k.label(), k.source_with(None, whole), groups.clone())
        }),
    );
    out.extend(
        [EditKind::Places, EditKind::Moves, EditKind::Records].map(|kind| {
            let label = format!("stereocull.scatter.{kind:?}");
            (
                label,
                scatter_source(whole, kind),
                lists(&[&SCATTER_BINDINGS]),
            )
        }),
    );
    let others: [(&str, String, Vec<Vec<Binding>>); 10] = [
        (
            "keep_mark",
            keep_mark_source(whole),
            lists(&[&MARK_TILES_BINDINGS]),
        ),
        (
            "keep_list",
            keep_list_source(),
            lists(&[&KEEP_LIST_BINDINGS]),
        ),
        ("shadow", shadow_source(whole), lists(&[&DRAW_BINDINGS])),
        (
            "shadow.cutout",
            shadow_cutout_source(whole),
            lists(&[&DRAW_BINDINGS, &MATERIAL_BINDINGS]),
        ),
        (
            "far_composite",
            far_composite_source(),
            lists(&[&FAR_COMPOSITE_BINDINGS]),
        ),
        (
            "foveated_composite",
            foveated_composite_source(),
            lists(&[&FOVEATED_COMPOSITE_BINDINGS]),
        ),
        ("skin", skin_source(), lists(&[&SKIN_BINDINGS])),
        (
            "keep_tiles",
            keep_tiles_source(wgpu::TextureFormat::Rgba8UnormSrgb, wgpu::Color::BLACK),
            lists(&[&KEEP_TILES_BINDINGS]),
        ),
        ("pose", pose_source(), lists(&[&POSE_BINDINGS])),
        (
            "depth_resolve",
            depth_resolve_source(),
            lists(&[&DEPTH_RESOLVE_BINDINGS]),
        ),
    ];
    out.extend(others.map(|(l, s, g)| (format!("stereocull.{l}"), s, g)));
    out.extend(
        [(1, false), (4, false), (1, true)]
            .into_iter()
            .flat_map(|v| [1, PYRAMID_SET_DEPTHS].map(|depths| (v, depths)))
            .map(|((samples, layered), depths)| {
                let label = format!("stereocull.occlusion_pyramid.x{samples}.{layered}.{depths}");
                let list = pyramid_bindings(samples, layered, depths);
                let source = pyramid_source(samples, layered, depths);
                (label, source, vec![list])
            }),
    );
    out
}

/// Whether WGSL global `var` of `module` is what `want` declares: a buffer in its
/// address space and access, a texture of its dimension, sample type and sampling, a
/// sampler of its kind.
fn global_is(module: &Module, var: &naga::GlobalVariable, want: &Binding) -> bool {
    use naga::{AddressSpace, ImageClass, ImageDimension, ScalarKind, StorageAccess};
    let inner = &module.types[var.ty].inner;
    match (want.access, var.space, inner) {
        (Access::Uniform | Access::UniformDynamic, AddressSpace::Uniform, _) => true,
        (Access::StorageRead, AddressSpace::Storage { access }, _) => {
            !access.contains(StorageAccess::STORE)
        }
        (Access::StorageReadWrite, AddressSpace::Storage { access }, _) => {
            access.contains(StorageAccess::STORE)
        }
        (
            Access::Texture(kind),
            AddressSpace::Handle,
            TypeInner::Image {
                dim,
                arrayed,
                class,
            },
        ) => {
            let class_matches = match (kind.sample, class) {
                (wgpu::TextureSampleType::Depth, ImageClass::Depth { multi }) => {
                    *multi == kind.multisampled
                }
                (wgpu::TextureSampleType::Float { .. }, ImageClass::Sampled { kind: k, multi }) => {
                    *k == ScalarKind::Float && *multi == kind.multisampled
                }
                _ => false,
            };
            let array = kind.dimension == wgpu::TextureViewDimension::D2Array;
            *dim == ImageDimension::D2 && *arrayed == array && class_matches
        }
        (Access::Sampler(ty), AddressSpace::Handle, TypeInner::Sampler { comparison }) => {
            *comparison == (ty == wgpu::SamplerBindingType::Comparison)
        }
        _ => false,
    }
}

/// Every pipeline declares exactly its bind groups' lists (whose layouts are made from
/// the same lists): each global at group `g`, binding `i` is list `g`'s `i`th entry,
/// with its name and kind (buffer space and access, texture, sampler), and every entry
/// of every list is declared.
#[test]
fn every_pipeline_binds_what_its_lists_declare() {
    let pipelines = pipelines_and_their_lists();
    assert!(pipelines.len() > 40, "{}", pipelines.len());
    for (label, source, lists) in pipelines {
        let module = parse(&label, &source);
        let mut seen = Vec::new();
        for (_, var) in module.global_variables.iter() {
            let Some(binding) = &var.binding else {
                continue;
            };
            let name = var.name.as_deref().unwrap_or_default();
            let want = (lists.get(binding.group as usize))
                .and_then(|list| list.get(binding.binding as usize))
                .unwrap_or_else(|| panic!("{label}: {name} at {binding:?} is in no list"));
            assert_eq!(name, want.name, "{label}: {binding:?}");
            assert!(
                global_is(&module, var, want),
                "{label}: {name} is not {want:?}"
            );
            seen.push((binding.group, binding.binding));
        }
        seen.sort();
        let all: Vec<(u32, u32)> = (lists.iter().enumerate())
            .flat_map(|(g, list)| (0..list.len() as u32).map(move |i| (g as u32, i)))
            .collect();
        assert_eq!(seen, all, "{label}: bindings");
    }
}

/// No WGSL file declares a binding: every one comes from a list in
/// `src/shaders/bindings.rs`, which the layouts are made from too.
#[test]
fn no_wgsl_file_declares_its_own_bindings() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("wgsl");
    let mut files = 0;
    for sub in [dir.clone(), dir.join("shared")] {
        for entry in std::fs::read_dir(sub).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "wgsl") {
                let text = std::fs::read_to_string(&path).unwrap();
                assert!(
                    !text.contains("@group("),
                    "{} declares a binding",
                    path.display()
                );
                files += 1;
            }
        }
    }
    assert!(files > 30, "{files}");
}

/// The vertex buffer: each attribute's location, format and offset match `VertexInput`
/// in WGSL and the Rust `Vertex`, and the stride is the Rust size.
#[test]
fn vertex_layout_matches_wgsl() {
    let module = parse("draw", &DrawKey::ALL[0].source());
    let ty = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some("VertexInput"))
        .expect("VertexInput in WGSL")
        .1;
    let TypeInner::Struct { members, .. } = &ty.inner else {
        panic!("VertexInput is not a struct")
    };
    let rust = [
        ("position", offset_of!(Vertex, position)),
        ("normal", offset_of!(Vertex, normal)),
        ("uv", offset_of!(Vertex, uv)),
        ("material", offset_of!(Vertex, material)),
        ("tangent", offset_of!(Vertex, tangent)),
        ("uv1", offset_of!(Vertex, uv1)),
    ];
    assert_eq!(members.len(), rust.len());
    for ((member, (name, offset)), attribute) in members.iter().zip(rust).zip(VERTEX_ATTRIBUTES) {
        assert_eq!(member.name.as_deref(), Some(name));
        let Some(naga::Binding::Location { location, .. }) = member.binding else {
            panic!("{name} has no location")
        };
        assert_eq!(location, attribute.shader_location, "{name}");
        assert_eq!(attribute.offset as usize, offset, "{name} offset");
        let member_ty = &module.types[member.ty].inner;
        let wgsl_format = match member_ty {
            TypeInner::Vector {
                size: naga::VectorSize::Tri,
                scalar: naga::Scalar::F32,
            } => wgpu::VertexFormat::Float32x3,
            TypeInner::Vector {
                size: naga::VectorSize::Bi,
                scalar: naga::Scalar::F32,
            } => wgpu::VertexFormat::Float32x2,
            TypeInner::Scalar(naga::Scalar::U32) => wgpu::VertexFormat::Uint32,
            // Four bytes the vertex stage reads as -1..=1 ([i8; 4] in Rust).
            TypeInner::Vector {
                size: naga::VectorSize::Quad,
                scalar: naga::Scalar::F32,
            } if size_of_val(&Vertex::new(Default::default(), Default::default()).tangent) == 4 => {
                wgpu::VertexFormat::Snorm8x4
            }
            other => panic!("{name}: {other:?}"),
        };
        assert_eq!(attribute.format, wgsl_format, "{name}");
    }
    assert_eq!(size_of::<Vertex>(), 48);
}

/// Past one binding, a windowed array takes one binding per window, in order, after the
/// list's other bindings: the scatter pass with 5M instances and 80 MiB bindings binds
/// its edits and positions, five windows of records and two of spheres.
#[test]
fn windowed_arrays_take_one_binding_per_window() {
    let split = Windows::new(5 << 20, 80 << 20);
    assert_eq!(
        split.instances,
        Window {
            count: 5,
            shift: 20
        }
    );
    assert_eq!(
        split.spheres,
        Window {
            count: 2,
            shift: 22
        }
    );
    assert_eq!(Windows::new(1000, 64 << 20), Windows::WHOLE);
    let module = parse("scatter", &scatter_source(&split, EditKind::Moves));
    let mut bound: Vec<(u32, String)> = module
        .global_variables
        .iter()
        .filter_map(|(_, v)| Some((v.binding.as_ref()?.binding, v.name.clone()?)))
        .collect();
    bound.sort();
    let names: Vec<&str> = bound.iter().map(|(_, n)| n.as_str()).collect();
    assert_eq!(
        names,
        [
            "edits",
            "positions",
            "order",
            "visibility",
            "mesh_bounds",
            "instances_0",
            "instances_1",
            "instances_2",
            "instances_3",
            "instances_4",
            "spheres_0",
            "spheres_1"
        ]
    );
    assert!(bound.iter().enumerate().all(|(i, (b, _))| *b == i as u32));
}

/// The skinning pass's rest vertex and joint matrices as WGSL declares them, and the
/// words of `scene::Vertex` it writes (position, normal, tangent).
#[test]
fn skin_records_match_wgsl() {
    use stereocull::scene::Vertex;
    use stereocull::skin::{JointMatrix, SkinVertex};
    let source = stereocull::shaders::skin_source();
    let module = parse("skin", &source);
    let (members, span) = wgsl_struct(&module, "SkinVertex");
    assert_eq!(span as usize, size_of::<SkinVertex>(), "SkinVertex size");
    let found: Vec<(&str, usize)> = members
        .iter()
        .map(|(n, o)| (n.as_str(), *o as usize))
        .collect();
    let rust = [
        ("position", offset_of!(SkinVertex, position)),
        ("normal", offset_of!(SkinVertex, normal)),
        ("tangent", offset_of!(SkinVertex, tangent)),
        ("joints", offset_of!(SkinVertex, joints)),
        ("weights", offset_of!(SkinVertex, weights)),
        ("joint_base", offset_of!(SkinVertex, joint_base)),
        ("destination", offset_of!(SkinVertex, destination)),
    ];
    assert_eq!(found, rust, "SkinVertex members and offsets");
    assert_eq!(size_of::<JointMatrix>(), 48, "three vec4 rows");
    let word = |name: &str| {
        let declared = format!("const {name}: u32 = ");
        let at = source.find(&declared).unwrap() + declared.len();
        source[at..]
            .split('u')
            .next()
            .unwrap()
            .parse::<usize>()
            .unwrap()
            * 4
    };
    assert_eq!(word("VERTEX_WORDS"), size_of::<Vertex>());
    assert_eq!(word("TANGENT_WORD"), offset_of!(Vertex, tangent));
    assert_eq!(
        (offset_of!(Vertex, position), offset_of!(Vertex, normal)),
        (0, 12)
    );
}

/// The pose pass's tables as `wgsl/pose.wgsl` declares them.
#[test]
fn pose_records_match_wgsl() {
    use stereocull::pose_tables::{
        PoseChannelRecord, PoseNodeRecord, PoseParamsRecord, PoseTargetRecord, SkinJointRecord,
    };
    let module = parse("pose", &stereocull::shaders::pose_source());
    let check = |name: &str, size: usize, rust: &[(&str, usize)]| {
        let (members, span) = wgsl_struct(&module, name);
        assert_eq!(span as usize, size, "{name} size");
        let found: Vec<(&str, usize)> = (members.iter())
            .map(|(n, o)| (n.as_str(), *o as usize))
            .collect();
        assert_eq!(found, rust, "{name} members and offsets");
    };
    check(
        "PoseNode",
        size_of::<PoseNodeRecord>(),
        &[
            ("parent", offset_of!(PoseNodeRecord, parent)),
            ("first_channel", offset_of!(PoseNodeRecord, first_channel)),
            ("channels", offset_of!(PoseNodeRecord, channels)),
            ("unused", offset_of!(PoseNodeRecord, unused)),
            ("root_from", offset_of!(PoseNodeRecord, root_from)),
            ("translation", offset_of!(PoseNodeRecord, translation)),
            ("rotation", offset_of!(PoseNodeRecord, rotation)),
            ("scale", offset_of!(PoseNodeRecord, scale)),
        ],
    );
    check(
        "PoseParams",
        size_of::<PoseParamsRecord>(),
        &[
            ("node_row", offset_of!(PoseParamsRecord, node_row)),
            ("target_row", offset_of!(PoseParamsRecord, target_row)),
            ("nodes", offset_of!(PoseParamsRecord, nodes)),
            ("targets", offset_of!(PoseParamsRecord, targets)),
            ("ahead", offset_of!(PoseParamsRecord, ahead)),
        ],
    );
    check(
        "PoseChannel",
        size_of::<PoseChannelRecord>(),
        &[
            ("property", offset_of!(PoseChannelRecord, property)),
            (
                "interpolation",
                offset_of!(PoseChannelRecord, interpolation),
            ),
            ("first_key", offset_of!(PoseChannelRecord, first_key)),
            ("keys", offset_of!(PoseChannelRecord, keys)),
            ("first_value", offset_of!(PoseChannelRecord, first_value)),
            ("offset", offset_of!(PoseChannelRecord, offset)),
            ("speed", offset_of!(PoseChannelRecord, speed)),
            ("duration", offset_of!(PoseChannelRecord, duration)),
        ],
    );
    check(
        "PoseTarget",
        size_of::<PoseTargetRecord>(),
        &[
            ("slot", offset_of!(PoseTargetRecord, slot)),
            ("node", offset_of!(PoseTargetRecord, node)),
            ("joints", offset_of!(PoseTargetRecord, joints)),
            ("joint_base", offset_of!(PoseTargetRecord, joint_base)),
            ("bounds", offset_of!(PoseTargetRecord, bounds)),
            (
                "node_from_local",
                offset_of!(PoseTargetRecord, node_from_local),
            ),
            ("orbit", offset_of!(PoseTargetRecord, orbit)),
            ("bob", offset_of!(PoseTargetRecord, bob)),
            ("unused", offset_of!(PoseTargetRecord, unused)),
        ],
    );
    check(
        "SkinJoint",
        size_of::<SkinJointRecord>(),
        &[
            ("node", offset_of!(SkinJointRecord, node)),
            ("unused", offset_of!(SkinJointRecord, unused)),
            ("inverse_bind", offset_of!(SkinJointRecord, inverse_bind)),
            ("bounds", offset_of!(SkinJointRecord, bounds)),
        ],
    );
}

#[test]
fn pyramid_sets_match_wgsl() {
    let module = parse("pyramid", &pyramid_source(1, false, PYRAMID_SET_DEPTHS));
    let slice = |k: u32| PyramidSlice {
        origin: UVec2::new(k, k + 1),
        size: UVec2::new(k + 2, k + 3),
        base: k + 4,
        eye: k + 5,
        depth: k + 6,
    };
    let slices: Vec<PyramidSlice> = (0..3).map(|k| slice(10 * k + 1)).collect();
    let bytes = uniform_bytes(&PyramidSet::new(&slices));
    let (set, set_span) = wgsl_struct(&module, "PyramidSet");
    assert_eq!(bytes.len(), set_span as usize, "PyramidSet size");
    let (fields, span) = wgsl_struct(&module, "PyramidSlice");
    let offset =
        |members: &[(String, u32)], name: &str| members.iter().find(|(m, _)| m == name).unwrap().1;
    let u32_at = |o: u32| u32::from_le_bytes(bytes[o as usize..o as usize + 4].try_into().unwrap());
    // The third slice (k = 21), a whole stride after the second.
    let third = offset(&set, "slices") + 2 * span;
    let read: Vec<u32> = ["origin", "size", "base", "eye", "depth"]
        .iter()
        .map(|f| u32_at(third + offset(&fields, f)))
        .collect();
    assert_eq!(read, [21, 23, 25, 26, 27]);
    assert_eq!(u32_at(offset(&set, "count")), 3);
}
