//! `raylab render`: one frame to an image file.

use std::io::{IsTerminal, Write};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use raylab::{Bvh, Film, Lab, image_io, render_samples};

use raylab::camera::tidy;

use crate::scene_args::{STAGES_HELP, SceneArgs, Setup, tidy_vec3};
use crate::system;

/// Renders longer than this get a progress bar (on a terminal).
const PROGRESS_AFTER: Duration = Duration::from_millis(500);

#[derive(Args, Debug)]
#[command(after_long_help = STAGES_HELP, allow_negative_numbers = true)]
pub struct RenderArgs {
    #[command(flatten)]
    scene: SceneArgs,

    /// Output image; the format comes from the extension (.png or .ppm).
    #[arg(short, long, value_name = "FILE", default_value = "render.png")]
    output: PathBuf,

    /// Samples per pixel: 1 is the lab's ray through each pixel's centre; more spread over the
    /// pixel and averaged (anti-aliasing), exactly as `raylab view` refines a still picture.
    #[arg(long, value_name = "N", default_value = "1", value_parser = clap::value_parser!(u32).range(1..=MAX_SPP as i64))]
    spp: u32,
}

/// The most samples per pixel `--spp` accepts.
const MAX_SPP: u32 = 1 << 16;

pub fn run(args: &RenderArgs) -> Result<()> {
    // Everything that can be checked is checked before rendering, so no work is lost.
    let setup = args.scene.setup()?;
    let Setup { scene, camera, threads } = &setup;
    let (width, height) = (camera.width, camera.height);
    image_io::check_writable(&args.output)?;
    // With more than one sample, the sums and their mean: two films.
    let films = if args.spp > 1 { 2 } else { 1 };
    system::check_memory(films * Film::bytes_needed(width, height), width, height)?;
    let pool = setup.thread_pool()?;

    let start = Instant::now();
    let accel = pool.install(|| Bvh::new(&scene.vertices()));
    let build = start.elapsed();
    let stage = args.scene.stage;
    let integrator = Lab::new(scene, &accel, stage);
    let progress = Progress::new(height as u64 * args.spp as u64);
    let start = Instant::now();
    let film = pool.install(|| {
        render_samples(camera, &integrator, args.spp, &|rows| progress.advance(rows))
    })?;
    let elapsed = start.elapsed();
    progress.finish();

    image_io::save_rgb8(&args.output, &film.to_rgb8_clamped()?)?;
    let samples =
        if args.spp == 1 { String::new() } else { format!(", {} samples per pixel", args.spp) };
    let report = format!(
        "{}: {width}×{height}, {} ({} triangles) stage {stage}{samples}, {:.1} ms on {threads} \
         thread{} (+{:.1} ms BVH build)\n{camera}\nlight at {} power {}\n",
        args.output.display(),
        scene.name,
        scene.geometry.len(),
        elapsed.as_secs_f64() * 1e3,
        if *threads == 1 { "" } else { "s" },
        build.as_secs_f64() * 1e3,
        tidy_vec3(scene.lab_light().position),
        tidy(scene.lab_light().power.x),
    );
    // The image is written; a closed or full standard output is not worth a failure, but it
    // must not be a panic either (`println!` would panic).
    match std::io::stdout().lock().write_all(report.as_bytes()) {
        Err(error) if error.kind() != std::io::ErrorKind::BrokenPipe => {
            Err(error).context("cannot print the report to standard output")
        }
        _ => Ok(()),
    }
}

/// A progress bar that appears only on a terminal and only once a render has taken a while.
struct Progress {
    bar: ProgressBar,
    start: Instant,
    on_terminal: bool,
    shown: AtomicBool,
}

impl Progress {
    fn new(rows: u64) -> Self {
        let bar = ProgressBar::with_draw_target(Some(rows), ProgressDrawTarget::hidden());
        bar.set_style(
            ProgressStyle::with_template(
                "{bar:40} {pos}/{len} rows, {elapsed} elapsed, ~{eta} left",
            )
            .expect("the template is valid"),
        );
        Progress {
            bar,
            start: Instant::now(),
            on_terminal: std::io::stderr().is_terminal(),
            shown: AtomicBool::new(false),
        }
    }

    fn advance(&self, rows: u32) {
        self.bar.inc(rows as u64);
        if self.on_terminal
            && self.start.elapsed() > PROGRESS_AFTER
            && !self.shown.swap(true, Ordering::Relaxed)
        {
            self.bar.set_draw_target(ProgressDrawTarget::stderr());
        }
    }

    fn finish(&self) {
        self.bar.finish_and_clear();
    }
}
