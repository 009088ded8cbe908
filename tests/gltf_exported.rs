//! glTF as optimizers and exporters write it: `EXT_meshopt_compression` (the shared
//! samples recompressed here with meshoptimizer's own encoders), `KHR_mesh_quantization`
//! (integer attributes), `KHR_texture_basisu` (KTX2 images KTX-Software wrote), a
//! second set of texture coordinates, application-specific
//! attributes, and the rule that only an unread extension the file *requires* is an
//! error.

use std::path::{Path, PathBuf};

use serde_json::{Value, json};
use stereocull::scene::Scene;
use stereocull::scene_spec;

mod support;

use support::glb::{split_glb, write_glb};

fn element_size(accessor: &Value) -> usize {
    let components = match accessor["type"].as_str().unwrap() {
        "SCALAR" => 1,
        "VEC2" => 2,
        "VEC3" => 3,
        "VEC4" | "MAT2" => 4,
        "MAT3" => 9,
        _ => 16,
    };
    let bytes = match accessor["componentType"].as_u64().unwrap() {
        5120 | 5121 => 1,
        5122 | 5123 => 2,
        _ => 4,
    };
    components * bytes
}

/// The accessors a mesh primitive reads as (indices, vertex attributes).
fn primitive_accessors(json: &Value) -> (Vec<u64>, Vec<u64>) {
    let primitives: Vec<&Value> = (json["meshes"].as_array().unwrap().iter())
        .flat_map(|m| m["primitives"].as_array().unwrap().iter())
        .collect();
    let indices = primitives
        .iter()
        .filter_map(|p| p["indices"].as_u64())
        .collect();
    let attributes = (primitives.iter())
        .flat_map(|p| p["attributes"].as_object().unwrap().values())
        .filter_map(Value::as_u64)
        .collect();
    (indices, attributes)
}

/// How one buffer view would be compressed: its mode and element stride. A view of
/// primitives' indices (of 16 or 32 bits, each whole triangles) is TRIANGLES; one of vertex attributes
/// alone, of a stride that is a multiple of 4, is ATTRIBUTES; others stay plain.
fn compression_of(json: &Value, view: usize) -> Option<(&'static str, usize)> {
    let accessors: Vec<(u64, &Value)> = (json["accessors"].as_array()?.iter().enumerate())
        .filter(|(_, a)| a["bufferView"].as_u64() == Some(view as u64))
        .map(|(i, a)| (i as u64, a))
        .collect();
    let length = json["bufferViews"][view]["byteLength"].as_u64()? as usize;
    let (indices, attributes) = primitive_accessors(json);
    let &(index, first) = accessors.first()?;
    if indices.contains(&index) {
        let stride = element_size(first);
        let whole_triangles = |(i, a): &(u64, &Value)| {
            let count = a["count"].as_u64().unwrap_or(1) as usize;
            let at = a["byteOffset"].as_u64().unwrap_or(0) as usize;
            indices.contains(i)
                && element_size(a) == stride
                && count.is_multiple_of(3)
                && (at / stride).is_multiple_of(3)
        };
        let fits = (stride == 2 || stride == 4) && (length / stride).is_multiple_of(3);
        return (fits && accessors.iter().all(whole_triangles)).then_some(("TRIANGLES", stride));
    }
    let stride = (json["bufferViews"][view]["byteStride"].as_u64())
        .map_or(element_size(first), |s| s as usize);
    let fits = stride.is_multiple_of(4) && length.is_multiple_of(stride);
    let all_attributes = accessors.iter().all(|(i, _)| attributes.contains(i));
    (fits && all_attributes).then_some(("ATTRIBUTES", stride))
}

