//! The command line as a user runs it: `info` names the adapter, `cull` writes dumps
//! that follow the contract, bad input gives one line and a non-zero exit.

use std::process::Command;

mod support;

use encase::ShaderType;
use serde_json::Value;
use stereocull::contexts::{DisplayContext, FrameContext};
use stereocull::cull::rig::RigView;

fn stereocull(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_stereocull"))
        .args(args)
        .output()
        .expect("the binary runs")
}

#[test]
fn info_names_the_adapter() {
    let out = stereocull(&["info"]);
    let text = String::from_utf8_lossy(&out.stdout);
    eprintln!("{text}{}", String::from_utf8_lossy(&out.stderr));
    assert!(
        out.status.success(),
        "no adapter: CI must install mesa-vulkan-drivers"
    );
    assert!(text.starts_with("adapter: ") && text.len() > 20, "{text}");
    assert!(text.contains("multi_draw_indirect_count"), "{text}");
    assert!(
        text.contains("\ntier: full"),
        "lavapipe has every feature: {text}"
    );
    let coarse = |preset: &str| {
        text.lines()
            .find(|l| l.trim_start().starts_with(&format!("{preset} ")))
            .map(|l| l.split_whitespace().nth(1).unwrap_or_default().to_string())
    };
    // On a software adapter (lavapipe) auto leaves GPU culling without it: wgpu's
    // indirect validation costs more than it saves there.
    let software = text.lines().next().is_some_and(|l| l.contains(", Cpu,"));
    let gains = if software { "off" } else { "on" };
    for preset in ["hmd-peripheral", "cave"] {
        assert_eq!(coarse(preset).as_deref(), Some(gains), "{text}");
    }
    assert_eq!(software, text.contains("a software adapter"), "{text}");
    assert_eq!(coarse("hmd").as_deref(), Some("off"), "{text}");
}

/// The GL backend lacks indirect count and multiview: `info` names the tier and costs.
#[cfg(feature = "gl")]
#[test]
fn info_on_gl_names_the_fallback_tier_and_its_costs() {
    let out = Command::new(env!("CARGO_BIN_EXE_stereocull"))
        .arg("info")
        .env("WGPU_BACKEND", "gl")
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "no GL adapter: CI must install libegl1 libgl1-mesa-dri"
    );
    assert!(text.contains("(Gl, "), "{text}");
    assert!(text.contains("\ntier: gpu-driven with fallbacks"), "{text}");
    assert!(
        text.contains(&format!("{:40} no  (costs: ", "multi_draw_indirect_count")),
        "{text}"
    );
}

/// Checks one display's dump against the contract and returns its visible count.
fn check_display(d: &Value, scene_meshes: Option<usize>) -> usize {
    let views = d["views"].as_u64().unwrap();
    let visible: Vec<u64> = d["visible"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap())
        .collect();
    let draws = d["draws"].as_array().unwrap();
    assert_eq!(d["draw_count"].as_u64().unwrap() as usize, draws.len());
    let field = |draw: &Value, name: &str| draw[name].as_u64().unwrap();
    // Bin by bin, meshes ascending within a bin (a blended bin: a draw per instance,
    // in sorted order, so a mesh may repeat).
    let mut last = None;
    for draw in draws {
        let at = (field(draw, "bin"), field(draw, "mesh"));
        let blended = draw["blended"].as_bool().unwrap();
        let ascends = last.is_none_or(|l: (u64, u64)| l < at || (blended && l.0 == at.0));
        assert!(ascends, "draws ascend by bin, then mesh");
        last = Some(at);
        if let Some(m) = scene_meshes {
            assert!((at.1 as usize) < m);
        }
    }
    // Their instance ranges tile the visible list, ids ascending within each.
    let mut ranges: Vec<(u64, u64)> = (draws.iter())
        .map(|d| (field(d, "first_instance"), field(d, "instance_count")))
        .collect();
    ranges.sort();
    let mut next_instance = 0;
    for (first, count) in ranges {
        assert_eq!(first, next_instance, "draws are packed");
        assert!(count > 0 && count % views == 0);
        let ids = &visible[(first / views) as usize..((first + count) / views) as usize];
        assert!(
            ids.windows(2).all(|w| w[0] < w[1]),
            "ids ascend within a draw"
        );
        next_instance = first + count;
    }
    assert_eq!(next_instance, views * visible.len() as u64);
    visible.len()
}

fn dump(args: &[&str]) -> Value {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("dump.json");
    let mut all = args.to_vec();
    all.extend(["--dump-visible", path.to_str().unwrap()]);
    let out = stereocull(&all);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap()
}

#[test]
fn cull_dumps_follow_the_contract_for_every_preset() {
    for (rig, displays) in [("hmd", 1), ("cave", 5), ("hmd-peripheral", 3)] {
        let v = dump(&["cull", "--scene", "procedural:5000:12", "--rig", rig]);
        let list = v["displays"].as_array().unwrap();
        assert_eq!(list.len(), displays, "{rig}");
        for d in list {
            let n = check_display(d, Some(12));
            assert!(n > 0 && n < 5000, "{rig} {}: {n} visible", d["name"]);
        }
    }
}

/// `cull --displays A,B`: those displays' dumps equal their entries in the full rig's
/// dump, byte for byte, culled on the GPU and on the CPU, with levels of detail (whose
/// density the whole rig decides: a side panel alone would pick coarser levels) and the
/// far layer (by the frustum alone: the CPU cull has no occlusion).
#[test]
fn a_subset_of_displays_culls_as_the_full_rig() {
    for (rig, subset) in [
        ("cave", "front,left"),
        ("hmd-peripheral", "peripheral-left"),
    ] {
        for cull in ["gpu", "cpu"] {
            let args = [
                "cull",
                "--scene",
                "procedural:20000:8:3",
                "--rig",
                rig,
                "--cull",
                cull,
                "--lod",
                "on",
                "--far-layer",
                "on",
                "--occlusion",
                "off",
            ];
            let full = dump(&args);
            let part = dump(&[&args[..], &["--displays", subset]].concat());
            let names: Vec<&str> = subset.split(',').collect();
            let of = |v: &Value| -> Vec<Value> {
                let list = v["displays"].as_array().unwrap().iter();
                list.filter(|d| {
                    let name = d["name"].as_str().unwrap();
                    names
                        .iter()
                        .any(|n| name == *n || name == format!("{n}.far"))
                })
                .cloned()
                .collect()
            };
            let (expected, got) = (of(&full), of(&part));
            assert!(!expected.is_empty(), "{rig} {subset}");
            assert_eq!(
                got.len(),
                part["displays"].as_array().unwrap().len(),
                "{rig}: only the subset"
            );
            assert_eq!(got, expected, "{rig} {subset} {cull}");
        }
    }
}

/// The shared Khronos samples (CI has them beside the clone): name and path.
fn gltf_samples() -> Vec<(&'static str, String)> {
    [
        "Box",
        "BoxAnimated",
        "BoxTextured",
        "CesiumMilkTruck",
        "AlphaBlendModeTest",
    ]
    .into_iter()
    .map(|name| {
        (
            name,
            support::gltf_sample(name, "glb").display().to_string(),
        )
    })
    .collect()
}

#[test]
fn cull_dumps_the_shared_gltf_samples() {
    for (name, file) in gltf_samples() {
        // 5 m in front of each model, looking at it.
        let v = dump(&[
            "cull", "--scene", &file, "--rig", "hmd", "--viewer", "0,1,6",
        ]);
        let n = check_display(&v["displays"][0], None);
        assert!(n > 0, "{name}: nothing visible");
    }
}

