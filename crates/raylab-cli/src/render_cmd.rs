//! `raylab render`: one frame to an image file.

use std::io::Write;
use std::path::PathBuf;
use std::time::Duration;

use std::sync::RwLock;

use anyhow::{Context, Result, bail};
use clap::Args;
use raylab::camera::tidy;
use raylab::film::{ToneMap, format_bytes};
use raylab::parts::{self, Part, PartKind};
use raylab::session::{
    Checkpoints, Event, FrameOutcome, MAX_SPP, RenderJob, RenderOptions, ResolvedSettings,
};
use raylab::settings::{AovKind, IntegratorKind};
use raylab::{Filter, Region, SamplerKind, TriangleSampling};

use crate::args;
use crate::progress::Progress;
use crate::render_state::{self, Command, Interrupted};
use crate::scene_args::{STAGES_HELP, SceneArgs, Setup, tidy_vec3};

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

    /// What to compute: lab (the lab's light model), path (path tracing), or the first hit's
    /// albedo, normals or depth [default: the scene file's; path for scenes with area lights,
    /// else lab].
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

    /// Sample generator: sobol (Owen-scrambled, the default for path), independent, or lab.
    #[arg(long, value_name = "NAME")]
    sampler: Option<SamplerKind>,

    /// Pixel filter: box (each pixel the mean over its area) or gaussian (σ = 0.5 px, radius 2).
    #[arg(long, value_name = "NAME", value_parser = ["box", "gaussian"])]
    filter: Option<String>,

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
    let part = parts::read_part(state)?;
    if part.header.kind != PartKind::Checkpoint {
        bail!("{}: not a checkpoint (it is a finished image)", state.display());
    }
    let Some(json) = &part.header.command else {
        bail!("{}: the checkpoint records no command line to resume", state.display());
    };
    let command = Command::from_json(state, json)?;
    let recorded = <Recorded as clap::Parser>::try_parse_from(
        std::iter::once("raylab render".to_string()).chain(command.arguments.iter().cloned()),
    )
    .map_err(|e| {
        let text = e.to_string();
        anyhow::anyhow!(
            "{}: its recorded command line no longer parses: {}",
            state.display(),
            text.lines().next().unwrap_or("").trim_start_matches("error: ")
        )
    })?;
    std::env::set_current_dir(&command.directory).with_context(|| {
        format!(
            "{}: cannot go back to the directory the render started in, {}",
            state.display(),
            command.directory.display()
        )
    })?;
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
        max_depth: args.max_depth.map(|d| u32::try_from(d).ok()),
        seed: args.seed,
        sampler: args.sampler,
        filter: args.filter.as_deref().map(|name| match name {
            "gaussian" => Filter::GAUSSIAN,
            _ => Filter::Box,
        }),
        light_sampling: args.light_sampling,
        time_limit: args.time_limit,
    };
    let settings = ResolvedSettings::resolve(scene, &options);
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

    let progress: RwLock<Option<Progress>> = RwLock::new(None);
    let events = |event: Event| match event {
        Event::Started { rows, row_pixels, time_limit } => {
            *progress.write().expect("no panic holds it") =
                Some(Progress::new(rows, row_pixels, time_limit));
        }
        Event::Rows(rows) => {
            if let Some(bar) = &*progress.read().expect("no panic holds it") {
                bar.advance(rows);
            }
        }
        Event::Finished => {
            if let Some(bar) = progress.write().expect("no panic holds it").take() {
                bar.finish();
            }
        }
        Event::AlreadyRendered(output) => {
            eprintln!("raylab: {} is already rendered", output.display());
        }
        Event::Resumed { checkpoint, samples } => eprintln!(
            "raylab: going on from {} at {samples} samples per pixel",
            checkpoint.display()
        ),
        Event::CheckpointNotWritten(error) => {
            eprintln!("raylab: warning: no checkpoint written: {error}");
        }
    };
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
    let FrameOutcome { output, camera, film, samples: spp, first_sample, discarded, .. } = outcome;
    let Some(film) = film else { return Ok(()) }; // already rendered
    let (scene, settings) = (&setup.scene, job.settings());
    let (width, height) = (camera.width, camera.height);
    let region = job.region((width, height));
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
    let elapsed = outcome.elapsed;
    if outcome.checkpoint.is_some() && !outcome.checkpoint_time.is_zero() {
        eprintln!(
            "raylab: checkpoints took {:.1} ms of {:.1} ms",
            outcome.checkpoint_time.as_secs_f64() * 1e3,
            elapsed.as_secs_f64() * 1e3
        );
    }
    let samples = region.pixels() as f64 * (spp - first_sample) as f64;
    let what = match settings.integrator {
        IntegratorKind::Lab => format!("stage {}", settings.stage),
        IntegratorKind::Path => format!(
            "path tracing, max depth {}",
            settings.max_depth.map_or("unlimited".to_string(), |d| d.to_string())
        ),
        other => other.to_string(),
    };
    let spp_text = if spp == 1 { String::new() } else { format!(", {spp} samples per pixel") };
    let size = if region != Region::full(width, height) {
        format!("region {region} of {width}×{height}")
    } else {
        format!("{width}×{height}")
    };
    let threads = job.threads();
    let mut report = format!(
        "{}: {size}, {} ({} triangles) {what}{spp_text}, {:.1} ms on {threads} thread{} (+{:.1} \
         ms BVH build), {:.2} M samples/s\n{camera}\n",
        output.display(),
        scene.name,
        scene.geometry.len(),
        elapsed.as_secs_f64() * 1e3,
        if threads == 1 { "" } else { "s" },
        job.build_time().as_secs_f64() * 1e3,
        samples / elapsed.as_secs_f64().max(1e-9) / 1e6,
    );
    let (texture_bytes, images) = scene.texture_bytes();
    let textures = if images == 0 {
        String::new()
    } else {
        let plural = if images == 1 { "" } else { "s" };
        format!(", {images} texture{plural} {}", format_bytes(texture_bytes))
    };
    let geometry = &scene.geometry;
    let instances = if geometry.is_instanced() {
        let placed = geometry.instances().iter().filter(|x| x.placement.is_some()).count();
        format!(" ({} triangles stored; {placed} instances)", geometry.stored_len())
    } else {
        String::new()
    };
    let bvh_bytes = job.built_accel().map_or(0, |bvh| bvh.bytes() as u64);
    report += &format!(
        "scene loaded in {:.1} ms; memory: geometry {}{instances}, BVH {}{textures}\n",
        setup.load.as_secs_f64() * 1e3,
        format_bytes(geometry.bytes()),
        format_bytes(bvh_bytes),
    );
    if settings.integrator == IntegratorKind::Lab {
        let light = scene.lab_light();
        report +=
            &format!("light at {} power {}\n", tidy_vec3(light.position), tidy(light.power.x));
    }
    let extension = output.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
    if matches!(extension.as_deref(), Some("exr" | "pfm")) {
        let mean = film.pixels().iter().map(|p| p.as_dvec3()).sum::<glam::DVec3>()
            / film.pixels().len() as f64;
        report += &format!("mean radiance ({:.6}, {:.6}, {:.6})\n", mean.x, mean.y, mean.z);
    }
    // The image is written; a closed or full standard output is not worth a failure, but it
    // must not be a panic either (`println!` would panic).
    match std::io::stdout().lock().write_all(report.as_bytes()) {
        Err(error) if error.kind() != std::io::ErrorKind::BrokenPipe => {
            Err(error).context("cannot print the report to standard output")
        }
        _ => Ok(()),
    }
}
