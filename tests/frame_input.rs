//! A frame's input as data (`stereocull::frame_input`): its bytes round-trip, a message
//! cut short, of another version or not one at all is refused with an error naming
//! what is wrong, and a replica that applies the head's inputs (through their bytes) to
//! the same scene draws the same pixels and culls, byte for byte, frame after frame.

mod support;

use glam::{Affine3A, Quat, Vec3, Vec4};
use rand::{Rng, SeedableRng};
use stereocull::frame_input::{FRAME_INPUT_VERSION, FrameInput, SceneEdit, scene_identity};
use stereocull::live::{Handle, LiveScene};
use stereocull::readback::read_rgba8;
use stereocull::renderer::Renderer;
use stereocull::rig::{Gaze, Rig};
use stereocull::scene::Scene;

/// The head's edits of one frame: made on `live` through its own calls and recorded
/// in order (moves, recolors, material resets, removes and inserts, at random).
fn edit(live: &mut LiveScene, rng: &mut rand_pcg::Pcg64, meshes: u32) -> Vec<SceneEdit> {
    let mut edits = Vec::new();
    for _ in 0..12 {
        let handles = live.handles();
        let handle = handles[rng.random_range(0..handles.len())];
        let edit = match rng.random_range(0..5) {
            0 => {
                let at = Vec3::new(
                    rng.random_range(-4.0..4.0),
                    rng.random_range(0.0..3.0),
                    rng.random_range(-6.0..0.0),
                );
                let world_from_local =
                    Affine3A::from_rotation_translation(Quat::from_rotation_y(rng.random()), at);
                live.set_transform(handle, world_from_local).unwrap();
                SceneEdit::Transform {
                    handle,
                    world_from_local,
                }
            }
            1 => {
                let color = Vec4::new(rng.random(), rng.random(), rng.random(), 1.0);
                live.set_color(handle, color).unwrap();
                SceneEdit::Color { handle, color }
            }
            2 => {
                live.set_material(handle, None).unwrap();
                SceneEdit::Material {
                    handle,
                    material: None,
                }
            }
            3 => {
                live.remove(handle).unwrap();
                SceneEdit::Remove(handle)
            }
            _ => {
                let mut instance = *live.get(handle).unwrap();
                instance.mesh = rng.random_range(0..meshes);
                instance.world_from_local.translation += glam::Vec3A::new(0.3, 0.2, -0.4);
                let handle = live.insert(instance).unwrap();
                SceneEdit::Insert { handle, instance }
            }
        };
        edits.push(edit);
    }
    edits
}

fn input(frame: u64, rig: &Rig, edits: Vec<SceneEdit>) -> FrameInput {
    FrameInput {
        frame,
        time: frame as f32 / 90.0,
        viewer: rig.viewer,
        gaze: Some(Gaze::both(3.0 * frame as f32, -2.0)),
        edits,
    }
}

#[test]
fn inputs_round_trip_through_their_bytes() {
    let scene = stereocull::procedural::scene(200, 4, 7);
    let mut live = LiveScene::new(scene);
    let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
    let rig = Rig::preset("hmd-foveated").unwrap();
    for frame in 0..5 {
        let sent = input(frame, &rig, edit(&mut live, &mut rng, 4));
        let bytes = sent.to_bytes();
        assert_eq!(FrameInput::from_bytes(&bytes).unwrap(), sent);
        // A pose and a dozen edits in a few hundred bytes, not kilobytes.
        assert!(bytes.len() < 1200, "{} bytes", bytes.len());
    }
    // The pose alone, and a move: what a frame costs on the wire.
    let pose = input(9, &rig, Vec::new()).to_bytes().len();
    let handle = live.handles()[0];
    let moved = SceneEdit::Transform {
        handle,
        world_from_local: Affine3A::from_translation(Vec3::new(1.0, 2.0, 3.0)),
    };
    let one_move = input(9, &rig, vec![moved]).to_bytes().len() - pose;
    eprintln!("pose alone {pose} bytes, each move {one_move} bytes");
    assert!(pose <= 64 && one_move <= 56, "{pose}, {one_move}");
}