#[test]
fn bad_input_prints_one_line_and_fails() {
    for args in [
        vec!["cull", "--rig", "vive", "--dump-visible", "/tmp/x.json"],
        vec![
            "cull",
            "--scene",
            "procedural:abc",
            "--dump-visible",
            "/tmp/x.json",
        ],
        vec![
            "cull",
            "--scene",
            "procedural:0",
            "--dump-visible",
            "/tmp/x.json",
        ],
        vec![
            "cull",
            "--scene",
            "procedural:10:2:3:shiny",
            "--dump-visible",
            "/tmp/x.json",
        ],
        vec![
            "cull",
            "--scene",
            "/nonexistent.glb",
            "--dump-visible",
            "/tmp/x.json",
        ],
        vec![
            "cull",
            "--rig",
            "/nonexistent.toml",
            "--dump-visible",
            "/tmp/x.json",
        ],
    ] {
        let out = stereocull(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        assert!(err.starts_with("stereocull: "), "{err}");
    }
}

/// Every fuzzing finding renders as one line and exit code 1, never a panic (101).
#[test]
fn hostile_gltf_findings_render_as_one_line_errors() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/fuzz/regressions/gltf_import");
    let out_dir = tempfile::tempdir().unwrap();
    let out_dir = out_dir.path().to_str().unwrap();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let scene = path.to_str().unwrap();
        let out = stereocull(&["render", "--scene", scene, "--out", out_dir]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{scene}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{scene}: {err}");
        assert!(err.starts_with("stereocull: scene "), "{scene}: {err}");
    }
}

fn drawn_pixels(path: &std::path::Path, x0: u32, width: u32) -> usize {
    let image = image::open(path).unwrap().to_rgba8();
    let clear = *image.get_pixel(0, 0);
    (x0..x0 + width)
        .flat_map(|x| (0..image.height()).map(move |y| (x, y)))
        .filter(|&(x, y)| *image.get_pixel(x, y) != clear)
        .count()
}

#[test]
fn render_writes_one_image_per_display_and_stats() {
    for (rig, names) in [
        ("hmd", vec![("hmd", 2)]),
        (
            "cave",
            vec![
                ("front", 2),
                ("left", 2),
                ("right", 2),
                ("floor", 2),
                ("ceiling", 2),
            ],
        ),
        (
            "hmd-peripheral",
            vec![
                ("center", 2),
                ("peripheral-left", 1),
                ("peripheral-right", 1),
            ],
        ),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let out = stereocull(&[
            "render",
            "--rig",
            rig,
            "--width",
            "48",
            "--height",
            "40",
            "--occlusion",
            "off",
            "--out",
            dir.path().to_str().unwrap(),
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        for (name, views) in names {
            let path = dir.path().join(format!("{name}.png"));
            let (w, h) = image::image_dimensions(&path).unwrap();
            assert_eq!((w, h), (48 * views, 40), "{rig} {name}");
        }
        let stats: Value =
            serde_json::from_slice(&std::fs::read(dir.path().join("stats.json")).unwrap()).unwrap();
        assert_eq!(
            stats["frame"]["draw_calls"].as_u64(),
            Some(stats["displays"].as_array().unwrap().len() as u64)
        );
        assert!(stats["adapter"].as_str().unwrap().len() > 3);
    }
}

/// On a machine without a display, Mesa's device-select layer used to print two
/// `error: XDG_RUNTIME_DIR ...` lines before every successful run.
#[test]
fn a_successful_render_prints_no_error_line() {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_stereocull"))
        .args(["render", "--width", "32", "--height", "32", "--out"])
        .arg(dir.path())
        .env_remove("NODEVICE_SELECT")
        .env_remove("XDG_RUNTIME_DIR")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("DISPLAY")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let said = format!("{}{stderr}", String::from_utf8_lossy(&out.stdout));
    assert!(!said.to_lowercase().contains("error"), "{said}");
}

#[test]
fn render_takes_msaa_and_names_the_counts_it_lacks() {
    let dir = tempfile::tempdir().unwrap();
    let args = ["render", "--width", "32", "--height", "24", "--out"];
    let out = stereocull(&[&args[..], &[dir.path().to_str().unwrap(), "--msaa", "4"]].concat());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        image::image_dimensions(dir.path().join("hmd.png")).unwrap(),
        (64, 24)
    );
    // Without --msaa, render antialiases at 4x where the adapter can (lavapipe can).
    let out = stereocull(&[&args[..], &[dir.path().to_str().unwrap()]].concat());
    assert!(out.status.success());
    let stats: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("stats.json")).unwrap()).unwrap();
    assert_eq!(stats["msaa"], 4, "assumes lavapipe");
    let out = stereocull(&[&args[..], &[dir.path().to_str().unwrap(), "--msaa", "3"]].concat());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("--msaa 3") && err.contains("1, 4"),
        "assumes lavapipe: {err}"
    );
}

#[test]
fn render_draws_the_shared_gltf_samples_in_both_eyes() {
    for (name, file) in gltf_samples() {
        let dir = tempfile::tempdir().unwrap();
        let args = [
            "render", "--scene", &file, "--viewer", "0,0.5,4", "--width", "64", "--height", "64",
        ];
        let out = stereocull(&[&args[..], &["--out", dir.path().to_str().unwrap()]].concat());
        assert!(
            out.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let png = dir.path().join("hmd.png");
        assert!(drawn_pixels(&png, 0, 64) > 20, "{name}: left eye empty");
        assert!(drawn_pixels(&png, 64, 64) > 20, "{name}: right eye empty");
    }
}

/// `render` at 40 x 32 pixels per eye with `extra` arguments, into a new directory:
/// the directory and its `stats.json`.
fn render_stats(extra: &[&str]) -> (tempfile::TempDir, Value) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    let args = ["render", "--width", "40", "--height", "32", "--out", out];
    let run = stereocull(&[&args[..], extra].concat());
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    let text = std::fs::read_to_string(dir.path().join("stats.json")).unwrap();
    let stats = serde_json::from_str(&text).unwrap();
    (dir, stats)
}

