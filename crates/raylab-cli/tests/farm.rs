//! Renders split into tiles and regions and merged again, interrupted and resumed: the pixels
//! must be exactly those of one uninterrupted render, and bad parts must be refused with their
//! reason.

use std::path::Path;
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

use raylab::parts::{self, PartKind};

#[path = "common/farm.rs"]
mod common;
use common::{animated_box, bits};

fn raylab(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_raylab")).args(args).current_dir(dir).output().expect("runs")
}

fn spawn(dir: &Path, args: &[&str]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_raylab"))
        .args(args)
        .current_dir(dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("runs")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

fn mitsuba_box() -> String {
    concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes/cornell-mitsuba.toml").to_string()
}

/// Runs `raylab ARGS` and insists that it succeeds.
fn ok(dir: &Path, args: &[&str]) -> Output {
    let out = raylab(dir, args);
    assert!(out.status.success(), "raylab {args:?}: {}", text(&out.stderr));
    out
}

/// Tiles for several counts (27 rows: 2, 4 and 5 do not divide it) and a set of regions,
/// merged, give the single render's pixels bit for bit, extra layers included.
#[test]
fn tiles_and_regions_merge_to_the_single_render_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = mitsuba_box();
    let common = ["--size", "40x27", "--spp", "2", "--aov", "albedo,depth"];
    let render = |extra: &[&str], output: &str| {
        let mut args = vec!["render", scene.as_str(), "-o", output];
        args.extend_from_slice(&common);
        args.extend_from_slice(extra);
        ok(d, &args);
    };
    render(&[], "single.exr");
    let single = bits(&d.join("single.exr"));
    assert_eq!(single.1, 2);
    assert!(single.0.iter().any(|(name, _)| name == "albedo.R"), "the layers are there");
    for count in [1u32, 2, 4, 5] {
        let mut names = Vec::new();
        for index in 0..count {
            let name = format!("tile-{index}-of-{count}.exr");
            render(&["--tile", &format!("{index}/{count}")], &name);
            names.push(name);
        }
        let merged = format!("merged-{count}.exr");
        let mut args = vec!["merge", "-o", merged.as_str()];
        args.extend(names.iter().map(String::as_str));
        let out = ok(d, &args);
        assert!(text(&out.stdout).contains(&format!("from {count} parts")));
        assert_eq!(bits(&d.join(&merged)), single, "{count} tiles");
    }
    // Regions in any order: two side by side over the top, one across the bottom.
    for (region, name) in
        [("0,10,40,27", "bottom.exr"), ("17,0,40,10", "right.exr"), ("0,0,17,10", "left.exr")]
    {
        render(&["--region", region], name);
    }
    ok(d, &["merge", "bottom.exr", "right.exr", "left.exr", "-o", "regions.exr"]);
    assert_eq!(bits(&d.join("regions.exr")), single, "regions");
    // PNG out of a merge is the PNG of the single render.
    ok(d, &["merge", "tile-0-of-2.exr", "tile-1-of-2.exr", "-o", "merged.png"]);
    ok(d, &["render", scene.as_str(), "-o", "single.png", "--size", "40x27", "--spp", "2"]);
    let png = |name: &str| image::open(d.join(name)).unwrap().to_rgb8();
    assert!(png("merged.png") == png("single.png"), "the merged PNG is the single render's");
}

/// The lab's integrator (packets of camera and shadow rays) tiles as exactly as the path tracer.
#[test]
fn lab_frame_tiles_merge_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    ok(d, &["render", "-o", "single.exr", "--size", "50x37"]);
    for index in 0..3 {
        let tile = format!("{index}/3");
        ok(d, &["render", "-o", &format!("t{index}.exr"), "--size", "50x37", "--tile", &tile]);
    }
    ok(d, &["merge", "t2.exr", "t0.exr", "t1.exr", "-o", "merged.exr"]);
    assert_eq!(bits(&d.join("merged.exr")), bits(&d.join("single.exr")));
}