/// `glb` with every vertex and index view it can compress written as
/// `EXT_meshopt_compression` requires: the compressed bytes in buffer 0, the views'
/// decoded places in a fallback buffer 1 without data. Other views (images, animation
/// data) stay plain in buffer 0. Returns the file and how many views it compressed.
fn meshopt_compressed(glb: &[u8]) -> (Vec<u8>, usize) {
    let (mut json, bin) = split_glb(glb);
    let mut out = Vec::new();
    let mut fallback = 0usize;
    let mut compressed = 0;
    let views = json["bufferViews"].as_array().unwrap().len();
    for v in 0..views {
        let view = json["bufferViews"][v].clone();
        let at = view["byteOffset"].as_u64().unwrap_or(0) as usize;
        let length = view["byteLength"].as_u64().unwrap() as usize;
        let bytes = &bin[at..at + length];
        while !out.len().is_multiple_of(4) {
            out.push(0);
        }
        let Some((mode, stride)) = compression_of(&json, v) else {
            json["bufferViews"][v]["byteOffset"] = json!(out.len());
            out.extend_from_slice(bytes);
            continue;
        };
        let count = length / stride;
        let encoded = match (mode, stride) {
            ("TRIANGLES", 2) => {
                let indices: Vec<u32> = (bytes.chunks_exact(2))
                    .map(|c| u16::from_le_bytes([c[0], c[1]]) as u32)
                    .collect();
                let vertices = *indices.iter().max().unwrap() as usize + 1;
                meshopt::encode_index_buffer(&indices, vertices).unwrap()
            }
            ("TRIANGLES", _) => {
                let indices: Vec<u32> = bytemuck::pod_collect_to_vec(bytes);
                let vertices = *indices.iter().max().unwrap() as usize + 1;
                meshopt::encode_index_buffer(&indices, vertices).unwrap()
            }
            _ => encode_vertices(bytes, stride),
        };
        let place = fallback;
        fallback += length.next_multiple_of(4);
        json["bufferViews"][v] = json!({
            "buffer": 1, "byteOffset": place, "byteLength": length,
            "extensions": {"EXT_meshopt_compression": {
                "buffer": 0, "byteOffset": out.len(), "byteLength": encoded.len(),
                "byteStride": stride, "count": count, "mode": mode}}
        });
        if let Some(s) = view.get("byteStride") {
            json["bufferViews"][v]["byteStride"] = s.clone();
        }
        if let Some(t) = view.get("target") {
            json["bufferViews"][v]["target"] = t.clone();
        }
        out.extend_from_slice(&encoded);
        compressed += 1;
    }
    json["buffers"] = json!([
        {"byteLength": out.len().next_multiple_of(4)},
        {"byteLength": fallback, "extensions": {"EXT_meshopt_compression": {"fallback": true}}}
    ]);
    for list in ["extensionsUsed", "extensionsRequired"] {
        let mut names = json[list].as_array().cloned().unwrap_or_default();
        names.push(json!("EXT_meshopt_compression"));
        json[list] = json!(names);
    }
    (write_glb(&json, &out), compressed)
}

/// meshoptimizer's vertex codec over elements of `stride` bytes (a multiple of 4): as
/// words of that many bytes, which the codec treats as opaque bytes.
fn encode_vertices(bytes: &[u8], stride: usize) -> Vec<u8> {
    macro_rules! encode {
        ($($n:literal)*) => {
            match stride / 4 {
                $($n => meshopt::encode_vertex_buffer::<[u32; $n]>(&bytemuck::pod_collect_to_vec(bytes)).unwrap(),)*
                _ => panic!("stride {stride}"),
            }
        };
    }
    encode!(1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16)
}

fn load_bytes(dir: &Path, name: &str, bytes: &[u8]) -> Scene {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    scene_spec::load(path.to_str().unwrap()).unwrap()
}

/// Each triangle rotated to start at its least index: meshoptimizer's index codec may
/// rotate a triangle's corners (keeping its winding), never reorder triangles.
fn canonical_triangles(indices: &[u32]) -> Vec<[u32; 3]> {
    (indices.chunks_exact(3))
        .map(|t| {
            let least = (0..3).min_by_key(|&i| t[i]).unwrap();
            [t[least], t[(least + 1) % 3], t[(least + 2) % 3]]
        })
        .collect()
}

/// The same vertices, meshes and instances, and each mesh the same triangles at its
/// finest level. Coarser levels are simplified from those triangles, and meshoptimizer's
/// simplifier may choose differently for a rotated triangle, so they are not compared.
fn assert_same_geometry(a: &Scene, b: &Scene, what: &str) {
    assert_eq!(a.vertices, b.vertices, "{what}: vertices");
    assert_eq!(a.meshes.len(), b.meshes.len(), "{what}: meshes");
    for (m, (x, y)) in a.meshes.iter().zip(&b.meshes).enumerate() {
        assert_eq!(
            (x.first_index, x.index_count, x.base_vertex),
            (y.first_index, y.index_count, y.base_vertex),
            "{what}: mesh {m}"
        );
        let finest = |s: &Scene| {
            let range = x.first_index as usize..(x.first_index + x.index_count) as usize;
            canonical_triangles(&s.indices[range])
        };
        assert_eq!(finest(a), finest(b), "{what}: mesh {m}'s triangles");
    }
    assert_eq!(a.instances.len(), b.instances.len(), "{what}: instances");
    assert!(
        !a.vertices.is_empty() && !a.indices.is_empty(),
        "{what}: empty"
    );
}

/// Every GLB among the shared samples (written by nobody here), recompressed with
/// meshoptimizer's encoders, imports to the same vertices, triangles (in order, each
/// with its winding) and instances as the original: the decoders undo exactly what the
/// encoders wrote.
#[test]
fn meshopt_compressed_samples_decode_to_their_originals() {
    let dir = tempfile::tempdir().unwrap();
    let mut total = 0;
    for name in [
        "Box",
        "BoxAnimated",
        "BoxTextured",
        "CesiumMilkTruck",
        "AlphaBlendModeTest",
    ] {
        let original_path = support::gltf_sample(name, "glb");
        let glb = std::fs::read(&original_path).unwrap();
        let original = scene_spec::load(original_path.to_str().unwrap()).unwrap();
        let (packed, views) = meshopt_compressed(&glb);
        assert!(views >= 2, "{name}: only {views} views compressed");
        total += views;
        let decoded = load_bytes(dir.path(), &format!("{name}-meshopt.glb"), &packed);
        assert_same_geometry(&decoded, &original, name);
    }
    assert!(total >= 12, "{total} views compressed in all");
}