/// `render --compositor-depth` writes each display's depth layer (4x MSAA resolved to
/// the nearest sample) as raw f32 beside its contract: the file holds width x height
/// values in [0, 1], the drawn pixels nearer than the far plane's 1.
#[test]
fn render_writes_the_compositor_depth_and_its_contract() {
    let (_dir, stats) = render_stats(&["--compositor-depth"]);
    let depth = &stats["displays"][0]["depth"];
    assert_eq!(depth["resolve"], "nearest sample");
    assert_eq!(
        (depth["min_depth"].as_f64(), depth["max_depth"].as_f64()),
        (Some(0.0), Some(1.0))
    );
    assert_eq!(depth["reversed_z"], false);
    assert_eq!(
        depth["views"][1]["rect"],
        serde_json::json!([40, 0, 40, 32])
    );
    assert_eq!(
        (depth["width"].as_u64(), depth["height"].as_u64()),
        (Some(80), Some(32))
    );
    let bytes = std::fs::read(depth["file"].as_str().unwrap()).unwrap();
    let values: Vec<f32> = bytes
        .chunks(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    assert_eq!(values.len(), 80 * 32);
    assert!(values.iter().all(|v| (0.0..=1.0).contains(v)));
    let drawn = values.iter().filter(|&&v| v < 1.0).count();
    assert!(drawn > 200, "{drawn} drawn pixels");
}

/// `render --visibility-mask on` reports the pixels the `hmd` preset's mask hides (its
/// CPU twin's count) and the fragment invocations beside them; off, none are masked.
#[test]
fn render_reports_masked_pixels_and_fragments() {
    let frame = |on: &str| {
        let (_dir, stats) = render_stats(&["--visibility-mask", on, "--msaa", "1"]);
        let frame = &stats["frame"];
        let count = |key: &str| frame[key].as_u64();
        (
            count("masked_pixels").unwrap(),
            count("fragment_invocations"),
            count("samples_passed"),
        )
    };
    let mask = stereocull::rig::VisibilityMask::headset();
    let expected: u64 = (0..2).map(|v| mask.hidden_pixels(v, (40, 32))).sum();
    let (on, off) = (frame("on"), frame("off"));
    assert_eq!((on.0, off.0), (expected, 0));
    assert!(expected > 0);
    // The samples passing depth: the scene's, not the mask's; fewer with the mask (the
    // scene covers some of the hidden area), and never more than the fragments shaded
    // (one sample a fragment without MSAA).
    let (Some(passed_on), Some(passed_off)) = (on.2, off.2) else {
        panic!("samples_passed is reported: {on:?} {off:?}");
    };
    assert!(
        0 < passed_on && passed_on < passed_off,
        "{passed_on} {passed_off}"
    );
    if let (Some(shaded_on), Some(shaded_off)) = (on.1, off.1) {
        assert!(passed_on <= shaded_on && passed_off <= shaded_off);
    }
}

/// `render --motion-vectors on` (4x MSAA, resolved) draws the previous frame at
/// `--previous-yaw` first and writes each display's vectors, width x height x 2 f32:
/// turned right since, the scene moves left, and the background holds zero. A mode
/// that writes none says so in one line.
#[test]
fn render_writes_motion_vectors_from_the_previous_pose() {
    let args = [
        "--motion-vectors",
        "on",
        "--previous-yaw",
        "3",
        "--msaa",
        "4",
    ];
    let (dir, stats) = render_stats(&args);
    let motion = &stats["displays"][0]["motion"];
    assert_eq!(
        (motion["width"].as_u64(), motion["height"].as_u64()),
        (Some(80), Some(32))
    );
    let bytes = std::fs::read(motion["file"].as_str().unwrap()).unwrap();
    let values: Vec<f32> = bytes
        .chunks(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    assert_eq!(values.len(), 80 * 32 * 2);
    let leftward = values.chunks(2).filter(|v| v[0] < -0.2).count();
    let rightward = values.chunks(2).filter(|v| v[0] > 0.2).count();
    assert!(
        leftward > 500 && rightward == 0,
        "{leftward} left, {rightward} right"
    );
    assert!(values.chunks(2).any(|v| v == [0.0, 0.0]), "the background");
    assert!(dir.path().join("hmd-motion.png").exists());

    let out = stereocull(&["render", "--mode", "multiview", "--motion-vectors", "on"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("motion vectors"), "{err}");
}

/// One file of each kind exporters and optimizers write, from the importer's corpus
/// seeds: each renders in both eyes. The lights-only seed loads but has nothing to
/// draw, which `render` says in its one line. (The other seeds are small synthetic
/// files for the parser, not exports.)
#[test]
fn render_draws_every_kind_of_exported_file() {
    let corpus = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/corpus/gltf_import");
    let kinds = [
        ("seed-Box.glb", "a node matrix"),
        ("seed-BoxAnimated.glb", "node animation"),
        ("seed-room.glb", "many meshes and materials"),
        ("seed-lights-box.glb", "KHR_lights_punctual with a mesh"),
        ("seed-two-uv-sets.glb", "a texture on TEXCOORD_1"),
        ("seed-morph-targets.glb", "morph targets, animated"),
        (
            "seed-quantized.glb",
            "KHR_mesh_quantization and a _BARYCENTRIC attribute",
        ),
        ("seed-meshopt-BoxTextured.glb", "EXT_meshopt_compression"),
        ("seed-ktx2-etc1s.glb", "KHR_texture_basisu, ETC1S"),
        (
            "seed-ktx2-uastc.glb",
            "KHR_texture_basisu, UASTC + Zstandard",
        ),
        ("seed-lights.glb", "KHR_lights_punctual alone"),
    ];
    for (name, kind) in kinds {
        let seed = corpus.join(name);
        let dir = tempfile::tempdir().unwrap();
        let args = [
            "render",
            "--scene",
            seed.to_str().unwrap(),
            "--viewer",
            "0,0.5,4",
            "--width",
            "64",
            "--height",
            "64",
            "--out",
            dir.path().to_str().unwrap(),
        ];
        let out = stereocull(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        if name == "seed-lights.glb" {
            assert!(
                stderr.contains("no mesh instances to draw"),
                "{name}: {stderr}"
            );
            continue;
        }
        assert!(out.status.success(), "{name} ({kind}): {stderr}");
        let png = dir.path().join("hmd.png");
        assert!(
            drawn_pixels(&png, 0, 64) > 20,
            "{name} ({kind}): left eye empty"
        );
        assert!(
            drawn_pixels(&png, 64, 64) > 20,
            "{name} ({kind}): right eye empty"
        );
    }
}

/// `stress` of `frames` frames of `scene` on `rig` at 16x16 pixels per eye, occlusion
/// off, its report as JSON: the arguments.
fn stress_args<'a>(scene: &'a str, rig: &'a str, frames: &'a str) -> Vec<&'a str> {
    vec![
        "stress",
        "--scene",
        scene,
        "--rig",
        rig,
        "--frames",
        frames,
        "--width",
        "16",
        "--height",
        "16",
        "--occlusion",
        "off",
        "--json",
    ]
}

/// [`stress_args`] run, its report parsed.
fn stress_json(scene: &str, rig: &str, frames: &str) -> Value {
    let out = stereocull(&stress_args(scene, rig, frames));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

#[test]
fn stress_reports_per_frame_and_summary_figures() {
    let v = stress_json("procedural:20000", "cave", "3");
    assert_eq!(v["frames"].as_array().unwrap().len(), 3);
    let s = &v["summary"];
    assert_eq!(s["draw_calls_per_frame"].as_u64(), Some(5), "one per wall");
    assert_eq!(
        s["dispatches_per_frame"].as_u64(),
        Some(3),
        "the rig cull's three for the five walls: cull, draws, compact"
    );
    let levels = &s["dispatches_per_level"];
    assert_eq!(levels["frame"].as_u64(), Some(3), "{levels}");
    assert_eq!(levels["display"].as_u64(), Some(0), "{levels}");
    assert!(s["cpu_ms_median"].as_f64().unwrap() > 0.0);
    assert_eq!(
        s["memory"].as_array().unwrap().len(),
        3,
        "a sample after each frame"
    );
    assert!(
        s["visible_mean"]
            .as_array()
            .unwrap()
            .iter()
            .all(|v| v.as_f64().unwrap() > 0.0)
    );
}

/// `stress --latch` latches each frame's pose at its submit: the summary says so and
/// reports the pose's age at the submit either way (how the two compare is a figure,
/// docs/performance.md, not a test). With the CPU cull it is the one-line error naming
/// the GPU cull.
#[test]
fn stress_latches_the_pose_at_the_submit() {
    let run = |latch: bool, cull: &str| {
        let mut args = stress_args("procedural:5000", "cave", "5");
        args.extend(["--cull", cull]);
        if latch {
            args.push("--latch");
        }
        stereocull(&args)
    };
    let summary = |latch: bool| {
        let out = run(latch, "gpu");
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v: Value = serde_json::from_slice(&out.stdout).unwrap();
        v["summary"].clone()
    };
    let (latched, sampled) = (summary(true), summary(false));
    assert_eq!(
        (latched["latch"].as_bool(), sampled["latch"].as_bool()),
        (Some(true), Some(false))
    );
    let age = |s: &Value| s["pose_age_at_submit_ms_median"].as_f64().unwrap();
    assert!(age(&latched) > 0.0 && age(&sampled) > 0.0);
    let cpu = run(true, "cpu");
    let err = String::from_utf8_lossy(&cpu.stderr);
    assert!(
        !cpu.status.success() && err.contains("GPU cull") && err.lines().count() == 1,
        "{err}"
    );
}

/// The soak run, shortened for CI (the README's runs 10,000 frames): with the viewer
/// moving every frame, the live wgpu objects and the device allocations stay exactly
/// constant, and process memory does not grow past allocator noise after warm-up (a
/// leak of one small buffer per frame would add tens of MiB here, spread over every
/// interval between samples).
#[test]
fn stress_soak_holds_memory_and_gpu_allocations_constant() {
    let v = stress_json("procedural:1000", "hmd", "1000");
    let memory = v["summary"]["memory"].as_array().unwrap();
    eprintln!("{memory:?}");
    assert_eq!(memory.len(), 11, "after frame 1 and every 100 frames");
    let series =
        |key: &str| -> Vec<Option<u64>> { memory.iter().map(|m| m[key].as_u64()).collect() };
    let objects = series("wgpu_objects");
    assert!(objects[0].is_some_and(|n| n > 0), "{objects:?}");
    assert!(
        objects.iter().all(|n| *n == objects[0]),
        "wgpu objects changed: {objects:?}"
    );
    let allocated = series("gpu_allocated_bytes");
    assert!(
        allocated.iter().all(|n| *n == allocated[0]),
        "device allocations changed: {allocated:?}"
    );
    let rss: Vec<u64> = series("rss_kib").into_iter().map(|r| r.unwrap()).collect();
    // After warm-up, without its largest single step between two samples: on a loaded
    // 2-core machine RSS once stepped up by 30-62 MiB between two samples (the allocator
    // or the driver taking memory once) and stayed flat, with the wgpu objects and
    // device allocations constant. A leak grows in every interval, so removing one
    // interval leaves most of it.
    let steps: Vec<u64> = rss[2..]
        .windows(2)
        .map(|w| w[1].saturating_sub(w[0]))
        .collect();
    let growth = steps.iter().sum::<u64>() - steps.iter().max().unwrap_or(&0);
    assert!(
        growth < 24 * 1024,
        "RSS grew {growth} KiB after frame 200, beside its largest step: {rss:?}"
    );
}

#[test]
fn profile_writes_table_csv_json_and_chart() {
    let dir = tempfile::tempdir().unwrap();
    let out = stereocull(&[
        "profile",
        "--occlusion",
        "off",
        "--instances",
        "300,900",
        "--rig",
        "hmd",
        "--frames",
        "2",
        "--warmup",
        "1",
        "--width",
        "16",
        "--height",
        "16",
        "--out",
        dir.path().to_str().unwrap(),
        "--trace",
        dir.path().join("trace.json").to_str().unwrap(),
    ]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(text.contains("indirect validation"), "{text}");
    // The trace: per configuration a frame scope, the display inside, its passes inside.
    let trace: Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("trace.json")).unwrap()).unwrap();
    let names: Vec<&str> = trace["traceEvents"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["name"].as_str().unwrap())
        .collect();
    assert_eq!(
        names[..4],
        ["hmd multi-camera cpu 300", "hmd", "draw", "draw"]
    );
    let instanced = names
        .iter()
        .position(|n| *n == "hmd instanced gpu 900")
        .unwrap();
    // GPU culling times the floor kernel and the rig cull in the frame scope, before
    // the display.
    assert_eq!(
        names[instanced + 1..instanced + 6],
        ["frame", "cull_floor", "rig_cull", "hmd", "draw"]
    );
    let csv = std::fs::read_to_string(dir.path().join("profile.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some(
            "mode,cull,rig,instances,cpu_ms_median,cpu_ms_p95,gpu_ms_median,gpu_ms_p95,draw_calls,dispatches,bytes_uploaded,adapter,moving_percent,churn_percent,sync_ms_median,triangles_submitted,coarse_cull,sphere_tests,shadows,shadow_passes,floor_ms_median,cull_over_floor,cull_over_floor_wall,moved,staging_ms_median,copy_ms_median,sync_staging_ns_per_move,extra_ns_per_move,fragment_invocations,target_pixels"
        )
    );
    // 3 classic modes (CPU cull only) + instanced and multiview with both culls, per count.
    assert_eq!(lines.count(), 2 * 7);
    let rows: Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("profile.json")).unwrap()).unwrap();
    let rows = rows.as_array().unwrap();
    assert_eq!(rows.len(), 14);
    for r in rows {
        let (mode, calls) = (
            r["mode"].as_str().unwrap(),
            r["draw_calls"].as_u64().unwrap(),
        );
        match mode {
            "instanced" | "multiview" => assert_eq!(calls, 1, "{r}"),
            _ => assert!(calls > 10, "{mode}: one call per visible instance: {r}"),
        }
        assert!(
            r["gpu_ms_median"].as_f64().unwrap() > 0.0,
            "lavapipe has timestamps: {r}"
        );
        let over_floor = r["cull_over_floor"].as_array().unwrap();
        match r["cull"].as_str().unwrap() {
            "gpu" => {
                assert!(r["floor_ms_median"].as_f64().unwrap() > 0.0, "{r}");
                assert_eq!(over_floor.len(), 1, "one display: {r}");
                assert!(over_floor[0]["ratio"].as_f64().unwrap() > 0.0, "{r}");
                assert!(over_floor[0]["wall_ratio"].as_f64().unwrap() > 0.0, "{r}");
            }
            _ => assert!(
                over_floor.is_empty() && r["floor_ms_median"].is_null(),
                "{r}"
            ),
        }
    }
    let svg = std::fs::read_to_string(dir.path().join("profile.svg")).unwrap();
    assert!(
        svg.starts_with("<svg") && svg.contains("polyline") && svg.contains("instanced / gpu cull")
    );
}

