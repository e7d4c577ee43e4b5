//! `raylab render` end to end: the default render, options, and every kind of bad input, which
//! must give a clear one-line error and a non-zero exit, never a panic or a partial file.

use std::path::Path;
use std::process::{Command, Output};

use glam::Vec3;
use raylab::{BruteForce, Camera, Lab, Scene, Stage, render};

fn raylab(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_raylab")).args(args).current_dir(dir).output().expect("runs")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

fn files_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

#[test]
fn render_with_no_arguments_writes_the_lab_frame() {
    let dir = tempfile::tempdir().unwrap();
    let out = raylab(dir.path(), &["render"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    assert!(stdout.starts_with("render.png: 500×500"), "{stdout}");
    assert!(stdout.contains(" ms "), "the time taken: {stdout}");
    assert!(stdout.contains("field of view 53.13° × 53.13°"), "{stdout}");
    // Not a terminal: no progress bar, nothing on stderr.
    assert_eq!(text(&out.stderr), "");
    let image = image::open(dir.path().join("render.png")).unwrap().to_rgb8();
    assert_eq!(image.dimensions(), (500, 500));
    assert_eq!(files_in(dir.path()), ["render.png"], "no temporary files are left behind");
}

#[test]
fn options_give_the_same_pixels_as_the_library() {
    let dir = tempfile::tempdir().unwrap();
    let out = raylab(
        dir.path(),
        &[
            "render",
            "cornell",
            "-o",
            "x.png",
            "--size",
            "64x48",
            "--camera",
            "0.1,-0.2,-2.5",
            "--yaw",
            "-10",
            "--fov",
            "60",
            "--light",
            "0.2,-0.4,-0.5",
            "--light-power",
            "9",
            "--stage",
            "shadows",
            "--threads",
            "3",
        ],
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("on 3 threads"));
    let from_cli = image::open(dir.path().join("x.png")).unwrap().to_rgb8();

    let mut scene = Scene::built_in("cornell").unwrap();
    scene.light.position = Vec3::new(0.2, -0.4, -0.5);
    scene.light.power = Vec3::splat(9.0);
    let camera = Camera {
        position: Vec3::new(0.1, -0.2, -2.5),
        yaw: (-10f32).to_radians(),
        focal_length_px: Camera::focal_length_for_fov(64, 60.0),
        width: 64,
        height: 48,
    };
    let accel = BruteForce::new(&scene.triangles);
    let film = render(&camera, &Lab::new(&scene, &accel, Stage::Shadows), &|_| {}).unwrap();
    assert!(from_cli == film.to_rgb8_clamped().unwrap());
}

#[test]
fn ppm_output_and_numbered_stages() {
    let dir = tempfile::tempdir().unwrap();
    let out = raylab(
        dir.path(),
        &["render", "-o", "lab.ppm", "--size", "20x10", "--stage", "1", "--focal", "20"],
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let bytes = std::fs::read(dir.path().join("lab.ppm")).unwrap();
    assert!(bytes.starts_with(b"P6\n20 10\n255\n"));
    assert_eq!(bytes.len(), 13 + 20 * 10 * 3);
}

#[test]
fn help_gives_the_true_field_of_view() {
    let out = raylab(Path::new("."), &["render", "--help"]);
    assert!(out.status.success());
    let help = text(&out.stdout);
    assert!(help.contains("53.13°") && help.contains("2·atan(W / 2f)"), "{help}");
    assert!(help.contains("--stage") && help.contains("reflected"), "{help}");
}

#[test]
fn bad_input_is_a_one_line_error_and_leaves_no_file() {
    let cases: &[(&[&str], &str)] = &[
        (&["--size", "0x10"], "at least 1"),
        (&["--size", "-5x5"], "at least 1"),
        (&["--size", "10x-5"], "at least 1"),
        (&["--size", "500"], "WIDTHxHEIGHT"),
        (&["--size", "1000000x1000000"], "memory"),
        (&["--size", "4294967295x4294967295"], "memory"),
        (&["--camera", "nan,0,0"], "not a finite number"),
        (&["--camera", "0,0"], "three numbers"),
        (&["--yaw", "inf"], "not a finite number"),
        (&["--focal", "1e39"], "not a finite number"),
        (&["--focal", "-3"], "greater than 0"),
        (&["--fov", "180"], "between 0° and 180°"),
        (&["--fov", "30", "--focal", "100"], "cannot be used with"),
        (&["--light", "0,NaN,0"], "not a finite number"),
        (&["--light-power", "-1"], "must not be negative"),
        (&["--fov", "1e-40"], "too small"),
        (&["--bogus"], "unexpected argument"),
        (&["-o", "out.jpg"], "unknown image format '.jpg'"),
        (&["-o", "out"], "no extension"),
        (&["-o", "missing/out.png"], "folder 'missing' does not exist"),
        (&["-o", "/proc/raylab-test.png"], "cannot write '/proc/raylab-test.png'"),
        (&["-o", "folder.png"], "it is a folder"),
        (&["--threads", "100000"], "more than 1024"),
        (&["sponza"], "unknown scene 'sponza'"),
        (&["--stage", "7"], "unknown stage '7'"),
    ];
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("folder.png")).unwrap();
    let before = files_in(dir.path());
    for (args, expected) in cases {
        let out = raylab(dir.path(), &[&["render"], *args].concat());
        let stderr = text(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(!stderr.contains("panicked"), "{args:?} panicked: {stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{args:?}: not one line: {stderr}");
        let first_line = stderr.lines().next().unwrap_or("");
        assert!(first_line.contains("error:"), "{args:?}: {stderr}");
        assert!(
            first_line.contains(expected),
            "{args:?}: expected '{expected}' in the first line: {stderr}"
        );
        assert_eq!(files_in(dir.path()), before, "{args:?} left a file behind");
    }
}

#[cfg(target_os = "linux")]
#[test]
fn a_full_standard_output_is_an_error_not_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    // Every Linux system has /dev/full; without it this test must fail, not pass silently.
    let full = std::fs::OpenOptions::new().write(true).open("/dev/full").expect("/dev/full");
    {
        let out = Command::new(env!("CARGO_BIN_EXE_raylab"))
            .args(["render", "--size", "8x8"])
            .current_dir(dir.path())
            .stdout(full)
            .output()
            .unwrap();
        let stderr = text(&out.stderr);
        assert!(!stderr.contains("panicked"), "{stderr}");
        assert!(stderr.starts_with("raylab: error: cannot print"), "{stderr}");
        assert_eq!(out.status.code(), Some(1));
        // The image itself was written whole.
        assert_eq!(image::open(dir.path().join("render.png")).unwrap().width(), 8);
    }
}

#[test]
fn a_rejected_render_keeps_the_previous_image() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("render.png"), b"the previous picture").unwrap();
    let out = raylab(dir.path(), &["render", "--size", "0x0"]);
    assert!(!out.status.success());
    assert_eq!(std::fs::read(dir.path().join("render.png")).unwrap(), b"the previous picture");
    assert_eq!(files_in(dir.path()), ["render.png"]);
}
