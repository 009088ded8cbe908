//! Posing, the frame context's first work: glTF node animations sampled as glTF
//! defines (`STEP`, `LINEAR` with rotations along the shorter arc, `CUBICSPLINE`),
//! malformed channels rejected by name, and `BoxAnimated` (a file nobody here wrote)
//! posed where an independent reading of its keys puts it, and drawn there.

mod support;

use glam::{Affine3A, DQuat, DVec3, Quat, Vec3, Vec4};
use rand::{Rng, SeedableRng};
use stereocull::live::LiveScene;
use stereocull::pose::{Channel, Interpolation, Property};
use stereocull::renderer::RendererOptions;
use stereocull::scene_spec;
use support::Tolerance;

fn channel(
    property: Property,
    interpolation: Interpolation,
    times: &[f32],
    values: &[Vec4],
) -> Channel {
    Channel {
        node: 0,
        property,
        interpolation,
        times: times.to_vec(),
        values: values.to_vec(),
    }
}

/// Keys held before the first and after the last; straight lines between; a step
/// holds its key's value up to the next key.
#[test]
fn linear_and_step_channels_sample_as_gltf_defines() {
    let values = [
        Vec4::new(1.0, 2.0, 3.0, 0.0),
        Vec4::new(3.0, -2.0, 0.0, 0.0),
        Vec4::ZERO,
    ];
    let times = [0.5, 1.5, 3.5];
    let linear = channel(
        Property::Translation,
        Interpolation::Linear,
        &times,
        &values,
    );
    assert_eq!(linear.sample(-1.0), values[0]);
    assert_eq!(linear.sample(9.0), values[2]);
    assert_eq!(linear.sample(1.0), Vec4::new(2.0, 0.0, 1.5, 0.0));
    assert_eq!(linear.sample(2.0), values[1] * 0.75);
    let step = Channel {
        interpolation: Interpolation::Step,
        ..linear
    };
    assert_eq!(step.sample(1.49), values[0]);
    assert_eq!(step.sample(1.5), values[1]);
    assert_eq!(step.sample(3.4), values[1]);
}

/// Rotations interpolate along the great arc, and along the shorter of the two a
/// quaternion and its negation give: half way from identity to 90 degrees about y is
/// 45 degrees, whichever sign the second key was written with.
#[test]
fn linear_rotations_take_the_shorter_arc() {
    let quarter = Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
    for end in [quarter, -quarter] {
        let c = channel(
            Property::Rotation,
            Interpolation::Linear,
            &[0.0, 2.0],
            &[Vec4::from(Quat::IDENTITY), Vec4::from(end)],
        );
        let half = Quat::from_vec4(c.sample(1.0)).normalize();
        let want = Quat::from_rotation_y(std::f32::consts::FRAC_PI_4);
        assert!(half.angle_between(want) < 1e-5, "{half} against {want}");
    }
}

/// A cubic spline passes through its keys with the slopes its tangents give (glTF
/// scales the tangents by the keys' spacing): checked at random keys and tangents by
/// finite differences, and a spline with zero tangents is symmetric about the middle.
#[test]
fn cubic_splines_pass_through_keys_with_their_tangents() {
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(41);
    let mut random = || {
        Vec4::new(
            rng.random_range(-2.0..2.0),
            rng.random_range(-2.0..2.0),
            rng.random_range(-2.0..2.0),
            0.0,
        )
    };
    let values: Vec<Vec4> = (0..9).map(|_| random()).collect();
    let times = [0.0, 0.7, 2.0];
    let c = channel(
        Property::Translation,
        Interpolation::CubicSpline,
        &times,
        &values,
    );
    for (k, &t) in times.iter().enumerate() {
        assert!((c.sample(t) - values[3 * k + 1]).length() < 1e-6, "key {k}");
    }
    let h = 1e-3;
    // The slope leaving key 0 is its out-tangent; arriving at key 1, key 1's in-tangent.
    let leaving = (c.sample(h) - c.sample(0.0)) / h;
    assert!(
        (leaving - values[2]).length() < 0.02,
        "{leaving} against {}",
        values[2]
    );
    let arriving = (c.sample(0.7) - c.sample(0.7 - h)) / h;
    assert!(
        (arriving - values[3]).length() < 0.02,
        "{arriving} against {}",
        values[3]
    );
    let flat = [
        Vec4::ZERO,
        Vec4::ZERO,
        Vec4::ZERO,
        Vec4::ZERO,
        Vec4::ONE,
        Vec4::ZERO,
    ];
    let flat = channel(
        Property::Scale,
        Interpolation::CubicSpline,
        &[0.0, 1.0],
        &flat,
    );
    assert!((flat.sample(0.5) - Vec4::splat(0.5)).length() < 1e-6);
    assert!((flat.sample(0.25) + flat.sample(0.75) - Vec4::ONE).length() < 1e-6);
}