/// Parts that do not belong together, overlap, leave holes, are damaged or are not parts are
/// refused with one line naming the file and the reason, and nothing is written.
#[test]
fn merge_refuses_parts_that_do_not_fit() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = mitsuba_box();
    let part = |extra: &[&str], output: &str| {
        let mut args = vec!["render", scene.as_str(), "-o", output, "--size", "16x9"];
        args.extend_from_slice(extra);
        ok(d, &args);
    };
    part(&["--tile", "0/2"], "a.exr");
    part(&["--tile", "1/2"], "b.exr");
    part(&["--tile", "1/2", "--spp", "3"], "b-spp.exr");
    part(&["--tile", "1/2", "--seed", "7"], "b-seed.exr");
    part(&["--region", "0,4,16,9"], "b-overlap.exr");
    part(&["--region", "0,6,16,9"], "b-short.exr");
    ok(d, &["render", "cornell", "-o", "b-scene.exr", "--size", "16x9", "--tile", "1/2"]);
    ok(d, &["render", scene.as_str(), "-o", "b-size.exr", "--size", "16x10", "--tile", "1/2"]);
    let bytes = std::fs::read(d.join("b.exr")).unwrap();
    std::fs::write(d.join("b-truncated.exr"), &bytes[..bytes.len() / 2]).unwrap();
    std::fs::write(d.join("b-text.exr"), "not an image").unwrap();
    // Eight bytes flipped in the middle of the compressed pixels.
    let mut corrupt = bytes.clone();
    let middle = corrupt.len() / 2;
    corrupt[middle..middle + 8].iter_mut().for_each(|b| *b ^= 0xFF);
    std::fs::write(d.join("b-corrupt.exr"), corrupt).unwrap();
    let film = raylab::Film::from_pixels(16, 4, vec![glam::Vec3::ONE; 64]);
    raylab::image_io::save_exr_layers(&d.join("b-plain.exr"), &film, &[]).unwrap();
    let cases: [(&[&str], &str); 13] = [
        (
            &["a.exr", "b-spp.exr"],
            "b-spp.exr does not belong with a.exr: other settings (spp=3 against spp=64)",
        ),
        (
            &["a.exr", "b-seed.exr"],
            "b-seed.exr does not belong with a.exr: other settings (seed=7 against seed=0)",
        ),
        (&["a.exr", "b-scene.exr"], "b-scene.exr does not belong with a.exr: another scene"),
        (
            &["a.exr", "b-size.exr"],
            "b-size.exr does not belong with a.exr: another image size (16×10 against 16×9)",
        ),
        (&["a.exr", "b-overlap.exr"], "b-overlap.exr overlaps a.exr: both hold pixels of 0,4,16,5"),
        (
            &["a.exr", "b-short.exr"],
            "the parts leave 16 of 144 pixels uncovered, the first at column 0, row 5",
        ),
        (&["a.exr"], "the parts leave 64 of 144 pixels uncovered, the first at column 0, row 5"),
        (&["a.exr", "b.exr", "b.exr"], "b.exr: given twice"),
        (&["a.exr", "b-truncated.exr"], "b-truncated.exr"),
        (&["a.exr", "b-text.exr"], "b-text.exr"),
        (&["a.exr", "b-corrupt.exr"], "b-corrupt.exr"),
        (
            &["a.exr", "b-plain.exr"],
            "b-plain.exr: no raylab.kind attribute: not a part raylab wrote",
        ),
        (&["a.exr", "missing.exr"], "missing.exr"),
    ];
    for (inputs, expected) in cases {
        let mut args = vec!["merge", "-o", "out.exr"];
        args.extend_from_slice(inputs);
        let out = raylab(d, &args);
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{inputs:?}: {stderr}");
        assert!(stderr.starts_with("raylab: error: "), "{inputs:?}: {stderr}");
        assert!(stderr.contains(expected), "{inputs:?}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "one line: {stderr}");
        assert!(!d.join("out.exr").exists(), "{inputs:?}: nothing written");
    }
    // The output may not be one of the parts, whatever its name says.
    let out = raylab(d, &["merge", "a.exr", "b.exr", "-o", "./b.exr"]);
    assert!(text(&out.stderr).contains("the output would overwrite one of the parts"));
    // The good pair merges.
    ok(d, &["merge", "a.exr", "b.exr", "-o", "out.exr"]);
    // Times too long for any clock are refused, not a panic.
    for option in ["--checkpoint", "--time-limit"] {
        let out = raylab(d, &["render", "-o", "t.exr", option, "1e30"]);
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains("1e30 seconds is more than a century"), "{stderr}");
    }
    // A tile needs OpenEXR output, and tiles are numbered from 0.
    let out = raylab(d, &["render", "-o", "t.png", "--tile", "0/2"]);
    assert!(text(&out.stderr).contains("the output must end in .exr"));
    let out = raylab(d, &["render", "-o", "t.exr", "--tile", "2/2"]);
    assert!(text(&out.stderr).contains("numbered 0 to N-1"), "{}", text(&out.stderr));
    let out = raylab(d, &["render", "-o", "t.exr", "--region", "0,0,501,10"]);
    assert!(text(&out.stderr).contains("reaches outside the 500×500 image"));
}