/// `profile --cull gpu,cpu --occlusion on`: the CPU-culled row records each frame in two
/// halves (its pyramids read back between them) and draws what the GPU-culled row
/// draws: the same triangles and the same counts per phase.
#[test]
fn profile_culls_by_occlusion_on_the_cpu_too() {
    let dir = tempfile::tempdir().unwrap();
    let out = stereocull(&[
        "profile",
        "--rooms",
        "--instances",
        "400",
        "--rig",
        "hmd",
        "--modes",
        "instanced",
        "--cull",
        "gpu,cpu",
        "--occlusion",
        "on",
        "--frames",
        "2",
        "--warmup",
        "2",
        "--width",
        "32",
        "--height",
        "32",
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rows: Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("profile.json")).unwrap()).unwrap();
    let rows = rows.as_array().unwrap();
    assert_eq!(rows.len(), 2);
    let (gpu, cpu) = (&rows[0], &rows[1]);
    assert_eq!(
        (gpu["cull"].as_str(), cpu["cull"].as_str()),
        (Some("gpu"), Some("cpu"))
    );
    assert_eq!(gpu["triangles_submitted"], cpu["triangles_submitted"]);
    assert_eq!(gpu["occlusion_displays"], cpu["occlusion_displays"]);
    assert!(
        cpu["occlusion_displays"][0]["early"].as_u64().unwrap() > 0,
        "{cpu}"
    );
    let passes: Vec<&str> = (cpu["passes"].as_array().unwrap().iter())
        .map(|p| p["name"].as_str().unwrap())
        .collect();
    // The rooms' lamps: their clusters once per frame, then the display's passes.
    assert_eq!(
        passes,
        ["light_clusters", "draw", "pyramid", "late_draw"],
        "{cpu}"
    );
}

