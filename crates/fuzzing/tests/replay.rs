//! Replays, on stable, every input the fuzz targets found a crash with
//! (`fuzz/regressions/<target>/`) and the kept corpus (`fuzz/corpus/<target>/`), so
//! a fixed crash stays fixed. See `fuzz/Cargo.toml` for running the fuzzers.

use std::path::{Path, PathBuf};

fn inputs(target: &str) -> Vec<PathBuf> {
    let fuzz = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz");
    let mut files = Vec::new();
    for kind in ["regressions", "corpus"] {
        if let Ok(entries) = std::fs::read_dir(fuzz.join(kind).join(target)) {
            files.extend(entries.flatten().map(|e| e.path()).filter(|p| p.is_file()));
        }
    }
    files.sort();
    files
}

fn replay(target: &str, check: fn(&[u8])) {
    let files = inputs(target);
    for path in &files {
        let data = std::fs::read(path).expect("readable");
        let result = std::panic::catch_unwind(|| check(&data));
        assert!(result.is_ok(), "{target}: {} fails", path.display());
    }
    println!("{target}: {} inputs replayed", files.len());
}

#[test]
fn rig_file() {
    replay("rig_file", fuzzing::rig_file);
}

#[test]
fn obj_mesh() {
    replay("obj_mesh", fuzzing::obj_mesh);
}

#[test]
fn image_mesh() {
    replay("image_mesh", fuzzing::image_mesh);
}

#[test]
fn rig_handles() {
    replay("rig_handles", fuzzing::rig_handles);
}

#[test]
fn layered() {
    replay("layered", fuzzing::layered);
}