/// A filtered view (octahedral normals, as gltfpack writes them): the import applies
/// the filter, so its normals are what meshoptimizer's own filter decoder gives (and
/// within the encoding's error of the originals), not the raw encoded bytes.
#[test]
fn meshopt_octahedral_normals_are_unfiltered() {
    let normals: Vec<[f32; 4]> = (0..12)
        .map(|i| {
            let a = i as f32 * 0.5;
            let n = glam::Vec3::new(a.cos(), (a * 0.7).sin(), a.sin() + 0.3).normalize();
            [n.x, n.y, n.z, 0.0]
        })
        .collect();
    let encoded: Vec<[i8; 4]> = meshopt::encode_filter_oct(&normals, 8);
    let mut expected = encoded.clone();
    meshopt::decode_filter_oct(&mut expected);
    let positions: Vec<[f32; 3]> = (0..12).map(|i| [i as f32, (i % 3) as f32, 0.5]).collect();
    let packed_normals = encode_vertices(bytemuck::cast_slice(&encoded), 4);
    let packed_positions = encode_vertices(bytemuck::cast_slice(&positions), 12);
    let mut bin = packed_positions.clone();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let normals_at = bin.len();
    bin.extend_from_slice(&packed_normals);
    let ext = |at: usize, len: usize, stride: usize, filter: &str| {
        json!({"EXT_meshopt_compression": {"buffer": 0, "byteOffset": at, "byteLength": len,
            "byteStride": stride, "count": 12, "mode": "ATTRIBUTES", "filter": filter}})
    };
    let json = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["EXT_meshopt_compression", "KHR_mesh_quantization"],
        "extensionsRequired": ["EXT_meshopt_compression", "KHR_mesh_quantization"],
        "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}}]}],
        "buffers": [{"byteLength": bin.len()},
            {"byteLength": 192, "extensions": {"EXT_meshopt_compression": {"fallback": true}}}],
        "bufferViews": [
            {"buffer": 1, "byteOffset": 0, "byteLength": 144, "byteStride": 12, "target": 34962,
             "extensions": ext(0, packed_positions.len(), 12, "NONE")},
            {"buffer": 1, "byteOffset": 144, "byteLength": 48, "byteStride": 4, "target": 34962,
             "extensions": ext(normals_at, packed_normals.len(), 4, "OCTAHEDRAL")}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 12, "type": "VEC3",
             "min": [0, 0, 0.5], "max": [11, 2, 0.5]},
            {"bufferView": 1, "componentType": 5120, "normalized": true, "count": 12, "type": "VEC3"}
        ]
    });
    let dir = tempfile::tempdir().unwrap();
    let scene = load_bytes(dir.path(), "oct.glb", &write_glb(&json, &bin));
    for (i, v) in scene.vertices.iter().enumerate() {
        assert_eq!(v.position, positions[i]);
        let want = expected[i].map(|c| (c as f32 / 127.0).max(-1.0));
        assert_eq!(v.normal, [want[0], want[1], want[2]], "vertex {i}");
        let n = glam::Vec3::from(v.normal).normalize();
        let dot = n.dot(glam::Vec4::from(normals[i]).truncate());
        assert!(dot > 0.999, "vertex {i}: {dot}");
    }
}

