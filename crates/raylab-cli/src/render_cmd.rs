//! `raylab render`: one frame to an image file.

use std::path::PathBuf;
use std::time::Duration;

use anyhow::Result;
use clap::Args;
use raylab::film::ToneMap;
use raylab::parts::Part;
use raylab::session::{
    Checkpoints, Event, FrameOutcome, FrameSummary, MAX_SPP, RenderJob, RenderOptions,
    ResolvedSettings,
};
use raylab::settings::{AovKind, IntegratorKind, MaxDepth};
use raylab::{Filter, Region, SamplerKind, TriangleSampling};

use crate::args;
use crate::progress::FrameProgress;
use crate::render_state::{self, Command, Interrupted};
use crate::scene_args::{STAGES_HELP, SceneArgs, Setup};

#[derive(Args, Debug)]
// An option given twice takes its last value, so that a script's defaults (the farm scripts'
// --threads and --checkpoint) can be overridden by the options passed on to it.
#[command(after_long_help = STAGES_HELP, allow_negative_numbers = true, args_override_self = true)]
pub struct RenderArgs {
    #[command(flatten)]
    scene: SceneArgs,

    /// Output image; the format comes from the extension: .png or .ppm (8-bit, through the
    /// display transform), .exr or .pfm (linear radiance, 32-bit float).
    #[arg(short, long, value_name = "FILE", default_value = "render.png")]
    output: PathBuf,

    /// What to compute: lab (the lab's light model), path (path tracing), path-scalar (the
    /// same pixels, one path at a time), or the first hit's albedo, normals or depth [default:
    /// the scene file's; path where a surface emits or a light is not a point light, else
    /// lab].
    #[arg(long, value_name = "NAME")]
    integrator: Option<IntegratorKind>,

    /// Samples per pixel [default: the scene file's; else 1 for lab (the ray through each
    /// pixel's centre, exactly as `raylab view` refines a still picture) and 16 otherwise].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=MAX_SPP as i64))]
    spp: Option<u32>,

    /// Longest path in segments, as Mitsuba counts them (1: emitters seen directly, 2: direct
    /// light, ...; -1: unlimited) [default: the scene file's, else unlimited].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(i64).range(-1..=65536))]
    max_depth: Option<i64>,

    /// How points on area lights are sampled: area (uniformly, as Mitsuba) or solid-angle (less
    /// noise from large lights close by).
    #[arg(long, value_name = "HOW", default_value = "area")]
    light_sampling: TriangleSampling,

    /// Seed of every random number: the same seed, scene and samples give the same pixels on
    /// any number of threads [default: the scene file's, else 0].
    #[arg(long, value_name = "N")]
    seed: Option<u64>,

    /// Sample generator: sobol (Owen-scrambled, the default for path), multijitter (correlated
    /// multi-jittered points laid out for --spp: lower error where pixels hold edges),
    /// independent, or lab.
    #[arg(long, value_name = "NAME")]
    sampler: Option<SamplerKind>,

    /// Pixel filter: box (each pixel the mean over its area) or gaussian (σ = 0.5 px, radius 2).
    #[arg(long, value_name = "NAME")]
    filter: Option<Filter>,

    /// Extra layers for .exr output, comma-separated: albedo, normals, depth (the first hit's,
    /// averaged over the same samples as the image).
    #[arg(long, value_name = "LIST", value_delimiter = ',')]
    aov: Vec<AovKind>,

    /// Render progressively for this long, then write the picture with the samples per pixel
    /// reached (at least one; at most --spp when it is given).
    #[arg(long, value_name = "SECONDS", value_parser = args::seconds)]
    time_limit: Option<Duration>,

    /// Brightness of .png/.ppm output in stops: radiance is multiplied by 2^EV.
    #[arg(long, value_name = "EV", default_value = "0", value_parser = args::finite_f32)]
    exposure: f32,

    /// Tone mapping of .png/.ppm output: clamp, reinhard or aces.
    #[arg(long, value_name = "NAME", default_value = "clamp")]
    tonemap: ToneMap,

    /// Render only tile I of N (numbered from 0): a strip of whole rows, the first H mod N
    /// strips one row taller. The output must be .exr; `raylab merge` assembles the tiles into
    /// exactly the image a single render gives.
    #[arg(long, value_name = "I/N", value_parser = args::tile, conflicts_with = "region")]
    tile: Option<(u32, u32)>,

    /// Render only columns X0..X1 and rows Y0..Y1 (from the top left, the ends excluded) into an
    /// .exr part for `raylab merge`.
    #[arg(long, value_name = "X0,Y0,X1,Y1", value_parser = args::region)]
    region: Option<[u32; 4]>,

    /// Write a checkpoint beside the output (NAME.checkpoint.exr) at most every SECONDS and on
    /// an interrupt. Run the same command again (or `--resume` the checkpoint) to go on from it
    /// to exactly the image of an uninterrupted render; a finished render deletes it.
    #[arg(long, value_name = "SECONDS", value_parser = args::seconds)]
    checkpoint: Option<Duration>,

    /// Render frames A to B (both included; or one frame, N) of the animation the scene file's
    /// camera keyframes describe, each to the output name with its frame number in place of a
    /// printf-style %d or %0Nd: `-o out_%04d.exr` writes out_0001.exr, out_0002.exr, ...
    #[arg(long, value_name = "A..B", value_parser = args::frames)]
    frames: Option<(u32, u32)>,

