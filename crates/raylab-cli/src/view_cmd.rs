//! `raylab view`: the lab's interactive window, or its frames without one (`--headless`).
//!
//! Input → [`Controller`] → [`FrameRenderer`] → window: the controller and the frame function are
//! the library's, pure and tested without a window; this file and [`crate::view_window`] only
//! connect them.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use clap::Args;
use raylab::interactive::{
    Controller, FrameRenderer, Motion, Pose, View, ViewMode, rgb8_from_0rgb,
};
use raylab::session::{self, RenderJob, RenderOptions, ResolvedSettings};
use raylab::settings::IntegratorKind;
use raylab::{Film, PathSettings, SampleSettings, Scene, SceneBvh, image_io};

use crate::scene_args::{STAGES_HELP, SceneArgs};
use crate::{stats, view_window};

/// The key map, printed by `raylab view --help` and the H key.
pub const KEYS_HELP: &str = "\
Keys (motion is per second, not per frame):
  Up / Down          camera forward / back along its view direction
  Left / Right       camera yaw, the lab's R(y) (60°/s)
  Page Up / Down     camera up / down
  mouse drag         look around: grab the picture (yaw and pitch)
  W / S              light forward / back (horizontally, as the camera faces)
  A / D              light left / right
  Q / E              light up / down
  + / - , wheel      faster / slower (×√2 a step)
  1 2 3 4 5          lab stage: flat, direct, reflected, shadows, ambient
  6 7 8 9            path tracing, albedo, normals, depth
  P                  screenshot to raylab-view-N.png (the path is printed)
  R                  reset camera and light
  H                  print these keys
  Esc                quit
The title bar shows frames per second, milliseconds per frame and samples per pixel: a still
picture keeps refining (anti-aliasing) up to --max-spp samples.";

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
    /// depth; keys 1-9 switch [default: the scene file's; path for scenes with area lights,
    /// else lab].
    #[arg(long, value_name = "NAME")]
    integrator: Option<IntegratorKind>,

    /// A still picture refines up to this many samples per pixel.
    #[arg(long, value_name = "N", default_value = "1024", value_parser = clap::value_parser!(u32).range(1..=65536))]
    max_spp: u32,
}

