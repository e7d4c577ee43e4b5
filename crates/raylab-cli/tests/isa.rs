//! `RAYLAB_ISA`: every instruction set this CPU has renders the same pixels, in the path
//! tracer and the lab's light model; a set it lacks, or no set at all, is one line and exit 2.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use raylab::cpu::Isa;

fn raylab(dir: &Path, isa: &str, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_raylab"))
        .args(args)
        .env("RAYLAB_ISA", isa)
        .current_dir(dir)
        .output()
        .expect("runs")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

fn data(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../raylab/tests/data").join(path)
}

/// The teapot (a tree, not the flat list of small scenes), path traced under the sky and in the
/// lab's model, with each set this CPU supports forced: the same bytes every time.
#[test]
fn every_instruction_set_renders_the_same_pixels() {
    let dir = tempfile::tempdir().unwrap();
    let teapot = data("meshes/teapot.obj");
    let sky = data("mitsuba-envmap/sky.hdr");
    let (teapot, sky) = (teapot.to_str().unwrap(), sky.to_str().unwrap());
    let supported: Vec<Isa> = Isa::ALL.into_iter().filter(|isa| isa.is_supported()).collect();
    assert!(supported.len() >= 2, "at least the portable set and SSE2: {supported:?}");
    for (kind, extra) in [
        ("path", vec!["--env", sky, "--spp", "4"]),
        ("lab", vec!["--spp", "2", "--stage", "ambient"]),
    ] {
        let mut pictures = Vec::new();
        for isa in &supported {
            let out = format!("{kind}-{}.pfm", isa.name());
            let mut args = vec!["render", teapot, "--size", "40x30", "-o", &out];
            args.extend_from_slice(&extra);
            let output = raylab(dir.path(), isa.name(), &args);
            assert!(output.status.success(), "{}: {}", isa.name(), text(&output.stderr));
            pictures.push((isa.name(), std::fs::read(dir.path().join(&out)).unwrap()));
        }
        let (first, reference) = &pictures[0];
        for (name, bytes) in &pictures[1..] {
            assert!(bytes == reference, "{kind}: {name} differs from {first}");
        }
    }
}

/// A name that is no set, and (on a CPU without AVX-512) a set the CPU lacks: one line naming
/// the variable, exit 2, no picture.
#[test]
fn a_wrong_instruction_set_is_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let mut cases = vec![("avx3", "unknown instruction set 'avx3'")];
    if !Isa::Avx512.is_supported() {
        cases.push(("avx512", "this CPU cannot run avx512"));
    }
    for (isa, message) in cases {
        let output = raylab(dir.path(), isa, &["render", "-o", "x.png"]);
        let stderr = text(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{stderr}");
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        assert!(stderr.starts_with("raylab: error: RAYLAB_ISA: "), "{stderr}");
        assert!(stderr.contains(message), "{stderr}");
        assert!(!dir.path().join("x.png").exists());
    }
    // Empty is unset.
    let output = raylab(dir.path(), "", &["render", "--size", "8x8", "-o", "x.png"]);
    assert!(output.status.success(), "{}", text(&output.stderr));
}
