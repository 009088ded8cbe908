//! Rig presets, the example rig files, and what a user sees for a bad rig.

use stereocull::rig::{Mount, PRESETS, Rig};

fn assets(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/rigs")
        .join(name)
}

/// The files in assets/rigs describe exactly the presets, in JSON and in TOML.
/// `STEREOCULL_RECORD=1` rewrites them from the presets.
#[test]
fn example_rig_files_equal_the_presets() {
    for preset in PRESETS {
        let rig = Rig::preset(preset).unwrap();
        for ext in ["json", "toml"] {
            let path = assets(&format!("{preset}.{ext}"));
            if std::env::var_os("STEREOCULL_RECORD").is_some() {
                let text = match ext {
                    "json" => serde_json::to_string_pretty(&rig).unwrap(),
                    _ => toml::to_string(&rig).unwrap(),
                };
                std::fs::write(&path, text).unwrap();
            }
            let loaded = Rig::load(path.to_str().unwrap()).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(loaded, rig, "{}", path.display());
        }
    }
}

fn error_of(text: &str, ext: &str) -> String {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(format!("rig.{ext}"));
    std::fs::write(&path, text).unwrap();
    let e = Rig::load(path.to_str().unwrap()).expect_err("a bad rig loaded");
    let msg = e.to_string();
    assert!(
        msg.contains("rig.") && !msg.contains('\n'),
        "one line naming the file: {msg}"
    );
    msg
}

fn hmd_json() -> String {
    serde_json::to_string_pretty(&Rig::preset("hmd").unwrap()).unwrap()
}

#[test]
fn malformed_rig_files_name_the_line_or_field() {
    let msg = error_of(
        "{\n  \"viewer\": {\n    \"position\": [0, 1,]\n  }\n}",
        "json",
    );
    assert!(msg.contains("line 3"), "{msg}");
    let msg = error_of(&hmd_json().replace("\"ipd\"", "\"ipdd\""), "json");
    assert!(msg.contains("ipdd"), "{msg}");
    let msg = error_of("[viewer]\nposition = [0, 1]\n", "toml");
    assert!(msg.contains("line 2") || msg.contains("position"), "{msg}");
}

#[test]
fn out_of_range_values_are_refused_with_the_field_named() {
    let rig = || Rig::preset("hmd").unwrap();
    let check = |mutate: &dyn Fn(&mut Rig), needle: &str| {
        let mut r = rig();
        mutate(&mut r);
        let msg = r.validate("test").expect_err("accepted").to_string();
        assert!(msg.contains(needle), "{needle:?} not in {msg:?}");
    };
    check(&|r| r.viewer.ipd = -0.01, "ipd");
    check(&|r| r.near = 2000.0, "near");
    check(&|r| r.far = f32::INFINITY, "far");
    check(&|r| r.displays[0].resolution = [0, 100], "resolution");
    let fov =
        |r: &mut Rig, f: &dyn Fn(&mut stereocull::frustum::Fov)| match &mut r.displays[0].mount {
            Mount::Head(h) => f(&mut h.fov),
            Mount::Screen(_) | Mount::Views(_) => panic!("hmd is head-fixed"),
        };
    check(&|r| fov(r, &|f| f.left = f32::INFINITY), "fov");
    check(&|r| fov(r, &|f| f.right = -2.0), "fov");
    check(&|r| r.displays.clear(), "at least one display");
    check(&|r| r.viewer.position[0] = f32::NAN, "finite");
    // A display with neither mount, or both, cannot be built; a file can say it.
    let mut neither: serde_json::Value = serde_json::from_str(&hmd_json()).unwrap();
    neither["displays"][0]
        .as_object_mut()
        .unwrap()
        .remove("head");
    let msg = error_of(&neither.to_string(), "json");
    assert!(msg.contains("exactly one"), "{msg}");
    let mut cave = Rig::preset("cave").unwrap();
    if let Mount::Screen(s) = &mut cave.displays[0].mount {
        s.lower_right = s.lower_left;
    }
    let msg = cave.validate("cave").unwrap_err().to_string();
    assert!(msg.contains("degenerate") && msg.contains("front"), "{msg}");
}

#[test]
fn unknown_presets_list_the_known_ones() {
    let msg = Rig::load("vive").unwrap_err().to_string();
    assert!(msg.contains("hmd, cave, hmd-peripheral"), "{msg}");
}

#[test]
fn a_viewer_behind_a_cave_wall_is_an_error_not_a_wrong_frustum() {
    let mut cave = Rig::preset("cave").unwrap();
    cave.viewer.position = [0.0, 1.6, -2.0];
    let msg = cave.resolve().unwrap_err().to_string();
    assert!(msg.contains("behind the screen"), "{msg}");
}

#[test]
fn every_rig_file_in_assets_loads() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/rigs");
    let mut count = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        let rig = Rig::load(path.to_str().unwrap()).unwrap_or_else(|e| panic!("{e}"));
        assert!(!rig.displays.is_empty());
        count += 1;
    }
    assert!(count >= 7, "{count} rig files");
}
