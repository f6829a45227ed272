//! Replays the fuzz targets' committed seeds and regression inputs
//! (`tests/fuzz/native/<target>/`) through the targets' own framing and checks
//! (`tuckercodec_core::fuzzing`), without libFuzzer: each must run without a panic.

use std::path::PathBuf;

use tuckercodec_core::fuzzing::TARGETS;

/// `tests/fuzz/native/` of the repository that holds this crate.
fn seeds_folder() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../tests/fuzz/native")
}

#[test]
fn every_seed_runs_through_its_target() {
    let folder = seeds_folder();
    assert!(folder.is_dir(), "no seed folder {}", folder.display());
    for (name, target) in TARGETS {
        let mut paths: Vec<PathBuf> = std::fs::read_dir(folder.join(name))
            .unwrap_or_else(|error| panic!("seeds of {name}: {error}"))
            .map(|entry| entry.expect("a folder entry").path())
            .filter(|path| path.is_file())
            .collect();
        paths.sort();
        assert!(!paths.is_empty(), "no seeds for {name}");
        for path in paths {
            let data = std::fs::read(&path).expect("a seed file");
            let outcome = std::panic::catch_unwind(|| target(&data));
            assert!(outcome.is_ok(), "{name} panics on {}", path.display());
        }
    }
}

#[test]
fn every_seed_folder_is_a_target() {
    for entry in std::fs::read_dir(seeds_folder()).expect("the seed folder") {
        let entry = entry.expect("a folder entry");
        let name = entry.file_name().to_string_lossy().into_owned();
        if entry.path().is_dir() {
            assert!(
                TARGETS.iter().any(|(target, _)| *target == name),
                "seeds for no target: {name}"
            );
        }
    }
}
