//! The render session: everything between "a scene and some options" and "an image on disk",
//! for the command line, `raylab view`, and any program that renders with raylab.
//!
//! ```text
//! Scene::open ─▶ RenderOptions ─▶ ResolvedSettings::resolve ─▶ RenderJob::new (BVH, threads)
//!                                                                   │
//!        CameraOptions::camera ─▶ Camera ─▶ RenderJob::render_frame ─▶ image, part or checkpoint
//! ```
//!
//! - [`RenderOptions`] are what a caller overrides (the command line's `--spp`, `--integrator`,
//!   ...); [`ResolvedSettings::resolve`] is the one rule that merges them with the scene file's
//!   `[render]` settings and the defaults: the integrator is the option's, else the file's, else
//!   `path` for scenes that some surface or a light other than a point light lights
//!   (`Scene::needs_path_tracing`) and `lab` for others; samples per pixel 1 for `lab` and
//!   16 otherwise; the seed 0; unlimited depth.
//! - [`CameraOptions`] place the camera: the scene file's camera (or an animation's at a frame,
//!   the lab's, or one framing a model), with any override of position, angles, focal length
//!   and lens.
//! - A [`RenderJob`] holds the scene, its BVH, the thread pool, the resolved settings, the
//!   region (a tile or any rectangle of the image), the AOV layers (computed in the same pass,
//!   [`WithAovs`](crate::integrator::WithAovs)), the time limit and the checkpoint policy. It
//!   renders a frame ([`RenderJob::render_frame`]) or an animation's frames
//!   ([`RenderJob::render_frames`]), reports through a callback ([`Event`]), and stops cleanly
//!   between passes when its stop flag is set: the image so far is written with the samples it
//!   reached, and a checkpoint with it.
//! - What decides a render's pixels besides the scene is its [`RenderIdentity`], a typed
//!   structure stored as JSON in every part and checkpoint it writes: parts merge
//!   ([`merge_parts`]) and checkpoints resume only where identities are equal.
//!
//! Determinism: the pixels depend on the scene, the identity and nothing else: not the thread
//! count, the tiling, the region a part covers, or how often the render stopped and resumed.

mod camera_options;
mod checkpoint;
mod event;
mod identity;
mod job;
mod merge;
mod summary;

use std::time::Duration;

pub use camera_options::CameraOptions;
pub use checkpoint::{Checkpoints, checkpoint_path};
pub use event::Event;
pub use identity::{CameraIdentity, IdentityError, RenderIdentity};
pub use job::{FilmOutcome, FrameOutcome, RenderJob, check_memory, frame_path};
pub use merge::{MergeReport, merge_parts};
pub use summary::FrameSummary;

use crate::film::{Display, ToneMap};
use crate::filter::Filter;
use crate::integrator::{PathSettings, Stage, TriangleSampling};
use crate::render::SampleSettings;
use crate::sampling::SamplerKind;
use crate::scene::Scene;
use crate::settings::{IntegratorKind, MaxDepth};

/// The most samples per pixel a render takes.
pub const MAX_SPP: u32 = 1 << 16;