/// `KHR_mesh_quantization` as gltfpack writes it: positions as unnormalized shorts
/// (scaled back by the node), normals as normalized bytes, coordinates as normalized
/// unsigned shorts, tangents as normalized bytes; a custom attribute (`_BARYCENTRIC`)
/// beside them is ignored. The values are chosen exact in both forms.
#[test]
fn quantized_attributes_and_custom_attributes_are_read() {
    let positions: [[i16; 4]; 3] = [[0, 0, 0, 0], [200, 0, 0, 0], [0, 400, -100, 0]];
    let normals: [[i8; 4]; 3] = [[0, 0, 127, 0], [0, 127, 0, 0], [-128, 0, 0, 0]];
    let uvs: [[u16; 2]; 3] = [[0, 0], [65535, 0], [0, 65535]];
    let tangents: [[i8; 4]; 3] = [[127, 0, 0, 127], [127, 0, 0, -127], [0, 0, 127, 127]];
    let barycentric: [[u8; 4]; 3] = [[255, 0, 0, 0], [0, 255, 0, 0], [0, 0, 255, 0]];
    let mut bin = Vec::new();
    bin.extend_from_slice(bytemuck::cast_slice(&positions));
    bin.extend_from_slice(bytemuck::cast_slice(&normals));
    bin.extend_from_slice(bytemuck::cast_slice(&uvs));
    bin.extend_from_slice(bytemuck::cast_slice(&tangents));
    bin.extend_from_slice(bytemuck::cast_slice(&barycentric));
    let view = |at: usize, len: usize, stride: usize| json!({"buffer": 0, "byteOffset": at, "byteLength": len, "byteStride": stride, "target": 34962});
    let json = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_mesh_quantization"],
        "extensionsRequired": ["KHR_mesh_quantization"],
        "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "scale": [0.01, 0.01, 0.01]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2,
            "TANGENT": 3, "_BARYCENTRIC": 4}, "material": 0}]}],
        "materials": [{"normalTexture": {"index": 0}}],
        "textures": [{"source": 0}],
        "images": [{"uri": "data:image/png;base64,iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR4nGNoaPj/HwAGggL/s75RMwAAAABJRU5ErkJggg=="}],
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": [view(0, 24, 8), view(24, 12, 4), view(36, 12, 4), view(48, 12, 4), view(60, 12, 4)],
        "accessors": [
            {"bufferView": 0, "componentType": 5122, "count": 3, "type": "VEC3",
             "min": [0, 0, -100], "max": [200, 400, 0]},
            {"bufferView": 1, "componentType": 5120, "normalized": true, "count": 3, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5123, "normalized": true, "count": 3, "type": "VEC2"},
            {"bufferView": 3, "componentType": 5120, "normalized": true, "count": 3, "type": "VEC4"},
            {"bufferView": 4, "componentType": 5121, "normalized": true, "count": 3, "type": "VEC3"}
        ]
    });
    let dir = tempfile::tempdir().unwrap();
    let scene = load_bytes(dir.path(), "quantized.glb", &write_glb(&json, &bin));
    let got: Vec<_> = (scene.vertices.iter())
        .map(|v| (v.position, v.normal, v.uv, v.tangent))
        .collect();
    assert_eq!(
        got,
        [
            (
                [0.0, 0.0, 0.0],
                [0.0, 0.0, 1.0],
                [0.0, 0.0],
                [127, 0, 0, 127]
            ),
            (
                [200.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [1.0, 0.0],
                [127, 0, 0, -127]
            ),
            (
                [0.0, 400.0, -100.0],
                [-1.0, 0.0, 0.0],
                [0.0, 1.0],
                [0, 0, 127, 127]
            ),
        ]
    );
    let scale = scene.instances[0].world_from_local.matrix3.x_axis.x;
    assert!((scale - 0.01).abs() < 1e-7, "{scale}");
}

fn write_with_extensions(dir: &Path, used: &[&str], required: &[&str]) -> PathBuf {
    let floats: [f32; 9] = [0., 0., 0., 1., 0., 0., 0., 1., 0.];
    let json = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": used, "extensionsRequired": required,
        "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "extensions": {"VENDOR_thing": {"x": 1}}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "buffers": [{"byteLength": 36}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
            "min": [0, 0, 0], "max": [1, 1, 0]}]
    });
    let path = dir.join(format!("{}.glb", required.join("-")));
    std::fs::write(&path, write_glb(&json, bytemuck::cast_slice(&floats))).unwrap();
    path
}

/// An extension the file only uses is listed and ignored; one it requires and we do not
/// read is an error naming it, and for Draco the way to a readable file.
#[test]
fn only_unread_required_extensions_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let used = [
        "VENDOR_thing",
        "KHR_materials_clearcoat",
        "KHR_mesh_quantization",
    ];
    let path = write_with_extensions(dir.path(), &used, &["KHR_mesh_quantization"]);
    let scene = scene_spec::load(path.to_str().unwrap()).unwrap();
    assert_eq!(scene.instances.len(), 1);
    let uses = stereocull::gltf_import::extension_uses(&path).unwrap();
    let listed: Vec<_> = uses
        .iter()
        .map(|u| (u.name.as_str(), u.required, u.read))
        .collect();
    assert_eq!(
        listed,
        [
            ("VENDOR_thing", false, false),
            ("KHR_materials_clearcoat", false, false),
            ("KHR_mesh_quantization", true, true),
        ]
    );
    let error = |required: &str| {
        let path = write_with_extensions(dir.path(), &[required], &[required]);
        let e = scene_spec::load(path.to_str().unwrap())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains(&format!("requires the extension {required}")),
            "{e}"
        );
        e
    };
    assert!(error("VENDOR_thing").contains("does not read"));
    assert!(error("KHR_draco_mesh_compression").contains("gltf-transform"));
}

