//! A render job: a scene with its BVH, threads and resolved settings, rendering frames to
//! files (see the module documentation of [`crate::session`]).

use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

mod frames;

use super::event::Event;
pub use frames::frame_path;

use super::checkpoint::{Checkpoints, channels_of, checkpoint_path, resume_from};
use super::{RenderIdentity, ResolvedSettings, SessionError};
use crate::bvh::{BuildSettings, Bvh, SceneBvh};
use crate::camera::Camera;
use crate::film::{Display, Film, ToneMap, format_bytes};
use crate::image_io::{self, ImageFormat, ImageIoError};
use crate::integrator::{Choice, Chosen, Integrator, WithAovs};
use crate::parts::{self, Part, PartHeader, PartKind};
use crate::region::Region;
use crate::render::Accumulator;
use crate::scene::Scene;
use crate::settings::{AovKind, IntegratorKind};

/// What rendering a frame did.
#[derive(Debug)]
pub struct FrameOutcome {
    /// The file written (or found already rendered).
    pub output: PathBuf,
    /// The camera it was rendered through.
    pub camera: Camera,
    /// The picture (the mean of the samples), `None` where the output was already rendered.
    pub film: Option<Film>,
    /// Samples per pixel reached.
    pub samples: u32,
    /// The first sample this run added (more than 0 when it went on from a checkpoint).
    pub first_sample: u32,
    /// Samples that were not finite (NaN or infinite) and count as black.
    pub discarded: u64,
    /// The time the passes took (layers included, checkpoints included).
    pub elapsed: Duration,
    /// The time checkpoints took.
    pub checkpoint_time: Duration,
    /// Whether the stop flag ended it early.
    pub interrupted: bool,
    /// The checkpoint, where checkpoints are written (after an interrupt, the one to resume).
    pub checkpoint: Option<PathBuf>,
}

/// What [`RenderJob::passes`] did.
struct Passes {
    interrupted: bool,
    checkpoint_time: Duration,
    elapsed: Duration,
    /// Samples the integrator itself discarded.
    base_discarded: u64,
}

/// What rendering a frame into memory did ([`RenderJob::render_film`]).
#[derive(Debug)]
pub struct FilmOutcome {
    /// The picture (the mean of the samples) of the region, row by row.
    pub film: Film,
    /// The AOV layers ([`RenderJob::aovs`]), in order, of the region.
    pub layers: Vec<Film>,
    /// The part of the image rendered.
    pub region: Region,
    /// Samples per pixel reached.
    pub samples: u32,
    /// Samples that were not finite (NaN or infinite) and count as black.
    pub discarded: u64,
    /// The time the passes took.
    pub elapsed: Duration,
    /// Whether the stop flag ended it early.
    pub interrupted: bool,
}

/// A scene ready to render: see the module documentation of [`crate::session`].
pub struct RenderJob<'s> {
    scene: &'s Scene,
    settings: ResolvedSettings,
    pool: rayon::ThreadPool,
    threads: usize,
    accel: OnceLock<SceneBvh>,
    build_time: Duration,
    /// The part of the image to render ([`Region::full`] where `None`).
    pub region: Option<Region>,
    /// Extra layers of `.exr` output, from the same samples.
    pub aovs: Vec<AovKind>,
    /// Whether and how often to write checkpoints.
    pub checkpoints: Option<Checkpoints>,
    /// Brightness of 8-bit output in stops.
    pub exposure: f32,
    /// Tone mapping of 8-bit output.
    pub tone_map: ToneMap,
    stop: Option<&'s AtomicBool>,
}

