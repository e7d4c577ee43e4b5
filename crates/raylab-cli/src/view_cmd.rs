//! `raylab view`: the lab's interactive window, or its frames without one (`--headless`).
//!
//! Input → [`Controller`] → [`FrameRenderer`] → window: the controller and the frame function are
//! the library's, pure and tested without a window; this file and [`crate::view_window`] only
//! connect them.

use std::path::PathBuf;

use anyhow::{Result, bail};
use clap::Args;
use raylab::interactive::{Controller, Pose, View, ViewMode};
use raylab::session::{self, RenderJob, RenderOptions, ResolvedSettings};
use raylab::settings::IntegratorKind;
use raylab::{Film, SampleSettings, Scene, image_io};

use crate::scene_args::{STAGES_HELP, SceneArgs};
use crate::view_session::{KEYS_HELP, Session};
use crate::view_window;

#[derive(Args, Debug)]
#[command(after_help = KEYS_HELP, after_long_help = format!("{KEYS_HELP}\n\n{STAGES_HELP}"), allow_negative_numbers = true)]
pub struct ViewArgs {
    #[command(flatten)]
    scene: SceneArgs,

    /// Render without a window and print each frame's time: the frame function `raylab view`
    /// uses, for benchmarks. The camera and light move on a fixed path (unless --still), every
    /// frame at full resolution.
    #[arg(long)]
    headless: bool,

    /// With --headless: how many frames to render.
    #[arg(long, value_name = "N", default_value = "300", requires = "headless", value_parser = clap::value_parser!(u32).range(1..))]
    frames: u32,

    /// With --headless: keep the camera still, so that frames refine one picture.
    #[arg(long, requires = "headless")]
    still: bool,

    /// Write the picture shown last to this PNG (or PPM) file: after the last frame, or when the
    /// window closes.
    #[arg(long, value_name = "FILE")]
    screenshot: Option<PathBuf>,

    /// Close the window after this many frames, or once the picture has --max-spp samples (with
    /// --screenshot: after writing it).
    #[arg(long, value_name = "N", conflicts_with = "headless", value_parser = clap::value_parser!(u32).range(1..))]
    exit_after_frames: Option<u32>,

    /// What to show first: lab (the lab's light model), path (path tracing), albedo, normals or
    /// depth; keys 1-9 switch [default: the scene file's; path where a surface emits or a
    /// light is not a point light, else lab].
    #[arg(long, value_name = "NAME")]
    integrator: Option<IntegratorKind>,

    /// A still picture refines up to this many samples per pixel.
    #[arg(long, value_name = "N", default_value = "1024", value_parser = clap::value_parser!(u32).range(1..=65536))]
    max_spp: u32,
}

/// The largest window side `raylab view` opens (X11 windows cannot be wider than 32,767).
const MAX_WINDOW_SIDE: u32 = 16_384;

pub fn run(args: &ViewArgs) -> Result<()> {
    let setup = args.scene.setup()?;
    let scene = &setup.scene;
    let cameras = args.scene.camera_options();
    let (width, height) = cameras.size(scene);
    if width.max(height) > MAX_WINDOW_SIDE {
        bail!(
            "--size {width}x{height} is too large for a window: at most {MAX_WINDOW_SIDE} pixels a side"
        );
    }
    // The picture's sums, the window's words and their spare: about twice a film.
    session::check_memory(Film::bytes_needed(width, height).saturating_mul(2), width, height)?;
    if let Some(path) = &args.screenshot {
        image_io::check_writable(path)?;
    }
    if !args.headless {
        // Before loading anything big: say at once when there is nowhere to show a window.
        view_window::check_display()?;
    }
    let options = RenderOptions {
        integrator: args.integrator,
        stage: args.scene.stage,
        ..RenderOptions::default()
    };
    let settings = ResolvedSettings::resolve(scene, &options);
    for warning in settings.warnings(scene) {
        eprintln!("raylab: warning: {warning}");
    }
    let mut job = RenderJob::new(scene, settings, args.scene.threads())?;
    let camera = cameras.camera(setup.first_camera(), scene, setup.is_model, job.accel()?)?;
    let accel = job.built_accel().expect("built above");
    let home = Pose {
        position: camera.position,
        yaw: camera.yaw,
        pitch: camera.pitch,
        light: scene.lab_light().position,
    };
    let view = View {
        pose: home,
        mode: ViewMode::of(settings.integrator, settings.stage),
        width: camera.width,
        height: camera.height,
        focal: (camera.width, camera.focal_length_px),
        lens: (camera.aperture_radius, camera.focus_distance),
        roll: camera.roll,
    };
    let session = Session {
        scene,
        accel,
        pool: job.pool(),
        controller: Controller::new(home, motion_speed(scene)),
        view,
        max_spp: args.max_spp,
        path_settings: settings.path_settings(),
        // Frames go on without a known end: no sample count (`multijitter` is then `sobol`).
        sample_settings: SampleSettings { count: 0, ..settings.samples },
        screenshot: args.screenshot.as_deref(),
        exit_after_frames: args.exit_after_frames,
    };
    if args.headless {
        crate::headless::headless(session, args.frames, args.still)
    } else {
        view_window::run(session)
    }
}

/// Scene units per second at the starting speed: a quarter of the scene's diagonal, so that the
/// lab's box (2 units across) is crossed in about two seconds, whatever the model's units.
fn motion_speed(scene: &Scene) -> f32 {
    let diagonal = scene.bounds().map_or(1.0, |(lo, hi)| (hi - lo).length());
    if diagonal.is_finite() && diagonal > 0.0 { diagonal / 4.0 } else { 1.0 }
}
