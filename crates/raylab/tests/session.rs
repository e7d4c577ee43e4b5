//! The render session gives the pixels of the renderer's own parts put together by hand: an
//! accumulator adding passes of the scene's integrator, for every scene in `scenes/`, the lab's
//! box and a model; a region holds the whole image's pixels there; a render stopped after its
//! first pass and resumed from its checkpoint ends with the uninterrupted render's pixels; AOV
//! layers from the same pass are the layers a pass of their own gives.

mod common;

use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

use raylab::integrator::{Aov, Integrator, Lab, PathScalar as PathTracer};
use raylab::parts::{self, Channel};
use raylab::scene::{LoadOptions, OpenedScene};
use raylab::session::{
    CameraOptions, Checkpoints, Event, RenderJob, RenderOptions, ResolvedSettings,
};
use raylab::settings::{AovKind, IntegratorKind};
use raylab::{Accumulator, Camera, Film, Region, Scene, SceneBvh};

const SIZE: (u32, u32) = (24, 16);

/// The scenes of `scenes/`, the built-in lab box and a model file.
fn scene_names() -> Vec<String> {
    common::scene_names(&["bunny_lowres.obj"])
}

fn open(name: &str) -> OpenedScene {
    Scene::open(name, &LoadOptions::default()).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// The picture made by hand: an accumulator adding `spp` passes of the scene's integrator
/// (`path` and `path-scalar` both by the scalar path tracer: the session's `path` is the
/// wavefront, which must give the same bits).
fn by_hand(scene: &Scene, settings: &ResolvedSettings, camera: &Camera, region: Region) -> Film {
    let accel = SceneBvh::build(&scene.geometry).unwrap();
    let lab = Lab::new(scene, &accel, settings.stage).for_camera(camera);
    let path = PathTracer::new(scene, &accel, settings.path_settings());
    let aov;
    let integrator: &dyn Integrator = match settings.integrator {
        IntegratorKind::Lab => &lab,
        IntegratorKind::Path | IntegratorKind::PathScalar => &path,
        IntegratorKind::Aov(kind) => {
            aov = Aov::new(scene, &accel, kind);
            &aov
        }
    };
    let mut accumulator = Accumulator::for_region(camera.width, camera.height, region).unwrap();
    accumulator.settings = settings.samples;
    for _ in 0..settings.spp() {
        accumulator.add_sample(camera, integrator);
    }
    accumulator.mean().unwrap()
}

fn bits(film: &Film) -> Vec<[u32; 3]> {
    film.pixels().iter().map(|p| p.to_array().map(f32::to_bits)).collect()
}

fn channel_bits(channels: &[Channel], name: &str) -> Vec<u32> {
    let channel = channels.iter().find(|c| c.0 == name).unwrap_or_else(|| panic!("{name}"));
    channel.1.iter().map(|v| v.to_bits()).collect()
}

fn read_film(path: &Path, width: u32, height: u32) -> Film {
    let part = parts::read_part(path).unwrap();
    parts::beauty(&part.channels, width, height).expect("R, G and B")
}

fn no_events(_: Event) {}

#[test]
fn a_job_gives_the_pixels_of_its_parts_put_together_by_hand() {
    let dir = tempfile::tempdir().unwrap();
    for name in scene_names() {
        let OpenedScene { scene, is_model } = open(&name);
        let options = RenderOptions { spp: Some(2), ..RenderOptions::default() };
        let settings = ResolvedSettings::resolve(&scene, &options);
        let mut job = RenderJob::new(&scene, settings, 2).unwrap();
        let cameras = CameraOptions { size: Some(SIZE), ..CameraOptions::default() };
        let first = scene.camera.or(scene.keyframes.first().map(|k| k.camera));
        let camera = cameras.camera(first, &scene, is_model, job.accel().unwrap()).unwrap();
        let output = dir.path().join("whole.exr");
        let outcome = job.render_frame(&camera, &output, None, &no_events).unwrap();
        assert_eq!((outcome.samples, outcome.interrupted), (2, false), "{name}");
        let expected = by_hand(&scene, &settings, &camera, Region::full(SIZE.0, SIZE.1));
        let whole = read_film(&output, SIZE.0, SIZE.1);
        assert!(bits(&whole) == bits(&expected), "{name}: the job's pixels differ");
        assert!(whole.pixels().iter().any(|p| p.max_element() > 0.0), "{name}: all black");

        // A region holds the whole image's pixels there.
        let region = Region::new([5, 3, 17, 11], SIZE.0, SIZE.1).unwrap();
        job.region = Some(region);
        let part = dir.path().join("part.exr");
        job.render_frame(&camera, &part, None, &no_events).unwrap();
        let expected = by_hand(&scene, &settings, &camera, region);
        let part = read_film(&part, region.width(), region.height());
        assert!(bits(&part) == bits(&expected), "{name}: the region's pixels differ");

        // In memory (`render_film`, what the Python package calls): the same pixels.
        let in_memory = job.render_film(&camera, &no_events).unwrap();
        assert_eq!((in_memory.samples, in_memory.region), (2, region), "{name}");
        assert!(bits(&in_memory.film) == bits(&expected), "{name}: the film's pixels differ");
        job.region = None;
        let in_memory = job.render_film(&camera, &no_events).unwrap();
        assert!(bits(&in_memory.film) == bits(&whole), "{name}: the whole film differs");
    }
}

#[test]
fn a_stopped_render_resumes_from_its_checkpoint_to_the_same_pixels() {
    let dir = tempfile::tempdir().unwrap();
    let name = common::repository().join("scenes/cornell-mitsuba.toml").display().to_string();
    let OpenedScene { scene, is_model } = open(&name);
    let options = RenderOptions { spp: Some(3), ..RenderOptions::default() };
    let settings = ResolvedSettings::resolve(&scene, &options);
    let cameras = CameraOptions { size: Some(SIZE), ..CameraOptions::default() };
    let output = dir.path().join("out.exr");
    let checkpoints = Some(Checkpoints { every: std::time::Duration::ZERO, command: None });

    // Stopped during its first pass: it finishes the pass, writes the checkpoint and the picture.
    let stop = AtomicBool::new(false);
    let mut job = RenderJob::new(&scene, settings, 2).unwrap();
    job.checkpoints = checkpoints.clone();
    job.aovs = vec![AovKind::Albedo, AovKind::Depth];
    job.stop_when(&stop);
    let camera = cameras.camera(scene.camera, &scene, is_model, job.accel().unwrap()).unwrap();
    let stop_at_once = |event: Event| {
        if let Event::Rows(_) = event {
            stop.store(true, Ordering::Relaxed);
        }
    };
    let stopped = job.render_frame(&camera, &output, None, &stop_at_once).unwrap();
    assert!(stopped.interrupted && stopped.samples == 1, "{stopped:?}");
    let checkpoint = stopped.checkpoint.clone().expect("checkpoints are on");
    assert!(checkpoint.exists());

    // The same render again goes on from the checkpoint, and deletes it when done.
    let mut job = RenderJob::new(&scene, settings, 1).unwrap();
    job.checkpoints = checkpoints;
    job.aovs = vec![AovKind::Albedo, AovKind::Depth];
    let resumed = std::sync::Mutex::new(None);
    let note = |event: Event| {
        if let Event::Resumed { samples, .. } = event {
            *resumed.lock().unwrap() = Some(samples);
        }
    };
    let done = job.render_frame(&camera, &output, None, &note).unwrap();
    assert_eq!((*resumed.lock().unwrap(), done.first_sample, done.samples), (Some(1), 1, 3));
    assert!(!checkpoint.exists(), "a finished render deletes its checkpoint");
    let resumed_channels = parts::read_part(&output).unwrap().channels;

    // An uninterrupted render, on another thread count.
    let mut job = RenderJob::new(&scene, settings, 3).unwrap();
    job.aovs = vec![AovKind::Albedo, AovKind::Depth];
    let straight = dir.path().join("straight.exr");
    job.render_frame(&camera, &straight, None, &no_events).unwrap();
    let straight_channels = parts::read_part(&straight).unwrap().channels;
    for name in ["R", "G", "B", "albedo.R", "albedo.G", "albedo.B", "depth.Z"] {
        assert_eq!(
            channel_bits(&resumed_channels, name),
            channel_bits(&straight_channels, name),
            "{name}"
        );
    }
}

#[test]
fn layers_from_the_same_pass_are_those_of_a_pass_of_their_own() {
    let dir = tempfile::tempdir().unwrap();
    let name = common::repository().join("scenes/showcase.toml").display().to_string();
    let OpenedScene { scene, is_model } = open(&name);
    let options = RenderOptions { spp: Some(2), ..RenderOptions::default() };
    let settings = ResolvedSettings::resolve(&scene, &options);
    assert_eq!(settings.integrator, IntegratorKind::Path);
    let mut job = RenderJob::new(&scene, settings, 2).unwrap();
    job.aovs = AovKind::ALL.to_vec();
    let cameras = CameraOptions { size: Some(SIZE), ..CameraOptions::default() };
    let camera = cameras.camera(scene.camera, &scene, is_model, job.accel().unwrap()).unwrap();
    let output = dir.path().join("layers.exr");
    job.render_frame(&camera, &output, None, &no_events).unwrap();
    let channels = parts::read_part(&output).unwrap().channels;
    // The colour is the render's without layers.
    let full = Region::full(SIZE.0, SIZE.1);
    let beauty = by_hand(&scene, &settings, &camera, full);
    let beauty_r: Vec<u32> = beauty.pixels().iter().map(|p| p.x.to_bits()).collect();
    assert_eq!(channel_bits(&channels, "R"), beauty_r);
    // Each layer is its AOV rendered alone: the path tracer and the AOVs use the same sampler
    // (Sobol'), so their camera rays are the same.
    for kind in AovKind::ALL {
        let alone = ResolvedSettings { integrator: IntegratorKind::Aov(kind), ..settings };
        let film = by_hand(&scene, &alone, &camera, full);
        let (name, axis) = if kind == AovKind::Depth {
            ("depth.Z".to_string(), 0)
        } else {
            (format!("{kind}.G"), 1)
        };
        let expected: Vec<u32> = film.pixels().iter().map(|p| p[axis].to_bits()).collect();
        assert_eq!(channel_bits(&channels, &name), expected, "{name}");
        assert!(expected.iter().any(|&b| b != 0), "{name}: all zero");
    }
}