/// Each malformed channel is an error saying what is wrong with it.
#[test]
fn malformed_channels_are_errors_naming_the_fault() {
    let v = Vec4::ONE;
    let cases = [
        (
            channel(
                Property::Scale,
                Interpolation::Linear,
                &[0.0, 1.0, 1.0],
                &[v; 3],
            ),
            "not increasing: key 2",
        ),
        (
            channel(Property::Scale, Interpolation::Linear, &[0.0, 1.0], &[v; 3]),
            "3 output values for 2 keyframe times",
        ),
        (
            channel(
                Property::Scale,
                Interpolation::CubicSpline,
                &[0.0, 1.0],
                &[v; 2],
            ),
            "3 per key",
        ),
        (
            channel(
                Property::Scale,
                Interpolation::Step,
                &[0.0, f32::NAN],
                &[v; 2],
            ),
            "not a finite number",
        ),
        (
            channel(
                Property::Scale,
                Interpolation::Step,
                &[0.0, 1.0],
                &[v, Vec4::splat(f32::INFINITY)],
            ),
            "output value 1 is not finite",
        ),
        (
            channel(Property::Scale, Interpolation::Step, &[], &[]),
            "no keyframes",
        ),
    ];
    for (c, want) in cases {
        let err = c.check().unwrap_err();
        assert!(err.contains(want), "{err} (want {want:?})");
    }
}

/// BoxAnimated's posed nodes from an independent reading of its keys (the gltf crate's
/// own reader, interpolated and composed here in f64): the moving part's world
/// transform at `time`.
fn box_animated_reference(time: f64) -> Affine3A {
    let path = support::gltf_sample("BoxAnimated", "glb");
    let (document, buffers, _) = gltf::import(path).unwrap();
    let animation = document.animations().next().unwrap();
    let mut translation = DVec3::ZERO;
    let mut rotation = DQuat::IDENTITY;
    let duration = 3.708329916000366;
    let t = time % duration;
    for c in animation.channels() {
        let reader = c.reader(|b| Some(&buffers[b.index()]));
        let times: Vec<f64> = reader.read_inputs().unwrap().map(f64::from).collect();
        let k = times
            .iter()
            .rposition(|&x| x <= t)
            .unwrap_or(0)
            .min(times.len() - 2);
        let u = ((t - times[k]) / (times[k + 1] - times[k])).clamp(0.0, 1.0);
        match reader.read_outputs().unwrap() {
            gltf::animation::util::ReadOutputs::Translations(v) => {
                let v: Vec<DVec3> = v.map(|x| Vec3::from(x).as_dvec3()).collect();
                translation = v[k].lerp(v[k + 1], u);
            }
            gltf::animation::util::ReadOutputs::Rotations(r) => {
                let r: Vec<DQuat> = r
                    .into_f32()
                    .map(|q| Quat::from_array(q).as_dquat())
                    .collect();
                rotation = r[k].slerp(r[k + 1], u);
            }
            _ => unreachable!("BoxAnimated moves translations and rotations"),
        }
    }
    // nodes[0] (translated, rotated by its rest quaternion) holds nodes[1] holds
    // nodes[2] (the rotating mesh); the rest rotations are the identity's negation.
    let node0 = glam::DAffine3::from_translation(translation);
    let node2 = glam::DAffine3::from_quat(rotation);
    let world = node0 * node2;
    Affine3A::from_mat4(glam::DMat4::from(world).as_mat4())
}

