//! Replays the fuzz targets' committed seeds and regression inputs
//! (`tests/fuzz/native/<target>/`) through the targets' own framing and checks
//! (`tuckercodec_core::fuzzing`), without libFuzzer: each must run without a panic.

use std::path::PathBuf;

use tuckercodec_core::fuzzing::TARGETS;

/// `tests/fuzz/native/` of the repository that holds this crate.
fn seeds_folder() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../tests/fuzz/native")
}

/// The seeds are in the repository, not in an sdist (which ships the crates alone): without
/// the repository's `tests/` there is nothing to replay.
fn in_repository() -> bool {
    let tests = seeds_folder().join("../..");
    if !tests.is_dir() {
        eprintln!("no {}: not a checkout, no seeds to replay", tests.display());
    }
    tests.is_dir()
}

#[test]
fn every_seed_runs_through_its_target() {
    if !in_repository() {
        return;
    }
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
    if !in_repository() {
        return;
    }
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
