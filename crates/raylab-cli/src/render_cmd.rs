//! `raylab render`: one frame to an image file.

use std::io::{IsTerminal, Write};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use clap::Args;
use glam::Vec3;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use raylab::film::format_bytes;
use raylab::{Bvh, Camera, Film, Lab, Scene, Stage, image_io, render};

use crate::args::{self, Size};
use crate::system;

/// The most threads `--threads` accepts.
const MAX_THREADS: usize = 1024;

/// Renders longer than this get a progress bar (on a terminal).
const PROGRESS_AFTER: Duration = Duration::from_millis(500);

#[derive(Args, Debug)]
#[command(after_long_help = STAGES_HELP, allow_negative_numbers = true)]
pub struct RenderArgs {
    /// The scene: `cornell`, the lab's Cornell box (30 triangles, y down), or a model file
    /// (.obj with its .mtl, .ply, either optionally .gz; y up, framed by the camera unless
    /// --camera is given).
    #[arg(default_value = "cornell", value_name = "SCENE|MODEL")]
    scene: String,

    /// Output image; the format comes from the extension (.png or .ppm).
    #[arg(short, long, value_name = "FILE", default_value = "render.png")]
    output: PathBuf,

    /// Image size in pixels.
    #[arg(long, value_name = "WxH", default_value = "500x500", value_parser = args::size, allow_hyphen_values = true)]
    size: Size,

    /// Camera position (lab axes: x right, y down, z forward) [default: the lab's (0, 0, -3) for
    /// `cornell`; for a model, in front of it, framing its bounding box].
    #[arg(long, value_name = "X,Y,Z", value_parser = args::vec3, allow_hyphen_values = true)]
    camera: Option<Vec3>,

    /// Camera yaw in degrees: rotation about the vertical axis, positive toward +x (the lab's R(y)).
    #[arg(long, value_name = "DEG", default_value = "0", value_parser = args::finite_f32, allow_hyphen_values = true)]
    yaw: f32,

    /// Focal length in pixels [default: the image width, as the lab's f = 500 for 500×500, which
    /// is a 53.13° horizontal field of view: fov = 2·atan(W / 2f), not 90°].
    #[arg(long, value_name = "PX", value_parser = args::positive_f32, conflicts_with = "fov")]
    focal: Option<f32>,

    /// Horizontal field of view in degrees, instead of --focal (sets f = W / (2·tan(fov/2))).
    #[arg(long, value_name = "DEG", value_parser = args::fov_deg)]
    fov: Option<f32>,

    /// Point-light position [default: the lab's (0, -0.5, -0.7); for a model, above it, to the
    /// right and in front].
    #[arg(long, value_name = "X,Y,Z", value_parser = args::vec3, allow_hyphen_values = true)]
    light: Option<Vec3>,

    /// Point-light power P per channel [default: the lab's 14; for a model, enough for an
    /// irradiance of 1 at its centre].
    #[arg(long, value_name = "WATTS", value_parser = args::non_negative_f32)]
    light_power: Option<f32>,

    /// How much of the lab's light model to show (see below).
    #[arg(long, value_name = "STAGE", default_value = "ambient")]
    stage: Stage,

    /// Threads to render with [default: one per core].
    #[arg(long, value_name = "N")]
    threads: Option<usize>,
}

const STAGES_HELP: &str = "\
Stages, the lab's steps in order (--stage NAME or 1-5):
  flat       flat triangle colour ρ, black where nothing is hit
  direct     the light's power per area D = P·max(r̂·n̂,0)/(4πr²) alone (lab eq. 27)
  reflected  ρ∗D, no shadows
  shadows    ρ∗D with shadow rays
  ambient    ρ∗(D+N) with shadows and constant ambient N = 0.5 (lab eq. 30; the default)

Every channel is clamped to [0,1] and shown without gamma, as in the lab.";