/// BoxAnimated at several times: the instance its animations move is posed where the
/// independent reading puts it, the still one stays, and a live scene poses the same.
#[test]
fn box_animated_poses_where_an_independent_reading_puts_it() {
    let scene =
        scene_spec::load(support::gltf_sample("BoxAnimated", "glb").to_str().unwrap()).unwrap();
    assert_eq!(scene.posing.clips.len(), 1);
    assert_eq!(scene.posing.clips[0].channels.len(), 2);
    let moving = scene
        .posing
        .instances
        .iter()
        .map(|i| i.instance)
        .collect::<Vec<_>>();
    assert_eq!(moving.len(), 1, "one instance hangs on the animated nodes");
    let mut live = LiveScene::new(scene.clone());
    for time in [0.0, 0.9, 1.6, 2.2, 3.0, 4.5] {
        let mut posed = scene.clone();
        posed.pose(time);
        let got = posed.instances[moving[0] as usize].world_from_local;
        let want = box_animated_reference(time as f64);
        let error = (glam::Mat4::from(got) - glam::Mat4::from(want))
            .abs()
            .to_cols_array();
        let worst = error.iter().fold(0.0f32, |a, &b| a.max(b));
        assert!(worst < 1e-5, "t = {time}: {got:?} against {want:?}");
        for (i, (a, b)) in posed.instances.iter().zip(&scene.instances).enumerate() {
            if i as u32 != moving[0] {
                assert_eq!(a.world_from_local, b.world_from_local, "instance {i} stays");
            }
        }
        assert_eq!(live.pose(time).unwrap(), 1);
        assert_eq!(
            live.scene().instances[moving[0] as usize].world_from_local,
            got
        );
    }
}

/// Drawn: BoxAnimated posed at a time draws its moving part where the independently
/// posed copy is (the same transform to f32 rounding, so at most a few edge pixels one
/// level apart), and two times draw different images.
#[test]
fn box_animated_draws_its_moving_part_where_a_cpu_posed_copy_is() {
    let gpu = support::gpu();
    let mut rig = support::sized("hmd", 96, 80);
    rig.viewer.position = [0.0, 1.0, 6.0];
    let options = RendererOptions {
        shadows: false,
        ..support::frustum_only()
    };
    let scene =
        scene_spec::load(support::gltf_sample("BoxAnimated", "glb").to_str().unwrap()).unwrap();
    let moving = scene.posing.instances[0].instance as usize;
    let draw = |time: f32, reference: bool| {
        let mut s = scene.clone();
        match reference {
            false => s.pose(time),
            true => s.instances[moving].world_from_local = box_animated_reference(time as f64),
        }
        support::render(&gpu, &s, &rig, options.clone())
            .unwrap()
            .remove(0)
    };
    let mut images = Vec::new();
    for time in [0.4, 2.0] {
        let posed = draw(time, false);
        let name = format!("box-animated-{time}");
        support::assert_images_match(&name, &posed, &draw(time, true), Tolerance::RECOMPILED);
        images.push(posed);
    }
    assert_ne!(images[0], images[1], "the part moves between the two times");
    assert_ne!(images[0], draw(0.0, false), "and away from its rest pose");
}

/// A one-triangle glTF whose node is translated by an animation with `times` and
/// `outputs` (VEC3) keys under `interpolation`, as JSON with its buffer inline.
fn animated_triangle(times: &[f32], outputs: &[[f32; 3]], interpolation: &str) -> String {
    use base64::Engine;
    let mut bytes: Vec<u8> = Vec::new();
    let triangle = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    bytes.extend(bytemuck::cast_slice(&triangle));
    bytes.extend(bytemuck::cast_slice(times));
    bytes.extend(bytemuck::cast_slice(outputs));
    let data = base64::engine::general_purpose::STANDARD.encode(&bytes);
    let (t, o) = (times.len(), outputs.len());
    serde_json::json!({
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": "moved"}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "buffers": [{"byteLength": bytes.len(), "uri": format!("data:application/octet-stream;base64,{data}")}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 4 * t},
            {"buffer": 0, "byteOffset": 36 + 4 * t, "byteLength": 12 * o}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5126, "count": t, "type": "SCALAR"},
            {"bufferView": 2, "componentType": 5126, "count": o, "type": "VEC3"}
        ],
        "animations": [{"name": "slide", "channels": [{"sampler": 0, "target": {"node": 0, "path": "translation"}}],
            "samplers": [{"input": 1, "output": 2, "interpolation": interpolation}]}]
    })
    .to_string()
}

fn import(json: &str) -> stereocull::Result<stereocull::Scene> {
    stereocull::gltf_import::import_bytes(json.as_bytes(), None, std::path::Path::new("test.gltf"))
}

