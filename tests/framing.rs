//! The viewer placed from the scene: `--viewer fit` (every eye sees the whole scene,
//! and the scene's bounding sphere touches the tightest window's edge) and `--camera N`
//! (the file's camera, equal to the same pose and field of view given by hand).

use std::path::{Path, PathBuf};
use std::process::Command;

use glam::{DVec3, EulerRot, Quat, Vec3, Vec4};
use serde_json::json;
use stereocull::frustum::View;
use stereocull::rig::framing::{FACING_DEG, FIT_ELEVATION_DEG, fit_viewer};
use stereocull::rig::{Mount, Rig};

mod support;

use support::glb::{split_glb, write_glb};

/// The signed distances of `sphere`'s center from `eye`'s four side planes, in f64.
fn side_distances(eye: &View, sphere: Vec4) -> [f64; 4] {
    let [l, r, u, d] = eye.fov.tangents();
    let to_center = sphere.truncate().as_dvec3() - eye.world_from_view.translation;
    [
        DVec3::new(1.0, 0.0, -l),
        DVec3::new(-1.0, 0.0, -r),
        DVec3::new(0.0, 1.0, -d),
        DVec3::new(0.0, -1.0, -u),
    ]
    .map(|n| {
        let n = eye.world_from_view.transform_vector3(n.normalize());
        n.dot(to_center)
    })
}

#[test]
fn a_fitted_viewer_sees_the_whole_sphere_in_every_eye_and_no_farther_than_it_must() {
    let spheres = [
        Vec4::new(3.0, -2.0, 7.0, 0.05),
        Vec4::new(0.0, 1.0, -3.0, 1.0),
        Vec4::new(-500.0, 20.0, 1000.0, 150.0),
    ];
    for preset in ["hmd", "hmd-foveated", "hmd-peripheral"] {
        for (k, &sphere) in spheres.iter().enumerate() {
            let mut rig = Rig::preset(preset).unwrap();
            rig.viewer.yaw_deg = 35.0 * k as f32;
            rig.viewer.pitch_deg = -FIT_ELEVATION_DEG;
            let distance = fit_viewer(&mut rig, sphere).unwrap();
            let resolved = rig.resolve().unwrap();
            let from_viewer = sphere.truncate().as_dvec3() - rig.viewer.position();
            assert!((from_viewer.length() - distance).abs() < 1e-3 * distance);
            // The displays that look where the viewer looks: the peripheral rig's
            // turned panels see the scene's side, if anything.
            let forward = rig.viewer.orientation() * DVec3::NEG_Z;
            let mut tightest = f64::INFINITY;
            for eye in resolved.displays.iter().flat_map(|d| d.eyes.iter().take(2)) {
                let axis = eye.world_from_view.transform_vector3(DVec3::NEG_Z);
                if axis.dot(forward) < FACING_DEG.to_radians().cos() {
                    continue;
                }
                let r = f64::from(sphere.w);
                for s in side_distances(eye, sphere) {
                    assert!(s >= r * (1.0 - 1e-6), "{preset} {k}: {s} < {r}");
                    tightest = tightest.min((s - r) / r);
                }
                let planes = eye.frustum().planes;
                assert!(stereocull::frustum::sphere_in_planes(&planes, sphere));
            }
            assert!(
                tightest < 1e-4,
                "{preset} {k}: the sphere stays {tightest} off"
            );
        }
    }
}

#[test]
fn a_room_fixed_rig_is_not_fitted() {
    let mut rig = Rig::preset("cave").unwrap();
    let err = fit_viewer(&mut rig, Vec4::new(0.0, 0.0, 0.0, 1.0)).unwrap_err();
    assert!(err.contains("fixed in the room"), "{err}");
}

/// Box.glb (a 1 m cube) scaled by `scale` about its center and moved to `at`, under a
/// new root; with `camera`, a perspective camera node at that position and rotation.
fn placed_box(scale: f32, at: Vec3, camera: Option<(Vec3, Quat)>) -> Vec<u8> {
    let glb = std::fs::read(support::gltf_sample("Box", "glb")).unwrap();
    let (mut json, bin) = split_glb(&glb);
    let roots = json["scenes"][0]["nodes"].clone();
    let nodes = json["nodes"].as_array_mut().unwrap();
    let scale = [scale; 3];
    nodes.push(json!({"children": roots, "scale": scale, "translation": at.to_array()}));
    let mut top = vec![json!(nodes.len() - 1)];
    if let Some((position, rotation)) = camera {
        let node = json!({"camera": 0, "translation": position.to_array(), "rotation": rotation.to_array()});
        nodes.push(node);
        top.push(json!(nodes.len() - 1));
        let perspective = json!({"yfov": 0.7, "znear": 0.02, "zfar": 80.0});
        json["cameras"] = json!([{"type": "perspective", "perspective": perspective}]);
    }
    json["scenes"][0]["nodes"] = json!(top);
    write_glb(&json, &bin)
}

fn stereocull(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_stereocull"))
        .args(args)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    let errors = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{args:?}: {text}{errors}");
    text
}

fn render(scene: &Path, out: &Path, more: &[&str]) -> image::RgbaImage {
    let (scene, dir) = (scene.to_str().unwrap(), out.to_str().unwrap());
    let mut args = vec![
        "render", "--scene", scene, "--width", "96", "--height", "96",
    ];
    args.extend_from_slice(more);
    args.extend_from_slice(&["--out", dir]);
    stereocull(&args);
    image::open(out.join("hmd.png")).unwrap().to_rgba8()
}