pub fn run(args: &RenderArgs) -> Result<()> {
    // Everything that can be checked is checked before rendering, so no work is lost.
    let (mut scene, is_model) = load_scene(&args.scene)?;
    if let Some(position) = args.light {
        scene.light.position = position;
    }
    if let Some(power) = args.light_power {
        scene.light.power = Vec3::splat(power);
    }
    scene.validate()?;

    let Size { width, height } = args.size;
    let focal_length_px = match (args.focal, args.fov) {
        (Some(focal), _) => focal,
        (None, Some(fov)) => Camera::focal_length_for_fov(width, fov),
        (None, None) => Camera::lab(width, height).focal_length_px,
    };
    if !focal_length_px.is_finite() {
        bail!("--fov {} is too small: the focal length would be infinite", args.fov.unwrap_or(0.0));
    }
    let default_position = match scene.bounds() {
        Some((lo, hi)) if is_model => Camera::framing(lo, hi, width, height).position,
        _ => Camera::lab(width, height).position,
    };
    let camera = Camera {
        position: args.camera.unwrap_or(default_position),
        yaw: args.yaw.to_radians(),
        focal_length_px,
        width,
        height,
    };

    image_io::check_writable(&args.output)?;
    let needed = Film::bytes_needed(width, height);
    if let Some(available) = system::available_memory_bytes()
        && needed > available
    {
        bail!(
            "image size {width}×{height} needs {} of memory, but only {} is available",
            format_bytes(needed),
            format_bytes(available)
        );
    }
    let threads = match args.threads {
        None | Some(0) => system::cores(),
        Some(n) if n > MAX_THREADS => bail!("--threads {n} is more than {MAX_THREADS}"),
        Some(n) => n,
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .context("cannot start the render threads")?;

    let start = Instant::now();
    let accel = pool.install(|| Bvh::new(&scene.triangles));
    let build = start.elapsed();
    let integrator = Lab::new(&scene, &accel, args.stage);
    let progress = Progress::new(height);
    let start = Instant::now();
    let film = pool.install(|| render(&camera, &integrator, &|rows| progress.advance(rows)))?;
    let elapsed = start.elapsed();
    progress.finish();

    image_io::save_rgb8(&args.output, &film.to_rgb8_clamped()?)?;
    let report = format!(
        "{}: {width}×{height}, {} ({} triangles) stage {}, {:.1} ms on {threads} thread{} \
         (+{:.1} ms BVH build)\n{camera}\nlight at {} power {}\n",
        args.output.display(),
        scene.name,
        scene.triangles.len(),
        args.stage,
        elapsed.as_secs_f64() * 1e3,
        if threads == 1 { "" } else { "s" },
        build.as_secs_f64() * 1e3,
        tidy_vec3(scene.light.position),
        tidy(scene.light.power.x),
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

/// A built-in scene by name, or a model file (anything that looks like a path). The flag says
/// whether it is a model.
fn load_scene(name: &str) -> Result<(Scene, bool)> {
    let path = std::path::Path::new(name);
    let looks_like_a_file = path.exists() || name.contains('/') || name.contains('.');
    match Scene::built_in(name) {
        Ok(scene) => return Ok((scene, false)),
        // Neither a built-in name nor a file: say what the built-in scenes are.
        Err(unknown) if !looks_like_a_file => return Err(unknown.into()),
        Err(_) => {}
    }
    let loaded = raylab::scene::load_mesh(path)?;
    for warning in &loaded.warnings {
        eprintln!("raylab: warning: {warning}");
    }
    Ok((Scene::from_mesh(&loaded.mesh), true))
}

/// A number with at most 4 significant decimals and no trailing zeros.
fn tidy(v: f32) -> String {
    let s = format!("{v:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.into() }
}

fn tidy_vec3(v: Vec3) -> String {
    format!("({}, {}, {})", tidy(v.x), tidy(v.y), tidy(v.z))
}

/// A progress bar that appears only on a terminal and only once a render has taken a while.
struct Progress {
    bar: ProgressBar,
    start: Instant,
    on_terminal: bool,
    shown: AtomicBool,
}

impl Progress {
    fn new(rows: u32) -> Self {
        let bar = ProgressBar::with_draw_target(Some(rows as u64), ProgressDrawTarget::hidden());
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