impl<'s> RenderJob<'s> {
    /// A job rendering `scene` with `settings` on `threads` threads (0: one per core), its BVH
    /// built on first use (see [`accel`](Self::accel)).
    pub fn new(
        scene: &'s Scene,
        settings: ResolvedSettings,
        threads: usize,
    ) -> Result<RenderJob<'s>, SessionError> {
        const MAX_THREADS: usize = 1024;
        if threads > MAX_THREADS {
            return Err(SessionError::Invalid(format!(
                "{threads} render threads is more than {MAX_THREADS}"
            )));
        }
        let threads = if threads == 0 { cores() } else { threads };
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(|e| SessionError::Invalid(format!("cannot start the render threads: {e}")))?;
        Ok(RenderJob {
            scene,
            settings,
            pool,
            threads,
            accel: OnceLock::new(),
            build_time: Duration::ZERO,
            region: None,
            aovs: Vec::new(),
            checkpoints: None,
            exposure: 0.0,
            tone_map: ToneMap::Clamp,
            stop: None,
        })
    }

    /// Stops the render between passes once `flag` is set (an interrupt handler sets it).
    pub fn stop_when(&mut self, flag: &'s AtomicBool) {
        self.stop = Some(flag);
    }

    /// The scene.
    pub fn scene(&self) -> &'s Scene {
        self.scene
    }

    /// The resolved settings.
    pub fn settings(&self) -> &ResolvedSettings {
        &self.settings
    }

    /// The render threads.
    pub fn threads(&self) -> usize {
        self.threads
    }

    /// The thread pool the job renders on.
    pub fn pool(&self) -> &rayon::ThreadPool {
        &self.pool
    }

    /// How long building the BVH took (zero before it is built).
    pub fn build_time(&self) -> Duration {
        self.build_time
    }

    /// The BVH over the scene, built on the job's threads the first time it is asked for:
    /// refused with one line where the scene has more triangles than a BVH holds, or needs
    /// more memory to build than the machine has available.
    pub fn accel(&mut self) -> Result<&SceneBvh, SessionError> {
        if self.accel.get().is_none() {
            let (scene, start) = (self.scene, Instant::now());
            let geometry = &scene.geometry;
            // A mesh drawn in several places is built over once.
            check_bvh_memory(&scene.name, geometry.stored_len(), crate::memory::available_bytes())?;
            let bvh = self
                .pool
                .install(|| SceneBvh::build(geometry))
                .map_err(|e| SessionError::Invalid(format!("{}: {e}", scene.name)))?;
            self.build_time = start.elapsed();
            let _ = self.accel.set(bvh);
        }
        Ok(self.accel.get().expect("built above"))
    }

    /// The BVH, where it is built.
    pub fn built_accel(&self) -> Option<&SceneBvh> {
        self.accel.get()
    }

    /// Checks, before any work, that `output` can be written as this job writes it: the
    /// format from its extension, its folder, `.exr` for layers and for parts of an image, and
    /// the memory for the picture of `size`.
    pub fn check_output(&self, output: &Path, size: (u32, u32)) -> Result<(), SessionError> {
        let format = image_io::check_writable(output)?;
        if !self.aovs.is_empty() && format != ImageFormat::Exr {
            return Err(SessionError::Invalid(format!(
                "extra layers (AOVs) are written into an OpenEXR file: the output must end in \
                 .exr, not {}",
                output.display()
            )));
        }
        let region = self.region(size);
        if region != Region::full(size.0, size.1) && format != ImageFormat::Exr {
            return Err(SessionError::Invalid(format!(
                "a part of the image (a tile or a region) is written for `raylab merge`, which \
                 needs OpenEXR: the output must end in .exr, not {}",
                output.display()
            )));
        }
        self.check_film_memory(region)
    }

    /// Refuses a region whose films (the sums and their mean, and each layer's) need more
    /// memory than the machine has available.
    fn check_film_memory(&self, region: Region) -> Result<(), SessionError> {
        let films = 2 * (1 + self.aovs.len() as u64);
        let bytes = Film::bytes_needed(region.width(), region.height()).saturating_mul(films);
        check_memory(bytes, region.width(), region.height())
    }

    /// The part of an image of `size` this job renders.
    pub fn region(&self, (width, height): (u32, u32)) -> Region {
        self.region.unwrap_or(Region::full(width, height))
    }

    /// The identity of a render through `camera` (see [`RenderIdentity`]).
    pub fn identity(&self, camera: &Camera) -> RenderIdentity {
        let s = &self.settings;
        let sampler = s.samples.sampler.unwrap_or(match s.integrator {
            IntegratorKind::Lab => crate::sampling::SamplerKind::Lab,
            _ => crate::sampling::SamplerKind::Sobol,
        });
        RenderIdentity::new(
            camera,
            s.integrator,
            s.stage,
            s.spp(),
            s.samples.seed,
            sampler,
            s.samples.filter,
            s.max_depth,
            s.light_sampling,
            self.aovs.clone(),
        )
    }

    /// How 8-bit output shows the picture.
    pub fn display(&self) -> Display {
        self.settings.display(self.exposure, self.tone_map)
    }

    fn stopped(&self) -> bool {
        self.stop.is_some_and(|flag| flag.load(Ordering::Relaxed))
    }

    /// Renders one frame through `camera` into `output` (an image, or an `.exr` part of the
    /// image with its header), going on from `resume` (a checkpoint) or from this render's own
    /// checkpoint where there is one. With the stop flag set, it stops between passes and
    /// writes what it has ([`FrameOutcome::interrupted`]).
    pub fn render_frame(
        &mut self,
        camera: &Camera,
        output: &Path,
        resume: Option<Part>,
        events: &(dyn Fn(Event) + Sync),
    ) -> Result<FrameOutcome, SessionError> {
        let (width, height) = (camera.width, camera.height);
        self.check_output(output, (width, height))?;
        self.accel()?;
        let (scene, settings, region) = (self.scene, self.settings, self.region((width, height)));
        let identity = self.identity(camera);
        let header = PartHeader {
            kind: PartKind::Image,
            image: (width, height),
            region,
            samples: 0,
            scene_hash: format!("{:016x}", scene.content_hash()),
            settings: identity.to_text(),
            command: self.checkpoints.as_ref().and_then(|c| c.command.clone()),
        };
        let checkpoint = self.checkpoints.as_ref().map(|c| (checkpoint_path(output), c.every));
        // An image that an earlier run of the same render finished (a requeued job, a rerun
        // after an interrupt) is not rendered again.
        if checkpoint.is_some()
            && output.exists()
            && parts::read_part(output).is_ok_and(|done| {
                let h = &done.header;
                (h.kind, h.samples, &h.scene_hash, &h.settings, h.region)
                    == (
                        PartKind::Image,
                        settings.spp(),
                        &header.scene_hash,
                        &header.settings,
                        region,
                    )
            })
        {
            events(Event::AlreadyRendered(output));
            return Ok(FrameOutcome {
                output: output.to_path_buf(),
                camera: *camera,
                film: None,
                samples: settings.spp(),
                first_sample: settings.spp(),
                discarded: 0,
                elapsed: Duration::ZERO,
                checkpoint_time: Duration::ZERO,
                interrupted: false,
                checkpoint: checkpoint.map(|(path, _)| path),
            });
        }
        let resume = match (resume, &checkpoint) {
            (Some(part), _) => Some(part),
            (None, Some((path, _))) if path.exists() => Some(parts::read_part(path)?),
            _ => None,
        };

        let mut accumulator = match resume {
            Some(part) => resume_from(part, &header, &self.aovs, settings, events)?,
            None => {
                let mut accumulator = Accumulator::for_region(width, height, region)?;
                accumulator.settings = settings.samples;
                accumulator.with_layers(self.aovs.len(), None)?
            }
        };
        let first_sample = accumulator.samples();
        // A checkpoint that cannot be written is reported, and the render goes on: its work is
        // not thrown away for want of a checkpoint.
        let write_checkpoint = |accumulator: &Accumulator, path: &Path| -> Duration {
            let start = Instant::now();
            let state = PartHeader {
                kind: PartKind::Checkpoint,
                samples: accumulator.samples(),
                ..header.clone()
            };
            let channels = channels_of(accumulator.sums(), accumulator.layer_sums(), &self.aovs);
            if let Err(error) =
                parts::write_exr(path, (width, height), region, channels, Some(&state))
            {
                events(Event::CheckpointNotWritten(&error));
            }
            start.elapsed()
        };
        let Passes { interrupted, checkpoint_time, elapsed, base_discarded } =
            self.passes(camera, &mut accumulator, checkpoint.as_ref(), &write_checkpoint, events);
        // The work so far is kept first: on a pre-empted node the time left may be short.
        if interrupted && let Some((path, _)) = &checkpoint {
            write_checkpoint(&accumulator, path);
        }
        let samples = accumulator.samples();
        if samples == 0 {
            events(Event::Finished);
            return Err(SessionError::NothingRendered);
        }
        let film = accumulator.mean()?;
        let layers = (0..self.aovs.len())
            .map(|k| accumulator.layer_mean(k))
            .collect::<Result<Vec<_>, _>>()?;
        events(Event::Finished);

        if image_io::check_writable(output)? == ImageFormat::Exr {
            let header = PartHeader { samples, command: None, ..header.clone() };
            let channels = channels_of(&film, &layers, &self.aovs);
            parts::write_exr(output, (width, height), region, channels, Some(&header))?;
        } else {
            image_io::save_film(output, &film, &self.display())?;
        }
        if !interrupted
            && let Some((path, _)) = &checkpoint
            && path.exists()
        {
            std::fs::remove_file(path).map_err(|source| ImageIoError::Io {
                action: "delete the finished render's checkpoint",
                path: path.clone(),
                source,
            })?;
        }
        Ok(FrameOutcome {
            output: output.to_path_buf(),
            camera: *camera,
            film: Some(film),
            samples,
            first_sample,
            discarded: base_discarded + accumulator.discarded_samples(),
            elapsed,
            checkpoint_time,
            interrupted,
            checkpoint: checkpoint.map(|(path, _)| path),
        })
    }

    /// The passes of a frame into `accumulator`, from the samples it holds to the settings'
    /// count (or the stop flag, or the time limit), with checkpoints to `checkpoint` (its path
    /// and how often) written by `write_checkpoint`.
    fn passes(
        &self,
        camera: &Camera,
        accumulator: &mut Accumulator,
        checkpoint: Option<&(PathBuf, Duration)>,
        write_checkpoint: &(dyn Fn(&Accumulator, &Path) -> Duration + Sync),
        events: &(dyn Fn(Event) + Sync),
    ) -> Passes {
        let accel = self.accel.get().expect("the BVH is built before the passes");
        let (scene, settings) = (self.scene, self.settings);
        let region = accumulator.region();
        // The integrator, with its layers.
        let choice = Choice {
            kind: settings.integrator,
            stage: settings.stage,
            path: settings.path_settings(),
            lights: None,
        };
        let base = Chosen::new(&choice, scene, accel, camera);
        let with_layers = WithAovs::new(&base, scene, accel, &self.aovs);
        let integrator: &dyn Integrator = if self.aovs.is_empty() { &base } else { &with_layers };

        let first_sample = accumulator.samples();
        let passes = settings.spp().saturating_sub(first_sample) as u64;
        events(Event::Started {
            rows: region.height() as u64 * passes,
            row_pixels: region.width() as u64,
            time_limit: settings.time_limit,
        });
        let start = Instant::now();
        let mut last_checkpoint = Instant::now();
        let mut checkpoint_time = Duration::ZERO;
        let mut interrupted = false;
        // Passes go in groups, each pixel's samples side by side (the same pixels, faster:
        // `Accumulator::add_samples_with_progress`): as many as take about a quarter of a
        // second, so that a stop or a checkpoint waits no longer than that, and no more than the
        // time limit leaves room for. The first group is one pass, which times them.
        let mut group = 1;
        self.pool.install(|| {
            while accumulator.samples() < settings.spp() {
                if self.stopped() {
                    interrupted = true;
                    break;
                }
                let count = group.min(settings.spp() - accumulator.samples());
                let pass_start = Instant::now();
                accumulator.add_samples_with_progress(camera, integrator, count, &|rows| {
                    events(Event::Rows(rows))
                });
                let left = settings.time_limit.map(|limit| limit.saturating_sub(start.elapsed()));
                group = passes_per_group(pass_start.elapsed() / count, left);
                if left == Some(Duration::ZERO) {
                    break;
                }
                if let Some((path, every)) = &checkpoint
                    && last_checkpoint.elapsed() >= *every
                    && accumulator.samples() < settings.spp()
                {
                    checkpoint_time += write_checkpoint(accumulator, path);
                    last_checkpoint = Instant::now();
                }
            }
        });
        interrupted |= self.stopped();
        Passes {
            interrupted,
            checkpoint_time,
            elapsed: start.elapsed(),
            base_discarded: base.discarded_samples(),
        }
    }

    /// Renders one frame through `camera` into memory, as [`render_frame`](Self::render_frame)
    /// renders it into a file (the same pixels, for the job's region), without checkpoints.
    /// With the stop flag set, it stops between passes and returns what it has
    /// ([`FilmOutcome::interrupted`]).
    pub fn render_film(
        &mut self,
        camera: &Camera,
        events: &(dyn Fn(Event) + Sync),
    ) -> Result<FilmOutcome, SessionError> {
        let region = self.region((camera.width, camera.height));
        self.check_film_memory(region)?;
        self.accel()?;
        let mut accumulator = Accumulator::for_region(camera.width, camera.height, region)?;
        accumulator.settings = self.settings.samples;
        let mut accumulator = accumulator.with_layers(self.aovs.len(), None)?;
        let no_checkpoint = |_: &Accumulator, _: &Path| Duration::ZERO;
        let passes = self.passes(camera, &mut accumulator, None, &no_checkpoint, events);
        let samples = accumulator.samples();
        events(Event::Finished);
        if samples == 0 {
            return Err(SessionError::NothingRendered);
        }
        Ok(FilmOutcome {
            film: accumulator.mean()?,
            layers: (0..self.aovs.len())
                .map(|k| accumulator.layer_mean(k))
                .collect::<Result<Vec<_>, _>>()?,
            region,
            samples,
            discarded: passes.base_discarded + accumulator.discarded_samples(),
            elapsed: passes.elapsed,
            interrupted: passes.interrupted,
        })
    }
}

