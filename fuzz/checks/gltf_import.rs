//! What the `gltf_import` fuzz target holds any input to, shared with `tests/fuzz_corpus.rs`, which
//! replays the corpus and every past finding in CI.

use std::path::Path;

use stereocull::cull::cpu;
use stereocull::pose_tables::{PoseNodeRecord, PoseTables};
use stereocull::records::CullLayout;
use stereocull::rig::Rig;

/// Any bytes as a glTF or GLB file: an error, or a scene whose materials a renderer
/// accepts and that the culler handles within the cull contract, material bins included
/// (non-finite instances dropped first, as `scene_spec::load` does).
pub fn gltf_import(data: &[u8]) {
    let Ok(mut scene) = stereocull::gltf_import::import_bytes(data, None, Path::new("fuzz.glb"))
    else {
        return;
    };
    scene.drop_non_finite_instances();
    // Posing samples every channel and walks every posed tree: any time, no panic, and
    // only instances that exist move.
    let n = scene.instances.len();
    assert!(
        scene
            .posing
            .instances
            .iter()
            .all(|i| (i.instance as usize) < n)
    );
    // The skinning pass writes only the scene's vertices and reads only its joints.
    let skins = &scene.skins;
    for v in &skins.vertices {
        assert!((v.destination as usize) < scene.vertices.len());
        let joints = v.joints.map(|j| v.joint_base as usize + j as usize);
        assert!(joints.iter().all(|&j| j < skins.joint_matrices.len()));
    }
    // The morph pass reads only its offsets and weights and writes only the scene's
    // vertices or the skins' rest vertices.
    let morphs = &scene.morphs;
    for v in &morphs.vertices {
        let written = match v.skinned {
            0 => scene.vertices.len(),
            _ => skins.vertices.len(),
        };
        assert!((v.destination as usize) < written);
        assert!((v.first_delta + v.targets) as usize <= morphs.deltas.len());
        assert!((v.first_weight + v.targets) as usize <= morphs.weights.len());
    }
    // Lights are valid as read, and the posed ones exist.
    assert!(scene.lights.iter().all(|l| l.check().is_ok()));
    let lights = scene.lights.len();
    assert!(
        scene
            .posing
            .lights
            .iter()
            .all(|l| (l.instance as usize) < lights)
    );
    for time in [-1.0, 0.0, 0.37, 1e6] {
        scene.pose(time);
    }
    scene.drop_non_finite_instances();
    let n = scene.instances.len();
    // Posing on the GPU reads only what its tables index (a tree too deep is an error).
    if let Ok(Some(tables)) = PoseTables::new(&scene, |_| true) {
        check_pose_tables(&tables, n, scene.skins.joint_matrices.len());
    }
    // The importer checks everything the material records need (textures, finite
    // cutoffs, one material per primitive), so a renderer never refuses an import.
    if let Err(e) = stereocull::materials::records(&scene) {
        panic!("an imported scene's materials: {e}");
    }
    let layout = CullLayout::new(&scene);
    let rig = Rig::preset("hmd").expect("the hmd preset");
    let job = rig.cull_jobs().expect("the hmd display").remove(0);
    let out = cpu::cull(&layout, &job);
    assert!(out.visible.len() <= n && out.visible.iter().all(|&i| (i as usize) < n));
    assert_eq!(out.bins.len(), layout.bins.kinds.len());
    assert_eq!(out.packed_draws().count(), out.draw_count as usize);
    let drawn: u32 = out.draws.iter().map(|d| d.instance_count).sum();
    assert_eq!(
        drawn as usize,
        out.visible.len() * job.instances_per_object as usize
    );
}

/// Every index of the pose pass's tables in range: nodes' parents (earlier) and
/// channels, channels' keys and values, targets' slots, nodes, joints and matrices.
fn check_pose_tables(t: &PoseTables, instances: usize, joint_matrices: usize) {
    for (i, node) in t.nodes.iter().enumerate() {
        assert!(node.parent == PoseNodeRecord::ROOT || (node.parent as usize) < i);
        assert!((node.first_channel + node.channels) as usize <= t.channels.len());
    }
    for c in &t.channels {
        let per_key = if c.interpolation == 2 { 3 } else { 1 };
        assert!(c.keys >= 1 && (c.first_key + c.keys) as usize <= t.times.len());
        assert!((c.first_value + per_key * c.keys) as usize <= t.values.len());
    }
    for target in &t.targets {
        assert!((target.slot as usize) < instances);
        match target.joints {
            0 => assert!((target.node as usize) < t.nodes.len()),
            joints => {
                assert!((target.node + joints) as usize <= t.joints.len());
                assert!((target.joint_base + joints) as usize <= joint_matrices);
            }
        }
    }
    assert!(t.joints.iter().all(|j| (j.node as usize) < t.nodes.len()));
}
