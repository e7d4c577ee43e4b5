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
    scene.point_light_mut().position = Vec3::new(0.2, -0.4, -0.5);
    scene.point_light_mut().power = Vec3::splat(9.0);
    let camera = Camera {
        position: Vec3::new(0.1, -0.2, -2.5),
        yaw: (-10f32).to_radians(),
        pitch: 0.0,
        focal_length_px: Camera::focal_length_for_fov(64, 60.0),
        width: 64,
        height: 48,
        ..Camera::lab(64, 48)
    };
    let accel = BruteForce::new(&scene.vertices());
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
        (&["--instancing", "some"], "expected auto, keep or flatten"),
        (&["--flatten", "--instancing", "keep"], "cannot be used with"),
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

fn mesh_data(path: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../raylab/tests/data/meshes").join(path)
}

#[test]
fn a_model_renders_upright_framed_and_lit() {
    let dir = tempfile::tempdir().unwrap();
    let teapot = mesh_data("teapot.obj");
    let out = raylab(
        dir.path(),
        &["render", teapot.to_str().unwrap(), "-o", "t.png", "--size", "120x80"],
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    assert!(stdout.contains("teapot") && stdout.contains("992 triangles"), "{stdout}");
    let image = image::open(dir.path().join("t.png")).unwrap().to_rgb8();
    // Framed: the teapot is in the picture but does not touch the border; the background is black.
    let lit = |x: u32, y: u32| image.get_pixel(x, y).0.iter().any(|&c| c > 0);
    let border_lit =
        (0..120).any(|x| lit(x, 0) || lit(x, 79)) || (0..80).any(|y| lit(0, y) || lit(119, y));
    assert!(!border_lit, "the model touches the border");
    let covered =
        (0..80).flat_map(|y| (0..120).map(move |x| (x, y))).filter(|&(x, y)| lit(x, y)).count();
    assert!(covered > 120 * 80 / 10, "the model covers only {covered} pixels");
    // Lit: brighter than the ambient term alone somewhere (the light reaches it).
    let brightest = image.pixels().map(|p| p.0[0]).max().unwrap();
    assert!(brightest > 150, "brightest {brightest}");
    // Upright and not mirrored: a y-up triangle with its apex at the top and its right angle at
    // the bottom right must appear so.
    std::fs::write(dir.path().join("tent.obj"), "v -1 0 0\nv 1 0 0\nv 1 2 0\nf 1 2 3\n").unwrap();
    let out = raylab(dir.path(), &["render", "tent.obj", "-o", "tent.png", "--size", "100x100"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let image = image::open(dir.path().join("tent.png")).unwrap().to_rgb8();
    let lit = |x: u32, y: u32| image.get_pixel(x, y).0.iter().any(|&c| c > 0);
    let row = |y: u32| (0..100).filter(|&x| lit(x, y)).collect::<Vec<u32>>();
    let rows: Vec<u32> = (0..100).filter(|&y| !row(y).is_empty()).collect();
    let (top, bottom) = (row(rows[0]), row(*rows.last().unwrap()));
    assert!(top.len() * 4 < bottom.len(), "apex row {} wide, base row {}", top.len(), bottom.len());
    assert!(top[0] > 50, "the apex is on the right, not mirrored: {top:?}");
}

#[test]
fn a_broken_model_is_one_line_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("bad.obj"), "v 0 0 0\nv 1 0 0\nf 1 2 3\n").unwrap();
    let out = raylab(dir.path(), &["render", "bad.obj", "-o", "x.png"]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.contains("bad.obj") && stderr.contains("line 3"), "{stderr}");
    assert!(!dir.path().join("x.png").exists());
    let out = raylab(dir.path(), &["render", "missing.ply"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("missing.ply"));
}

#[test]
fn bench_generates_traces_and_reports() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = mesh_data("cornell_box/cornell_box.obj");
    let mesh = mesh.to_str().unwrap();
    let out = raylab(dir.path(), &["bench", mesh, "--generate", "rays", "--size", "32x24"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let primary = raylab::ray_sets::read_rays(&dir.path().join("rays/primary.rays")).unwrap();
    assert_eq!(primary.len(), 32 * 24);
    let out = raylab(
        dir.path(),
        &[
            "bench",
            mesh,
            "--rays",
            "rays",
            "--reps",
            "1",
            "--threads",
            "2",
            "--json",
            "b.json",
            "--write-hits",
            "hits",
            "--counts",
        ],
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    for word in ["primary", "shadow", "diffuse", "Mr/s", "BVH build", "per triangle"] {
        assert!(stdout.contains(word), "{word}: {stdout}");
    }
    // The box's 32 triangles make one wide node over eight leaves of four: every camera ray
    // tests exactly that node.
    let counts: Vec<&str> = stdout.lines().filter(|l| l.ends_with(" records")).collect();
    assert_eq!(counts.len(), 3, "{stdout}");
    assert!(counts[0].starts_with("primary   closest      1.00 nodes"), "{stdout}");
    let json = std::fs::read_to_string(dir.path().join("b.json")).unwrap();
    for key in [
        "\"triangles\": 32",
        "\"build_ms\"",
        "\"bvh_bytes\"",
        "\"primary\": {\"closest\": {\"1\": ",
        "\"packet\": {\"1\": ",
        "\"shadow\": {\"occluded\"",
        "\"diffuse\": {\"closest\"",
    ] {
        assert!(json.contains(key), "{key}: {json}");
    }
    // The answers written back are raylab's own: tracing them again gives the same.
    let hits = raylab::ray_sets::read_hits(&dir.path().join("hits/primary.hits")).unwrap();
    assert_eq!(hits.len(), primary.len());
    assert!(hits.iter().filter(|h| h.is_hit()).count() > primary.len() / 2);
    let occluded =
        raylab::ray_sets::read_occluded(&dir.path().join("hits/shadow.occluded")).unwrap();
    assert_eq!(occluded.len(), hits.iter().filter(|h| h.is_hit()).count());
    // One thread: every figure once, no duplicate keys.
    let out = raylab(
        dir.path(),
        &[
            "bench",
            mesh,
            "--rays",
            "rays",
            "--reps",
            "1",
            "--threads",
            "1",
            "--json",
            "one.json",
            "--size",
            "32x24",
        ],
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let json = std::fs::read_to_string(dir.path().join("one.json")).unwrap();
    // Three sets of single rays, the packets, and the three sets as batches.
    assert_eq!(json.matches("\"1\":").count(), 8, "{json}");
    assert!(
        text(&out.stdout).contains("primary packets: 768 of 768 answers identical to single rays"),
        "{}",
        text(&out.stdout)
    );
    // The batch engine's answers are the single rays' (768 primary rays, and a shadow and a
    // diffuse ray per primary hit).
    let stdout = text(&out.stdout);
    let batches = stdout.lines().find(|l| l.starts_with("batches: ")).expect("a batches line");
    let words: Vec<&str> = batches.split_whitespace().collect();
    assert_eq!(words[1], words[3], "{batches}");
    assert!(words[1].parse::<usize>().unwrap() > 768, "{batches}");
    assert!(!text(&out.stdout).contains("1 threads"), "{}", text(&out.stdout));
    // With the answers in the ray folder, bench reports full agreement.
    std::fs::copy(dir.path().join("hits/primary.hits"), dir.path().join("rays/primary.hits"))
        .unwrap();
    let out =
        raylab(dir.path(), &["bench", mesh, "--rays", "rays", "--reps", "1", "--threads", "1"]);
    assert!(text(&out.stdout).contains("primary.hits: 768 of 768 agree"), "{}", text(&out.stdout));
    // Either collapse gives the same answers; a third is refused by name.
    for (collapse, says) in [
        ("greedy", "greedy collapse"),
        ("optimal", "optimal over binary leaves of up to 4"),
        ("optimal:2", "optimal over binary leaves of up to 2"),
    ] {
        let args = ["bench", mesh, "--rays", "rays", "--reps", "1", "--threads", "1"];
        let out =
            raylab(dir.path(), &[&args[..], &["--collapse", collapse, "--build", "high"]].concat());
        let stdout = text(&out.stdout);
        assert!(out.status.success(), "{}", text(&out.stderr));
        assert!(
            stdout.contains(says) && stdout.contains("primary.hits: 768 of 768 agree"),
            "{stdout}"
        );
    }
    for bad in ["best", "optimal:0", "optimal:x", "optimal:9"] {
        let out = raylab(dir.path(), &["bench", mesh, "--rays", "rays", "--collapse", bad]);
        assert_eq!(out.status.code(), Some(1));
        let stderr = text(&out.stderr);
        assert!(stderr.contains(&format!("unknown --collapse '{bad}'")), "{stderr}");
    }
    // Embree's figures beside raylab's, from its summary.json; another mesh's is refused.
    let summary = |triangles: usize| {
        format!(
            r#"{{"embree": {{"version": "3.13.5", "robust": false}},
            "mesh_stats": {{"triangles": {triangles}}}, "results": [{{"set": "diffuse",
            "query": "closest", "mode": "single", "threads": 1, "rays": 768,
            "mrays_per_s": 1234.5}}]}}"#
        )
    };
    std::fs::write(dir.path().join("embree.json"), summary(32)).unwrap();
    std::fs::write(dir.path().join("other.json"), summary(31)).unwrap();
    let bench = |summary: &str| {
        let args = ["bench", mesh, "--rays", "rays", "--reps", "1", "--threads", "1"];
        raylab(dir.path(), &[&args[..], &["--embree", summary]].concat())
    };
    let out = bench("embree.json");
    let stdout = text(&out.stdout);
    assert!(stdout.contains("beside Embree") && stdout.contains("1234.50"), "{stdout}");
    let out = bench("other.json");
    assert_eq!(out.status.code(), Some(1));
    assert!(
        text(&out.stderr).contains("31 triangles, not this mesh's 32"),
        "{}",
        text(&out.stderr)
    );
    // Bad input: one line, non-zero.
    let out = raylab(dir.path(), &["bench", mesh, "--rays", "nowhere"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("nowhere"), "{}", text(&out.stderr));
    std::fs::write(dir.path().join("rays/shadow.rays"), b"RAYS junk").unwrap();
    let out = raylab(dir.path(), &["bench", mesh, "--rays", "rays"]);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(text(&out.stderr).lines().count(), 1);
    assert!(text(&out.stderr).contains("shadow.rays"), "{}", text(&out.stderr));
}

fn scene_file(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes").join(name).display().to_string()
}

#[test]
fn scene_files_render_path_traced_radiance_to_exr_and_pfm() {
    let dir = tempfile::tempdir().unwrap();
    let cbox = scene_file("cornell-mitsuba.toml");
    for name in ["cbox.exr", "cbox.pfm"] {
        let out =
            raylab(dir.path(), &["render", &cbox, "--size", "32x32", "--spp", "4", "-o", name]);
        assert!(out.status.success(), "{}", text(&out.stderr));
        let stdout = text(&out.stdout);
        assert!(stdout.contains("path tracing, max depth 8, 4 samples per pixel"), "{stdout}");
        assert!(stdout.contains("M samples/s") && stdout.contains("mean radiance ("), "{stdout}");
        let film = raylab::image_io::load_film(&dir.path().join(name)).unwrap();
        assert_eq!((film.width(), film.height()), (32, 32));
        // Linear radiance: the light's pixels are far above 1.
        assert!(film.pixels().iter().any(|p| p.x > 10.0), "{name}");
    }
    // A sound scene discards no sample.
    let out =
        raylab(dir.path(), &["render", &cbox, "--size", "16x16", "--spp", "2", "-o", "s.pfm"]);
    assert!(!text(&out.stderr).contains("not finite"), "{}", text(&out.stderr));
    // A point light 0.001 above a sphere: I/d² overflows, and the render says how often.
    let hot = "[render]\nsize = [16, 16]\nspp = 2\nintegrator = \"path\"\n\
        [camera]\nposition = [0, 0, 3]\ntarget = [0, 0, 0]\nfov = 40\n\
        [materials.white]\ntype = \"diffuse\"\nreflectance = [0.8, 0.8, 0.8]\n\
        [[shapes]]\ntype = \"sphere\"\nmaterial = \"white\"\n\
        [[lights]]\ntype = \"point\"\nposition = [0, 0, 1.001]\nintensity = [1e37, 1e37, 1e37]\n";
    std::fs::write(dir.path().join("hot.toml"), hot).unwrap();
    let out = raylab(dir.path(), &["render", "hot.toml", "-o", "hot.pfm"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stderr = text(&out.stderr);
    assert!(
        stderr.contains("of 512 samples were not finite") && stderr.lines().count() == 1,
        "{stderr}"
    );
    // Seeds change the noise, and the same seed gives the same file.
    let render = |seed: &str, name: &str| {
        let args = ["render", &cbox, "--size", "16x16", "--spp", "2", "--seed", seed, "-o", name];
        assert!(raylab(dir.path(), &args).status.success());
        std::fs::read(dir.path().join(name)).unwrap()
    };
    assert_eq!(render("7", "a.pfm"), render("7", "b.pfm"));
    assert_ne!(render("7", "a.pfm"), render("8", "c.pfm"));
    // AOVs as extra EXR layers, averaged over the same samples.
    let args = [
        "render",
        &cbox,
        "--size",
        "16x16",
        "--spp",
        "2",
        "--aov",
        "albedo,depth",
        "-o",
        "aov.exr",
    ];
    assert!(raylab(dir.path(), &args).status.success());
    let channels = raylab::image_io::load_exr_channels(&dir.path().join("aov.exr")).unwrap();
    let names: Vec<&str> = channels.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["B", "G", "R", "albedo.B", "albedo.G", "albedo.R", "depth.Z"]);
    let depth = &channels[6].1;
    // The box's back wall is 4.9 from the camera; the centre pixel sees the tall box, nearer.
    assert!(
        depth.iter().all(|&d| (0.0..=6.0).contains(&d)) && depth[8 * 16 + 8] > 3.0,
        "{depth:?}"
    );
    let out = raylab(dir.path(), &["render", &cbox, "--aov", "albedo", "-o", "aov.png"]);
    assert!(text(&out.stderr).contains("must end in .exr"), "{}", text(&out.stderr));
    // The other integrators and the display options.
    for args in [
        &["--integrator", "albedo"][..],
        &["--integrator", "normals"],
        &["--integrator", "depth"],
        &["--tonemap", "aces", "--exposure", "1"],
        &["--filter", "gaussian", "--sampler", "independent", "--max-depth", "2"],
        &["--aperture", "0.1", "--focus-distance", "4"],
    ] {
        let mut all = vec!["render", &cbox, "--size", "16x16", "--spp", "2", "-o", "x.png"];
        all.extend_from_slice(args);
        let out = raylab(dir.path(), &all);
        assert!(out.status.success(), "{args:?}: {}", text(&out.stderr));
    }
    // Every shipped scene loads and renders.
    for name in ["cornell-lab.toml", "showcase.toml"] {
        let out = raylab(
            dir.path(),
            &["render", &scene_file(name), "--size", "8x6", "--spp", "1", "-o", "s.png"],
        );
        assert!(out.status.success(), "{name}: {}", text(&out.stderr));
    }
}

#[test]
fn a_bad_scene_file_is_one_line_with_its_place_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("bad.toml"), "[camera]\nposition = [0, 0, 1]\nfov = 500\n")
        .unwrap();
    std::fs::write(
        dir.path().join("typo.toml"),
        "[[shapes]]\ntype = \"sphere\"\nmaterial = \"gold\"\n",
    )
    .unwrap();
    for (file, expected) in [
        ("bad.toml", "bad.toml:1:1: fov 500"),
        ("typo.toml", "typo.toml:3:12: no material named 'gold'"),
    ] {
        let out = raylab(dir.path(), &["render", file, "-o", "out.exr"]);
        assert_eq!(out.status.code(), Some(1), "{file}");
        let stderr = text(&out.stderr);
        assert!(stderr.contains(expected), "{stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "one line: {stderr}");
        assert!(!dir.path().join("out.exr").exists());
    }
}

#[test]
fn view_headless_path_traces_a_scene_file() {
    let dir = tempfile::tempdir().unwrap();
    let cbox = scene_file("cornell-mitsuba.toml");
    let args = [
        "view",
        &cbox,
        "--headless",
        "--still",
        "--frames",
        "3",
        "--size",
        "24x24",
        "--screenshot",
        "v.png",
    ];
    let out = raylab(dir.path(), &args);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("frame 3: "), "{}", text(&out.stdout));
    // The screenshot is the sRGB picture of `render --spp 3`.
    let rendered =
        raylab(dir.path(), &["render", &cbox, "--size", "24x24", "--spp", "3", "-o", "r.png"]);
    assert!(rendered.status.success());
    let load = |name: &str| image::open(dir.path().join(name)).unwrap().to_rgb8();
    assert!(load("v.png") == load("r.png"));
}

#[test]
fn a_time_limit_renders_progressively_until_then() {
    let dir = tempfile::tempdir().unwrap();
    let cbox = scene_file("cornell-mitsuba.toml");
    let start = std::time::Instant::now();
    let out = raylab(
        dir.path(),
        &["render", &cbox, "--size", "16x16", "--time-limit", "0.3", "-o", "t.pfm"],
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    let spp: u32 = stdout
        .split(" samples per pixel")
        .next()
        .and_then(|s| s.rsplit(", ").next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("{stdout}"));
    // Many passes of a tiny image fit in 0.3 s, and the whole run is not much longer.
    assert!(spp > 4, "{stdout}");
    assert!(start.elapsed().as_secs_f64() < 30.0);
    // With --spp, at most that many.
    let out = raylab(
        dir.path(),
        &["render", &cbox, "--size", "8x8", "--time-limit", "30", "--spp", "3", "-o", "u.pfm"],
    );
    assert!(text(&out.stdout).contains(", 3 samples per pixel"), "{}", text(&out.stdout));
}

/// A textured glTF renders from the command line, and the report says what the scene holds:
/// its load time and the memory of its geometry, BVH and textures (the 211² logo with its
/// mip-maps: 211² + 105² + 52² + … + 1 = 59,141 texels of 4 bytes, 236,564 bytes).
#[test]
fn the_report_gives_load_time_and_memory() {
    let dir = tempfile::tempdir().unwrap();
    let model = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../raylab/tests/data/meshes/BoxTextured/BoxTextured.gltf"
    );
    let out = raylab(dir.path(), &["render", model, "-o", "box.png", "--size", "32x32"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    assert!(stdout.contains("scene loaded in "), "{stdout}");
    assert!(stdout.contains("memory: geometry "), "{stdout}");
    assert!(stdout.contains(", 1 texture 231.0 KiB"), "{stdout}");
}

/// Each cause of an error is said once: a message that quotes the operating system's reason
/// is not followed by the reason again.
#[test]
fn an_error_says_its_cause_once() {
    let dir = tempfile::tempdir().unwrap();
    let out = raylab(dir.path(), &["merge", "nothere.exr", "-o", "x.exr"]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "one line: {stderr}");
    assert!(stderr.contains("nothere.exr"), "{stderr}");
    let reason = std::io::Error::from_raw_os_error(2).to_string(); // ENOENT's own words
    assert_eq!(stderr.matches(&reason).count(), 1, "the cause once: {stderr}");
    assert_eq!(files_in(dir.path()), Vec::<String>::new(), "nothing written");
}

/// A missing argument is named: clap's whole message on the one line, not cut before the
/// argument.
#[test]
fn a_missing_argument_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let out = raylab(dir.path(), &["merge", "-o", "x.exr"]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "one line: {stderr}");
    assert!(
        stderr.contains("the following required arguments were not provided: <PART>..."),
        "{stderr}"
    );
}
