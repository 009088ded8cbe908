//! Views as an XR runtime hands them over: a pose and four angles per view
//! (`Mount::Views`), against OpenXR's projection and against the head-fixed rig that
//! describes the same eyes.

mod support;

use glam::{DAffine3, DMat4};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use stereocull::frustum::{Fov, View};
use stereocull::renderer::{CullMode, RendererOptions, StereoMode};
use stereocull::rig::{FovAngles, Mount, PosedView, Rig};
use stereocull::scene_spec;
use support::{Tolerance, assert_images_match, gpu, sized};

/// OpenXR's `XrMatrix4x4f_CreateProjectionFov` for a y-up clip space with depth from 0
/// at `near` to 1 at `far` (its D3D flavour, which wgpu's clip space is), written out
/// from the runtime's angles in f64, column-major.
fn openxr_projection(fov: &FovAngles, near: f64, far: f64) -> DMat4 {
    let tan = |a: f32| (a as f64).tan();
    let (l, r) = (tan(fov.angle_left), tan(fov.angle_right));
    let (u, d) = (tan(fov.angle_up), tan(fov.angle_down));
    let (width, height) = (r - l, u - d);
    let mut m = [0.0; 16];
    m[0] = 2.0 / width;
    m[8] = (r + l) / width;
    m[5] = 2.0 / height;
    m[9] = (u + d) / height;
    m[10] = -far / (far - near);
    m[11] = -1.0;
    m[14] = -(far * near) / (far - near);
    DMat4::from_cols_array(&m)
}

fn random_angles(rng: &mut Pcg64Mcg) -> FovAngles {
    // Asymmetric windows, some not spanning the axis (an inset beside the gaze).
    let left: f32 = rng.random_range(-1.3..0.4);
    let down: f32 = rng.random_range(-1.3..0.4);
    FovAngles {
        angle_left: left,
        angle_right: rng.random_range(left + 0.05..1.3),
        angle_up: rng.random_range(down + 0.05..1.3),
        angle_down: down,
    }
}

#[test]
fn the_projection_from_angles_is_openxrs() {
    let mut rng = Pcg64Mcg::seed_from_u64(23);
    for _ in 0..200 {
        let angles = random_angles(&mut rng);
        let (near, far) = (rng.random_range(0.01..0.5), rng.random_range(10.0..2000.0));
        let view = View {
            world_from_view: DAffine3::IDENTITY,
            fov: angles.tangents(),
            near,
            far,
        };
        let ours = view.clip_from_view().as_dmat4();
        let theirs = openxr_projection(&angles, near as f64, far as f64);
        for (a, b) in ours.to_cols_array().iter().zip(theirs.to_cols_array()) {
            assert!(
                (a - b).abs() <= 1e-5 * b.abs().max(1.0),
                "{angles:?}: ours {ours} against OpenXR's {theirs}"
            );
        }
        // And the meaning of the angles: a point on the right edge's ray lands on x = 1.
        let edge = glam::DVec4::new((angles.angle_right as f64).tan(), 0.0, -1.0, 1.0);
        let clip = theirs * edge;
        assert!((clip.x / clip.w - 1.0).abs() < 1e-9, "{angles:?}");
    }
}

/// The nearest f32 to `t` whose trip through an angle and back is exact, so that a
/// rig built from it and its posed twin resolve to the same bits.
fn round_trips(t: f32) -> f32 {
    let back = |t: f32| ((t as f64).atan() as f32 as f64).tan() as f32;
    let mut x = t;
    while back(x) != x {
        x = x.next_up();
    }
    x
}

#[test]
fn posed_views_draw_what_the_head_fixed_rig_draws() {
    let mut head = sized("hmd", 96, 96);
    let Mount::Head(panel) = &mut head.displays[0].mount else {
        panic!("hmd is head-fixed");
    };
    let f = panel.fov;
    panel.fov = Fov {
        left: round_trips(f.left),
        right: round_trips(f.right),
        up: round_trips(f.up),
        down: round_trips(f.down),
    };
    let posed = head.as_posed().unwrap();
    // Axis-aligned, eyes at f32-exact positions: the same eyes, display frustum and
    // apex to the bit, so the images below must be identical.
    assert_eq!(posed.resolve().unwrap(), head.resolve().unwrap());
    let gpu = gpu();
    let scene = scene_spec::load("procedural:2000:8").unwrap();
    for cull in [CullMode::Gpu, CullMode::Cpu] {
        let options = RendererOptions {
            cull,
            mode: StereoMode::Instanced,
            ..Default::default()
        };
        let a = support::render(&gpu, &scene, &posed, options.clone()).unwrap();
        let b = support::render(&gpu, &scene, &head, options).unwrap();
        let drawn = a[0].pixels().filter(|p| **p != a[0][(0, 0)]).count();
        assert!(drawn > 96 * 96 / 10, "the scene is in view ({drawn} px)");
        // Exact on any CPU: both rigs resolve to the same bits (asserted above), so the
        // same pipeline draws the same draws from the same contexts.
        assert_images_match(&format!("posed-{cull:?}"), &a[0], &b[0], Tolerance::EXACT);
    }
}