/// Per eye (left half, right half): the share of pixels that are not the background
/// (the top-left corner's color), and whether the half's border is all background.
fn coverage(image: &image::RgbaImage) -> [(f64, bool); 2] {
    let background = *image.get_pixel(0, 0);
    let (w, h) = (image.width() / 2, image.height());
    [0, 1].map(|eye| {
        let (mut covered, mut border_clear) = (0, true);
        for y in 0..h {
            for x in 0..w {
                let object = *image.get_pixel(eye * w + x, y) != background;
                covered += u32::from(object);
                let on_border = x == 0 || y == 0 || x == w - 1 || y == h - 1;
                border_clear &= !(object && on_border);
            }
        }
        (f64::from(covered) / f64::from(w * h), border_clear)
    })
}

/// A 10 cm box and a 200 m one, each away from the origin: `--viewer fit` shows each
/// whole in both eyes (nothing touches a half's border) and large: its bounding sphere
/// touches the tightest edge of the `hmd`'s asymmetric windows, so the cube inside it,
/// seen from 20 degrees above, covers a tenth of each eye or more (14 % here).
#[test]
fn fit_frames_small_and_large_scenes_whole_in_both_eyes() {
    let dir = tempfile::tempdir().unwrap();
    for (name, scale, at) in [
        ("small", 0.1, Vec3::new(4.0, 1.0, -6.0)),
        ("large", 200.0, Vec3::new(-300.0, 0.0, 500.0)),
    ] {
        let path = dir.path().join(format!("{name}.glb"));
        std::fs::write(&path, placed_box(scale, at, None)).unwrap();
        let out = dir.path().join(name);
        let fitted = render(&path, &out, &["--viewer", "fit"]);
        let by_default = render(&path, &dir.path().join(format!("{name}-default")), &[]);
        assert_eq!(
            fitted, by_default,
            "{name}: a camera-less file is fitted by default"
        );
        for (eye, (share, border_clear)) in coverage(&fitted).into_iter().enumerate() {
            assert!(
                border_clear,
                "{name}, eye {eye}: the box reaches the border"
            );
            assert!(share > 0.1, "{name}, eye {eye}: the box covers {share}");
        }
    }
}

/// The file's camera looks as a rig set by hand to its pose, field of view and clip
/// planes does: `--camera 0`, the default for a file with a camera, and `--viewer`,
/// `--yaw`, `--pitch` with a rig file holding the same window give the same bytes.
#[test]
fn a_files_camera_equals_the_same_view_set_by_hand() {
    let dir = tempfile::tempdir().unwrap();
    let rotation = Quat::from_euler(EulerRot::YXZ, 25f32.to_radians(), -15f32.to_radians(), 0.0);
    let position = rotation * Vec3::new(0.3, 0.0, 3.0);
    let path = dir.path().join("camera.glb");
    std::fs::write(
        &path,
        placed_box(1.0, Vec3::ZERO, Some((position, rotation))),
    )
    .unwrap();
    let scene = stereocull::scene_spec::load(path.to_str().unwrap()).unwrap();
    let camera = &scene.cameras[0];
    let info = stereocull(&["info", "--scene", path.to_str().unwrap()]);
    assert!(info.contains("camera 0: "), "{info}");

    let [yaw, pitch, roll] = camera.yaw_pitch_roll_deg();
    let mut rig = Rig::preset("hmd").unwrap();
    rig.viewer.roll_deg = roll;
    (rig.near, rig.far) = (0.02, 80.0);
    let Mount::Head(head) = &mut rig.displays[0].mount else {
        unreachable!("the hmd preset is head-mounted")
    };
    let t = 0.35f32.tan();
    head.fov = stereocull::frustum::Fov {
        left: t,
        right: t,
        up: t,
        down: t,
    };
    let rig_path = dir.path().join("by-hand.json");
    std::fs::write(&rig_path, serde_json::to_string(&rig).unwrap()).unwrap();

    let through = render(&path, &dir.path().join("camera"), &["--camera", "0"]);
    let by_default = render(&path, &dir.path().join("default"), &[]);
    let p = camera.position;
    let by_hand = render(
        &path,
        &dir.path().join("by-hand"),
        &[
            "--rig",
            rig_path.to_str().unwrap(),
            "--viewer",
            &format!("{:?},{:?},{:?}", p.x, p.y, p.z),
            "--yaw",
            &format!("{yaw:?}"),
            "--pitch",
            &format!("{pitch:?}"),
        ],
    );
    assert!(coverage(&through).iter().all(|&(share, _)| share > 0.05));
    assert_eq!(through, by_default);
    assert_eq!(through, by_hand);
}

#[test]
fn a_camera_that_is_not_there_is_one_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let path: PathBuf = dir.path().join("box.glb");
    std::fs::write(&path, placed_box(1.0, Vec3::ZERO, None)).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_stereocull"))
        .args(["render", "--scene", path.to_str().unwrap(), "--camera", "1"])
        .args(["--out", dir.path().to_str().unwrap()])
        .output()
        .unwrap();
    let errors = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{errors}");
    assert_eq!(errors.trim().lines().count(), 1, "{errors}");
    assert!(
        errors.contains("--camera 1: the scene has 0 camera(s)"),
        "{errors}"
    );
}
