//! `raylab view` end to end: headless frames, the refined picture against `raylab render` of as
//! many samples, a real window under Xvfb (a virtual X server) checked the same way, keys typed
//! into it (xdotool), and the errors: no display, a display that is not there, an unwritable
//! screenshot.
//!
//! The window tests need Debian's `xvfb` and `xdotool` packages (`.ci/run` installs them).
//! Without them a test says on standard error that it is skipped, unless `RAYLAB_REQUIRE_XVFB=1`
//! is set (as `.ci/run` sets it), in which case it fails: in CI it can never pass by not running.

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

use image::RgbImage;
use raylab::image_compare::{compare_rgb8, save_failure_images};

fn raylab(dir: &Path) -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_raylab"));
    command.current_dir(dir);
    command
}

fn run(dir: &Path, args: &[&str]) -> Output {
    raylab(dir).args(args).output().expect("runs")
}

/// `raylab` with no display at all.
fn without_display(dir: &Path, args: &[&str]) -> Output {
    raylab(dir)
        .args(args)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("WAYLAND_SOCKET")
        .output()
        .expect("runs")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

fn load(path: &Path) -> RgbImage {
    image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgb8()
}

/// Fails, leaving both images and their difference in a temporary folder, unless the images are
/// the same pixel for pixel.
fn assert_same_picture(name: &str, actual: &RgbImage, expected: &RgbImage) {
    let difference = compare_rgb8(actual, expected, 0);
    if difference.as_ref().is_none_or(|d| d.pixels_over_tolerance > 0) {
        let folder = save_failure_images(name, actual, expected).unwrap();
        panic!(
            "{name}: the pictures differ ({difference:?}, sizes {:?} and {:?}); actual, expected \
             and diff images are in {}",
            actual.dimensions(),
            expected.dimensions(),
            folder.display()
        );
    }
}

/// The arguments that choose the camera, the light and the stage, away from the defaults so that
/// both commands must honour them.
const SCENE_ARGS: [&str; 12] = [
    "--size",
    "96x72",
    "--camera",
    "0.1,-0.1,-2.8",
    "--yaw",
    "-8",
    "--pitch",
    "5",
    "--light",
    "0.2,-0.4,-0.6",
    "--stage",
    "shadows",
];

/// `raylab render` of the scene arguments with `spp` samples per pixel, in `dir`.
fn reference_render(dir: &Path, spp: u32) -> RgbImage {
    let spp = spp.to_string();
    let mut args = vec!["render", "-o", "reference.png", "--spp", &spp];
    args.extend(SCENE_ARGS);
    let out = run(dir, &args);
    assert!(out.status.success(), "{}", text(&out.stderr));
    load(&dir.join("reference.png"))
}

#[test]
fn headless_frames_print_their_times_and_the_median() {
    let dir = tempfile::tempdir().unwrap();
    let out = run(dir.path(), &["view", "--headless", "--frames", "5", "--size", "64x48"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    let frames: Vec<&str> = stdout.lines().filter(|l| l.starts_with("frame ")).collect();
    assert_eq!(frames.len(), 5, "{stdout}");
    assert!(frames[0].contains("64×48, 1 spp") && !frames[0].contains("moving"), "{stdout}");
    // The camera moves on its path: every later frame is a new picture.
    assert!(frames[1..].iter().all(|l| l.ends_with("1 spp, moving")), "{stdout}");
    let summary = stdout.lines().last().unwrap();
    assert!(summary.starts_with("5 frames of cornell (30 triangles) at 64×48"), "{summary}");
    assert!(summary.contains("median") && summary.contains("frames per second"), "{summary}");
}

#[test]
fn a_still_headless_view_refines_to_the_render_of_as_many_samples() {
    let dir = tempfile::tempdir().unwrap();
    let mut args = vec!["view", "--headless", "--still", "--frames", "6", "--screenshot", "s.png"];
    args.extend(SCENE_ARGS);
    let out = run(dir.path(), &args);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("frame 6: ") && text(&out.stdout).contains("6 spp"));
    let shown = load(&dir.path().join("s.png"));
    assert_same_picture("headless-still", &shown, &reference_render(dir.path(), 6));
}

#[test]
fn refining_stops_at_max_spp() {
    let dir = tempfile::tempdir().unwrap();
    let out = run(
        dir.path(),
        &["view", "--headless", "--still", "--frames", "10", "--max-spp", "3", "--size", "8x8"],
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    assert_eq!(stdout.lines().filter(|l| l.starts_with("frame ")).count(), 3, "{stdout}");
    assert!(stdout.contains("all its 3 samples per pixel"), "{stdout}");
}

#[test]
fn without_a_display_view_says_so_and_suggests_headless() {
    let dir = tempfile::tempdir().unwrap();
    let out = without_display(dir.path(), &["view"]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.starts_with("raylab: error: cannot open a window"), "{stderr}");
    assert!(stderr.contains("no display") && stderr.contains("--headless"), "{stderr}");
    // The same without a window works.
    let out =
        without_display(dir.path(), &["view", "--headless", "--frames", "1", "--size", "4x4"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
}

#[test]
fn a_display_that_is_not_there_is_an_error_not_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let out = raylab(dir.path())
        .args(["view", "--screenshot", "s.png", "--exit-after-frames", "1"])
        .env("DISPLAY", ":4711")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("WAYLAND_SOCKET")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.contains("':4711'") && stderr.contains("--headless"), "{stderr}");
    assert!(!dir.path().join("s.png").exists());
}

#[test]
fn an_unwritable_screenshot_fails_before_rendering() {
    let dir = tempfile::tempdir().unwrap();
    let out = without_display(
        dir.path(),
        &["view", "--headless", "--frames", "1", "--screenshot", "no/such/folder/s.png"],
    );
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    assert!(stderr.contains("no/such/folder") && stderr.lines().count() == 1, "{stderr}");
    assert!(!text(&out.stdout).contains("frame 1"), "{}", text(&out.stdout));
    let out = run(dir.path(), &["view", "--frames", "3"]);
    assert_eq!(out.status.code(), Some(2), "--frames needs --headless");
    // X11 windows cannot be that wide: an error, not a panic in the window system.
    let out = run(dir.path(), &["view", "--size", "70000x10"]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    assert!(stderr.contains("too large for a window") && stderr.lines().count() == 1, "{stderr}");
}

#[test]
fn help_prints_the_key_map() {
    let out = run(Path::new("."), &["view", "--help"]);
    assert!(out.status.success());
    let help = text(&out.stdout);
    for expected in [
        "Up / Down",
        "Left / Right",
        "R(y)",
        "W / S",
        "A / D",
        "Q / E",
        "mouse drag",
        "Esc",
        "--headless",
    ] {
        assert!(help.contains(expected), "{expected} is missing from:\n{help}");
    }
}

/// A virtual X server, stopped when dropped.
struct Xvfb {
    child: Child,
    display: String,
}

impl Xvfb {
    /// Starts Xvfb on a free display, or `None` (with a message) when it is not installed and
    /// not required.
    fn start() -> Option<Xvfb> {
        let spawned = Command::new("Xvfb")
            .args(["-displayfd", "1", "-screen", "0", "640x480x24", "-nolisten", "tcp"])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn();
        let mut child = match spawned {
            Ok(child) => child,
            Err(error) => {
                let required = std::env::var_os("RAYLAB_REQUIRE_XVFB").is_some_and(|v| v == "1");
                assert!(!required, "RAYLAB_REQUIRE_XVFB=1 but Xvfb cannot start: {error}");
                eprintln!(
                    "SKIPPED: the window test needs Xvfb (Debian: apt-get install xvfb): {error}"
                );
                return None;
            }
        };
        // Xvfb writes the display number it chose once it accepts connections.
        let mut line = String::new();
        BufReader::new(child.stdout.take().unwrap()).read_line(&mut line).unwrap();
        let number: u32 = line.trim().parse().unwrap_or_else(|_| panic!("Xvfb said {line:?}"));
        Some(Xvfb { child, display: format!(":{number}") })
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Runs `command` to its end or fails after `limit`.
fn output_within(mut command: Command, limit: Duration) -> Output {
    let mut child = command.stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap();
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > limit {
            let _ = child.kill();
            let out = child.wait_with_output().unwrap();
            panic!("still running after {limit:?}; stderr: {}", text(&out.stderr));
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

#[test]
fn the_window_shows_what_render_renders() {
    let Some(xvfb) = Xvfb::start() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let mut command = raylab(dir.path());
    command
        .args(["view", "--screenshot", "window.png", "--exit-after-frames", "5"])
        .args(SCENE_ARGS)
        .env("DISPLAY", &xvfb.display)
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("WAYLAND_SOCKET");
    let out = output_within(command, Duration::from_secs(120));
    assert!(out.status.success(), "exit {:?}: {}", out.status, text(&out.stderr));
    let stdout = text(&out.stdout);
    assert!(
        stdout.contains("screenshot: window.png (96×72, 5 samples per pixel)"),
        "{stdout}{}",
        text(&out.stderr)
    );
    assert_eq!(stdout.matches("screenshot:").count(), 1, "{stdout}");
    // Five frames of a still camera are five samples per pixel: `raylab render --spp 5`.
    let shown = load(&dir.path().join("window.png"));
    assert_same_picture("window", &shown, &reference_render(dir.path(), 5));

    // Asked for more frames than the picture will get, the window closes when it is finished.
    let mut command = raylab(dir.path());
    command
        .args(["view", "--screenshot", "done.png", "--exit-after-frames", "50", "--max-spp", "3"])
        .args(SCENE_ARGS)
        .env("DISPLAY", &xvfb.display);
    let out = output_within(command, Duration::from_secs(120));
    assert!(out.status.success(), "exit {:?}: {}", out.status, text(&out.stderr));
    assert!(text(&out.stdout).contains("(96×72, 3 samples per pixel)"), "{}", text(&out.stdout));
    let shown = load(&dir.path().join("done.png"));
    assert_same_picture("window-done", &shown, &reference_render(dir.path(), 3));
}

/// Runs `xdotool` on the virtual display; `None` (with a message) when it is not installed and
/// not required.
fn xdotool(xvfb: &Xvfb, args: &[&str]) -> Option<String> {
    let out = match Command::new("xdotool").args(args).env("DISPLAY", &xvfb.display).output() {
        Ok(out) => out,
        Err(error) => {
            let required = std::env::var_os("RAYLAB_REQUIRE_XVFB").is_some_and(|v| v == "1");
            assert!(!required, "RAYLAB_REQUIRE_XVFB=1 but xdotool cannot run: {error}");
            eprintln!("SKIPPED: the input test needs xdotool (Debian: apt-get install xdotool)");
            return None;
        }
    };
    assert!(out.status.success(), "xdotool {args:?}: {}", text(&out.stderr));
    Some(text(&out.stdout).trim().to_string())
}

/// A user at the keyboard: resize the window, hold RIGHT for half a second (60°/s: a yaw of
/// about 30°), press P for a screenshot and Esc to quit. The screenshot has the new size and
/// shows the camera turned by about 30°; the title shows the frame rate and the samples.
#[test]
fn keys_turn_the_camera_and_the_window_resizes() {
    let Some(xvfb) = Xvfb::start() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let mut child = raylab(dir.path())
        .args(["view", "--size", "96x72", "--screenshot", "closed.png"])
        .env("DISPLAY", &xvfb.display)
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("WAYLAND_SOCKET")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let pause = |ms| std::thread::sleep(Duration::from_millis(ms));
    let Some(window) = xdotool(&xvfb, &["search", "--sync", "--name", "^raylab"]) else {
        let _ = child.kill();
        let _ = child.wait();
        return;
    };
    let window = window.lines().next().unwrap().to_string();
    xdotool(&xvfb, &["windowfocus", "--sync", &window]);
    xdotool(&xvfb, &["windowsize", "--sync", &window, "120", "90"]);
    pause(300);
    xdotool(&xvfb, &["keydown", "Right"]);
    pause(500);
    xdotool(&xvfb, &["keyup", "Right"]);
    pause(700);
    let title = xdotool(&xvfb, &["getwindowname", &window]).unwrap();
    xdotool(&xvfb, &["key", "p"]);
    pause(300);
    xdotool(&xvfb, &["key", "Escape"]);
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > Duration::from_secs(60) {
            let _ = child.kill();
            let _ = child.wait();
            panic!("Esc did not close the window");
        }
        pause(20);
    }
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success(), "exit {:?}: {}", out.status, text(&out.stderr));
    // "raylab — cornell — 93 fps, 10.6 ms/frame, 372 spp — stage ambient — arrows …"
    let number_before = |unit: &str| -> f64 {
        let before = title.split(unit).next().unwrap_or_else(|| panic!("no {unit} in {title}"));
        let number = before.rsplit(' ').next().unwrap_or_else(|| panic!("{title}"));
        number.parse().unwrap_or_else(|_| panic!("{number:?} in {title}"))
    };
    assert!(number_before(" fps") > 0.0, "{title}");
    assert!(number_before(" ms/frame") > 0.0, "{title}");
    assert!(number_before(" spp") >= 1.0, "{title}");
    assert!(title.contains("stage ambient") && title.contains("Esc quit"), "{title}");
    let stdout = text(&out.stdout);
    assert!(stdout.contains("screenshot: raylab-view-1.png (120×90, "), "{stdout}");
    // --screenshot without --exit-after-frames: written when the window closed.
    assert!(stdout.contains("screenshot: closed.png (120×90, "), "{stdout}");
    assert_eq!(load(&dir.path().join("closed.png")).dimensions(), (120, 90));
    let shown = load(&dir.path().join("raylab-view-1.png"));

    // Which yaw is it? The render it is closest to, among yaws 5° apart.
    let (mut best_yaw, mut best_error) = (0, f64::INFINITY);
    for yaw in (0..=60).step_by(5) {
        let yaw_arg = yaw.to_string();
        let args = ["render", "--size", "120x90", "--spp", "16", "--yaw", &yaw_arg, "-o", "y.png"];
        let out = run(dir.path(), &args);
        assert!(out.status.success(), "{}", text(&out.stderr));
        let error =
            compare_rgb8(&shown, &load(&dir.path().join("y.png")), 0).unwrap().mean_abs_diff;
        if error < best_error {
            (best_yaw, best_error) = (yaw, error);
        }
    }
    eprintln!("turned by about {best_yaw}° (mean difference {best_error:.2} levels)");
    // Half a second at 60°/s, give or take the delivery of the key events.
    assert!((15..=45).contains(&best_yaw), "the camera turned by about {best_yaw}°");
}