#[test]
fn a_damaged_message_is_refused_with_what_is_wrong() {
    let rig = Rig::preset("hmd").unwrap();
    let handle: Handle = serde_json::from_str(r#"{"slot": 3, "generation": 1}"#).unwrap();
    let bytes = input(4, &rig, vec![SceneEdit::Remove(handle)]).to_bytes();
    let error = |b: &[u8]| FrameInput::from_bytes(b).unwrap_err().to_string();
    let cut = error(&bytes[..bytes.len() - 1]);
    assert!(cut.contains("its header says"), "{cut}");
    assert!(error(&bytes[..5]).contains("shorter than the 10-byte header"));
    let mut other = bytes.clone();
    other[4..6].copy_from_slice(&(FRAME_INPUT_VERSION + 1).to_le_bytes());
    let version = error(&other);
    assert!(
        version.contains(&format!(
            "version {}, this build reads version {FRAME_INPUT_VERSION}",
            FRAME_INPUT_VERSION + 1
        )),
        "{version}"
    );
    let mut alien = bytes.clone();
    alien[0] = b'X';
    assert!(error(&alien).contains("no SCFI magic"));
    let mut longer = bytes.clone();
    longer.push(0);
    assert!(error(&longer).contains("its header says"));
}

/// Four frames: the head edits its scene and sends each frame's input as bytes; the
/// replica applies them to its own copy and draws. Images and every display's cull are
/// equal, exactly (the same pipelines draw the same draws from the same records).
#[test]
fn a_replica_applying_the_heads_inputs_draws_what_the_head_draws() {
    let gpu = support::gpu();
    let scene: Scene = stereocull::procedural::scene(2_000, 6, 11);
    // A foveated display keeps a gaze (or none) for its renderer's life.
    let mut rig = support::sized("hmd-foveated", 64, 64);
    rig.set_gaze(Gaze::both(0.0, 0.0)).unwrap();
    let options = support::frustum_only();
    let mut head = (LiveScene::new(scene.clone()), rig.clone());
    let mut replica = (LiveScene::new(scene.clone()), rig.clone());
    let mut renderers: Vec<Renderer> = (0..2)
        .map(|_| Renderer::new(&gpu.device, &scene, &rig, options.clone()).unwrap())
        .collect();
    let targets: Vec<_> = renderers
        .iter()
        .map(|r| r.create_targets(&gpu.device))
        .collect();
    let mut rng = rand_pcg::Pcg64::seed_from_u64(5);
    for frame in 0..4 {
        let edits = edit(&mut head.0, &mut rng, 6);
        head.1.viewer.yaw_deg += 4.0;
        let sent = input(frame, &head.1, edits);
        head.1.set_gaze(sent.gaze.unwrap()).unwrap();
        let received = FrameInput::from_bytes(&sent.to_bytes()).unwrap();
        received.apply(&mut replica.0, &mut replica.1).unwrap();
        assert_eq!(replica.1, head.1, "frame {frame}: the rigs");
        let mut images = Vec::new();
        let mut culls = Vec::new();
        for (k, (live, rig)) in [&mut head, &mut replica].into_iter().enumerate() {
            let renderer = &mut renderers[k];
            renderer.sync(&gpu.device, &gpu.queue, live).unwrap();
            renderer
                .submit_frame(&gpu.device, &gpu.queue, rig, received.time, &targets[k])
                .unwrap();
            images.push(read_rgba8(&gpu.device, &gpu.queue, &targets[k][0].color).unwrap());
            culls.push(support::read_culls(&gpu, renderer, rig));
        }
        assert!(images[0] == images[1], "frame {frame}: images differ");
        assert_eq!(culls[0], culls[1], "frame {frame}: culls differ");
        assert!(
            !culls[0][0].visible.is_empty(),
            "frame {frame}: nothing drawn"
        );
    }
    // The replica's own scene took every insert at the head's handle.
    assert_eq!(replica.0.handles(), head.0.handles());
}

#[test]
fn the_scene_identity_tells_files_and_specs_apart() {
    let a = scene_identity("procedural:1000").unwrap();
    assert_eq!(a, scene_identity("procedural:1000").unwrap());
    assert_ne!(a, scene_identity("procedural:1001").unwrap());
    let file = support::gltf_sample("BoxAnimated", "glb");
    let spec = file.to_str().unwrap();
    let copy = std::env::temp_dir().join("stereocull-identity.glb");
    let mut bytes = std::fs::read(&file).unwrap();
    std::fs::write(&copy, &bytes).unwrap();
    let copied = copy.to_str().unwrap();
    let before = scene_identity(copied).unwrap();
    assert_ne!(scene_identity(spec).unwrap(), a);
    bytes[100] ^= 1;
    std::fs::write(&copy, &bytes).unwrap();
    assert_ne!(scene_identity(copied).unwrap(), before, "a changed file");
}