/// `profile --moving 0,5`: the moving row is priced against the static one of the same
/// run, per move and beside a plain copy of the same bytes, phase by phase; the static
/// row stages nothing.
#[test]
fn profile_prices_moves_against_a_plain_copy() {
    let dir = tempfile::tempdir().unwrap();
    let out = stereocull(&[
        "profile",
        "--instances",
        "2000",
        "--rig",
        "hmd",
        "--modes",
        "instanced",
        "--cull",
        "gpu,cpu",
        "--moving",
        "0,5",
        "--frames",
        "3",
        "--warmup",
        "1",
        "--width",
        "8",
        "--height",
        "8",
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rows: Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("profile.json")).unwrap()).unwrap();
    let rows = rows.as_array().unwrap();
    assert_eq!(rows.len(), 4, "two culls, two percents");
    for r in rows {
        let moving = r["moving_percent"].as_f64().unwrap();
        let edits = &r["edits"];
        if moving == 0.0 {
            assert_eq!(r["moved"], 0, "{r}");
            assert_eq!(r["staging_ms_median"].as_f64().unwrap(), 0.0, "{r}");
            assert!(edits.is_null() && r["copy_ms_median"].is_null(), "{r}");
            continue;
        }
        assert_eq!(r["moved"], 100, "5 % of 2,000: {r}");
        let positive = |key: &str| edits[key].as_f64().is_some_and(|v| v > 0.0);
        for key in [
            "copy_ns_per_move",
            "sync_staging_ns_per_move",
            "sync_staging_over_copy",
        ] {
            assert!(positive(key), "{key}: {r}");
        }
        // The GPU culler stages the moves (the CPU one takes them into its layout and
        // uploads its cull results instead).
        if r["cull"] == "gpu" {
            assert!(r["staging_ms_median"].as_f64().unwrap() > 0.0, "{r}");
        }
        for phase in [
            "sync_ms",
            "prepare_ms",
            "staging_ms",
            "encode_ms",
            "submit_ms",
        ] {
            assert!(
                edits[phase].as_f64().is_some_and(f64::is_finite),
                "{phase}: {r}"
            );
        }
    }
    assert_eq!(text.matches("\nedits hmd instanced").count(), 2, "{text}");
}

