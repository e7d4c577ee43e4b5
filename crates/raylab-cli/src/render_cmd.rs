//! `raylab render`: one frame to an image file.

use std::io::Write;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use clap::Args;
use raylab::film::{Display, ToneMap};
use raylab::parts::{self, Part, PartHeader, PartKind};
use raylab::{
    Accumulator, Aov, AovKind, Camera, Film, Filter, Integrator, Lab, Path, PathSettings, Region,
    SampleSettings, SamplerKind, TriangleSampling, image_io,
};

use raylab::camera::tidy;

use crate::args;
use crate::progress::Progress;
use crate::render_state::{self, Command, Interrupted};
use crate::scene_args::{STAGES_HELP, SceneArgs, Setup, tidy_vec3};
use crate::system;

/// The AOV integrator's kind for `albedo`, `normals` or `depth`.
fn aov_kind(name: &str) -> AovKind {
    match name {
        "albedo" => AovKind::Albedo,
        "normals" => AovKind::Normals,
        _ => AovKind::Depth,
    }
}

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
    #[arg(long, value_name = "NAME", value_parser = ["lab", "path", "albedo", "normals", "depth"])]
    integrator: Option<String>,

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
    #[arg(long, value_name = "LIST", value_delimiter = ',', value_parser = ["albedo", "normals", "depth"])]
    aov: Vec<String>,

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

