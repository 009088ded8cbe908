//! Shader checks that need no GPU: every variant validates with naga, and every struct
//! the GPU reads has the same layout in Rust and in WGSL (offsets read by naga).

use std::mem::{offset_of, size_of};

use glam::{Mat4, Vec2, Vec3, Vec4};
use naga::{Module, TypeInner};
use stereocull::contexts::{DisplayContext, EyeContext, FrameContext, uniform_bytes};
use stereocull::records::{DrawArgs, InstanceRecord, MeshRecord};
use stereocull::shaders::{CullPass, all_sources};

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
    parse("cull", &CullPass::Cull.source())
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
            ("reserved", offset_of!(InstanceRecord, reserved)),
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
    assert_eq!(size_of::<DrawArgs>(), 20);
    assert_eq!(size_of::<InstanceRecord>(), 64);
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
        position: Vec3::new(seed + 4.0, seed + 4.1, seed + 4.2),
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
            ("position", 14.0),
        ],
    );
    let d = DisplayContext {
        view_from_world: distinct_mat(1.0),
        world_from_view: distinct_mat(2.0),
        clip_from_view: distinct_mat(3.0),
        view_from_clip: distinct_mat(4.0),
        eye: [eye(10.0), eye(20.0)],
        position: Vec3::new(5.0, 5.1, 5.2),
        resolution: Vec2::new(6.0, 6.1),
        planes: std::array::from_fn(|i| Vec4::splat(7.0 + i as f32)),
        views: 2,
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
            ("views", f32::from_bits(2)),
        ],
    );
    // The second eye sits one EyeContext span after the first, and the last plane five
    // vec4s after the first.
    let (members, _) = wgsl_struct(&module(), "DisplayContext");
    let at = |n: &str| members.iter().find(|(m, _)| m == n).unwrap().1;
    let (_, eye_span) = wgsl_struct(&module(), "EyeContext");
    assert_eq!(f32_at(&bytes, at("eye") + eye_span), 20.0);
    assert_eq!(f32_at(&bytes, at("eye") + eye_span + 4 * 64), 24.0);
    assert_eq!(f32_at(&bytes, at("planes") + 5 * 16), 12.0);

    let f = FrameContext {
        view_from_world: distinct_mat(1.0),
        world_from_view: distinct_mat(2.0),
        viewer_position: Vec3::new(3.0, 3.1, 3.2),
        viewer_direction: Vec3::new(4.0, 4.1, 4.2),
        time: 5.0,
    };
    check_uniform(
        "FrameContext",
        &uniform_bytes(&f),
        &[
            ("view_from_world", 1.0),
            ("world_from_view", 2.0),
            ("viewer_position", 3.0),
            ("viewer_direction", 4.0),
            ("time", 5.0),
        ],
    );
}