/// `cull --frames N --moving P --churn P`: the GPU's buffers after N frames of seeded
/// edits equal the CPU reference's, and the edits changed what is visible.
#[test]
fn cull_after_edits_dumps_the_same_buffers_from_gpu_and_cpu() {
    let dir = tempfile::tempdir().unwrap();
    let dump = |cull: &str, frames: &str, moving: &str| {
        let path = dir.path().join(format!("{cull}-{frames}-{moving}.json"));
        let args = [
            "cull",
            "--scene",
            "procedural:6000:12",
            "--rig",
            "cave",
            "--cull",
            cull,
            "--frames",
            frames,
            "--moving",
            moving,
            "--churn",
            "2",
            "--occlusion",
            "off",
            "--dump-visible",
            path.to_str().unwrap(),
        ];
        let out = stereocull(&args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        std::fs::read(path).unwrap()
    };
    let gpu = dump("gpu", "6", "20");
    assert!(
        gpu == dump("cpu", "6", "20"),
        "GPU and CPU dumps differ after edits"
    );
    assert!(gpu != dump("cpu", "1", "0"), "the edits changed nothing");
}

/// `stress --moving --churn --json`: per-frame sync figures, the scatter dispatch, the
/// bytes that moves cost, triangles submitted named in the summary.
#[test]
fn stress_with_moving_instances_reports_what_they_cost() {
    let args = [
        "stress",
        "--scene",
        "procedural:5000",
        "--frames",
        "3",
        "--width",
        "16",
        "--height",
        "16",
        "--moving",
        "10",
        "--occlusion",
        "off",
        "--json",
    ];
    let out = stereocull(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    let frame = &v["frames"][2];
    assert_eq!(frame["moved"], 500);
    assert_eq!(
        frame["dispatches"], 4,
        "the scatter, then the rig cull's three passes"
    );
    // The edits' header, 56 bytes per moved instance, then the frame and display
    // contexts and the display's record in the rig cull.
    let contexts = FrameContext::min_size().get()
        + DisplayContext::min_size().get()
        + RigView::min_size().get();
    let header = size_of::<stereocull::records::EditHeader>() as u64;
    assert_eq!(frame["bytes_uploaded"], header + 56 * 500 + contexts);
    assert!(frame["staging_ms"].as_f64().unwrap() > 0.0, "{frame}");
    let summary = &v["summary"];
    assert!(
        summary["staging_ms_median"].as_f64().unwrap() > 0.0,
        "{summary}"
    );
    assert!(
        summary["triangles_submitted_median"].as_f64().unwrap() > 1000.0,
        "{summary}"
    );
    assert_eq!(summary["moving_percent"], 10.0);
}

/// `stats.json` lists the frame's passes by level: on `cave` with shadows, the coarse
/// cull and occlusion forced on, the frame level runs `coarse_cull`, `shadow_cull` and
/// `shadow` once each, every wall its `cull` and `draw` and occlusion's `pyramid`,
/// `late_cull` and `late_draw`; the shadow and draw passes carry their vertex-shader
/// invocations (lavapipe has pipeline statistics). Each wall's occlusion report adds up.
#[test]
fn render_reports_the_passes_of_each_level() {
    let dir = tempfile::tempdir().unwrap();
    let out = stereocull(&[
        "render",
        "--rig",
        "cave",
        "--width",
        "24",
        "--height",
        "24",
        "--msaa",
        "1",
        "--shadows",
        "on",
        "--coarse-cull",
        "on",
        "--occlusion",
        "on",
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stats: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("stats.json")).unwrap())
            .unwrap();
    let passes = stats["passes"].as_array().unwrap();
    let at = |level: &str| -> Vec<&str> {
        passes
            .iter()
            .filter(|p| p["level"] == level)
            .map(|p| p["name"].as_str().unwrap())
            .collect()
    };
    // Every display's pyramids in one set of dispatches, after every early draw.
    assert_eq!(
        at("frame"),
        ["coarse_cull", "shadow_cull", "shadow", "pyramid"],
        "{stats}"
    );
    // Every display's early half, then (over the coarse cull's blocks) its own late
    // cull, then every display's late draw.
    let halves = [["cull", "draw"].repeat(5), ["late_cull"].repeat(5)];
    let occluded = [halves.concat(), ["late_draw"].repeat(5)].concat();
    assert_eq!(at("display"), occluded, "{stats}");
    let reports = stats["occlusion"].as_array().unwrap();
    assert_eq!(reports.len(), 5, "{stats}");
    for r in reports {
        let n = |k: &str| r[k].as_u64().unwrap();
        assert_eq!(n("frustum"), n("early") + n("late") + n("occluded"), "{r}");
        assert!(n("early") > 0, "primed by two frames: {r}");
    }
    assert!(stats["occlusion_bytes"]["per_display"].as_u64().unwrap() > 0);
    assert!(at("eye").is_empty());
    assert_eq!(stats["passes_per_level"]["frame"], 4);
    assert_eq!(stats["coarse_cull"], true);
    assert_eq!(stats["shadows"], true);
    for p in passes
        .iter()
        .filter(|p| p["name"] == "shadow" || p["name"] == "draw")
    {
        assert!(p["vertex_invocations"].as_u64().unwrap() > 0, "{p}");
    }
    let walls: Vec<&str> = passes
        .iter()
        .filter(|p| p["name"] == "draw")
        .map(|p| p["display"].as_str().unwrap())
        .collect();
    assert_eq!(walls, ["front", "left", "right", "floor", "ceiling"]);
}

/// With the far layer and occlusion, a display's far layer waits for its pyramids: its
/// cull and pass run between the late cull and the late draw (which opens with the
/// composite), and the occlusion report counts the far instances the frustum keeps and
/// those the pyramids hide.
#[test]
fn render_culls_the_far_layer_against_the_pyramids() {
    let dir = tempfile::tempdir().unwrap();
    let out = stereocull(&[
        "render",
        "--scene",
        "city:4000",
        "--rig",
        "hmd",
        "--width",
        "64",
        "--height",
        "64",
        "--far-layer",
        "on",
        "--occlusion",
        "on",
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stats: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("stats.json")).unwrap())
            .unwrap();
    let passes: Vec<&str> = (stats["passes"].as_array().unwrap().iter())
        .filter(|p| p["level"] == "display")
        .map(|p| p["name"].as_str().unwrap())
        .collect();
    // The early and late culls are the frame's rig cull's, the pyramids a frame pass.
    let order = ["draw", "far_cull", "far_layer", "late_draw"];
    assert_eq!(passes, order, "{stats}");
    let all: Vec<&str> = (stats["passes"].as_array().unwrap().iter())
        .map(|p| p["name"].as_str().unwrap())
        .collect();
    let frame = ["rig_cull", "draw", "pyramid", "rig_late_cull", "far_cull"];
    assert_eq!(all[..5], frame, "{stats}");
    let report = &stats["occlusion"][0];
    let n = |k: &str| report[k].as_u64().unwrap();
    assert!(
        n("far_frustum") > 0 && n("far_occluded") <= n("far_frustum"),
        "{report}"
    );
}

/// With the far layer (and shadows and the coarse cull, which change no cull), `cull`
/// dumps each stereo display's near cull and its far cull (`<name>.far`, one view),
/// GPU and CPU alike (by the frustum alone: the CPU cull has no occlusion); together
/// they hold what the display sees without it.
#[test]
fn cull_dumps_far_layers_alike_on_gpu_and_cpu() {
    let base = [
        "cull",
        "--scene",
        "city:4000",
        "--rig",
        "hmd-peripheral",
        "--width",
        "64",
        "--height",
        "64",
        "--occlusion",
        "off",
    ];
    let with = [
        &base[..],
        &[
            "--far-layer",
            "on",
            "--shadows",
            "on",
            "--coarse-cull",
            "on",
        ],
    ]
    .concat();
    let cpu = dump(&[&with[..], &["--cull", "cpu"]].concat());
    let gpu = dump(&[&with[..], &["--cull", "gpu"]].concat());
    assert_eq!(cpu, gpu);
    let names: Vec<&str> = cpu["displays"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d["name"].as_str().unwrap())
        .collect();
    assert_eq!(
        names,
        [
            "center",
            "peripheral-left",
            "peripheral-right",
            "center.far"
        ]
    );
    let ids = |d: &Value| -> Vec<u64> {
        let mut v: Vec<u64> = d["visible"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_u64().unwrap())
            .collect();
        v.sort();
        v
    };
    let whole = dump(&[&base[..], &["--cull", "cpu"]].concat());
    let mut both = [ids(&cpu["displays"][0]), ids(&cpu["displays"][3])].concat();
    both.sort();
    assert!(
        !ids(&cpu["displays"][3]).is_empty(),
        "the city's buildings are far"
    );
    assert_eq!(both, ids(&whole["displays"][0]));
}

/// `cull --occlusion on` culls rendered frames on the CPU too (their pyramids read back
/// halfway): after three frames of a walk-in viewer, the early (`<name>`) and late
/// (`<name>.late`) phases and the far layer's cull are the GPU's byte for byte.
#[test]
fn cull_with_occlusion_dumps_alike_on_gpu_and_cpu() {
    let base = [
        "cull",
        "--scene",
        "rooms:400:5",
        "--rig",
        "hmd",
        "--width",
        "64",
        "--height",
        "48",
        "--occlusion",
        "on",
        "--frames",
        "3",
        "--far-layer",
        "on",
    ];
    let cpu = dump(&[&base[..], &["--cull", "cpu"]].concat());
    let gpu = dump(&[&base[..], &["--cull", "gpu"]].concat());
    assert_eq!(cpu, gpu);
    let names: Vec<&str> = (cpu["displays"].as_array().unwrap().iter())
        .map(|d| d["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["hmd", "hmd.far", "hmd.late"]);
    assert!(!cpu["displays"][0]["visible"].as_array().unwrap().is_empty());
}

/// `cull --occlusion on` after frames of churn (instances removed and inserted again,
/// others moving): the GPU's early and late phases equal the CPU cull's on every preset
/// that culls by occlusion, and the churn changed what they hold. (CPU culling once
/// kept a re-inserted instance's place marked as drawn last frame.)
#[test]
fn cull_with_occlusion_after_churn_dumps_alike_on_gpu_and_cpu() {
    for rig in ["hmd", "cave", "hmd-peripheral"] {
        let run = |cull: &str, churn: &str| {
            let args = [
                "cull",
                "--scene",
                "rooms:2000:3",
                "--rig",
                rig,
                "--width",
                "64",
                "--height",
                "48",
                "--occlusion",
                "on",
                "--frames",
                "4",
                "--moving",
                "5",
                "--churn",
                churn,
                "--cull",
                cull,
            ];
            dump(&args)
        };
        let gpu = run("gpu", "5");
        assert_eq!(run("cpu", "5"), gpu, "{rig}");
        assert_ne!(run("gpu", "0"), gpu, "{rig}: the churn changed nothing");
    }
}

/// `diff` states what LOD costs in pixels: LOD on against off differs in some pixels but
/// not most (at 160 x 160 about 16 %: objects a few pixels wide, their silhouettes moved
/// by up to a pixel), an image against itself in none, and images of two sizes give one line and
/// a non-zero exit.
#[test]
fn diff_counts_the_pixels_lod_changes() {
    let dir = tempfile::tempdir().unwrap();
    let render = |lod: &str, size: &str| {
        let out_dir = dir.path().join(format!("{lod}-{size}"));
        let out = stereocull(&[
            "render",
            "--scene",
            "procedural:3000",
            "--lod",
            lod,
            "--width",
            size,
            "--height",
            size,
            "--out",
            out_dir.to_str().unwrap(),
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        out_dir.join("hmd.png").to_str().unwrap().to_string()
    };
    let (on, off) = (render("on", "160"), render("off", "160"));
    let diff_png = dir.path().join("diff.png");
    let differing = |a: &str, b: &str| {
        let out = stereocull(&["diff", a, b, "--out", diff_png.to_str().unwrap()]);
        let text = String::from_utf8_lossy(&out.stdout).to_string();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(text.starts_with("320 x 160: "), "{text}");
        text.split_whitespace()
            .nth(3)
            .unwrap()
            .parse::<u64>()
            .unwrap()
    };
    let lod = differing(&on, &off);
    assert!(
        lod > 0 && lod < 320 * 160 / 4,
        "{lod} pixels differ with LOD"
    );
    assert_eq!(image::image_dimensions(&diff_png).unwrap(), (320, 160));
    assert_eq!(differing(&on, &on), 0);
    let out = stereocull(&["diff", &on, &render("on", "96")]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("only images of one size compare"), "{err}");
}

/// A foveated rig renders its composite as `<name>.png` (each eye at the display's
/// resolution) and its four views as drawn as `<name>-views.png`, and `stats.json` gives
/// the views and where each lies; a gaze far off the axis is clamped and said so; a gaze
/// on a rig without foveation is one line.
#[test]
fn render_composites_a_foveated_display() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().to_str().unwrap();
    let args = [
        "render",
        "--rig",
        "hmd-foveated",
        "--width",
        "64",
        "--height",
        "48",
    ];
    for (gaze, clamped) in [("5,2", false), ("60,0", true)] {
        let out = stereocull(&[&args[..], &["--gaze", gaze, "--out", out_dir]].concat());
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{stderr}");
        assert_eq!(stderr.contains("moved inside"), clamped, "{stderr}");
        let size = |name: &str| image::image_dimensions(dir.path().join(name)).unwrap();
        assert_eq!(
            size("hmd.png"),
            (128, 48),
            "each eye at the display's resolution"
        );
        // Outer views at half density (32 x 24), insets at 0.35 of 64 x 48 (22 x 17).
        assert_eq!(size("hmd-views.png"), (2 * 32 + 2 * 22, 24));
        let stats: Value =
            serde_json::from_slice(&std::fs::read(dir.path().join("stats.json")).unwrap()).unwrap();
        let display = &stats["displays"][0];
        assert_eq!(display["views"], 4);
        assert_eq!(display["gaze_clamped"], clamped);
        assert_eq!(display["pixels"], 2 * 32 * 24 + 2 * 22 * 17);
        assert_eq!(display["viewports"][2], serde_json::json!([64, 0, 22, 17]));
    }
    let out = stereocull(&["render", "--gaze", "1,1", "--width", "16", "--height", "16"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("--gaze") && err.contains("no foveated display"),
        "{err}"
    );
}

/// The inset cull's dump (`<name>.inset`) is the same from the GPU and the CPU.
#[test]
fn cull_dumps_inset_culls_alike_on_gpu_and_cpu() {
    let dir = tempfile::tempdir().unwrap();
    let path = |cull: &str| dir.path().join(format!("{cull}.json"));
    for cull in ["gpu", "cpu"] {
        let out = stereocull(&[
            "cull",
            "--scene",
            "procedural:20000:8",
            "--rig",
            "hmd-foveated",
            "--gaze",
            "8,3",
            "--inset-cull",
            "on",
            "--cull",
            cull,
            "--dump-visible",
            path(cull).to_str().unwrap(),
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let read = |cull: &str| -> Value {
        serde_json::from_slice(&std::fs::read(path(cull)).unwrap()).unwrap()
    };
    let (gpu, cpu) = (read("gpu"), read("cpu"));
    assert_eq!(gpu, cpu);
    let names: Vec<_> = gpu["displays"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d["name"].clone())
        .collect();
    assert_eq!(names, ["hmd", "hmd.inset"]);
    let visible: Vec<usize> = (gpu["displays"].as_array().unwrap().iter())
        .map(|d| {
            assert_eq!(d["views"], 2);
            check_display(d, None)
        })
        .collect();
    assert!(
        visible[1] > 0 && 2 * visible[1] < visible[0],
        "{visible:?}: the insets see less"
    );
}

/// `render --time T` poses a file's node animations at T (`--animation off`: its rest
/// pose whatever the time), and `stress` plays them on its clock: posed on the CPU,
/// only the animated instance is uploaded again each frame; on the GPU, nothing more
/// than a still frame's.
#[test]
fn render_poses_node_animations_at_its_time() {
    let file = gltf_samples()
        .into_iter()
        .find(|(name, _)| *name == "BoxAnimated")
        .unwrap()
        .1;
    let dir = tempfile::tempdir().unwrap();
    let render = |time: &str, animation: &str| {
        let out_dir = dir.path().join(format!("{time}-{animation}"));
        let out = stereocull(&[
            "render",
            "--scene",
            &file,
            "--viewer",
            "0,1,6",
            "--width",
            "48",
            "--height",
            "40",
            "--time",
            time,
            "--animation",
            animation,
            "--out",
            out_dir.to_str().unwrap(),
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        std::fs::read(out_dir.join("hmd.png")).unwrap()
    };
    let rest = render("0", "on");
    assert_ne!(render("2", "on"), rest, "posed at 2 s");
    assert_eq!(
        render("2", "off"),
        rest,
        "--animation off keeps the rest pose"
    );
    let uploads = |animation: &str, posing: &str| {
        let out = stereocull(&[
            "stress",
            "--scene",
            &file,
            "--frames",
            "3",
            "--width",
            "16",
            "--height",
            "16",
            "--animation",
            animation,
            "--posing",
            posing,
            "--json",
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let report: Value = serde_json::from_slice(&out.stdout).unwrap();
        (report["frames"].as_array().unwrap().iter())
            .map(|f| f["bytes_uploaded"].as_u64().unwrap())
            .collect::<Vec<u64>>()
    };
    let (on, off) = (uploads("on", "cpu"), uploads("off", "cpu"));
    let posed = on.iter().zip(&off).all(|(a, b)| a > b);
    assert!(
        posed,
        "posed on the CPU, each frame sends the pose: {on:?} against {off:?}"
    );
    let on_gpu = uploads("on", "gpu");
    assert_eq!(on_gpu, off, "posed on the GPU, only the time changes");
}

/// A skinned file plays in `stress`: one skinning pass per frame at the frame level,
/// the same skinned vertices per frame on `hmd` and on `cave`'s five walls (per-eye
/// skinning would be ten times as many there).
#[test]
fn stress_skins_once_per_frame_whatever_the_rig() {
    let file = support::gltf_sample("SimpleSkin", "gltf")
        .display()
        .to_string();
    let skinned = |rig: &str| {
        let report = stress_json(&file, rig, "3");
        let frame_passes = &report["frames"][2]["passes"];
        let skins = (frame_passes.as_array().unwrap().iter())
            .filter(|p| p["name"] == "skin" && p["level"] == "frame")
            .count();
        assert_eq!(skins, 1, "{rig}: one skinning pass");
        report["summary"]["skinned_vertices_per_frame"]
            .as_u64()
            .unwrap()
    };
    let (hmd, cave) = (skinned("hmd"), skinned("cave"));
    assert_eq!((hmd, cave), (10, 10), "cave / hmd = 1");
}

/// `profile --crowd` plays the walking crowd on its clock in every mode: each
/// configuration's traced frame holds the frame-level `skin` pass, and those culled on
/// the GPU a `pose` pass (posed on the GPU by default there).
#[test]
fn profile_plays_the_crowd_in_every_mode() {
    let dir = tempfile::tempdir().unwrap();
    let trace = dir.path().join("trace.json");
    let out = stereocull(&[
        "profile",
        "--crowd",
        "--instances",
        "30",
        "--rig",
        "hmd",
        "--frames",
        "2",
        "--warmup",
        "1",
        "--width",
        "16",
        "--height",
        "16",
        "--occlusion",
        "off",
        "--out",
        dir.path().to_str().unwrap(),
        "--trace",
        trace.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let trace: Value = serde_json::from_slice(&std::fs::read(trace).unwrap()).unwrap();
    let events = trace["traceEvents"].as_array().unwrap();
    let configurations = events.iter().filter(|e| {
        e["name"]
            .as_str()
            .is_some_and(|n| n.starts_with("hmd ") && n.ends_with(" 30"))
    });
    let skins = events.iter().filter(|e| e["name"] == "skin").count();
    assert!(
        skins > 0 && skins == configurations.count(),
        "one skin pass per configuration's frame: {skins}"
    );
    // `--posing auto`: on the GPU exactly where the cull runs there, one pose pass each.
    let rows: Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("profile.json")).unwrap()).unwrap();
    let rows = rows.as_array().unwrap();
    assert!(rows.iter().all(|r| r["posing"] == r["cull"]), "{rows:?}");
    let gpu_posed = rows.iter().filter(|r| r["posing"] == "gpu").count();
    let poses = events.iter().filter(|e| e["name"] == "pose").count();
    assert!(
        gpu_posed > 0 && poses == gpu_posed,
        "{poses} pose passes, {gpu_posed} rows"
    );
}

/// `--frames-per-submit 2`: `render` writes each display's second frame beside its
/// first (the same viewer, `--dt` later), each a display's stereo image; `stress` walks
/// the viewer through both and reports the CPU per displayed frame.
#[test]
fn two_frames_per_submission_write_the_next_frame_and_its_cpu_share() {
    let (dir, stats) = render_stats(&["--rig", "cave", "--frames-per-submit", "2", "--msaa", "1"]);
    assert_eq!(stats["frames_per_submit"].as_u64(), Some(2));
    for d in stats["displays"].as_array().unwrap() {
        let name = d["name"].as_str().unwrap();
        let next = dir.path().join(format!("{name}-next.png"));
        assert_eq!(d["next_image"].as_str(), next.to_str(), "{name}");
        let (first, second) = (
            image::open(dir.path().join(format!("{name}.png"))),
            image::open(&next),
        );
        let (first, second) = (first.unwrap().to_rgba8(), second.unwrap().to_rgba8());
        assert_eq!(first.dimensions(), (80, 32), "{name}: one frame's two eyes");
        assert_eq!(second.dimensions(), first.dimensions(), "{name}");
    }
    // A node animation is posed for each frame: the box turns between the two images.
    let animated = support::gltf_sample("BoxAnimated", "glb");
    let out_dir = dir.path().join("animated");
    let out = stereocull(&[
        "render",
        "--scene",
        animated.to_str().unwrap(),
        "--viewer",
        "0,1,6",
        "--time",
        "0.5",
        "--dt",
        "0.3",
        "--frames-per-submit",
        "2",
        "--width",
        "48",
        "--height",
        "48",
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let read = |f: &str| image::open(out_dir.join(f)).unwrap().to_rgba8();
    let (now, next) = (read("hmd.png"), read("hmd-next.png"));
    let turned = now
        .pixels()
        .zip(next.pixels())
        .filter(|(a, b)| a != b)
        .count();
    assert!(turned > 20, "the box barely moved: {turned} pixels");
    let mut args = stress_args("procedural:5000", "hmd", "3");
    args.extend(["--frames-per-submit", "2"]);
    let out = stereocull(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    let s = &v["summary"];
    assert_eq!(s["frames_per_submit"].as_u64(), Some(2));
    let (per_submit, per_frame) = (
        s["cpu_ms_median"].as_f64().unwrap(),
        s["cpu_ms_per_displayed_frame_median"].as_f64().unwrap(),
    );
    assert!(
        per_frame > 0.0 && (per_frame * 2.0 - per_submit).abs() < 1e-9,
        "{s}"
    );
    // The classic modes submit each frame on its own: one line, not a frame.
    let out = stereocull(&[
        "render",
        "--mode",
        "multi-pass",
        "--cull",
        "cpu",
        "--frames-per-submit",
        "2",
        "--width",
        "16",
        "--height",
        "16",
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.lines().count() == 1 && stderr.contains("one at a time"),
        "{stderr}"
    );
}

/// `profile --keep-unchanged off,on`: its viewer holds still, so the `on` rows redraw
/// only the tiles their moved instances changed after the first (warm-up) frame, and
/// the comparison against the `off` rows is printed; a mode that never keeps is
/// skipped with its reason.
#[test]
fn profile_compares_keeping_unchanged_pixels_with_drawing_whole() {
    let dir = tempfile::tempdir().unwrap();
    let out = stereocull(&[
        "profile",
        "--instances",
        "2000",
        "--rig",
        "hmd",
        "--modes",
        "instanced,multi-pass",
        "--cull",
        "cpu",
        "--moving",
        "1",
        "--keep-unchanged",
        "off,on",
        "--frames",
        "3",
        "--warmup",
        "1",
        "--width",
        "64",
        "--height",
        "64",
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(text.contains("unchanged pixels kept"), "{text}");
    assert!(
        text.contains("skipped multi-pass with --keep-unchanged on"),
        "{text}"
    );
    let rows: Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("profile.json")).unwrap()).unwrap();
    let rows = rows.as_array().unwrap();
    assert_eq!(rows.len(), 3, "instanced off and on, multi-pass off");
    for r in rows {
        let tiles = r["tiles_changed_median"].as_f64().unwrap();
        match r["keep_unchanged"].as_str().unwrap() {
            "on" => {
                assert_eq!(r["whole_redraws"], 0, "every timed frame keeps: {r}");
                assert!(tiles > 0.0 && tiles <= 32.0, "two eyes of 4 x 4 tiles: {r}");
            }
            _ => assert_eq!(tiles, 0.0, "{r}"),
        }
    }
}

/// `stress --still --keep-unchanged on` redraws only the changed tiles after its first
/// frame and reports them; what never keeps is refused with one line.
#[test]
fn a_still_head_keeps_unchanged_pixels_and_stress_reports_the_tiles() {
    let mut args = stress_args("procedural:2000", "hmd", "4");
    args.extend(["--still", "--moving", "1", "--keep-unchanged", "on"]);
    let out = stereocull(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    let frames = v["frames"].as_array().unwrap();
    assert_eq!(frames[0]["whole_redraw"].as_str(), Some("first_frame"));
    assert!(
        frames[1..].iter().all(|f| f["whole_redraw"].is_null()),
        "{v}"
    );
    // 16 x 16 pixels per eye: one tile each, 256 pixels a tile.
    let pixels = |f: &Value| f["pixels_redrawn"].as_u64().unwrap();
    assert_eq!(pixels(&frames[0]), 2 * 16 * 16, "{v}");
    for f in &frames[1..] {
        assert_eq!(pixels(f), 256 * f["tiles_changed"].as_u64().unwrap(), "{v}");
    }
    let s = &v["summary"];
    assert_eq!(s["whole_redraws"].as_u64(), Some(1));
    assert!(s["tiles_changed_median"].as_f64().unwrap() > 0.0, "{s}");
    assert!(s["pixels_redrawn_median"].as_f64().unwrap() > 0.0, "{s}");
    assert!(s.get("fragment_invocations_median").is_some(), "{s}");
    let mut args = stress_args("procedural:200", "hmd", "2");
    args.extend(["--keep-unchanged", "on", "--motion-vectors", "on"]);
    let out = stereocull(&args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.lines().count() == 1 && stderr.contains("motion"),
        "{stderr}"
    );
}
