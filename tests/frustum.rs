//! Property tests of the eye, display and frame frusta on every preset, with random
//! viewer poses (fixed seeds).

use glam::{DVec3, Vec3, Vec4Swizzles};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use stereocull::frustum::{Frustum, View};

fn dvec(a: [f32; 3]) -> DVec3 {
    DVec3::from(a.map(f64::from))
}
use stereocull::rig::{Mount, PRESETS, Rig};

/// A point uniformly distributed in the volume of `v`'s frustum.
fn point_in(v: &View, rng: &mut Pcg64Mcg) -> Vec3 {
    let (n3, f3) = (v.near.powi(3), v.far.powi(3));
    let dist = (rng.random::<f32>() * (f3 - n3) + n3).cbrt() as f64;
    let tx = rng.random_range(-v.fov.left..=v.fov.right) as f64;
    let ty = rng.random_range(-v.fov.down..=v.fov.up) as f64;
    v.world_from_view
        .transform_point3(DVec3::new(tx * dist, ty * dist, -dist))
        .as_vec3()
}

/// Inside, allowing float error that grows with distance from `origin`.
fn inside(f: &Frustum, p: Vec3, origin: Vec3) -> bool {
    let tolerance = 1e-5 * (1.0 + p.distance(origin));
    f.planes
        .iter()
        .all(|pl| pl.xyz().dot(p) + pl.w >= -tolerance)
}

/// Each preset with its viewer moved and turned at random (inside the CAVE for `cave`).
fn random_rigs(seed: u64) -> Vec<(String, Rig)> {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let mut rigs = Vec::new();
    for preset in PRESETS {
        for k in 0..8 {
            let mut rig = Rig::preset(preset).unwrap();
            let v = &mut rig.viewer;
            v.position = [
                rng.random_range(-1.0..1.0),
                rng.random_range(1.0..2.0),
                rng.random_range(-1.0..1.0),
            ];
            v.yaw_deg = rng.random_range(-180.0..180.0);
            v.pitch_deg = rng.random_range(-60.0..60.0);
            v.roll_deg = rng.random_range(-20.0..20.0);
            v.ipd = rng.random_range(0.05..0.075);
            if let Mount::Head(h) = &mut rig.displays[0].mount {
                h.cant_deg = if k % 2 == 0 {
                    0.0
                } else {
                    rng.random_range(0.0..15.0)
                };
            }
            rig.validate(preset).unwrap();
            rigs.push((format!("{preset}#{k}"), rig));
        }
    }
    rigs
}

#[test]
fn points_inside_any_eye_are_inside_its_display_frustum() {
    let mut rng = Pcg64Mcg::seed_from_u64(7);
    for (name, rig) in random_rigs(1) {
        for (d, resolved) in rig.resolve().unwrap().displays.iter().enumerate() {
            let planes = resolved.combined.frustum();
            for (e, eye) in resolved.eyes.iter().enumerate() {
                for _ in 0..2000 {
                    let p = point_in(eye, &mut rng);
                    assert!(
                        inside(&planes, p, eye.position()),
                        "{name} display {d} eye {e}: {p} outside the display frustum"
                    );
                }
            }
        }
    }
}

/// Volume of the display frustum over the volume of the union of its eye frusta,
/// estimated by sampling the display frustum uniformly.
fn volume_factor(rig: &Rig, d: usize, rng: &mut Pcg64Mcg) -> f64 {
    let resolved = &rig.resolve().unwrap().displays[d];
    let display = resolved.combined;
    let eyes: Vec<Frustum> = resolved.eyes.iter().map(View::frustum).collect();
    let samples = 20_000;
    let hits = (0..samples)
        .filter(|_| {
            let p = point_in(&display, rng);
            eyes.iter().any(|f| f.contains_point(p))
        })
        .count();
    samples as f64 / hits as f64
}

/// Parallel eyes (HMD without cant, CAVE walls) give a display frustum within 2 % of
/// the union's volume (measured worst: 1.013). Canted eyes cannot do as well with six
/// planes: a rectangular window must hold both eyes' outer corner rays, so the vertical
/// tangents grow (measured worst at up to 15 degrees of cant: 2.6).
#[test]
fn display_frustum_is_not_much_larger_than_the_union_of_its_eyes() {
    let mut rng = Pcg64Mcg::seed_from_u64(11);
    let (mut parallel, mut canted): (f64, f64) = (1.0, 1.0);
    for (name, mut rig) in random_rigs(2) {
        // A short far plane makes the near-field overhead (around the apex) visible.
        rig.far = 20.0;
        for d in 0..rig.displays.len() {
            let factor = volume_factor(&rig, d, &mut rng);
            println!(
                "{name} {}: display / union volume = {factor:.4}",
                rig.displays[d].name
            );
            let cant = match &rig.displays[d].mount {
                Mount::Head(h) => h.cant_deg,
                Mount::Screen(_) | Mount::Views(_) => 0.0,
            };
            let worst = if cant > 0.0 {
                &mut canted
            } else {
                &mut parallel
            };
            *worst = worst.max(factor);
        }
    }
    println!("worst display / union volume: parallel eyes {parallel:.4}, canted eyes {canted:.4}");
    assert!(
        parallel < 1.02,
        "display frustum too loose for parallel eyes: {parallel}"
    );
    assert!(
        canted < 3.0,
        "display frustum too loose for canted eyes: {canted}"
    );
}

