//! glTF import on the shared Khronos samples (written by nobody here), hostile files,
//! and EXT_mesh_gpu_instancing on a small file written by the test.

// Expected values are copied verbatim from the files' JSON, digits and all.
#![allow(clippy::excessive_precision)]

use std::path::{Path, PathBuf};

use glam::{Affine3A, Mat4, Quat, Vec3, Vec4};
use stereocull::Error;
use stereocull::scene::{AlphaMode, Scene, Shading};
use stereocull::scene_spec;

mod support;

fn sample(name: &str) -> PathBuf {
    support::gltf_sample(name, "glb")
}

fn load(name: &str) -> Scene {
    let path = sample(name);
    scene_spec::load(path.to_str().unwrap()).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn assert_close(a: Mat4, b: Mat4, what: &str) {
    assert!(a.abs_diff_eq(b, 1e-6), "{what}:\n{a}\n!=\n{b}");
}

#[test]
fn box_root_matrix_reaches_the_mesh() {
    let s = load("Box");
    assert_eq!((s.instances.len(), s.meshes.len()), (1, 1));
    assert_eq!(s.meshes[0].index_count, 36, "12 triangles");
    // Node 0's matrix (Y-up to Z-up), column-major in the file.
    let root = Mat4::from_cols_array(&[
        1., 0., 0., 0., 0., 0., -1., 0., 0., 1., 0., 0., 0., 0., 0., 1.,
    ]);
    assert_close(
        Mat4::from(s.instances[0].world_from_local),
        root,
        "Box world transform",
    );
    assert_eq!(s.instances[0].color, Vec4::new(0.8, 0.0, 0.0, 1.0));
}

#[test]
fn box_animated_follows_scene_node_order_and_parents() {
    let s = load("BoxAnimated");
    assert_eq!((s.instances.len(), s.meshes.len()), (2, 2));
    // The scene lists node 3 (outer_box) before node 0 (the chain down to inner_box).
    assert!(
        s.meshes[s.instances[0].mesh as usize]
            .name
            .starts_with("outer_box")
    );
    assert!(
        s.meshes[s.instances[1].mesh as usize]
            .name
            .starts_with("inner_box")
    );
    let triangles: u32 = s.meshes.iter().map(|m| m.index_count / 3).sum();
    assert_eq!(triangles, 254);
}

#[test]
fn milk_truck_shares_its_wheel_mesh_between_two_nodes() {
    let s = load("CesiumMilkTruck");
    assert_eq!(s.instances.len(), 5, "3 body primitives + 2 wheel nodes");
    assert_eq!(
        s.meshes.len(),
        4,
        "one record per primitive; the wheels share one"
    );
    let meshes: Vec<u32> = s.instances.iter().map(|i| i.mesh).collect();
    assert_eq!(meshes, [0, 1, 2, 3, 3]);
    // Node 0's children are [3, 1]: the wheel under node 3 (x = +1.43) comes first.
    let wheel_rotation = Quat::from_xyzw(-0.0, -0.0, 0.08848590403795242, -0.9960774183273315);
    for (id, x) in [(3, 1.432669997215271), (4, -1.352329969406128)] {
        let want = Affine3A::from_rotation_translation(
            wheel_rotation,
            Vec3::new(x, 0.4277220070362091, -2.98022992950564e-08),
        );
        assert_close(
            Mat4::from(s.instances[id].world_from_local),
            Mat4::from(want),
            "wheel",
        );
    }
    let triangles: u32 = s
        .instances
        .iter()
        .map(|i| s.meshes[i.mesh as usize].index_count / 3)
        .sum();
    assert_eq!(triangles, 3624);
    // Materials without a baseColorFactor are white.
    assert_eq!(
        s.instances[1].color,
        Vec4::new(0.0, 0.04050629958510399, 0.021240700036287308, 1.0)
    );
    assert_eq!(s.instances[3].color, Vec4::ONE);
}

#[test]
fn alpha_blend_mode_test_has_nine_instances() {
    let s = load("AlphaBlendModeTest");
    assert_eq!((s.instances.len(), s.meshes.len()), (9, 9));
}

fn scene_error(path: &Path) -> String {
    match scene_spec::load(path.to_str().unwrap()) {
        Err(e @ Error::Scene { .. }) => e.to_string(),
        Err(other) => panic!("{}: wrong error kind: {other}", path.display()),
        Ok(_) => panic!("{}: loaded a broken file", path.display()),
    }
}

#[test]
fn truncated_garbage_and_missing_buffers_give_typed_errors() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = std::fs::read(sample("CesiumMilkTruck")).unwrap();
    for cut in [10, 100, bytes.len() / 2, bytes.len() - 1] {
        let p = dir.path().join(format!("cut{cut}.glb"));
        std::fs::write(&p, &bytes[..cut]).unwrap();
        let msg = scene_error(&p);
        assert!(msg.contains(&format!("cut{cut}.glb")), "{msg}");
    }
    let garbage: Vec<u8> = (0..4096u32)
        .map(|i| (i.wrapping_mul(2654435761) >> 13) as u8)
        .collect();
    let p = dir.path().join("garbage.glb");
    std::fs::write(&p, garbage).unwrap();
    scene_error(&p);

    let p = dir.path().join("missing.gltf");
    std::fs::write(&p, gltf_json(r#""uri": "nowhere.bin""#, "")).unwrap();
    let msg = scene_error(&p);
    assert!(msg.contains("buffer"), "{msg}");

    let p = dir.path().join("missing-image.gltf");
    std::fs::write(dir.path().join("tri.bin"), [0u8; 72]).unwrap();
    let json = gltf_json(r#""uri": "tri.bin""#, "").replacen(
        "\"scene\": 0,",
        "\"scene\": 0, \"images\": [{\"uri\": \"gone.png\"}],",
        1,
    );
    std::fs::write(&p, json).unwrap();
    let msg = scene_error(&p);
    assert!(msg.contains("image 0") && msg.contains("gone.png"), "{msg}");

    let msg = scene_error(&dir.path().join("no-such-file.glb"));
    assert!(msg.contains("no-such-file.glb"), "{msg}");
}

/// A glTF with one triangle mesh and one buffer (`buffer` is its source), used by node 0
/// (with `node_extra` spliced into it) and node 1 (plain, translated).
fn gltf_json(buffer: &str, node_extra: &str) -> String {
    format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "extensionsUsed": ["EXT_mesh_gpu_instancing"],
  "scene": 0,
  "scenes": [{{"nodes": [0, 1]}}],
  "nodes": [
    {{"mesh": 0 {node_extra}}},
    {{"mesh": 0, "translation": [0, 0, -7]}}
  ],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}}}]}}],
  "buffers": [{{{buffer}, "byteLength": 72}}],
  "bufferViews": [
    {{"buffer": 0, "byteOffset": 0, "byteLength": 36}},
    {{"buffer": 0, "byteOffset": 36, "byteLength": 36}}
  ],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
      "min": [0, 0, 0], "max": [1, 1, 0]}},
    {{"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC3"}}
  ]
}}"#
    )
}

