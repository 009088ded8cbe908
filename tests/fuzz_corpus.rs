//! The fuzz targets' checks (`fuzz/checks/`), run in CI without libFuzzer: every file of
//! the corpus and of past findings (`fuzz/corpus/<target>/`, `fuzz/regressions/<target>/`),
//! and deterministic mutations of the seeds (truncations, byte flips), so that a parser
//! regression shows here even between fuzzing runs.

#[path = "../fuzz/checks/gltf_import.rs"]
mod gltf_import;
#[path = "../fuzz/checks/rig_file.rs"]
mod rig_file;

use std::path::{Path, PathBuf};

use rand::{Rng, SeedableRng};

fn inputs(target: &str) -> Vec<PathBuf> {
    let fuzz = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz");
    let mut files: Vec<PathBuf> = ["corpus", "regressions"]
        .iter()
        .filter_map(|dir| std::fs::read_dir(fuzz.join(dir).join(target)).ok())
        .flatten()
        .map(|entry| entry.unwrap().path())
        .collect();
    files.sort();
    files
}

/// Runs `check` on `data`, naming `what` if it panics.
fn run(check: fn(&[u8]), data: &[u8], what: &str) {
    if std::panic::catch_unwind(|| check(data)).is_err() {
        panic!("{what} fails its fuzz check");
    }
}

fn replay(target: &str, check: fn(&[u8])) -> usize {
    let files = inputs(target);
    for file in &files {
        run(
            check,
            &std::fs::read(file).unwrap(),
            &file.display().to_string(),
        );
    }
    files.len()
}

/// Truncations at 64 places and 256 single-byte changes of every seed.
fn mutate_seeds(target: &str, check: fn(&[u8])) {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(0x5eed);
    for file in inputs(target)
        .iter()
        .filter(|f| name(f).starts_with("seed-"))
    {
        let seed = std::fs::read(file).unwrap();
        for _ in 0..64 {
            let at = rng.random_range(0..seed.len());
            run(check, &seed[..at], &format!("{} cut at {at}", name(file)));
        }
        for _ in 0..256 {
            let mut data = seed.clone();
            let at = rng.random_range(0..data.len());
            data[at] = rng.random();
            run(
                check,
                &data,
                &format!("{} with byte {at} = {}", name(file), data[at]),
            );
        }
    }
}

fn name(path: &Path) -> String {
    path.file_name().unwrap().to_string_lossy().into_owned()
}

#[test]
fn gltf_import_corpus_and_findings_replay() {
    let count = replay("gltf_import", gltf_import::gltf_import);
    assert!(count >= 4, "the corpus holds the seeds at least ({count})");
}

#[test]
fn rig_file_corpus_and_findings_replay() {
    let count = replay("rig_file", rig_file::rig_file);
    assert!(count >= 7, "the corpus holds the seeds at least ({count})");
}

#[test]
fn mutated_gltf_seeds_fail_cleanly() {
    mutate_seeds("gltf_import", gltf_import::gltf_import);
}

#[test]
fn mutated_rig_seeds_fail_cleanly() {
    mutate_seeds("rig_file", rig_file::rig_file);
}