/// Sends `signal` (a `kill` name: INT, TERM) to a child process.
fn signal(child: &Child, signal: &str) {
    let status = Command::new("kill")
        .args([&format!("-{signal}"), &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(status.success());
}

/// Waits until `path` exists (a render's first checkpoint), at most a minute.
fn wait_for(path: &Path) {
    let start = Instant::now();
    while !path.exists() {
        assert!(start.elapsed() < Duration::from_secs(60), "{} never appeared", path.display());
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// A render stopped by SIGINT or SIGTERM writes its image so far and a checkpoint, exits with
/// 130, and goes on to exactly the uninterrupted image, by `--resume` or by running the same
/// command again (a requeued job).
#[test]
fn an_interrupted_render_keeps_its_work_and_resumes_to_the_same_image() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = mitsuba_box();
    let args = |output: &'static str| -> Vec<String> {
        [scene.as_str(), "-o", output, "--size", "48x32", "--spp", "1500", "--checkpoint", "0.02"]
            .map(String::from)
            .to_vec()
    };
    let with_render = |a: Vec<String>| [vec!["render".to_string()], a].concat();
    let as_str = |a: &[String]| a.iter().map(String::as_str).collect::<Vec<_>>().join(" ");
    let run = |a: &[String]| raylab(d, &a.iter().map(String::as_str).collect::<Vec<_>>());
    let reference = run(&with_render(args("reference.exr")));
    assert!(reference.status.success(), "{}", text(&reference.stderr));
    assert!(!d.join("reference.checkpoint.exr").exists(), "a finished render deletes it");
    let reference = bits(&d.join("reference.exr"));
    assert_eq!(reference.1, 1500);

    for (kill_with, output, resume_by_rerun) in [("INT", "a.exr", false), ("TERM", "b.exr", true)] {
        let full = with_render(args(output));
        let child = spawn(d, &full.iter().map(String::as_str).collect::<Vec<_>>());
        let checkpoint = d.join(output.replace(".exr", ".checkpoint.exr"));
        wait_for(&checkpoint);
        signal(&child, kill_with);
        let out = child.wait_with_output().unwrap();
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(130), "{}: {stderr}", as_str(&full));
        assert!(stderr.contains(&format!("interrupted: wrote {output} with ")), "{stderr}");
        let (_, reached, _) = bits(&d.join(output));
        assert!((1..1500).contains(&reached), "{reached} samples per pixel so far");
        assert!(stderr.contains(&format!("with {reached} of 1500 samples per pixel")));
        let state = parts::read_part(&checkpoint).unwrap();
        assert_eq!((state.header.kind, state.header.samples), (PartKind::Checkpoint, reached));
        let again = if resume_by_rerun {
            run(&full)
        } else {
            let path = checkpoint.file_name().unwrap().to_str().unwrap().to_string();
            run(&["render".into(), "--resume".into(), path])
        };
        let stderr = text(&again.stderr);
        assert!(again.status.success(), "{stderr}");
        let name = checkpoint.file_name().unwrap().to_str().unwrap();
        assert!(
            stderr.contains(&format!("going on from {name} at {reached} samples per pixel")),
            "{stderr}"
        );
        assert_eq!(bits(&d.join(output)), reference, "resumed after SIG{kill_with}");
        assert!(!checkpoint.exists(), "a finished render deletes its checkpoint");
    }
}

/// A checkpoint of another render is not silently overwritten or used.
#[test]
fn a_checkpoint_of_another_render_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = mitsuba_box();
    let child = spawn(
        d,
        &[
            "render",
            &scene,
            "-o",
            "x.exr",
            "--size",
            "48x32",
            "--spp",
            "5000",
            "--checkpoint",
            "0.01",
        ],
    );
    wait_for(&d.join("x.checkpoint.exr"));
    signal(&child, "INT");
    assert_eq!(child.wait_with_output().unwrap().status.code(), Some(130));
    let out = raylab(
        d,
        &["render", &scene, "-o", "x.exr", "--size", "48x32", "--spp", "9", "--checkpoint", "1"],
    );
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr
            .contains("x.checkpoint.exr: cannot go on from this checkpoint: it has other settings"),
        "{stderr}"
    );
    let out = raylab(d, &["render", "--resume", "x.exr"]);
    assert!(text(&out.stderr).contains("x.exr: not a checkpoint"), "{}", text(&out.stderr));
}