#[test]
fn off_axis_screen_corners_project_to_ndc_corners() {
    for (name, rig) in random_rigs(3)
        .into_iter()
        .filter(|(n, _)| n.starts_with("cave"))
    {
        let resolved = rig.resolve().unwrap();
        for (display, r) in rig.displays.iter().zip(&resolved.displays) {
            let Mount::Screen(s) = &display.mount else {
                panic!("a cave wall is a screen")
            };
            let (ll, lr, ul) = (
                Vec3::from(s.lower_left),
                Vec3::from(s.lower_right),
                Vec3::from(s.upper_left),
            );
            let ur = lr + ul - ll;
            for eye in &r.eyes {
                let m = eye.clip_from_world();
                for (corner, want) in [
                    (ll, (-1.0, -1.0)),
                    (lr, (1.0, -1.0)),
                    (ur, (1.0, 1.0)),
                    (ul, (-1.0, 1.0)),
                ] {
                    let p = m.project_point3(corner);
                    assert!(
                        (p.x - want.0).abs() < 1e-4 && (p.y - want.1).abs() < 1e-4,
                        "{name} {}: corner {corner} -> {p}, want {want:?}",
                        display.name
                    );
                }
            }
        }
    }
}

#[test]
fn frame_frustum_holds_every_display_frustum_or_is_absent_for_the_cave() {
    let mut rng = Pcg64Mcg::seed_from_u64(5);
    for (name, rig) in random_rigs(4) {
        let resolved = rig.resolve().unwrap();
        let frame = resolved.frame();
        if name.starts_with("cave") {
            assert!(
                frame.is_none(),
                "{name}: walls all around cannot share one frustum"
            );
            continue;
        }
        let frame = frame.unwrap_or_else(|| panic!("{name}: no frame frustum"));
        let planes = frame.frustum();
        for r in &resolved.displays {
            let display = r.combined;
            for _ in 0..2000 {
                let p = point_in(&display, &mut rng);
                assert!(
                    inside(&planes, p, display.position()),
                    "{name}: {p} outside the frame frustum"
                );
            }
        }
    }
}

#[test]
fn stereo_display_apex_lies_behind_the_eyes() {
    for (name, rig) in random_rigs(6) {
        // Head-fixed panels only: CAVE eyes can sit at different depths from a wall,
        // where the apex need only lie behind the nearest eye's near plane.
        let resolved = rig.resolve().unwrap();
        for (d, r) in resolved.displays.iter().enumerate() {
            let eyes = &r.eyes;
            if eyes.len() < 2 || !matches!(rig.displays[d].mount, Mount::Head(_)) {
                continue;
            }
            let display = r.combined;
            let forward = display
                .world_from_view
                .transform_vector3(-DVec3::Z)
                .as_vec3();
            let behind = eyes
                .iter()
                .all(|e| (e.position() - display.position()).dot(forward) > 0.0);
            assert!(
                behind,
                "{name} display {d}: apex {} not behind the eyes",
                display.position()
            );
        }
    }
}

/// Screen corners a hair off a right angle (validation allows a cosine up to 1e-3) are
/// projected as their completion: the lower edge as given, the up direction made
/// perpendicular to it, the height of `upper_left` above the lower edge. That
/// rectangle's corners land on the NDC corners, and its eye frusta lie inside the
/// display frustum that culls for them.
#[test]
fn skewed_screen_corners_project_and_cull_as_their_completed_rectangle() {
    let mut rng = Pcg64Mcg::seed_from_u64(8);
    for (name, mut rig) in random_rigs(9)
        .into_iter()
        .filter(|(n, _)| n.starts_with("cave"))
    {
        let mut completed = Vec::new();
        for display in &mut rig.displays {
            let Mount::Screen(s) = &mut display.mount else {
                panic!("{name}: a cave wall is a screen")
            };
            let [ll, lr, ul] = [s.lower_left, s.lower_right, s.upper_left].map(dvec);
            let across = (lr - ll).normalize();
            let skew = rng.random_range(-9e-4..9e-4) * (ul - ll).length();
            s.upper_left = (ul + across * skew).as_vec3().into();
            let up = (dvec(s.upper_left) - ll).reject_from_normalized(across);
            completed.push([ll, lr, lr + up, ll + up]);
        }
        rig.validate(&name).unwrap();
        let resolved = rig.resolve().unwrap();
        for (r, corners) in resolved.displays.iter().zip(&completed) {
            let planes = r.combined.frustum();
            for eye in &r.eyes {
                let m = eye.clip_from_world();
                let ndc = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
                for (corner, want) in corners.iter().zip(ndc) {
                    let p = m.project_point3(corner.as_vec3());
                    let off = (p.x - want.0).abs().max((p.y - want.1).abs());
                    assert!(off < 1e-4, "{name}: corner {corner} -> {p}, want {want:?}");
                }
                for _ in 0..500 {
                    let p = point_in(eye, &mut rng);
                    assert!(inside(&planes, p, eye.position()), "{name}: {p} outside");
                }
            }
        }
    }
}
