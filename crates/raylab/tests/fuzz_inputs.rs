//! The fuzz targets' inputs in the normal test run: every crash input the fuzzers ever found
//! (each one goes into `tests/data/fuzz/TARGET/` as `crash-*`), a sample of their
//! corpora (`corpus-*`) and hand-made hostile files, through the very entry points the fuzz
//! targets call (`raylab::fuzzing`). Each must return: no panic, no abort, no allocation beyond
//! the declared limits. See `fuzz/README.md`.

use std::path::{Path, PathBuf};

fn inputs(target: &str) -> Vec<PathBuf> {
    let folder = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz").join(target);
    let mut files: Vec<PathBuf> =
        std::fs::read_dir(&folder).unwrap().map(|e| e.unwrap().path()).collect();
    files.sort();
    assert!(files.len() >= 5, "{}: the inputs are there", folder.display());
    files
}

fn run_all(target: &str, entry: fn(&[u8])) {
    for file in inputs(target) {
        let bytes = std::fs::read(&file).unwrap();
        let outcome = std::panic::catch_unwind(|| entry(&bytes));
        assert!(outcome.is_ok(), "{} panics", file.display());
    }
}

#[test]
fn obj_inputs() {
    run_all("obj", raylab::fuzzing::obj);
}

#[test]
fn ply_inputs() {
    run_all("ply", raylab::fuzzing::ply);
}

#[test]
fn gltf_inputs() {
    run_all("gltf", raylab::fuzzing::gltf);
}

/// The first crash the glTF fuzzer found: a primitive's POSITION names an accessor that does not
/// exist, which made the `gltf` crate's validation index out of bounds. Now a one-line error.
#[test]
fn a_missing_position_accessor_is_an_error() {
    let folder = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz/gltf");
    let crash =
        std::fs::read(folder.join("crash-d6171484682aa3215dba3db05fb03870392e6053")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("crash.gltf");
    std::fs::write(&path, crash).unwrap();
    let message = raylab::scene::load_mesh(&path).unwrap_err().to_string();
    assert!(message.contains("does not exist"), "{message}");
    assert!(message.starts_with(&path.display().to_string()) && !message.contains('\n'));
}

/// The second: TEXCOORD_0 (two floats, 8 bytes) in a buffer view whose stride is 4 bytes, which
/// made the `gltf` crate's reader assert. Now a one-line error naming the accessor.
#[test]
fn a_stride_shorter_than_its_elements_is_an_error() {
    let folder = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz/gltf");
    let crash =
        std::fs::read(folder.join("crash-284651b5b2de06e3a4a61ef4336617960504869a")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("crash.gltf");
    std::fs::write(&path, crash).unwrap();
    let message = raylab::scene::load_mesh(&path).unwrap_err().to_string();
    assert!(
        message.contains("TexCoords(0): accessor 3's buffer view has a stride of 4 bytes"),
        "{message}"
    );
    assert!(message.starts_with(&path.display().to_string()) && !message.contains('\n'));
}

#[test]
fn scene_file_inputs() {
    run_all("scene_file", raylab::fuzzing::scene_file);
}

#[test]
fn hdr_image_inputs() {
    run_all("hdr_image", raylab::fuzzing::hdr_image);
}

/// The parts' inputs, read as plain images (the same decoder, another entry point).
#[test]
fn exr_image_inputs() {
    run_all("exr_part", raylab::fuzzing::exr_image);
}

#[test]
fn exr_part_inputs() {
    run_all("exr_part", raylab::fuzzing::exr_part);
}

/// The hand-made parts are refused for their own reasons, the huge one before any allocation.
#[test]
fn hostile_parts_are_refused_with_their_reason() {
    let folder = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz/exr_part");
    let error = |name: &str| raylab::parts::read_part(&folder.join(name)).unwrap_err().to_string();
    assert!(
        error("huge-data-window.exr").ends_with(
            "huge-data-window.exr: it declares 100000×100000 pixels of 3 channels (111.8 GiB), \
             more than a part may hold (4.0 GiB)"
        ),
        "{}",
        error("huge-data-window.exr")
    );
    assert!(error("truncated.exr").contains("truncated.exr"));
    assert!(error("reversed-data-window.exr").contains("reversed-data-window.exr"));
    assert!(error("extreme-display-window.exr").contains("display window"));
    let part = raylab::parts::read_part(&folder.join("part.exr")).unwrap();
    assert_eq!(part.header.region, raylab::Region { x0: 0, y0: 1, x1: 4, y1: 2 });
}
