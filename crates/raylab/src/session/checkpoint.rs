//! Checkpoints: a render's sums written beside its output between passes, and read back to go
//! on from them (see [`Checkpoints`]).

use std::path::{Path, PathBuf};
use std::time::Duration;

use super::event::Event;
use super::{RenderIdentity, ResolvedSettings, SessionError};
use crate::film::Film;
use crate::parts::{self, Channel, Part, PartHeader, PartKind};
use crate::render::Accumulator;
use crate::settings::AovKind;

/// Checkpoints: the sums of the samples written beside the output (`NAME.checkpoint.exr`, see
/// [`checkpoint_path`]) at most every `every`, between passes, and when the render is stopped.
/// A render that finds its own checkpoint goes on from it; a finished render deletes it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Checkpoints {
    /// The least time between two checkpoints.
    pub every: Duration,
    /// What to record for resuming (the command line, say), stored in each checkpoint.
    pub command: Option<String>,
}

/// An accumulator going on from checkpoint `part`, if it is this render's (`header`).
pub(super) fn resume_from(
    part: Part,
    header: &PartHeader,
    aovs: &[AovKind],
    settings: ResolvedSettings,
    events: &(dyn Fn(Event) + Sync),
) -> Result<Accumulator, SessionError> {
    let h = &part.header;
    let problem = if h.kind != PartKind::Checkpoint {
        Some("it is not a checkpoint".to_string())
    } else if h.scene_hash != header.scene_hash {
        Some("the scene has changed since".to_string())
    } else if h.settings != header.settings {
        let file = part.path.display().to_string();
        // Say why in the identity's terms where it can be read.
        RenderIdentity::from_text(&file, &h.settings)?;
        Some(format!("it has other settings ('{}')", h.settings))
    } else if (h.image, h.region) != (header.image, header.region) {
        Some(format!("it holds region {} of {}×{}", h.region, h.image.0, h.image.1))
    } else {
        None
    };
    if let Some(problem) = problem {
        return Err(SessionError::Checkpoint { path: part.path.clone(), problem });
    }
    let (width, height) = (h.region.width(), h.region.height());
    let missing = |what: &str| SessionError::Checkpoint {
        path: part.path.clone(),
        problem: format!("it has no {what} channels"),
    };
    let sums = parts::beauty(&part.channels, width, height).ok_or_else(|| missing("R, G and B"))?;
    let layers = aovs
        .iter()
        .map(|kind| {
            layer_of(&part.channels, *kind, width, height).ok_or_else(|| missing(kind.name()))
        })
        .collect::<Result<Vec<_>, _>>()?;
    events(Event::Resumed { checkpoint: &part.path, samples: h.samples });
    let accumulator = Accumulator::resume(h.image, h.region, sums, h.samples, settings.samples)?;
    Ok(accumulator.with_layers(aovs.len(), Some(layers))?)
}

/// The channels of a picture and its layers (see [`parts::film_channels`]).
pub(super) fn channels_of(beauty: &Film, layers: &[Film], aovs: &[AovKind]) -> Vec<Channel> {
    let named: Vec<(&str, &Film)> = aovs.iter().map(|k| k.name()).zip(layers).collect();
    parts::film_channels(beauty, &named)
}

/// Layer `kind` of a part's channels: `NAME.R`, `NAME.G`, `NAME.B`, or `depth.Z` in every
/// channel (the depth layer is the same in all three).
pub(super) fn layer_of(
    channels: &[Channel],
    kind: AovKind,
    width: u32,
    height: u32,
) -> Option<Film> {
    let pixels = width as usize * height as usize;
    let find = |name: String| channels.iter().find(|c| c.0 == name && c.1.len() == pixels);
    let name = kind.name();
    let values: Vec<glam::Vec3> = if kind == AovKind::Depth {
        find(format!("{name}.Z"))?.1.iter().map(|&z| glam::Vec3::splat(z)).collect()
    } else {
        let (r, g, b) =
            (find(format!("{name}.R"))?, find(format!("{name}.G"))?, find(format!("{name}.B"))?);
        r.1.iter().zip(&g.1).zip(&b.1).map(|((&r, &g), &b)| glam::Vec3::new(r, g, b)).collect()
    };
    Some(Film::from_pixels(width, height, values))
}

/// Where the checkpoint of a render writing `output` goes: `NAME.checkpoint.exr` beside it.
pub fn checkpoint_path(output: &Path) -> PathBuf {
    let stem = output.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    output.with_file_name(format!("{stem}.checkpoint.exr"))
}