#[test]
fn turned_and_canted_posed_views_resolve_as_their_head_fixed_rig() {
    let mut rng = Pcg64Mcg::seed_from_u64(7);
    for _ in 0..50 {
        let mut head = sized("hmd", 64, 64);
        head.viewer.yaw_deg = rng.random_range(-180.0..180.0);
        head.viewer.pitch_deg = rng.random_range(-60.0..60.0);
        head.viewer.roll_deg = rng.random_range(-20.0..20.0);
        if let Mount::Head(panel) = &mut head.displays[0].mount {
            panel.cant_deg = rng.random_range(0.0..8.0);
        }
        let (a, b) = (
            head.as_posed().unwrap().resolve().unwrap(),
            head.resolve().unwrap(),
        );
        let (a, b) = (&a.displays[0], &b.displays[0]);
        for (x, y) in a.eyes.iter().zip(&b.eyes) {
            let (x, y) = (x.clip_from_world(), y.clip_from_world());
            assert!(x.abs_diff_eq(y, 1e-4), "{x} against {y}");
        }
        // The display frustum may differ by rounding (relative to the plane's offset,
        // a kilometre for the far plane), never by more.
        for (p, q) in a.planes.iter().zip(&b.planes) {
            let scale = q.w.abs().max(1.0);
            assert!(
                (*p - *q).abs().max_element() <= 1e-6 * scale + 1e-5,
                "{p} against {q}"
            );
        }
    }
}

#[test]
fn posed_views_read_from_a_rig_file() {
    let posed = Rig::preset("hmd").unwrap().as_posed().unwrap();
    let text = serde_json::to_string_pretty(&posed).unwrap();
    assert!(
        text.contains("\"views\"") && text.contains("angle_left"),
        "{text}"
    );
    let back = Rig::parse(&text, Some("json")).unwrap();
    assert_eq!(back, posed);
    let toml = toml::to_string(&posed).unwrap();
    assert_eq!(Rig::parse(&toml, Some("toml")).unwrap(), posed);
    back.validate("posed.json").unwrap();
    // The views are what the eyes are: moving one moves that eye and no other.
    let mut moved = back.clone();
    if let Mount::Views(v) = &mut moved.displays[0].mount {
        v[0].position[0] += 0.25;
    }
    let (before, after) = (back.resolve().unwrap(), moved.resolve().unwrap());
    let x = |r: &stereocull::rig::ResolvedRig, e: usize| {
        r.displays[0].eyes[e].world_from_view.translation.x
    };
    assert!((x(&after, 0) - x(&before, 0) - 0.25).abs() < 1e-6);
    assert_eq!(x(&after, 1), x(&before, 1));
}

#[test]
fn bad_posed_views_are_one_error_naming_the_display() {
    let good = Rig::preset("hmd").unwrap().as_posed().unwrap();
    type Spoil = fn(&mut Vec<PosedView>);
    let cases: [(&str, Spoil); 7] = [
        ("zero length", |v| v[1].orientation = [0.0; 4]),
        ("finite", |v| v[0].position[2] = f32::NAN),
        ("finite", |v| v[0].fov.angle_up = f32::INFINITY),
        ("angle_left < angle_right", |v| {
            v[0].fov.angle_left = v[0].fov.angle_right
        }),
        ("angle_down < angle_up", |v| v[1].fov.angle_down = 0.9 * 1.5),
        ("under 90 degrees", |v| v[1].fov.angle_right = 1.6),
        ("1 given, the display has 2", |v| v.truncate(1)),
    ];
    for (expected, spoil) in cases {
        let mut rig = good.clone();
        let Mount::Views(views) = &mut rig.displays[0].mount else {
            unreachable!()
        };
        spoil(views);
        let message = rig.validate("posed").unwrap_err().to_string();
        assert!(
            message.contains("(hmd)") && message.contains(expected) && !message.contains('\n'),
            "{expected}: {message}"
        );
    }
}

/// `assets/rigs/hmd-posed.json` is the `hmd` preset as a runtime would hand its views
/// over (`STEREOCULL_RECORD=1` rewrites it), and it loads through the CLI's path.
#[test]
fn the_example_posed_rig_is_the_hmd_as_a_runtime_poses_it() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/rigs/hmd-posed.json");
    let posed = Rig::preset("hmd").unwrap().as_posed().unwrap();
    if std::env::var_os("STEREOCULL_RECORD").is_some() {
        std::fs::write(&path, serde_json::to_string_pretty(&posed).unwrap()).unwrap();
    }
    let loaded = Rig::load(path.to_str().unwrap()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(loaded, posed);
}