    /// Go on with the render a checkpoint was written for, with the command line recorded in
    /// it (run from the directory it was started in).
    #[arg(long, value_name = "STATE", exclusive = true)]
    resume: Option<PathBuf>,
}

/// A wrapper to parse a checkpoint's recorded arguments as `raylab render` would.
#[derive(clap::Parser, Debug)]
#[command(name = "raylab render", allow_negative_numbers = true)]
struct Recorded {
    #[command(flatten)]
    args: RenderArgs,
}

pub fn run(args: &RenderArgs) -> Result<()> {
    let Some(state) = &args.resume else {
        let command = match args.checkpoint {
            Some(_) => Some(Command::of_this_process()?),
            None => None,
        };
        return render(args, command, None);
    };
    let (recorded, command, part) = render_state::recorded::<Recorded>(state)?;
    render(&recorded.args, Some(command), Some(part))
}

/// Renders as `args` say; with `command` (the command line to record), writes checkpoints;
/// with `state`, goes on from that checkpoint.
fn render(args: &RenderArgs, command: Option<Command>, state: Option<Part>) -> Result<()> {
    // Everything that can be checked is checked before rendering, so no work is lost.
    let setup = args.scene.setup()?;
    let scene = &setup.scene;
    let options = RenderOptions {
        integrator: args.integrator,
        stage: args.scene.stage,
        spp: args.spp,
        max_depth: args
            .max_depth
            .map(|d| u32::try_from(d).map_or(MaxDepth::Unlimited, MaxDepth::Segments)),
        seed: args.seed,
        sampler: args.sampler,
        filter: args.filter,
        light_sampling: args.light_sampling,
        time_limit: args.time_limit,
    };
    let settings = ResolvedSettings::resolve(scene, &options);
    for warning in settings.warnings(scene) {
        eprintln!("raylab: warning: {warning}");
    }
    let mut job = RenderJob::new(scene, settings, args.scene.threads())?;
    let cameras = args.scene.camera_options();
    let (width, height) = cameras.size(scene);
    job.region = match (args.tile, args.region) {
        (Some((index, count)), _) => Some(Region::tile(index, count, width, height)?),
        (None, Some(corners)) => Some(Region::new(corners, width, height)?),
        (None, None) => None,
    };
    job.aovs = args.aov.clone();
    job.checkpoints = args
        .checkpoint
        .map(|every| Checkpoints { every, command: command.as_ref().map(Command::to_json) });
    (job.exposure, job.tone_map) = (args.exposure, args.tonemap);
    job.check_output(&args.output, (width, height))?;
    if let Some((first, _)) = args.frames {
        raylab::session::frame_path(&args.output, first)?;
    }
    // Installed once for every frame: SIGINT and SIGTERM from here on end the render cleanly.
    let stop = render_state::interrupt_flag()?;
    job.stop_when(&stop);

    let progress = FrameProgress::default();
    let events = |event: Event| progress.on(event);
    let Some((first, last)) = args.frames else {
        let camera = cameras.camera(setup.first_camera(), scene, setup.is_model, job.accel()?)?;
        let outcome = job.render_frame(&camera, &args.output, state, &events)?;
        return report_frame(args, &setup, &job, outcome);
    };
    let camera_at = |job: &mut RenderJob, frame: u32| {
        let settings = scene.camera_at(frame as f32);
        cameras.camera(settings, scene, setup.is_model, job.accel()?)
    };
    let mut each =
        |job: &RenderJob, outcome: FrameOutcome| report_frame(args, &setup, job, outcome);
    if let Some(frame) =
        job.render_frames((first, last), &args.output, &camera_at, state, &events, &mut each)?
    {
        let report =
            format!("stopped before frame {frame}; frames {first} to {} are written", frame - 1);
        return Err(Interrupted { report }.into());
    }
    Ok(())
}

/// Prints what a frame's render did (or fails with [`Interrupted`] where it was stopped).
fn report_frame(
    args: &RenderArgs,
    setup: &Setup,
    job: &RenderJob,
    outcome: FrameOutcome,
) -> Result<()> {
    let FrameOutcome { ref output, ref camera, samples: spp, first_sample, discarded, .. } =
        outcome;
    if outcome.film.is_none() {
        return Ok(()); // already rendered
    }
    let region = job.region((camera.width, camera.height));
    if discarded > 0 {
        let total = region.pixels() * (spp - first_sample) as u64;
        eprintln!(
            "raylab: warning: {discarded} of {total} samples were not finite (NaN or infinite \
             radiance, e.g. from a degenerate triangle or normal) and count as black"
        );
    }
    if outcome.interrupted {
        let mut report = format!(
            "wrote {} with {spp} of {} samples per pixel",
            output.display(),
            args.spp.unwrap_or(spp.max(1))
        );
        if let Some(path) = &outcome.checkpoint {
            report += &format!("; resume with: raylab render --resume {}", path.display());
        }
        return Err(Interrupted { report }.into());
    }
    if outcome.checkpoint.is_some() && !outcome.checkpoint_time.is_zero() {
        eprintln!(
            "raylab: checkpoints took {:.1} ms of {:.1} ms",
            outcome.checkpoint_time.as_secs_f64() * 1e3,
            outcome.elapsed.as_secs_f64() * 1e3
        );
    }
    let mut report = FrameSummary { job, outcome: &outcome, load_time: setup.load }.to_string();
    if let Some(env) = &setup.env_report {
        report += env;
        report.push('\n');
    }
    crate::print_report(&report)
}
