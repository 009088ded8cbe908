//! Issue 40's import figures: one dense grid mesh written three ways (floats;
//! `KHR_mesh_quantization`: shorts and bytes; `EXT_meshopt_compression` over the
//! floats), each imported whole (levels of detail included), and meshoptimizer's
//! decoders alone on the compressed streams; then `KHR_texture_basisu`'s decode (KTX2 to
//! RGBA8) of KTX-Software's two encodings of one 1024 x 1024 image.
//!
//! `cargo bench --bench gltf_import`; under `cargo test` one small round.

use std::path::Path;
use std::time::{Duration, Instant};

use serde_json::{Value, json};

// The tests' GLB writer (its reader goes unused here).
#[allow(dead_code)]
#[path = "../tests/support/glb.rs"]
mod glb;

fn main() {
    let benching = std::env::args().any(|a| a == "--bench");
    let (side, rounds) = if benching { (500, 5) } else { (16, 1) };
    let grid = Grid::new(side);
    println!(
        "grid: {} vertices, {} triangles; medians of {rounds}",
        grid.positions.len(),
        grid.indices.len() / 3
    );
    for (name, file) in [
        ("floats", grid.floats()),
        ("quantized", grid.quantized()),
        ("meshopt", grid.meshopt()),
    ] {
        let time = median(rounds, || {
            let scene = stereocull::gltf_import::import_bytes(&file, None, Path::new(name))
                .expect("the grid imports");
            assert_eq!(scene.vertices.len(), grid.positions.len());
        });
        println!(
            "import {name:10} {:8} bytes  {:9.2} ms",
            file.len(),
            ms(time)
        );
    }
    let vertices: Vec<[f32; 8]> = grid.interleaved();
    let packed = meshopt::encode_vertex_buffer(&vertices).expect("encodes");
    let time = median(rounds, || {
        let out: Vec<[f32; 8]> =
            meshopt::decode_vertex_buffer(&packed, vertices.len()).expect("decodes");
        assert_eq!(out.len(), vertices.len());
    });
    let bytes = std::mem::size_of_val(vertices.as_slice()) as f64;
    println!(
        "meshopt vertex decode: {:.0} MB/s of decoded vertices ({} -> {} bytes)",
        bytes / time.as_secs_f64() / 1e6,
        packed.len(),
        bytes
    );
    let indices = meshopt::encode_index_buffer(&grid.indices, vertices.len()).expect("encodes");
    let time = median(rounds, || {
        let out: Vec<u32> =
            meshopt::decode_index_buffer(&indices, grid.indices.len()).expect("decodes");
        assert_eq!(out.len(), grid.indices.len());
    });
    println!(
        "meshopt index decode: {:.0} M triangles/s",
        grid.indices.len() as f64 / 3.0 / time.as_secs_f64() / 1e6
    );
    ktx2_decodes(rounds);
}

/// KTX2 (ETC1S with BasisLZ; UASTC with Zstandard) to RGBA8 texels.
fn ktx2_decodes(rounds: usize) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/ktx2");
    for name in [
        "ktx_document_basis.ktx2",
        "ktx_document_uastc_rdo4_zstd5.ktx2",
    ] {
        let file = std::fs::read(dir.join(name)).expect("the test KTX2 files are there");
        let mut texels = 0;
        let time = median(rounds, || {
            let image = stereocull::basisu::decode(&file).expect("decodes");
            texels = image.width() * image.height();
        });
        println!(
            "ktx2 decode {name:36} {:6} bytes {:8.2} ms  {:.0} M texels/s",
            file.len(),
            ms(time),
            f64::from(texels) / time.as_secs_f64() / 1e6
        );
    }
}