/// A second signal ends the render at once, inside the pass the first one would have waited
/// for: the image is not written (a pass of this size takes seconds, so a render that waited
/// for it would have written its image), and the checkpoint of the pass before is left whole.
#[test]
fn a_second_signal_exits_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = mitsuba_box();
    let args = ["render", &scene, "-o", "y.exr", "--size", "1600x1600", "--spp", "3"];
    let child = spawn(d, &[&args[..], &["--checkpoint", "0.001"]].concat());
    // The first pass is done (its checkpoint written) and the second has begun: two interrupts
    // in a row.
    let checkpoint = d.join("y.checkpoint.exr");
    wait_for(&checkpoint);
    signal(&child, "INT");
    // Apart, so that the two are not merged into one pending signal.
    std::thread::sleep(Duration::from_millis(200));
    signal(&child, "INT");
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(130), "{}", text(&out.stderr));
    assert!(!d.join("y.exr").exists(), "it did not wait for the pass to write the image");
    let state = parts::read_part(&checkpoint).unwrap();
    assert_eq!((state.header.kind, state.header.samples), (PartKind::Checkpoint, 1));
}

/// `--frames` renders the keyframed camera's frames to numbered files; each frame alone (a job
/// of its own) is the same image; frame 0 is the scene's own camera.
#[test]
fn frames_render_the_keyframed_camera_to_numbered_files() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = animated_box(d);
    let common = ["--size", "32x24", "--spp", "2"];
    let run = |extra: &[&str]| ok(d, &[&["render", scene.as_str()][..], &common, extra].concat());
    let out = run(&["--frames", "0..4", "-o", "f_%02d.exr"]);
    assert_eq!(text(&out.stdout).matches("samples per pixel").count(), 5, "{}", text(&out.stdout));
    let frames: Vec<_> = (0..=4).map(|f| bits(&d.join(format!("f_{f:02}.exr")))).collect();
    for pair in frames.windows(2) {
        assert!(pair[0].0 != pair[1].0, "the camera moves from frame to frame");
    }
    // Frame 0 is the scene's own [camera]; frame 2 rendered on its own is the same image.
    run(&["-o", "still.exr"]);
    assert_eq!(bits(&d.join("still.exr")), frames[0]);
    run(&["--frames", "2", "-o", "alone_%d.exr"]);
    assert_eq!(bits(&d.join("alone_2.exr")), frames[2]);
    // Mistakes.
    let out = raylab(d, &["render", scene.as_str(), "--frames", "0..1", "-o", "f.exr"]);
    assert!(text(&out.stderr).contains("needs the frame number's place"), "{}", text(&out.stderr));
    let out = raylab(d, &["render", "cornell", "--frames", "0..1", "-o", "f_%d.png"]);
    assert!(text(&out.stderr).contains("has no camera keyframes"), "{}", text(&out.stderr));
}

fn strs(a: &[String]) -> Vec<&str> {
    a.iter().map(String::as_str).collect()
}

/// An animation interrupted mid-frame and run again with the same command skips the frames it
/// finished, goes on from the checkpoint of the one it was in, and ends with the frames of an
/// uninterrupted run.
#[test]
fn an_interrupted_animation_goes_on_where_it_stopped() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = animated_box(d);
    let args = |pattern: &str| {
        let mut a = vec!["render", scene.as_str(), "--size", "32x24", "--spp", "2000"];
        a.extend(["--frames", "0..2", "-o", pattern, "--checkpoint", "0.02"]);
        a.into_iter().map(String::from).collect::<Vec<_>>()
    };
    let reference = args("ref_%d.exr");
    ok(d, &strs(&reference));
    let animation = args("a_%d.exr");
    let child = spawn(d, &strs(&animation));
    wait_for(&d.join("a_1.checkpoint.exr"));
    signal(&child, "INT");
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(130), "{}", text(&out.stderr));
    assert!(!d.join("a_2.exr").exists(), "the frames after the interrupted one wait");
    let again = ok(d, &strs(&animation));
    let stderr = text(&again.stderr);
    assert!(stderr.contains("a_0.exr is already rendered"), "{stderr}");
    assert!(stderr.contains("going on from a_1.checkpoint.exr"), "{stderr}");
    for f in 0..=2 {
        assert_eq!(bits(&d.join(format!("a_{f}.exr"))), bits(&d.join(format!("ref_{f}.exr"))));
    }
}