/// The importer reads a channel's keys and rejects a malformed one, naming the channel
/// and what is wrong; a well-formed one moves its node's instance.
#[test]
fn the_importer_names_malformed_animation_channels() {
    let at = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0]];
    let mut scene = import(&animated_triangle(&[0.0, 1.0], &at, "LINEAR")).unwrap();
    assert_eq!(scene.posing.clips[0].name, "slide");
    scene.pose(0.25);
    let moved = scene.instances[0].world_from_local.translation;
    assert_eq!(moved, glam::Vec3A::new(0.5, 0.0, 0.0));
    let cases = [
        (
            animated_triangle(&[0.0, 1.0, 0.5], &[at[0]; 3], "LINEAR"),
            "not increasing: key 2 at 0.5 s follows 1 s",
        ),
        (
            animated_triangle(&[0.0, 1.0], &[at[0]; 3], "STEP"),
            "3 output values for 2 keyframe times",
        ),
        (
            animated_triangle(&[0.0, 1.0], &at, "CUBICSPLINE"),
            "2 output values for 2 keyframe times (3 per key",
        ),
        (
            animated_triangle(&[0.0, 1.0], &[at[0], [f32::INFINITY, 0.0, 0.0]], "LINEAR"),
            "output value 1 is not finite",
        ),
    ];
    for (json, want) in cases {
        let err = import(&json)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(
            err.contains("animations[0].channels[0]: ") && err.contains(want),
            "{err} (want {want:?})"
        );
    }
}

/// Posed without its clips, every animated sample file's instances land where the
/// importer placed them: the posed trees keep the hierarchy, the still transform above
/// them and each instance's own copy transform.
#[test]
fn posing_without_clips_reproduces_the_imported_placement() {
    for name in ["BoxAnimated", "CesiumMilkTruck"] {
        let path = support::gltf_sample(name, "glb");
        let scene = scene_spec::load(path.to_str().unwrap()).unwrap();
        assert!(scene.is_animated(), "{name} is animated");
        let mut still = scene.posing.clone();
        still.clips.clear();
        for (i, world) in still.instances.iter().zip(still.instance_transforms(1.0)) {
            let placed = scene.instances[i.instance as usize].world_from_local;
            let error = (glam::Mat4::from(world) - glam::Mat4::from(placed)).abs();
            let worst = error.to_cols_array().into_iter().fold(0.0f32, f32::max);
            assert!(
                worst < 1e-5,
                "{name} instance {}: {world:?} against {placed:?}",
                i.instance
            );
        }
    }
}

/// Dropping instances (as loading drops non-finite ones) renumbers the posed ones and
/// forgets those dropped, so posing never moves another instance.
#[test]
fn dropped_instances_leave_posing_and_the_rest_keep_their_poses() {
    let path = support::gltf_sample("BoxAnimated", "glb");
    let scene = scene_spec::load(path.to_str().unwrap()).unwrap();
    let moving = scene.posing.instances[0].instance as usize;
    let still = 1 - moving;
    let mut without_still = scene.clone();
    without_still.instances[still]
        .world_from_local
        .translation
        .x = f32::NAN;
    assert_eq!(without_still.drop_non_finite_instances(), 1);
    assert_eq!(without_still.posing.instances[0].instance, 0);
    without_still.pose(2.0);
    let mut whole = scene.clone();
    whole.pose(2.0);
    assert_eq!(without_still.instances[0], whole.instances[moving]);
    let mut without_moving = scene.clone();
    without_moving.instances[moving]
        .world_from_local
        .translation
        .x = f32::NAN;
    without_moving.drop_non_finite_instances();
    assert!(without_moving.posing.instances.is_empty());
    without_moving.pose(2.0);
    assert_eq!(without_moving.instances[0], scene.instances[still]);
}

/// Importing keeps the file's placement: an animated node's instance stands where its
/// node's own transform puts it until a frame poses it, not at the clip's first key.
#[test]
fn an_imported_animated_node_keeps_its_rest_placement() {
    let keys = [[2.0, 0.0, 0.0], [4.0, 0.0, 0.0]];
    let mut scene = import(&animated_triangle(&[0.0, 1.0], &keys, "LINEAR")).unwrap();
    assert_eq!(
        scene.instances[0].world_from_local,
        glam::Affine3A::IDENTITY
    );
    scene.pose(0.0);
    assert_eq!(scene.instances[0].world_from_local.translation.x, 2.0);
}