/// About how long a group of passes may take: a stop or a checkpoint waits for the group in
/// flight. A quarter of a second: a 256×256 render's passes of a few milliseconds go sixteen
/// together, where grouping pays most; a pass that takes longer than this goes alone.
const GROUP_TIME: Duration = Duration::from_millis(250);

/// How many passes the next group takes, each taking `per_pass`: as many as fit in about
/// [`GROUP_TIME`], and in the time `left` under a limit; at least one, at most
/// [`PASS_GROUP`](crate::render::PASS_GROUP).
fn passes_per_group(per_pass: Duration, left: Option<Duration>) -> u32 {
    let budget = left.map_or(GROUP_TIME, |left| left.min(GROUP_TIME));
    let fits = budget.as_secs_f64() / per_pass.as_secs_f64().max(1e-9);
    (fits as u32).clamp(1, crate::render::PASS_GROUP)
}

/// The number of threads the machine runs at once.
fn cores() -> usize {
    std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1)
}

/// Refuses a `width×height` picture that needs more memory (`bytes`) than the machine has
/// available.
pub fn check_memory(bytes: u64, width: u32, height: u32) -> Result<(), SessionError> {
    match crate::memory::available_bytes() {
        Some(available) if bytes > available => Err(SessionError::OutOfMemory(format!(
            "image size {width}×{height} needs {} of memory, but only {} is available",
            format_bytes(bytes),
            format_bytes(available)
        ))),
        _ => Ok(()),
    }
}