/// `info --scene` lists what the file uses and what of it is read; `render` warns once
/// of what it draws without, and draws.
#[test]
fn info_lists_extensions_and_render_warns_once_of_unread_ones() {
    let dir = tempfile::tempdir().unwrap();
    let used = ["VENDOR_thing", "KHR_mesh_quantization"];
    let path = write_with_extensions(dir.path(), &used, &["KHR_mesh_quantization"]);
    let run = |args: &[&str]| {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_stereocull"))
            .args(args)
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&out.stdout).to_string();
        let errors = String::from_utf8_lossy(&out.stderr).to_string();
        assert!(out.status.success(), "{args:?}: {text}{errors}");
        (text, errors)
    };
    let scene = path.to_str().unwrap();
    let (text, _) = run(&["info", "--scene", scene]);
    let line = |name: &str| {
        text.lines()
            .find(|l| l.contains(name))
            .unwrap_or("")
            .to_string()
    };
    assert!(
        line("VENDOR_thing").ends_with("not read: drawn without it"),
        "{text}"
    );
    assert!(
        line("KHR_mesh_quantization (required)").ends_with("read"),
        "{text}"
    );
    assert!(text.contains("loads: 1 instances of 1 meshes"), "{text}");
    let out = dir.path().join("out");
    let (_, errors) = run(&[
        "render",
        "--scene",
        scene,
        "--width",
        "32",
        "--height",
        "32",
        "--out",
        out.to_str().unwrap(),
    ]);
    let warnings: Vec<_> = errors
        .lines()
        .filter(|l| l.contains("VENDOR_thing"))
        .collect();
    assert_eq!(warnings.len(), 1, "{errors}");
    let named = warnings[0]
        .split("drawn without them)")
        .nth(1)
        .unwrap_or("");
    assert_eq!(named.trim(), ": VENDOR_thing", "{errors}");
}

/// BoxTextured (written by nobody here) with its coordinates moved to `TEXCOORD_1`, and
/// `TEXCOORD_0` holding other ones (each vertex's u and v swapped): the base color reads
/// set `base`, and an emissive texture (times the default emissive factor, zero: it adds
/// nothing) reads set 0, so the material reads two sets when `base` is 1.
fn box_with_two_sets(base: u32) -> Vec<u8> {
    let glb = std::fs::read(support::gltf_sample("BoxTextured", "glb")).unwrap();
    let (mut json, mut bin) = split_glb(&glb);
    let attributes = &json["meshes"][0]["primitives"][0]["attributes"];
    let original = attributes["TEXCOORD_0"].as_u64().unwrap() as usize;
    let accessor = json["accessors"][original].clone();
    let view = &json["bufferViews"][accessor["bufferView"].as_u64().unwrap() as usize];
    let at = view["byteOffset"].as_u64().unwrap_or(0) as usize
        + accessor["byteOffset"].as_u64().unwrap_or(0) as usize;
    let stride = view["byteStride"].as_u64().unwrap_or(8) as usize;
    let count = accessor["count"].as_u64().unwrap() as usize;
    let swapped: Vec<[f32; 2]> = (0..count)
        .map(|i| {
            let uv: [f32; 2] =
                bytemuck::pod_read_unaligned(&bin[at + i * stride..at + i * stride + 8]);
            [uv[1], uv[0]]
        })
        .collect();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let views = json["bufferViews"].as_array().unwrap().len();
    let accessors = json["accessors"].as_array().unwrap().len();
    json["bufferViews"].as_array_mut().unwrap().push(json!(
        {"buffer": 0, "byteOffset": bin.len(), "byteLength": count * 8}));
    bin.extend_from_slice(bytemuck::cast_slice(&swapped));
    json["accessors"].as_array_mut().unwrap().push(json!(
        {"bufferView": views, "componentType": 5126, "count": count, "type": "VEC2"}));
    json["buffers"][0]["byteLength"] = json!(bin.len());
    let primitive = &mut json["meshes"][0]["primitives"][0];
    primitive["attributes"]["TEXCOORD_1"] = json!(original);
    primitive["attributes"]["TEXCOORD_0"] = json!(accessors);
    let material = &mut json["materials"][0];
    let texture = material["pbrMetallicRoughness"]["baseColorTexture"]["index"].clone();
    material["pbrMetallicRoughness"]["baseColorTexture"]["texCoord"] = json!(base);
    material["emissiveTexture"] = json!({"index": texture, "texCoord": 0});
    write_glb(&json, &bin)
}

/// The view of BoxTextured's +Z face, in mono.
fn facing_the_box() -> stereocull::rig::Rig {
    let mut rig = stereocull::rig::Rig::preset("hmd").unwrap();
    rig.viewer.position = [0.0, 0.0, 1.8];
    let display = &mut rig.displays[0];
    display.stereo = false;
    display.resolution = [160, 160];
    rig
}

/// A base color texture on `TEXCOORD_1` beside a texture on `TEXCOORD_0` reads the
/// second set: the box draws as the original, whose one set holds the same coordinates.
/// The two-set bin is another pipeline (a varying more), so the comparison allows what
/// recompiling allows (`Tolerance::RECOMPILED`); reading the first set instead (the
/// control) transposes the texture, far past it.
#[test]
fn a_texture_on_the_second_set_reads_the_second_set() {
    let dir = tempfile::tempdir().unwrap();
    let original_path = support::gltf_sample("BoxTextured", "glb");
    let original = scene_spec::load(original_path.to_str().unwrap()).unwrap();
    let two_sets = load_bytes(dir.path(), "two-sets.glb", &box_with_two_sets(1));
    let control = load_bytes(dir.path(), "control.glb", &box_with_two_sets(0));
    use stereocull::scene::SecondUv;
    assert_eq!(two_sets.materials[0].second_uv, SecondUv::BASE_COLOR);
    assert_eq!(control.materials[0].second_uv, SecondUv::default());
    for (v, o) in two_sets.vertices.iter().zip(&original.vertices) {
        assert_eq!(v.uv1, o.uv);
        assert_eq!(v.uv, [o.uv[1], o.uv[0]]);
    }
    let gpu = support::gpu();
    let rig = facing_the_box();
    let draw = |scene: &Scene| draw_with_formats(&gpu, scene, &rig).0;
    let reference = draw(&original);
    let tolerance = support::Tolerance::RECOMPILED;
    support::assert_images_match("second set", &draw(&two_sets), &reference, tolerance);
    let control = draw(&control);
    let differ = pixels_apart(&control, &reference, 8);
    assert!(differ > 500, "the control differs at {differ} pixels only");
}