#[test]
fn mesh_gpu_instancing_copies_follow_the_node_in_order() {
    let dir = tempfile::tempdir().unwrap();
    let floats: [f32; 18] = [
        0., 0., 0., 1., 0., 0., 0., 1., 0., // triangle
        1., 2., 3., -4., 5., 6., 7., -8., 9., // three translations
    ];
    std::fs::write(dir.path().join("tri.bin"), bytemuck::cast_slice(&floats)).unwrap();
    let p = dir.path().join("instanced.gltf");
    let ext = r#", "extensions": {"EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": 1}}}"#;
    std::fs::write(&p, gltf_json(r#""uri": "tri.bin""#, ext)).unwrap();
    let s = scene_spec::load(p.to_str().unwrap()).unwrap();
    assert_eq!(s.meshes.len(), 1);
    let t: Vec<Vec3> = s
        .instances
        .iter()
        .map(|i| i.world_from_local.translation.into())
        .collect();
    assert_eq!(
        t,
        [
            Vec3::new(1., 2., 3.),
            Vec3::new(-4., 5., 6.),
            Vec3::new(7., -8., 9.),
            Vec3::new(0., 0., -7.)
        ]
    );
    // No normals in the file: they are computed, facing +Z for this triangle.
    assert_eq!(s.vertices[0].normal, [0.0, 0.0, 1.0]);
}

/// `gltf_json` with its `nodes` and scene roots replaced, written beside `tri.bin`.
fn with_nodes(dir: &Path, nodes: serde_json::Value, roots: serde_json::Value) -> PathBuf {
    let floats: [f32; 18] = [
        0., 0., 0., 1., 0., 0., 0., 1., 0., 0., 0., 0., 0., 0., 0., 0., 0., 0.,
    ];
    std::fs::write(dir.join("tri.bin"), bytemuck::cast_slice(&floats)).unwrap();
    let mut json: serde_json::Value =
        serde_json::from_str(&gltf_json(r#""uri": "tri.bin""#, "")).unwrap();
    json["nodes"] = nodes;
    json["scenes"][0]["nodes"] = roots;
    let p = dir.join("nodes.gltf");
    std::fs::write(&p, json.to_string()).unwrap();
    p
}

#[test]
fn node_cycles_and_shared_children_are_errors_naming_the_node() {
    let dir = tempfile::tempdir().unwrap();
    let cycle = serde_json::json!([{"mesh": 0, "children": [1]}, {"mesh": 0, "children": [0]}]);
    let msg = scene_error(&with_nodes(dir.path(), cycle, serde_json::json!([0])));
    assert!(msg.contains("nodes[0] is reached twice"), "{msg}");
    let two_parents = serde_json::json!([{"children": [2]}, {"children": [2]}, {"mesh": 0}]);
    let msg = scene_error(&with_nodes(
        dir.path(),
        two_parents,
        serde_json::json!([0, 1]),
    ));
    assert!(msg.contains("nodes[2] is reached twice"), "{msg}");
}

/// Nesting deeper than recursion on a test thread's stack would survive.
#[test]
fn a_deep_node_chain_imports_with_every_translation_summed() {
    let dir = tempfile::tempdir().unwrap();
    let depth = 100_000;
    let nodes: Vec<_> = (0..depth)
        .map(|i| match i + 1 < depth {
            true => serde_json::json!({"children": [i + 1], "translation": [0.5, 0, 0]}),
            false => serde_json::json!({"mesh": 0, "translation": [0.5, 0, 0]}),
        })
        .collect();
    let p = with_nodes(dir.path(), nodes.into(), serde_json::json!([0]));
    let s = scene_spec::load(p.to_str().unwrap()).unwrap();
    assert_eq!(s.instances.len(), 1);
    let x = s.instances[0].world_from_local.translation.x;
    assert!((x - 0.5 * depth as f32).abs() < 1.0, "{x}");
}

/// The error for a file kept in `fuzz/regressions/gltf_import/`.
fn regression_error(name: &str) -> String {
    scene_error(
        &Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("fuzz/regressions/gltf_import")
            .join(name),
    )
}

/// Found by the `gltf_import` fuzz target: the gltf crate's validator panicked here.
#[test]
fn a_position_accessor_out_of_range_is_an_error_naming_the_field() {
    let msg = regression_error("position-accessor-out-of-range.glb");
    assert!(msg.contains("attributes.POSITION: accessor"), "{msg}");
}

/// Found by the `gltf_import` fuzz target: the gltf crate subtracted past zero here.
#[test]
fn a_glb_length_shorter_than_its_header_is_an_error() {
    let msg = regression_error("glb-length-below-header.glb");
    assert!(msg.contains("GLB header: length"), "{msg}");
}

/// Found by the `gltf_import` fuzz target (2026-12-02): texture coordinates of unsigned
/// ints, as wide as two floats, reached `unreachable!` in gltf's reader. The kept file is
/// BoxTextured with its TEXCOORD_0 retyped so: the finding's own PNG fails its CRC
/// outside fuzzing builds (the png crate skips the check under `cfg(fuzzing)`), which
/// would stop the import before the coordinates are read.
#[test]
fn texture_coordinates_of_unsigned_ints_are_an_error_naming_the_accessor() {
    let msg = regression_error("texcoord-of-unsigned-ints.glb");
    assert!(
        msg.contains("TEXCOORD_0: accessors[3] holds Vec2 U32"),
        "{msg}"
    );
}

/// Found by the `gltf_import` fuzz target: float indices reached `unreachable!` in gltf.
#[test]
fn float_indices_are_an_error_naming_the_accessor() {
    let msg = regression_error("float-indices.glb");
    assert!(
        msg.contains("indices: accessors[") && msg.contains("not unsigned integer SCALAR"),
        "{msg}"
    );
}

/// Found by the `gltf_import` fuzz target (a misspelled source field): the gltf crate
/// unwrapped the missing `uri` of an image without a `bufferView`.
#[test]
fn an_image_without_a_source_is_an_error_naming_the_image() {
    let msg = regression_error("image-with-mime-type-but-neither-uri-nor-buffer-view.glb");
    assert!(
        msg.contains("images[0] (\"lens\") has neither a uri nor a bufferView"),
        "{msg}"
    );
}

/// Found by the `gltf_import` fuzz target in fork mode: the gltf crate unwrapped the
/// missing `mimeType` of an image in a buffer view.
#[test]
fn an_image_in_a_buffer_view_needs_a_mime_type() {
    let msg = regression_error("image-in-buffer-view-without-mime-type.glb");
    assert!(
        msg.contains("images[0] lies in a bufferView but has no mimeType"),
        "{msg}"
    );
    let msg = regression_error("image-with-both-uri-and-buffer-view.gltf");
    assert!(
        msg.contains("images[0] has both a uri and a bufferView"),
        "{msg}"
    );
}

/// Found reading the gltf crate: `import_buffers` unwrapped the percent-decoding of a
/// relative buffer uri, which fails when the bytes are not UTF-8.
#[test]
fn a_buffer_uri_that_decodes_to_invalid_utf8_is_an_error_naming_it() {
    let msg = regression_error("buffer-uri-percent-decoding-to-invalid-utf8.gltf");
    assert!(
        msg.contains("buffers[0].uri \"mesh%FF%FE.bin\" percent-decodes"),
        "{msg}"
    );
}

/// Found reading the gltf crate: an animation's validator skips its channels' targets,
/// which `Channel::target().node()` unwraps (the skins and animations issue reads them).
#[test]
fn an_animation_channel_targeting_no_node_is_an_error() {
    let msg = regression_error("animation-channel-targeting-a-node-that-does-not-exist.gltf");
    assert!(
        msg.contains("animations[0].channels[0].target.node: node 7 does not exist"),
        "{msg}"
    );
}

/// Back faces are culled, so the import keeps what the author meant: a node that mirrors
/// gets the mesh's reversed twin (shared by every mirroring node), a `doubleSided`
/// material both windings.
#[test]
fn mirroring_nodes_and_double_sided_materials_keep_their_faces() {
    let dir = tempfile::tempdir().unwrap();
    let nodes = serde_json::json!([
        {"mesh": 0},
        {"mesh": 0, "scale": [-1, 1, 1]},
        {"mesh": 0, "scale": [1, -2, 1]},
        {"mesh": 0, "scale": [-1, -1, 1]}
    ]);
    let p = with_nodes(dir.path(), nodes, serde_json::json!([0, 1, 2, 3]));
    let s = scene_spec::load(p.to_str().unwrap()).unwrap();
    let meshes: Vec<u32> = s.instances.iter().map(|i| i.mesh).collect();
    assert_eq!(
        meshes,
        [0, 1, 1, 0],
        "the two mirroring nodes share one twin"
    );
    let triangle = |m: usize| {
        let first = s.meshes[m].first_index as usize;
        s.indices[first..first + s.meshes[m].index_count as usize].to_vec()
    };
    assert_eq!(triangle(0), [0, 1, 2]);
    assert_eq!(triangle(1), [0, 2, 1]);
    assert_eq!(s.meshes[1].base_vertex, s.meshes[0].base_vertex);

    let mut json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap();
    json["materials"] = serde_json::json!([{"doubleSided": true}]);
    json["meshes"][0]["primitives"][0]["material"] = serde_json::json!(0);
    std::fs::write(&p, json.to_string()).unwrap();
    let s = scene_spec::load(p.to_str().unwrap()).unwrap();
    assert_eq!(s.meshes.len(), 1, "double-sided: no twin needed");
    assert_eq!(s.indices, [0, 1, 2, 0, 2, 1]);
}

/// A textured material whose image does not decode, or whose primitive lacks the UV set
/// its texture reads, is an error naming the image or the set.
#[test]
fn broken_base_color_textures_are_errors_naming_what_is_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let p = with_nodes(
        dir.path(),
        serde_json::json!([{"mesh": 0}]),
        serde_json::json!([0]),
    );
    let mut json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap();
    json["images"] = serde_json::json!([{"uri": "data:image/png;base64,AAAA"}]);
    json["textures"] = serde_json::json!([{"source": 0}]);
    json["materials"] =
        serde_json::json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]);
    json["meshes"][0]["primitives"][0]["material"] = serde_json::json!(0);
    std::fs::write(&p, json.to_string()).unwrap();
    let msg = scene_error(&p);
    assert!(msg.contains("image 0"), "{msg}");

    let png = dir.path().join("red.png");
    image::RgbaImage::from_pixel(2, 2, image::Rgba([200, 10, 10, 255]))
        .save(&png)
        .unwrap();
    json["images"] = serde_json::json!([{"uri": "red.png"}]);
    std::fs::write(&p, json.to_string()).unwrap();
    let msg = scene_error(&p);
    assert!(msg.contains("TEXCOORD_0"), "{msg}");
}

/// Materials as the importer reads them: `alphaMode` with its cutoff (0.5 by default),
/// `KHR_materials_unlit` as unlit shading; each mesh of its own material, and one bin
/// per (alpha mode, shading) pair.
#[test]
fn alpha_modes_and_unlit_materials_are_read() {
    let dir = tempfile::tempdir().unwrap();
    let floats: [f32; 18] = [
        0., 0., 0., 1., 0., 0., 0., 1., 0., // triangle
        0., 0., 0., 0., 0., 0., 0., 0., 0., // unused
    ];
    std::fs::write(dir.path().join("tri.bin"), bytemuck::cast_slice(&floats)).unwrap();
    let mut json: serde_json::Value =
        serde_json::from_str(&gltf_json(r#""uri": "tri.bin""#, "")).unwrap();
    json["extensionsUsed"] = serde_json::json!(["KHR_materials_unlit"]);
    json["materials"] = serde_json::json!([
        {"name": "flat", "extensions": {"KHR_materials_unlit": {}}},
        {"name": "leaf", "alphaMode": "MASK", "alphaCutoff": 0.3},
        {"name": "fence", "alphaMode": "MASK"},
        {"name": "glass", "alphaMode": "BLEND"}
    ]);
    let primitive = |m: u32| serde_json::json!({"primitives": [{"attributes": {"POSITION": 0}, "material": m}]});
    json["meshes"] = serde_json::json!([primitive(0), primitive(1), primitive(2), primitive(3)]);
    json["nodes"] = serde_json::json!([{"mesh": 0}, {"mesh": 1}, {"mesh": 2}, {"mesh": 3}]);
    json["scenes"] = serde_json::json!([{"nodes": [0, 1, 2, 3]}]);
    let p = dir.path().join("materials.gltf");
    std::fs::write(&p, json.to_string()).unwrap();
    let s = scene_spec::load(p.to_str().unwrap()).unwrap();
    let read: Vec<(&str, AlphaMode, Shading)> = (s.materials.iter())
        .map(|m| (m.name.as_str(), m.alpha, m.shading))
        .collect();
    assert_eq!(
        read,
        [
            ("flat", AlphaMode::Opaque, Shading::Unlit),
            ("leaf", AlphaMode::Mask { cutoff: 0.3 }, Shading::Lit),
            ("fence", AlphaMode::Mask { cutoff: 0.5 }, Shading::Lit),
            ("glass", AlphaMode::Blend, Shading::Lit),
        ]
    );
    let bins = stereocull::bins::Bins::of(&s);
    // The two cutoffs share a bin: the cutoff is the material's data, not its pipeline.
    assert_eq!(bins.kinds.len(), 3, "{:?}", bins.kinds);
    assert_eq!(bins.first_blend_bin(), 2);
}

/// Found by the `gltf_import` fuzz target (2026-12-02, the run after the one above):
/// texture coordinates of three floats failed an assertion in gltf's reader. The kept
/// file is BoxTextured with its TEXCOORD_0 retyped so and its view's byteStride blanked
/// (which would otherwise be refused first).
#[test]
fn texture_coordinates_of_three_floats_are_an_error_naming_the_accessor() {
    let msg = regression_error("texcoord-of-three-floats.glb");
    assert!(msg.contains("accessors[3] holds Vec3 F32"), "{msg}");
}

/// The metallic-roughness model as the importer reads it from `AlphaBlendModeTest`
/// (written by nobody here): its floor's normal, occlusion and metallic-roughness
/// textures (the last two one image, read as data: one linear texture) beside its
/// sRGB base color, its file tangents, and the quads' factors (metallic 0, roughness
/// 0.8); glTF's defaults where a file is silent.
#[test]
fn metallic_roughness_materials_and_tangents_are_read() {
    use stereocull::scene::Encoding;
    let path = support::gltf_sample("AlphaBlendModeTest", "glb");
    let s = scene_spec::load(path.to_str().unwrap()).unwrap();
    let bed = s.materials.iter().find(|m| m.name == "MatBed").unwrap();
    let encoding = |t: Option<u32>| s.textures[t.unwrap() as usize].encoding;
    assert_eq!(encoding(bed.base_color_texture), Encoding::Srgb);
    assert_eq!(encoding(bed.normal_texture), Encoding::Linear);
    assert_eq!(bed.occlusion_texture, bed.metallic_roughness_texture);
    assert_eq!(encoding(bed.occlusion_texture), Encoding::Linear);
    assert_eq!(
        (bed.metallic, bed.roughness, bed.normal_scale),
        (1.0, 1.0, 1.0)
    );
    let quad = s.materials.iter().find(|m| m.name == "MatOpaque").unwrap();
    assert_eq!((quad.metallic, quad.roughness), (0.0, 0.8));
    assert_eq!(quad.emissive, glam::Vec3::ZERO);
    // Tangents from the file: unit (to a byte's rounding) and across the normal.
    for v in &s.vertices {
        let (t, n) = (v.tangent(), glam::Vec3::from(v.normal).normalize());
        assert!((t.truncate().length() - 1.0).abs() < 0.02, "{t}");
        assert!(t.truncate().dot(n).abs() < 0.02, "{t} across {n}");
        assert_eq!(t.w.abs(), 1.0);
    }
    // Every slot's texture must hold what the slot reads.
    let mut wrong = s.clone();
    wrong.materials[0].normal_texture = wrong.materials[0].base_color_texture;
    let gpu = support::gpu();
    let rig = stereocull::Rig::preset("hmd").unwrap();
    let options = stereocull::renderer::RendererOptions::default();
    let err = stereocull::renderer::Renderer::new(&gpu.device, &wrong, &rig, options)
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(
        err.contains("(normal map)") && err.contains("Srgb"),
        "{err}"
    );
}

/// `emissiveFactor` with `KHR_materials_emissive_strength`, the normal map's scale and
/// the occlusion's strength, and `KHR_texture_transform` as glTF composes it
/// (translation, then rotation, then scale).
#[test]
fn emission_strengths_and_texture_transforms_are_read() {
    let dir = tempfile::tempdir().unwrap();
    let floats: [f32; 18] = [
        0., 0., 0., 1., 0., 0., 0., 1., 0., // triangle
        0., 0., 1., 0., 0., 1., 0., 0., 0., // its coordinates, then unused
    ];
    std::fs::write(dir.path().join("tri.bin"), bytemuck::cast_slice(&floats)).unwrap();
    let mut json: serde_json::Value =
        serde_json::from_str(&gltf_json(r#""uri": "tri.bin""#, "")).unwrap();
    json["extensionsUsed"] =
        serde_json::json!(["KHR_materials_emissive_strength", "KHR_texture_transform"]);
    let png = dir.path().join("white.png");
    image::RgbaImage::from_pixel(2, 2, image::Rgba([255; 4]))
        .save(&png)
        .unwrap();
    json["images"] = serde_json::json!([{"uri": "white.png"}]);
    json["textures"] = serde_json::json!([{"source": 0}]);
    json["accessors"]
        .as_array_mut()
        .unwrap()
        .push(serde_json::json!(
            {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"}
        ));
    let transform = serde_json::json!({"KHR_texture_transform":
        {"offset": [0.5, 0.25], "rotation": 0.5, "scale": [2.0, 3.0]}});
    json["materials"] = serde_json::json!([{
        "name": "lamp",
        "emissiveFactor": [1.0, 0.5, 0.25],
        "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4.0}},
        "normalTexture": {"index": 0, "scale": 0.5},
        "occlusionTexture": {"index": 0, "strength": 0.25},
        "pbrMetallicRoughness": {"baseColorTexture": {"index": 0, "extensions": transform}}
    }]);
    json["meshes"] = serde_json::json!([{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 2}, "material": 0}]}]);
    let p = dir.path().join("lamp.gltf");
    std::fs::write(&p, json.to_string()).unwrap();
    let s = scene_spec::load(p.to_str().unwrap()).unwrap();
    let m = &s.materials[0];
    assert_eq!(m.emissive, glam::Vec3::new(1.0, 0.5, 0.25));
    assert_eq!(
        (m.emissive_strength, m.normal_scale, m.occlusion_strength),
        (4.0, 0.5, 0.25)
    );
    // A point of the texture's space: scaled, rotated, then offset.
    let uv = m.uv_transform.transform_point2(glam::Vec2::new(1.0, 0.0));
    let (s_, c) = 0.5f32.sin_cos();
    let want = glam::Vec2::new(0.5 + 2.0 * c, 0.25 - 2.0 * s_);
    assert!((uv - want).length() < 1e-6, "{uv} against {want}");
    // The normal map with no TANGENT in the file: generated, along +u.
    let t = s.vertices[0].tangent();
    assert!((t.truncate() - glam::Vec3::X).length() < 0.02, "{t}");
}