/// Whether a BVH over `triangles` fits in `available` bytes (unknown: assumed to fit).
fn check_bvh_memory(
    name: &str,
    triangles: usize,
    available: Option<u64>,
) -> Result<(), SessionError> {
    // What `Bvh::new` builds.
    let bytes = Bvh::build_bytes_estimate(triangles, &BuildSettings::for_triangles(triangles));
    match available {
        Some(available) if bytes > available => Err(SessionError::OutOfMemory(format!(
            "{name}: {triangles} triangles need about {} of memory for the BVH, but only {} is \
             available",
            format_bytes(bytes),
            format_bytes(available)
        ))),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bvh_larger_than_the_memory_is_one_line_error() {
        let error = check_bvh_memory("big.ply", 200_000_000, Some(8 << 30)).unwrap_err();
        let message = error.to_string();
        assert!(message.starts_with("big.ply: 200000000 triangles need about"), "{message}");
        assert!(!message.contains('\n'), "{message}");
        assert!(check_bvh_memory("small.obj", 1000, Some(8 << 30)).is_ok());
        assert!(check_bvh_memory("unknown.obj", 200_000_000, None).is_ok());
    }

    /// As many passes as take about a quarter of a second, within a time limit's room, from 1
    /// to 16.
    #[test]
    fn groups_take_a_quarter_of_a_second_and_fit_the_time_left() {
        let ms = Duration::from_millis;
        assert_eq!(passes_per_group(ms(10), None), 16);
        assert_eq!(passes_per_group(ms(20), None), 12);
        assert_eq!(passes_per_group(ms(70), None), 3);
        assert_eq!(passes_per_group(ms(400), None), 1);
        assert_eq!(passes_per_group(Duration::ZERO, None), 16);
        assert_eq!(passes_per_group(ms(10), Some(ms(55))), 5);
        assert_eq!(passes_per_group(ms(10), Some(ms(5000))), 16);
        assert_eq!(passes_per_group(ms(70), Some(ms(10))), 1);
    }

    #[test]
    fn checkpoints_sit_beside_the_output_and_frames_are_numbered() {
        assert_eq!(checkpoint_path(Path::new("out/a.exr")), Path::new("out/a.checkpoint.exr"));
        assert_eq!(checkpoint_path(Path::new("b.png")), Path::new("b.checkpoint.exr"));
        let path = |p: &str, f| frame_path(Path::new(p), f).map(|p| p.display().to_string());
        assert_eq!(path("out/f_%04d.exr", 7).unwrap(), "out/f_0007.exr");
        assert_eq!(path("%d.png", 12).unwrap(), "12.png");
        assert_eq!(path("a%2d_b.exr", 123).unwrap(), "a123_b.exr");
        assert!(path("out.exr", 1).unwrap_err().to_string().contains("like out_%04d.exr"));
        assert!(path("out_%04x.exr", 1).is_err());
        assert!(path("out_%d_%d.exr", 1).is_err());
    }
}
