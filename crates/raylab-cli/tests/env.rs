//! `--env`: a model lit by an HDR sky instead of its default light, in `render` and `view`;
//! the lab integrator's warning; and the mistakes, each one line.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn raylab(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_raylab")).args(args).current_dir(dir).output().expect("runs")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

fn data(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../raylab/tests/data").join(path)
}

/// The mean of an 8-bit picture's channels, 0–255.
fn mean_level(path: &Path) -> f64 {
    let image = image::open(path).unwrap().to_rgb8();
    image.pixels().flat_map(|p| p.0).map(f64::from).sum::<f64>() / (image.len() as f64)
}

/// The teapot under the sky: path traced (a model with an environment map needs it), lit by
/// the sky alone (the default light goes), its background the sky; brighter with
/// `--env-scale 2`, different with `--env-rotate`, and the same in `view`'s screenshot.
#[test]
fn a_model_under_a_sky_is_path_traced_and_lit_by_it() {
    let dir = tempfile::tempdir().unwrap();
    let teapot = data("meshes/teapot.obj");
    let sky = data("mitsuba-envmap/sky.hdr");
    let (teapot, sky) = (teapot.to_str().unwrap(), sky.to_str().unwrap());
    let render = |extra: &[&str], out: &str| {
        let mut args = vec!["render", teapot, "--env", sky, "--size", "48x32", "--spp", "4"];
        args.extend_from_slice(extra);
        args.extend_from_slice(&["-o", out]);
        let output = raylab(dir.path(), &args);
        assert!(output.status.success(), "{}", text(&output.stderr));
        text(&output.stdout)
    };
    let stdout = render(&[], "sky.png");
    assert!(stdout.contains("path tracing"), "{stdout}");
    // The top row is sky (blue above the horizon), not the lab's black.
    let image = image::open(dir.path().join("sky.png")).unwrap().to_rgb8();
    let top = image.get_pixel(0, 0).0;
    assert!(top[2] > 100 && top[2] > top[0], "{top:?}");
    render(&["--env-scale", "2"], "bright.png");
    let (one, two) =
        (mean_level(&dir.path().join("sky.png")), mean_level(&dir.path().join("bright.png")));
    assert!(two > 1.1 * one, "scale 2: {two} against {one}");
    render(&["--env-rotate", "180"], "turned.png");
    assert!(image::open(dir.path().join("turned.png")).unwrap().to_rgb8() != image);
    // `view` lights it the same way: its screenshot is the render's picture.
    let args = [
        "view",
        teapot,
        "--env",
        sky,
        "--headless",
        "--still",
        "--frames",
        "4",
        "--size",
        "48x32",
        "--screenshot",
        "v.png",
    ];
    let out = raylab(dir.path(), &args);
    assert!(out.status.success(), "{}", text(&out.stderr));
    render(&[], "r.png");
    let load = |name: &str| image::open(dir.path().join(name)).unwrap().to_rgb8();
    assert!(load("v.png") == load("r.png"));
}

/// The lab's light model ignores environment maps: `--integrator lab` says so.
#[test]
fn the_lab_integrator_warns_of_the_lights_it_ignores() {
    let dir = tempfile::tempdir().unwrap();
    let sky = data("mitsuba-envmap/sky.hdr");
    let args = [
        "render",
        "--env",
        sky.to_str().unwrap(),
        "--integrator",
        "lab",
        "--size",
        "16x16",
        "-o",
        "l.png",
    ];
    let out = raylab(dir.path(), &args);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stderr = text(&out.stderr);
    assert!(
        stderr.contains("warning: the lab integrator ignores the scene's envmap light"),
        "{stderr}"
    );
}

#[test]
fn env_mistakes_are_one_line_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("bad.hdr"),
        b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 4 +X 4\n\x02",
    )
    .unwrap();
    for (args, message) in [
        (vec!["render", "--env", "missing.hdr", "-o", "x.png"], "missing.hdr"),
        (vec!["render", "--env", "bad.hdr", "-o", "x.png"], "bad.hdr"),
        (vec!["render", "--env", "sky.png", "-o", "x.png"], "sky.png"),
        (vec!["render", "--env-rotate", "30", "-o", "x.png"], "--env"),
        (vec!["render", "--env", "bad.hdr", "--env-scale", "-1", "-o", "x.png"], "-1"),
    ] {
        let out = raylab(dir.path(), &args);
        assert_ne!(out.status.code(), Some(0), "{args:?}");
        let stderr = text(&out.stderr);
        assert!(stderr.contains(message), "{args:?}: {stderr}");
        assert!(!dir.path().join("x.png").exists(), "{args:?}");
    }
    // Not a clap usage error: the file's own problem is one line.
    let out = raylab(dir.path(), &["render", "--env", "bad.hdr", "-o", "x.png"]);
    assert_eq!(text(&out.stderr).lines().count(), 1, "{}", text(&out.stderr));
}
