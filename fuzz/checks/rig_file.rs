//! What the `rig_file` fuzz target holds any input to, shared with `tests/fuzz_corpus.rs`, which
//! replays the corpus and every past finding in CI.

use stereocull::contexts::DisplayContext;
use stereocull::rig::Rig;

/// Any bytes as a rig file (the first byte picks TOML or JSON): an error, or a rig
/// whose every display frustum is finite (or a typed error saying why none exists).
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
    for index in 0..rig.displays.len() {
        if let Ok(display) = DisplayContext::new(&rig, index) {
            let finite = display.planes.iter().all(|p| p.is_finite());
            assert!(finite, "display {index}: planes {:?}", display.planes);
        }
    }
    let _ = rig.frame_view();
}