/// Why a render could not be set up, run or written. Every message is one line naming what
/// it is about (the file, the option, the scene).
#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    /// Options that do not go together, or a value out of range.
    #[error("{0}")]
    Invalid(String),
    /// More memory than the machine has available.
    #[error("{0}")]
    OutOfMemory(String),
    /// An image, part or checkpoint that cannot be written or read.
    #[error(transparent)]
    Image(#[from] crate::image_io::ImageIoError),
    /// A part or checkpoint that is malformed or does not belong.
    #[error(transparent)]
    Part(#[from] crate::parts::PartError),
    /// A film that cannot be made.
    #[error(transparent)]
    Film(#[from] crate::film::FilmError),
    /// A tile or region outside the image.
    #[error(transparent)]
    Region(#[from] crate::region::RegionError),
    /// A part or checkpoint whose render identity cannot be read.
    #[error(transparent)]
    Identity(#[from] IdentityError),
    /// A checkpoint that is not this render's.
    #[error("{}: cannot go on from this checkpoint: {problem}; delete it to start afresh", .path.display())]
    Checkpoint {
        /// The checkpoint.
        path: std::path::PathBuf,
        /// Why not.
        problem: String,
    },
    /// The stop flag was set before the first sample: nothing was written.
    #[error("interrupted before the first sample: nothing written")]
    NothingRendered,
}

/// What a caller overrides of a scene's render settings; `None` leaves the scene file's value
/// (or the default) in place. See [`ResolvedSettings::resolve`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RenderOptions {
    /// What to compute.
    pub integrator: Option<IntegratorKind>,
    /// The lab integrator's stage.
    pub stage: Stage,
    /// Samples per pixel (at least 1, at most [`MAX_SPP`]).
    pub spp: Option<u32>,
    /// The longest path.
    pub max_depth: Option<MaxDepth>,
    /// The seed of every random number.
    pub seed: Option<u64>,
    /// The sample generator.
    pub sampler: Option<SamplerKind>,
    /// The pixel filter.
    pub filter: Option<Filter>,
    /// How points on area lights are sampled.
    pub light_sampling: TriangleSampling,
    /// Render progressively for this long, then stop with the samples reached (at most
    /// `spp` where that is given).
    pub time_limit: Option<Duration>,
}

/// Everything that decides how a scene is rendered, resolved from the scene file and the
/// [`RenderOptions`] by one rule.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ResolvedSettings {
    /// What to compute.
    pub integrator: IntegratorKind,
    /// The lab integrator's stage.
    pub stage: Stage,
    /// The longest path, `None` unlimited.
    pub max_depth: Option<u32>,
    /// How points on area lights are sampled.
    pub light_sampling: TriangleSampling,
    /// The seed, the sampler (`None`: the integrator's), the filter, the tiling, and the
    /// samples per pixel to reach (`count`; 0 where a time limit ends the render: see
    /// [`spp`](Self::spp)).
    pub samples: SampleSettings,
    /// Stop after this long.
    pub time_limit: Option<Duration>,
}

impl ResolvedSettings {
    /// The settings for rendering `scene` with `options`: an option where it is given, else the
    /// scene file's `[render]` value, else the default (see the module documentation).
    pub fn resolve(scene: &Scene, options: &RenderOptions) -> ResolvedSettings {
        let file = &scene.settings;
        let integrator = options
            .integrator
            .or(file.integrator)
            .unwrap_or_else(|| IntegratorKind::default_for(scene.needs_path_tracing()));
        let default_spp = if integrator == IntegratorKind::Lab { 1 } else { 16 };
        // With a time limit, the passes stop at the time (or at an --spp asked for): a count
        // not known in advance.
        let count = match (options.time_limit, options.spp) {
            (Some(_), None) => 0,
            _ => options.spp.or(file.spp).unwrap_or(default_spp).max(1),
        };
        ResolvedSettings {
            integrator,
            stage: options.stage,
            max_depth: options.max_depth.or(file.max_depth).and_then(MaxDepth::segments),
            light_sampling: options.light_sampling,
            samples: SampleSettings {
                seed: options.seed.or(file.seed).unwrap_or(0),
                sampler: options.sampler.or(file.sampler),
                filter: options.filter.or(file.filter).unwrap_or_default(),
                count,
                ..SampleSettings::default()
            },
            time_limit: options.time_limit,
        }
    }

    /// What the command line should warn of before rendering `scene` with these settings: the
    /// lights the `lab` integrator ignores, if it is the integrator.
    pub fn warnings(&self, scene: &Scene) -> Vec<String> {
        let ignored = scene.lights_the_lab_ignores();
        if self.integrator != IntegratorKind::Lab || ignored.is_empty() {
            return Vec::new();
        }
        vec![format!(
            "the lab integrator ignores the scene's {} light{} (its light model is the lab's \
             point light); --integrator path sees {}",
            ignored.join(", "),
            if ignored.len() == 1 { "" } else { "s" },
            if ignored.len() == 1 { "it" } else { "them" },
        )]
    }

    /// Samples per pixel to reach: the count, or with a time limit and no count [`MAX_SPP`].
    pub fn spp(&self) -> u32 {
        match self.samples.count {
            0 => MAX_SPP,
            count => count,
        }
    }

    /// The path tracer's settings.
    pub fn path_settings(&self) -> PathSettings {
        PathSettings {
            max_depth: self.max_depth,
            light_sampling: self.light_sampling,
            ..PathSettings::default()
        }
    }

    /// How pictures of this integrator are shown in 8 bits: the lab's linear clamp for `lab`,
    /// sRGB otherwise, with `exposure` (stops) and `tone_map`.
    pub fn display(&self, exposure: f32, tone_map: ToneMap) -> Display {
        Display { exposure, tone_map, srgb: !self.integrator.shows_linear() }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::AovKind;

    #[test]
    fn options_override_the_scene_file_which_overrides_the_defaults() {
        let mut scene = Scene::built_in("cornell").unwrap();
        let lab = ResolvedSettings::resolve(&scene, &RenderOptions::default());
        assert_eq!((lab.integrator, lab.spp(), lab.samples.seed), (IntegratorKind::Lab, 1, 0));
        assert_eq!(lab.max_depth, None);
        scene.settings.integrator = Some(IntegratorKind::Path);
        scene.settings.spp = Some(64);
        scene.settings.seed = Some(9);
        scene.settings.max_depth = Some(MaxDepth::Segments(8));
        let file = ResolvedSettings::resolve(&scene, &RenderOptions::default());
        assert_eq!((file.integrator, file.spp(), file.samples.seed), (IntegratorKind::Path, 64, 9));
        assert_eq!(file.max_depth, Some(8));
        let options = RenderOptions {
            integrator: Some(IntegratorKind::Aov(AovKind::Depth)),
            spp: Some(2),
            max_depth: Some(MaxDepth::Unlimited),
            seed: Some(3),
            ..RenderOptions::default()
        };
        let given = ResolvedSettings::resolve(&scene, &options);
        assert_eq!(given.integrator, IntegratorKind::Aov(AovKind::Depth));
        assert_eq!((given.spp(), given.samples.seed, given.max_depth), (2, 3, None));
        // A time limit without samples asked for runs until the time is up.
        let timed = RenderOptions { time_limit: Some(Duration::from_secs(1)), ..options };
        assert_eq!(
            ResolvedSettings::resolve(&scene, &RenderOptions { spp: None, ..timed }).spp(),
            MAX_SPP
        );
        // Without a scene file's choice, area lights make it path-traced, 16 samples.
        let mitsuba = Scene::open(
            concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes/cornell-lab.toml"),
            &crate::scene::LoadOptions::default(),
        )
        .unwrap()
        .scene;
        let mut plain = mitsuba.clone();
        plain.settings = Default::default();
        let path = ResolvedSettings::resolve(&plain, &RenderOptions::default());
        assert_eq!((path.integrator, path.spp()), (IntegratorKind::Path, 16));
        assert!(path.display(0.0, ToneMap::Clamp).srgb && !lab.display(0.0, ToneMap::Clamp).srgb);
    }
}