/// BoxTextured's JSON and binary chunk with `ktx2` one more image (`image/ktx2`) in a new
/// buffer view, and that image's index; no texture reads it yet.
fn box_with_ktx2_image(ktx2: &[u8]) -> (Value, Vec<u8>, usize) {
    let glb = std::fs::read(support::gltf_sample("BoxTextured", "glb")).unwrap();
    let (mut json, mut bin) = split_glb(&glb);
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let views = json["bufferViews"].as_array().unwrap().len();
    let images = json["images"].as_array().unwrap().len();
    json["bufferViews"].as_array_mut().unwrap().push(json!(
        {"buffer": 0, "byteOffset": bin.len(), "byteLength": ktx2.len()}));
    bin.extend_from_slice(ktx2);
    json["buffers"][0]["byteLength"] = json!(bin.len());
    json["images"].as_array_mut().unwrap().push(json!(
        {"bufferView": views, "mimeType": "image/ktx2"}));
    (json, bin, images)
}

/// BoxTextured with its texture's image `ktx2` (a KTX2 in a new buffer view) through
/// `KHR_texture_basisu`: `required` drops the core PNG source and requires the
/// extension; otherwise the PNG stays as the fallback and the extension is only used.
fn box_with_ktx2(ktx2: &[u8], required: bool) -> Vec<u8> {
    let (mut json, bin, images) = box_with_ktx2_image(ktx2);
    let texture = &mut json["textures"][0];
    texture["extensions"] = json!({"KHR_texture_basisu": {"source": images}});
    let name = json!("KHR_texture_basisu");
    json["extensionsUsed"] = json!([name]);
    if required {
        json["textures"][0]
            .as_object_mut()
            .unwrap()
            .remove("source");
        json["extensionsRequired"] = json!([name]);
    }
    write_glb(&json, &bin)
}

/// A texture whose only image is a KTX2 (Basis Universal, written by KTX-Software) loads
/// as its transcoded texels and, on a device without BC formats (which would keep it
/// BC7: the test below), draws exactly as the same texels from a PNG would;
/// beside a PNG fallback, the KTX2 is the one read. The control (the box's own PNG)
/// differs.
#[test]
fn a_basis_universal_texture_loads_and_draws() {
    let dir = tempfile::tempdir().unwrap();
    let ktx2_path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/ktx2/ktx_document_basis.ktx2");
    let ktx2 = std::fs::read(ktx2_path).unwrap();
    let texels = stereocull::basisu::decode(&ktx2).unwrap();
    let required = load_bytes(dir.path(), "required.glb", &box_with_ktx2(&ktx2, true));
    let beside_png = load_bytes(dir.path(), "fallback.glb", &box_with_ktx2(&ktx2, false));
    assert_eq!(required.textures.len(), 1);
    assert!(required.textures[0].image == texels);
    assert!(beside_png.textures[0].image == texels);
    let original_path = support::gltf_sample("BoxTextured", "glb");
    let original = scene_spec::load(original_path.to_str().unwrap()).unwrap();
    let mut as_png = original.clone();
    as_png.textures[0].image = texels;
    let gpu = support::gpu_with(wgpu::Features::all() - wgpu::Features::TEXTURE_COMPRESSION_BC);
    let rig = facing_the_box();
    let draw = |scene: &Scene| draw_with_formats(&gpu, scene, &rig).0;
    let reference = draw(&as_png);
    // Exact on any CPU: the same pipelines draw the same geometry with the same RGBA8
    // texels (the two scenes differ only in where the texels came from).
    support::assert_images_match(
        "basisu",
        &draw(&required),
        &reference,
        support::Tolerance::EXACT,
    );
    let control = draw(&original);
    let differ = pixels_apart(&control, &reference, 8);
    assert!(differ > 500, "the control differs at {differ} pixels only");
}

/// BoxTextured with its texture's image `ktx2` in a new buffer view: referenced
/// directly by the texture (`basisu` false: no extension, the way Bevy writes plain
/// KTX2 files) or through `KHR_texture_basisu`; the image is read as the base color
/// (sRGB) and as the metallic-roughness map (linear).
fn box_with_raw_ktx2(ktx2: &[u8], basisu: bool) -> Vec<u8> {
    let glb = match basisu {
        true => box_with_ktx2(ktx2, true),
        false => {
            let (mut json, bin, image) = box_with_ktx2_image(ktx2);
            json["textures"][0]["source"] = json!(image);
            write_glb(&json, &bin)
        }
    };
    let (mut json, bin) = split_glb(&glb);
    let pbr = &mut json["materials"][0]["pbrMetallicRoughness"];
    pbr["metallicRoughnessTexture"] = json!({"index": 0});
    write_glb(&json, &bin)
}