/// The most samples per pixel `--spp` accepts.
const MAX_SPP: u32 = 1 << 16;

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
    let Setup { scene, camera, threads, .. } = &setup;
    let (width, height) = (camera.width, camera.height);
    let format = image_io::check_writable(&args.output)?;
    if !args.aov.is_empty() && format != image_io::ImageFormat::Exr {
        bail!(
            "--aov writes extra layers into an OpenEXR file: the output must end in .exr, not {}",
            args.output.display()
        );
    }
    if let Some((first, _)) = args.frames {
        if scene.keyframes.is_empty() {
            bail!(
                "--frames renders an animation, and {} has no camera keyframes ([[keyframes]] \
                 in a scene file, see docs/scene-format.md)",
                scene.name
            );
        }
        args::frame_path(&args.output, first)?;
    }
    let settings = &scene.settings;
    let integrator_name = args
        .integrator
        .clone()
        .or_else(|| settings.integrator.clone())
        .unwrap_or_else(|| if scene.has_area_lights() { "path".into() } else { "lab".into() });
    let spp = match (args.time_limit, args.spp) {
        // With a time limit, the passes stop at the time (or at an --spp asked for).
        (Some(_), None) => MAX_SPP,
        _ => args.spp.or(settings.spp).unwrap_or(if integrator_name == "lab" { 1 } else { 16 }),
    };
    let deadline = args.time_limit;
    let max_depth = match args.max_depth {
        Some(-1) => None,
        Some(d) => Some(d as u32),
        None => settings.max_depth.unwrap_or(None),
    };
    let sample_settings = SampleSettings {
        seed: args.seed.or(settings.seed).unwrap_or(0),
        sampler: args.sampler.or(settings.sampler),
        filter: match args.filter.as_deref() {
            Some("gaussian") => Filter::GAUSSIAN,
            Some(_) => Filter::Box,
            None => settings.filter.unwrap_or_default(),
        },
        ..SampleSettings::default()
    };
    let region = match (args.tile, args.region) {
        (Some((index, count)), _) => Region::tile(index, count, width, height)?,
        (None, Some(corners)) => Region::new(corners, width, height)?,
        (None, None) => Region::full(width, height),
    };
    let is_part = region != Region::full(width, height);
    if is_part && format != image_io::ImageFormat::Exr {
        bail!(
            "--tile and --region write a part of the image for `raylab merge`, which needs \
             OpenEXR: the output must end in .exr, not {}",
            args.output.display()
        );
    }
    let (region_width, region_height) = (region.width(), region.height());
    // The sums and their mean: two films.
    system::check_memory(
        Film::bytes_needed(region_width, region_height).saturating_mul(2),
        region_width,
        region_height,
    )?;
    let pool = setup.thread_pool()?;
    // Installed once for every frame: SIGINT and SIGTERM from here on end the render cleanly.
    let stop = &render_state::interrupt_flag()?;

    let start = Instant::now();
    let accel = pool.install(|| system::build_bvh(&scene.name, &scene.geometry))?;
    let build = start.elapsed();
    let stage = args.scene.stage;
    // Its texture filtering follows each frame's camera (see `render_frame`).
    let lab = Lab::new(scene, &accel, stage).for_camera(camera);
    let path = (integrator_name == "path").then(|| {
        let settings = PathSettings {
            max_depth,
            light_sampling: args.light_sampling,
            ..PathSettings::default()
        };
        Path::new(scene, &accel, settings)
    });
    let aov;
    let integrator: &dyn Integrator = match (integrator_name.as_str(), &path) {
        ("lab", _) => &lab,
        (_, Some(path)) => path,
        (other, None) => {
            aov = Aov::new(scene, &accel, aov_kind(other));
            &aov
        }
    };
    // One frame (the whole render without --frames) to `output` through `camera`.
    let render_frame = |camera: &Camera,
                        output: &std::path::Path,
                        state: Option<Part>|
     -> Result<()> {
        // An animation's frames may change the field of view, and with it the pixels' ray cone.
        let frame_lab = lab.for_camera(camera);
        let integrator: &dyn Integrator =
            if integrator_name == "lab" { &frame_lab } else { integrator };
        // What the pixels depend on besides the scene: parts and checkpoints must agree on it.
        let settings_text = format!(
            "size={width}x{height}; camera={camera:?}; integrator={integrator_name}; \
         stage={stage}; spp={spp}; seed={}; sampler={:?}; filter={:?}; \
         max_depth={max_depth:?}; light_sampling={:?}",
            sample_settings.seed,
            sample_settings.sampler.unwrap_or_else(|| integrator.sampler_kind()),
            sample_settings.filter,
            args.light_sampling,
        );
        let header = PartHeader {
            kind: PartKind::Image,
            image: (width, height),
            region,
            samples: 0,
            scene_hash: format!("{:016x}", scene.content_hash()),
            settings: settings_text,
            command: command.as_ref().map(Command::to_json),
        };
        // An image (a frame of an animation, a tile) that a previous run of the same command
        // finished (a requeued job, a rerun after an interrupt) is not rendered again.
        if args.checkpoint.is_some()
            && output.exists()
            && parts::read_part(output).is_ok_and(|done| {
                let h = &done.header;
                (h.kind, h.samples, &h.scene_hash, &h.settings)
                    == (PartKind::Image, spp, &header.scene_hash, &header.settings)
                    && h.region == region
            })
        {
            eprintln!("raylab: {} is already rendered", output.display());
            return Ok(());
        }
        let checkpoint =
            args.checkpoint.map(|every| (render_state::checkpoint_path(output), every));
        // A checkpoint to go on from: the one asked for, or this render's own from an earlier run.
        let state = match (state, &checkpoint) {
            (Some(part), _) => Some(part),
            (None, Some((path, _))) if path.exists() => Some(parts::read_part(path)?),
            _ => None,
        };
        let mut accumulator = match state {
            Some(part) => {
                let h = &part.header;
                let problem = if h.kind != PartKind::Checkpoint {
                    Some("it is not a checkpoint".to_string())
                } else if h.scene_hash != header.scene_hash {
                    Some("the scene has changed since".to_string())
                } else if h.settings != header.settings {
                    Some(format!("it has other settings ('{}')", h.settings))
                } else if (h.image, h.region) != (header.image, header.region) {
                    Some(format!("it holds region {} of {}×{}", h.region, h.image.0, h.image.1))
                } else {
                    None
                };
                if let Some(problem) = problem {
                    bail!(
                        "{}: cannot go on from this checkpoint: {problem}; delete it to start \
                     afresh",
                        part.path.display()
                    );
                }
                let sums = parts::beauty(&part.channels, region_width, region_height)
                    .context("a checkpoint has R, G and B channels")?;
                eprintln!(
                    "raylab: going on from {} at {} samples per pixel",
                    part.path.display(),
                    h.samples
                );
                Accumulator::resume((width, height), region, sums, h.samples, sample_settings)?
            }
            None => {
                let mut accumulator = Accumulator::for_region(width, height, region)?;
                accumulator.settings = sample_settings;
                accumulator
            }
        };
        let first_sample = accumulator.samples();
        let passes = spp.saturating_sub(first_sample) as u64;
        let progress = Progress::new(region_height as u64 * passes, region_width as u64, deadline);
        let start = Instant::now();
        let mut last_checkpoint = Instant::now();
        let mut checkpoint_time = Duration::ZERO;
        // A checkpoint that cannot be written (a full disk, a vanished directory) is reported,
        // and the render goes on: its work is not thrown away for want of a checkpoint.
        let write_checkpoint = |accumulator: &Accumulator, path: &PathBuf| -> Duration {
            let start = Instant::now();
            let state = PartHeader {
                kind: PartKind::Checkpoint,
                samples: accumulator.samples(),
                ..header.clone()
            };
            let sums = parts::film_channels(accumulator.sums(), &[]);
            if let Err(error) = parts::write_exr(path, (width, height), region, sums, Some(&state))
            {
                eprintln!("raylab: warning: no checkpoint written: {error}");
            }
            start.elapsed()
        };
        let mut was_interrupted = false;
        pool.install(|| {
            while accumulator.samples() < spp {
                if render_state::interrupted(stop) {
                    was_interrupted = true;
                    break;
                }
                accumulator
                    .add_sample_with_progress(camera, integrator, &|rows| progress.advance(rows));
                if deadline.is_some_and(|limit| start.elapsed() >= limit) {
                    break;
                }
                if let Some((path, every)) = &checkpoint
                    && last_checkpoint.elapsed() >= *every
                    && accumulator.samples() < spp
                {
                    checkpoint_time += write_checkpoint(&accumulator, path);
                    last_checkpoint = Instant::now();
                }
            }
        });
        was_interrupted |= render_state::interrupted(stop);
        // The work so far is kept first: on a pre-empted node the time left may be short.
        if was_interrupted && let Some((path, _)) = &checkpoint {
            write_checkpoint(&accumulator, path);
        }
        let spp = accumulator.samples();
        if spp == 0 {
            progress.finish();
            bail!("interrupted before the first sample: nothing written");
        }
        let film = accumulator.mean()?;
        let discarded =
            path.as_ref().map_or(0, Path::discarded_samples) + accumulator.discarded_samples();
        if discarded > 0 {
            let total = region.pixels() * (spp - first_sample) as u64;
            eprintln!(
                "raylab: warning: {discarded} of {total} samples were not finite (NaN or infinite \
             radiance, e.g. from a degenerate triangle or normal) and count as black"
            );
        }
        // The extra layers, over the same samples; an interrupted render leaves them out rather
        // than spend another pass on them.
        let mut layers = Vec::new();
        for name in args.aov.iter().filter(|_| !was_interrupted) {
            let aov = Aov::new(scene, &accel, aov_kind(name));
            let layer = pool.install(|| -> Result<Film> {
                let mut accumulator = Accumulator::for_region(width, height, region)?;
                accumulator.settings = sample_settings;
                for _ in 0..spp {
                    accumulator.add_sample(camera, &aov);
                }
                Ok(accumulator.mean()?)
            })?;
            layers.push((name.as_str(), layer));
        }
        let elapsed = start.elapsed();
        progress.finish();

        let display = if integrator_name == "lab" {
            Display { exposure: args.exposure, tone_map: args.tonemap, srgb: false }
        } else {
            Display { exposure: args.exposure, tone_map: args.tonemap, srgb: true }
        };
        if format == image_io::ImageFormat::Exr {
            let layers: Vec<(&str, &Film)> =
                layers.iter().map(|(name, film)| (*name, film)).collect();
            let channels = parts::film_channels(&film, &layers);
            let header = PartHeader { samples: spp, command: None, ..header.clone() };
            parts::write_exr(output, (width, height), region, channels, Some(&header))?;
        } else {
            image_io::save_film(output, &film, &display)?;
        }
        if was_interrupted {
            let mut report = format!(
                "wrote {} with {spp} of {} samples per pixel",
                output.display(),
                args.spp.unwrap_or(spp.max(1))
            );
            if let Some((path, _)) = &checkpoint {
                report += &format!("; resume with: raylab render --resume {}", path.display());
            }
            return Err(Interrupted { report }.into());
        }
        if let Some((path, _)) = &checkpoint
            && path.exists()
        {
            std::fs::remove_file(path).with_context(|| {
                format!(
                    "the render is written, but its checkpoint {} cannot be deleted",
                    path.display()
                )
            })?;
        }
        if checkpoint.is_some() && !checkpoint_time.is_zero() {
            eprintln!(
                "raylab: checkpoints took {:.1} ms of {:.1} ms",
                checkpoint_time.as_secs_f64() * 1e3,
                elapsed.as_secs_f64() * 1e3
            );
        }
        let samples = region.pixels() as f64 * (spp - first_sample) as f64;
        let what = match integrator_name.as_str() {
            "lab" => format!("stage {stage}"),
            "path" => format!(
                "path tracing, max depth {}",
                max_depth.map_or("unlimited".to_string(), |d| d.to_string())
            ),
            other => other.to_string(),
        };
        let spp_text = if spp == 1 { String::new() } else { format!(", {spp} samples per pixel") };
        let size = if is_part {
            format!("region {region} of {width}×{height}")
        } else {
            format!("{width}×{height}")
        };
        let mut report = format!(
            "{}: {size}, {} ({} triangles) {what}{spp_text}, {:.1} ms on {threads} \
         thread{} (+{:.1} ms BVH build), {:.2} M samples/s\n{camera}\n",
            output.display(),
            scene.name,
            scene.geometry.len(),
            elapsed.as_secs_f64() * 1e3,
            if *threads == 1 { "" } else { "s" },
            build.as_secs_f64() * 1e3,
            samples / elapsed.as_secs_f64().max(1e-9) / 1e6,
        );
        let (texture_bytes, images) = scene.texture_bytes();
        let textures = if images == 0 {
            String::new()
        } else {
            format!(
                ", {images} texture{} {}",
                if images == 1 { "" } else { "s" },
                raylab::film::format_bytes(texture_bytes)
            )
        };
        let geometry = &scene.geometry;
        let instances = if geometry.is_instanced() {
            let placed = geometry.instances().iter().filter(|x| x.placement.is_some()).count();
            format!(" ({} triangles stored; {placed} instances)", geometry.stored_len())
        } else {
            String::new()
        };
        report += &format!(
            "scene loaded in {:.1} ms; memory: geometry {}{instances}, BVH {}{textures}\n",
            setup.load.as_secs_f64() * 1e3,
            raylab::film::format_bytes(geometry.bytes()),
            raylab::film::format_bytes(accel.bytes() as u64),
        );
        if integrator_name == "lab" {
            let light = scene.lab_light();
            report +=
                &format!("light at {} power {}\n", tidy_vec3(light.position), tidy(light.power.x));
        }
        if format.is_float() {
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
    };
    let Some((first, last)) = args.frames else {
        return render_frame(camera, &args.output, state);
    };
    let mut state = state;
    for frame in first..=last {
        if render_state::interrupted(stop) {
            let report = format!(
                "stopped before frame {frame}; frames {first} to {} are written",
                frame - 1
            );
            return Err(Interrupted { report }.into());
        }
        let output = args::frame_path(&args.output, frame)?;
        let settings = scene.camera_at(frame as f32);
        let camera = args.scene.camera(settings, scene, setup.is_model, width, height)?;
        let checkpoint = render_state::checkpoint_path(&output);
        render_frame(&camera, &output, state.take_if(|s| s.path == checkpoint))?;
    }
    Ok(())
}