fn median(rounds: usize, mut run: impl FnMut()) -> Duration {
    let mut times: Vec<Duration> = (0..rounds)
        .map(|_| {
            let start = Instant::now();
            run();
            start.elapsed()
        })
        .collect();
    times.sort();
    times[rounds / 2]
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// A `side` x `side` grid of a gently waved surface, with normals and coordinates.
struct Grid {
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    uvs: Vec<[f32; 2]>,
    indices: Vec<u32>,
}

impl Grid {
    fn new(side: usize) -> Grid {
        let at = |i: usize| (i % side, i / side);
        let scale = 1.0 / (side - 1) as f32;
        let positions = (0..side * side)
            .map(|i| {
                let (x, y) = at(i);
                let (u, v) = (x as f32 * scale, y as f32 * scale);
                [u, v, 0.05 * (u * 20.0).sin() * (v * 20.0).cos()]
            })
            .collect();
        let normals = vec![[0.0, 0.0, 1.0]; side * side];
        let uvs = (0..side * side)
            .map(|i| {
                let (x, y) = at(i);
                [x as f32 * scale, y as f32 * scale]
            })
            .collect();
        let mut indices = Vec::new();
        for y in 0..side - 1 {
            for x in 0..side - 1 {
                let a = (y * side + x) as u32;
                let (b, c, d) = (a + 1, a + side as u32, a + side as u32 + 1);
                indices.extend([a, b, d, a, d, c]);
            }
        }
        Grid {
            positions,
            normals,
            uvs,
            indices,
        }
    }

    fn interleaved(&self) -> Vec<[f32; 8]> {
        (self.positions.iter().zip(&self.normals).zip(&self.uvs))
            .map(|((p, n), t)| [p[0], p[1], p[2], n[0], n[1], n[2], t[0], t[1]])
            .collect()
    }

    /// The grid as a GLB of floats, its material textured so that the coordinates are
    /// read.
    fn floats(&self) -> Vec<u8> {
        let streams: [(&[u8], u32, &str, bool); 3] = [
            (bytemuck::cast_slice(&self.positions), 5126, "VEC3", false),
            (bytemuck::cast_slice(&self.normals), 5126, "VEC3", false),
            (bytemuck::cast_slice(&self.uvs), 5126, "VEC2", false),
        ];
        self.glb(&streams, &[])
    }

    /// Positions as shorts (the node scales them back), normals as bytes, coordinates
    /// as unsigned shorts.
    fn quantized(&self) -> Vec<u8> {
        let positions: Vec<[i16; 4]> = (self.positions.iter())
            .map(|p| {
                [0, 1, 2, 3].map(|c| {
                    if c < 3 {
                        (p[c] * 32767.0).round() as i16
                    } else {
                        0
                    }
                })
            })
            .collect();
        let normals: Vec<[i8; 4]> = (self.normals.iter())
            .map(|n| {
                [0, 1, 2, 3].map(|c| {
                    if c < 3 {
                        (n[c] * 127.0).round() as i8
                    } else {
                        0
                    }
                })
            })
            .collect();
        let uvs: Vec<[u16; 2]> = (self.uvs.iter())
            .map(|t| t.map(|c| (c * 65535.0).round() as u16))
            .collect();
        let streams: [(&[u8], u32, &str, bool); 3] = [
            (bytemuck::cast_slice(&positions), 5122, "VEC3", false),
            (bytemuck::cast_slice(&normals), 5120, "VEC3", true),
            (bytemuck::cast_slice(&uvs), 5123, "VEC2", true),
        ];
        self.glb(&streams, &["KHR_mesh_quantization"])
    }

    /// [`Grid::floats`] with every stream compressed by meshoptimizer.
    fn meshopt(&self) -> Vec<u8> {
        let streams: [(&[u8], u32, &str, bool); 3] = [
            (bytemuck::cast_slice(&self.positions), 5126, "VEC3", false),
            (bytemuck::cast_slice(&self.normals), 5126, "VEC3", false),
            (bytemuck::cast_slice(&self.uvs), 5126, "VEC2", false),
        ];
        self.glb(&streams, &["EXT_meshopt_compression"])
    }

    /// The GLB of `streams` (bytes, component type, type, normalized) and the indices;
    /// with `EXT_meshopt_compression` among `extensions`, every view compressed.
    fn glb(&self, streams: &[(&[u8], u32, &str, bool)], extensions: &[&str]) -> Vec<u8> {
        let count = self.positions.len();
        let meshopt = extensions.contains(&"EXT_meshopt_compression");
        let mut bin: Vec<u8> = Vec::new();
        let mut fallback = 0;
        let mut views = Vec::new();
        let mut view = |bytes: &[u8], stride: usize, indices: bool| {
            while !bin.len().is_multiple_of(4) {
                bin.push(0);
            }
            let at = bin.len();
            if !meshopt {
                bin.extend_from_slice(bytes);
                views.push(json!({"buffer": 0, "byteOffset": at, "byteLength": bytes.len()}));
                if !indices && let Some(last) = views.last_mut() {
                    last["byteStride"] = json!(stride);
                }
                return views.len() - 1;
            }
            let packed = match indices {
                true => meshopt::encode_index_buffer(bytemuck::cast_slice(bytes), count),
                false => encode(bytes, stride),
            }
            .expect("encodes");
            bin.extend_from_slice(&packed);
            let mode = if indices { "TRIANGLES" } else { "ATTRIBUTES" };
            views.push(
                json!({"buffer": 1, "byteOffset": fallback, "byteLength": bytes.len(),
                "extensions": {"EXT_meshopt_compression": {"buffer": 0, "byteOffset": at,
                "byteLength": packed.len(), "byteStride": stride,
                "count": bytes.len() / stride, "mode": mode}}}),
            );
            if !indices && let Some(last) = views.last_mut() {
                last["byteStride"] = json!(stride);
            }
            fallback += bytes.len().next_multiple_of(4);
            views.len() - 1
        };
        let mut accessors: Vec<Value> = Vec::new();
        for &(bytes, component, kind, normalized) in streams {
            let stride = bytes.len() / count;
            let v = view(bytes, stride, false);
            let mut a = json!({"bufferView": v, "componentType": component, "count": count,
                "type": kind, "normalized": normalized});
            if accessors.is_empty() {
                let (lo, hi) = if component == 5126 {
                    (0.0, 1.0)
                } else {
                    (-32767.0, 32767.0)
                };
                a["min"] = json!([lo, lo, lo]);
                a["max"] = json!([hi, hi, hi]);
            }
            accessors.push(a);
        }
        let v = view(bytemuck::cast_slice(&self.indices), 4, true);
        accessors.push(json!({"bufferView": v, "componentType": 5125,
            "count": self.indices.len(), "type": "SCALAR"}));
        let scale = if streams[0].1 == 5126 {
            1.0
        } else {
            1.0 / 32767.0
        };
        let mut buffers = vec![json!({"byteLength": bin.len()})];
        if meshopt {
            buffers.push(json!({"byteLength": fallback,
                "extensions": {"EXT_meshopt_compression": {"fallback": true}}}));
        }
        let png = "iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR4nGNoaPj/HwAGggL/s75RMwAAAABJRU5ErkJggg==";
        let json = json!({
            "asset": {"version": "2.0"},
            "extensionsUsed": extensions, "extensionsRequired": extensions,
            "scene": 0, "scenes": [{"nodes": [0]}],
            "nodes": [{"mesh": 0, "scale": [scale, scale, scale]}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1,
                "TEXCOORD_0": 2}, "indices": 3, "material": 0}]}],
            "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
            "textures": [{"source": 0}],
            "images": [{"uri": format!("data:image/png;base64,{png}")}],
            "buffers": buffers, "bufferViews": views, "accessors": accessors,
        });
        glb::write_glb(&json, &bin)
    }
}

/// meshoptimizer's vertex codec over elements of `stride` bytes (a multiple of 4).
fn encode(bytes: &[u8], stride: usize) -> meshopt::Result<Vec<u8>> {
    match stride {
        4 => meshopt::encode_vertex_buffer::<[u8; 4]>(bytemuck::cast_slice(bytes)),
        8 => meshopt::encode_vertex_buffer::<[u8; 8]>(bytemuck::cast_slice(bytes)),
        12 => meshopt::encode_vertex_buffer::<[u8; 12]>(bytemuck::cast_slice(bytes)),
        _ => panic!("stride {stride}"),
    }
}
