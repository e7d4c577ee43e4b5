//! Parts of a render put back together: `raylab merge`.

use std::path::{Path, PathBuf};

use super::{RenderIdentity, SessionError};
use crate::film::ToneMap;
use crate::image_io::{self, ImageFormat, ImageIoError};
use crate::parts;

/// What a merge wrote.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MergeReport {
    /// The whole image's size.
    pub size: (u32, u32),
    /// How many parts went into it.
    pub parts: usize,
    /// Samples per pixel.
    pub samples: u32,
}

/// Reads the parts `inputs` (written by renders of one scene with one identity, together
/// covering every pixel once), and writes the whole image to `output`: `.exr` with every
/// channel and the parts' header, or `.pfm`, or `.png`/`.ppm` through the display transform of
/// the render's integrator with `exposure` and `tone_map`. The output may not be one of the
/// parts.
pub fn merge_parts(
    inputs: &[PathBuf],
    output: &Path,
    exposure: f32,
    tone_map: ToneMap,
) -> Result<MergeReport, SessionError> {
    let format = image_io::check_writable(output)?;
    // By identity, not by name: `./a.exr` and `a.exr`, or a link, are the same file.
    if let Ok(output_file) = std::fs::canonicalize(output)
        && inputs.iter().any(|p| std::fs::canonicalize(p).is_ok_and(|p| p == output_file))
    {
        return Err(SessionError::Invalid(format!(
            "{}: the output would overwrite one of the parts",
            output.display()
        )));
    }
    let parts = inputs.iter().map(|p| parts::read_part(p)).collect::<Result<Vec<_>, _>>()?;
    let count = parts.len();
    let first = parts.first().map(|p| p.path.display().to_string()).unwrap_or_default();
    let (header, channels) = parts::merge(parts)?;
    // Every part has the first's settings (merge checked): its identity says how to show them.
    let identity = RenderIdentity::from_text(&first, &header.settings)?;
    let (width, height) = header.image;
    if format == ImageFormat::Exr {
        parts::write_exr(output, header.image, header.region, channels, Some(&header))?;
    } else {
        let film = parts::beauty(&channels, width, height).ok_or_else(|| ImageIoError::Float {
            action: "write",
            path: output.to_path_buf(),
            message: "the parts have no R, G and B channels".into(),
        })?;
        drop(channels);
        let display =
            crate::film::Display { exposure, tone_map, srgb: !identity.integrator.shows_linear() };
        image_io::save_film(output, &film, &display)?;
    }
    Ok(MergeReport { size: header.image, parts: count, samples: header.samples })
}