/// The plain formats a KTX2 image may hold (Vulkan's numbers), with their channels,
/// bytes per channel and whether 8-bit values are sRGB-encoded.
const RAW_FORMATS: [(&str, u32, usize, usize, bool); 12] = [
    ("R8_UNORM", 9, 1, 1, false),
    ("R8G8_UNORM", 16, 2, 1, false),
    ("R8G8B8_UNORM", 23, 3, 1, false),
    ("R8G8B8A8_UNORM", 37, 4, 1, false),
    ("R8_SRGB", 15, 1, 1, true),
    ("R8G8_SRGB", 22, 2, 1, true),
    ("R8G8B8_SRGB", 29, 3, 1, true),
    ("R8G8B8A8_SRGB", 43, 4, 1, true),
    ("R16_SFLOAT", 76, 1, 2, false),
    ("R16G16_SFLOAT", 83, 2, 2, false),
    ("R16G16B16_SFLOAT", 90, 3, 2, false),
    ("R16G16B16A16_SFLOAT", 97, 4, 2, false),
];

/// A texel of a plain format as a GPU samples it into an 8-bit slot read as sRGB
/// (`srgb`) or linear: missing green and blue 0, missing alpha 1, converted where the
/// format's transfer function is not the slot's.
fn sampled(channels: &[f32], srgb_format: bool, srgb_slot: bool) -> [u8; 4] {
    let linear_of = |s: f32| match s <= 0.04045 {
        true => s / 12.92,
        false => ((s + 0.055) / 1.055).powf(2.4),
    };
    let mut out = [0, 0, 0, 255];
    for (c, &v) in channels.iter().enumerate() {
        let linear = if srgb_format && c < 3 {
            linear_of(v)
        } else {
            v
        };
        out[c] = match (c < 3 && srgb_slot, srgb_format) {
            // An sRGB format's own bytes are the slot's.
            (true, true) => (v * 255.0).round() as u8,
            (true, false) => support::srgb(linear).round() as u8,
            _ => (linear.clamp(0.0, 1.0) * 255.0).round() as u8,
        };
    }
    out
}

/// A KTX2 image of each plain format, raw and Zstandard-supercompressed, referenced
/// directly and through `KHR_texture_basisu`, loads as what a GPU samples from it, for
/// the base color (sRGB) and the metallic-roughness map (linear). A format we do not
/// read is refused by name.
#[test]
fn plain_ktx2_textures_load_in_every_format() {
    use rand::{Rng, SeedableRng};
    let dir = tempfile::tempdir().unwrap();
    let mut rng = rand_pcg::Pcg64::seed_from_u64(66);
    let (w, h) = (5u32, 3u32);
    for (name, format, channels, size, srgb) in RAW_FORMATS {
        let values: Vec<f32> = (0..(w * h) as usize * channels)
            .map(|_| match size {
                1 => rng.random_range(0..=255u8) as f32 / 255.0,
                _ => half::f16::from_f32(rng.random_range(-0.25f32..1.25)).to_f32(),
            })
            .collect();
        let texels: Vec<u8> = match size {
            1 => values.iter().map(|v| (v * 255.0).round() as u8).collect(),
            _ => (values.iter())
                .flat_map(|&v| half::f16::from_f32(v).to_le_bytes())
                .collect(),
        };
        for (zstd, basisu) in [(false, false), (true, false), (false, true), (true, true)] {
            let ktx2 = support::ktx2::raw(format, (w, h), size as u32, &texels, zstd);
            let what = format!("{name} zstd {zstd} basisu {basisu}");
            let file = format!("{name}-{zstd}-{basisu}.glb");
            let scene = load_bytes(dir.path(), &file, &box_with_raw_ktx2(&ktx2, basisu));
            assert_eq!(scene.textures.len(), 2, "{what}");
            for texture in &scene.textures {
                let srgb_slot = texture.encoding == stereocull::scene::Encoding::Srgb;
                assert_eq!(texture.image.dimensions(), (w, h), "{what}");
                for (i, pixel) in texture.image.pixels().enumerate() {
                    let texel = &values[i * channels..][..channels];
                    let want = sampled(texel, srgb, srgb_slot);
                    assert_eq!(pixel.0, want, "{what} slot sRGB {srgb_slot} texel {i}");
                }
            }
        }
    }
    // A compressed format: refused, by name.
    let bc7 = support::ktx2::raw(145, (4, 4), 1, &[0; 16], false);
    let glb = box_with_raw_ktx2(&bc7, false);
    let path = dir.path().join("bc7.glb");
    std::fs::write(&path, glb).unwrap();
    let refused = scene_spec::load(path.to_str().unwrap())
        .unwrap_err()
        .to_string();
    assert!(refused.contains("BC7_UNORM_BLOCK"), "{refused}");
}

