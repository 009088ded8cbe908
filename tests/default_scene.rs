//! The built-in room: the committed asset is what `support::room` authors, and it
//! imports back to the same instances. `STEREOCULL_RECORD=1` rewrites the asset.

mod support;

use stereocull::scene_spec::{self, ROOM_GLB};
use support::room::{room, to_glb};

#[test]
fn default_scene_asset_is_current() {
    let bytes = to_glb(&room());
    if std::env::var_os("STEREOCULL_RECORD").is_some() {
        std::fs::write(
            concat!(env!("CARGO_MANIFEST_DIR"), "/assets/room.glb"),
            &bytes,
        )
        .unwrap();
        return;
    }
    assert!(
        ROOM_GLB == bytes.as_slice(),
        "assets/room.glb is stale: rerun with STEREOCULL_RECORD=1"
    );
}

#[test]
fn default_scene_round_trips_through_the_importer() {
    let authored = room();
    let loaded = scene_spec::load("default").unwrap();
    assert_eq!(loaded.instances.len(), authored.instances.len());
    for (a, b) in authored.instances.iter().zip(&loaded.instances) {
        assert!(a.world_from_local.abs_diff_eq(b.world_from_local, 1e-6));
        assert_eq!(a.color, b.color);
        let (ma, mb) = (
            &authored.meshes[a.mesh as usize],
            &loaded.meshes[b.mesh as usize],
        );
        assert_eq!(ma.index_count, mb.index_count);
        assert!(mb.name.starts_with(&ma.name), "{} vs {}", ma.name, mb.name);
    }
    // Real scale: a room about 8 m wide, objects from about 1 m to 11 m from the viewer.
    let viewer = glam::Vec3::new(0.0, 1.6, 2.0);
    let d: Vec<f32> = loaded
        .instances
        .iter()
        .map(|i| loaded.world_sphere(i).truncate().distance(viewer))
        .collect();
    assert!(
        d.iter().any(|&x| x < 1.0) && d.iter().any(|&x| x > 10.0),
        "{d:?}"
    );
}
