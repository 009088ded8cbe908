//! What the `rig_file` fuzz target holds any input to, shared with `tests/fuzz_corpus.rs`, which
//! replays the corpus and every past finding in CI.

use stereocull::rig::Rig;

/// Any bytes as a rig file (the first byte picks TOML or JSON): an error, or a rig
/// whose every display frustum, foveated inset frustum and the frame frustum, is finite
/// (or a typed error saying why none exists), and whose displays lay their views out
/// side by side and in layers.
pub fn rig_file(data: &[u8]) {
    let Some((&kind, rest)) = data.split_first() else {
        return;
    };
    let Ok(text) = std::str::from_utf8(rest) else {
        return;
    };
    let extension = if kind % 2 == 0 { "toml" } else { "json" };
    let Ok(rig) = Rig::parse(text, Some(extension)) else {
        return;
    };
    if rig.validate("fuzz").is_err() {
        return;
    }
    let Ok(resolved) = rig.resolve() else {
        return;
    };
    for d in &rig.displays {
        for layered in [false, true] {
            let layout = d.layout_in(layered);
            assert_eq!(layout.viewports().len() as u32, d.views());
        }
    }
    let insets = resolved.displays.iter().filter_map(|d| d.insets);
    let displays = resolved.displays.iter().map(|d| d.combined).chain(insets);
    for (index, view) in displays.chain(resolved.frame()).enumerate() {
        let planes = view.frustum().planes;
        assert!(
            planes.iter().all(|p| p.is_finite()),
            "frustum {index}: planes {planes:?}"
        );
    }
}