/// A plain KTX2 referenced directly draws exactly as the same texels from a PNG would.
#[test]
fn a_plain_ktx2_texture_draws_as_its_texels_do() {
    let dir = tempfile::tempdir().unwrap();
    let original_path = support::gltf_sample("BoxTextured", "glb");
    let original = scene_spec::load(original_path.to_str().unwrap()).unwrap();
    let png = original.textures[0].image.clone();
    let ktx2 = support::ktx2::raw(43, png.dimensions(), 1, png.as_raw(), true);
    let (mut json, bin, image) = box_with_ktx2_image(&ktx2);
    json["textures"][0]["source"] = json!(image);
    let scene = load_bytes(dir.path(), "direct.glb", &write_glb(&json, &bin));
    assert!(scene.textures[0].image == png);
    let gpu = support::gpu();
    let rig = facing_the_box();
    let draw = |scene: &Scene| draw_with_formats(&gpu, scene, &rig).0;
    // Exact on any CPU: the same pipelines draw the same geometry with the same texels.
    let reference = draw(&original);
    support::assert_images_match(
        "ktx2 raw",
        &draw(&scene),
        &reference,
        support::Tolerance::EXACT,
    );
}

/// Pixels where a color channel of `a` and `b` differs by more than `levels`.
fn pixels_apart(a: &image::RgbaImage, b: &image::RgbaImage, levels: u8) -> usize {
    (a.pixels().zip(b.pixels()))
        .filter(|(p, q)| (0..3).any(|c| p[c].abs_diff(q[c]) > levels))
        .count()
}

/// The image of `scene` on `gpu`, its texture arrays' formats, and the bytes its first
/// frame uploaded.
fn draw_with_formats(
    gpu: &stereocull::device::Gpu,
    scene: &Scene,
    rig: &stereocull::rig::Rig,
) -> (image::RgbaImage, [wgpu::TextureFormat; 2], u64) {
    let options = stereocull::renderer::RendererOptions::default();
    let mut renderer =
        stereocull::renderer::Renderer::new(&gpu.device, scene, rig, options).unwrap();
    let targets = renderer.create_targets(&gpu.device);
    let stats = (renderer.submit_frame(&gpu.device, &gpu.queue, rig, 0.0, &targets)).unwrap();
    let image =
        stereocull::readback::read_rgba8(&gpu.device, &gpu.queue, &targets[0].color).unwrap();
    (image, renderer.texture_formats(), stats.bytes_uploaded)
}

/// On a device that samples BC, Basis Universal textures stay block-compressed: the
/// color array is BC7 (the file's own levels, transcoded), a quarter of the RGBA8
/// upload; without BC they are RGBA8. Seen close (level 0 magnified, so that both
/// sample the same level: the RGBA8 road builds its own mip chain), both draw alike
/// within the codecs' error: UASTC transcodes to BC7 almost exactly (measured: no
/// pixel more than 4 levels apart), ETC1S through an approximation (measured: 13 of
/// 25,600 pixels more than 24 levels apart, none more than 32). The box's own PNG (the
/// control) differs at most pixels.
#[test]
fn basis_textures_stay_bc7_where_the_device_samples_bc() {
    let dir = tempfile::tempdir().unwrap();
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/ktx2");
    let bc = support::gpu();
    let bc_feature = wgpu::Features::TEXTURE_COMPRESSION_BC;
    assert!(
        bc.device.features().contains(bc_feature),
        "lavapipe samples BC"
    );
    let rgba = support::gpu_with(wgpu::Features::all() - bc_feature);
    let mut rig = facing_the_box();
    rig.viewer.position[2] = 0.57;
    let (control, ..) = draw_with_formats(
        &bc,
        &scene_spec::load(support::gltf_sample("BoxTextured", "glb").to_str().unwrap()).unwrap(),
        &rig,
    );
    let files = [
        ("ktx_document_basis.ktx2", 32),
        ("ktx_document_uastc_rdo4_zstd5.ktx2", 4),
    ];
    for (name, levels) in files {
        let ktx2 = std::fs::read(data.join(name)).unwrap();
        let scene = load_bytes(dir.path(), "box.glb", &box_with_ktx2(&ktx2, true));
        let (compressed, formats, bc_bytes) = draw_with_formats(&bc, &scene, &rig);
        assert_eq!(formats[0], wgpu::TextureFormat::Bc7RgbaUnormSrgb, "{name}");
        let (plain, formats, rgba_bytes) = draw_with_formats(&rgba, &scene, &rig);
        assert_eq!(formats[0], wgpu::TextureFormat::Rgba8UnormSrgb, "{name}");
        assert!(
            bc_bytes * 3 < rgba_bytes,
            "{name}: {bc_bytes} against {rgba_bytes}"
        );
        let tolerance = support::Tolerance { levels, share: 0.0 };
        support::assert_images_match(name, &compressed, &plain, tolerance);
        let differ = pixels_apart(&control, &plain, 32);
        assert!(
            differ > 10_000,
            "the control differs at {differ} pixels only"
        );
    }
}