/// What the window needs to start.
pub struct Session<'a> {
    pub scene: &'a Scene,
    pub accel: &'a SceneBvh,
    pub pool: &'a rayon::ThreadPool,
    pub controller: Controller,
    pub view: View,
    pub max_spp: u32,
    /// The scene file's path-tracing and sampling settings.
    pub path_settings: PathSettings,
    pub sample_settings: SampleSettings,
    pub screenshot: Option<&'a Path>,
    pub exit_after_frames: Option<u32>,
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
        sample_settings: settings.samples,
        screenshot: args.screenshot.as_deref(),
        exit_after_frames: args.exit_after_frames,
    };
    if args.headless {
        headless(session, args.frames, args.still)
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

/// Simulated frames per second of the headless path.
const HEADLESS_FPS: u32 = 60;

/// The keys the headless path holds from frame `frame` to the next (at 60 frames per second): the
/// camera swings its yaw ±20° while moving forward and back, and the light sweeps left and
/// right, so that every frame shows a new view (and new shadows).
fn scripted_motions(frame: u32) -> [(Motion, bool); 6] {
    // 60°/s: right for ⅓ s (0 → 20°), left for ⅔ s (→ −20°), right for ⅓ s (→ 0), over again.
    let swing = frame % 80;
    let turn_right = !(20..60).contains(&swing);
    let forward = frame % 120 < 60;
    let light_right = forward;
    [
        (Motion::TurnRight, turn_right),
        (Motion::TurnLeft, !turn_right),
        (Motion::Forward, forward),
        (Motion::Back, !forward),
        (Motion::LightRight, light_right),
        (Motion::LightLeft, !light_right),
    ]
}

/// `raylab view --headless`: the window's frames without the window, one line per frame, then
/// the median.
fn headless(mut session: Session, frames: u32, still: bool) -> Result<()> {
    let Session { scene, accel, pool, ref mut controller, mut view, .. } = session;
    // Benchmarks measure full-resolution frames: no budget.
    let mut renderer = FrameRenderer::new(None, session.max_spp);
    renderer.path_settings = session.path_settings;
    renderer.sample_settings = session.sample_settings;
    let mut times = Vec::with_capacity(frames as usize);
    let mut words = Vec::new();
    let run_start = Instant::now();
    for frame in 0..frames {
        // Simulated time: the path is the same on every machine.
        let at = Duration::from_secs(frame as u64) / HEADLESS_FPS;
        if !still {
            for (motion, held) in scripted_motions(frame) {
                match (held, controller.is_held(motion)) {
                    (true, false) => controller.press(motion, at),
                    (false, true) => controller.release(motion, at),
                    _ => {}
                }
            }
            controller.advance(at);
            view.pose = controller.pose();
        }
        if renderer.is_done(&view) {
            println!("the picture has all its {} samples per pixel: stopping", session.max_spp);
            break;
        }
        let info = pool.install(|| renderer.frame(scene, accel, &view, &mut words))?;
        let ms = info.render_time.as_secs_f64() * 1e3;
        times.push(ms);
        println!(
            "frame {}: {ms:.2} ms, {}×{}, {} spp{}",
            frame + 1,
            view.width,
            view.height,
            info.samples,
            if info.moving { ", moving" } else { "" }
        );
    }
    let total = run_start.elapsed();
    let summary = summarize(&mut times);
    println!(
        "{} frames of {} ({} triangles) at {}×{} on {} thread{}: median {:.2} ms ({:.1} frames \
         per second), mean {:.2} ms, 10th–90th percentile {:.2}–{:.2} ms; {:.2} s in all",
        times.len(),
        scene.name,
        scene.geometry.len(),
        view.width,
        view.height,
        pool.current_num_threads(),
        if pool.current_num_threads() == 1 { "" } else { "s" },
        summary.median,
        1e3 / summary.median,
        summary.mean,
        summary.p10,
        summary.p90,
        total.as_secs_f64(),
    );
    if let Some(path) = session.screenshot {
        save_screenshot(path, &words, view.width, view.height)?;
        println!("screenshot: {}", path.display());
    }
    Ok(())
}

struct Summary {
    median: f64,
    mean: f64,
    p10: f64,
    p90: f64,
}

/// Median, mean and 10th and 90th percentiles (nearest rank) of frame times.
fn summarize(times: &mut [f64]) -> Summary {
    let median = stats::median(times);
    let mean = times.iter().sum::<f64>() / times.len() as f64;
    Summary {
        median,
        mean,
        p10: stats::nearest_rank(times, 0.1),
        p90: stats::nearest_rank(times, 0.9),
    }
}

/// Writes a window buffer of `0x00RRGGBB` words to an image file (whole, or not at all).
pub fn save_screenshot(path: &Path, words: &[u32], width: u32, height: u32) -> Result<()> {
    image_io::save_rgb8(path, &rgb8_from_0rgb(words, width, height))
        .with_context(|| format!("cannot write the screenshot {}", path.display()))
}

/// The first `raylab-view-N.png` in the current folder that does not exist yet.
pub fn next_screenshot_path() -> Result<PathBuf> {
    for n in 1..100_000 {
        let path = PathBuf::from(format!("raylab-view-{n}.png"));
        if !path.try_exists().unwrap_or(true) {
            return Ok(path);
        }
    }
    bail!("cannot find a free screenshot name: raylab-view-1.png to raylab-view-99999.png exist")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scripted_path_swings_and_returns() {
        let mut c = Controller::new(
            Pose { position: glam::Vec3::ZERO, yaw: 0.0, pitch: 0.0, light: glam::Vec3::ZERO },
            1.0,
        );
        let mut max_yaw = 0.0f32;
        for frame in 0..=240 {
            let at = Duration::from_secs(frame as u64) / HEADLESS_FPS;
            for (motion, held) in scripted_motions(frame) {
                if held { c.press(motion, at) } else { c.release(motion, at) }
            }
            c.advance(at);
            max_yaw = max_yaw.max(c.pose().yaw.abs());
        }
        // Four seconds: three whole swings, two forward-and-back and light sweeps.
        assert!((max_yaw - 20f32.to_radians()).abs() < 0.02, "{}", max_yaw.to_degrees());
        assert!(c.pose().yaw.abs() < 0.02, "{}", c.pose().yaw);
        assert!(
            c.pose().position.length() < 0.05 && c.pose().light.length() < 0.05,
            "{:?}",
            c.pose()
        );
    }

    #[test]
    fn summaries_use_the_median() {
        let s = summarize(&mut [5.0, 1.0, 3.0, 100.0]);
        assert_eq!((s.median, s.mean, s.p10, s.p90), (4.0, 27.25, 1.0, 100.0));
        assert_eq!(summarize(&mut [2.0, 9.0, 4.0]).median, 4.0);
    }
}
