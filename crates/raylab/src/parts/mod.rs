//! Renders split into parts and assembled again, and checkpoints to resume from.
//!
//! A **part** is an OpenEXR file of one [`Region`] of an image: its data window is the region,
//! its display window the whole image (the OpenEXR way of saying where a crop belongs), and its
//! header records what the part must agree on with the others:
//!
//! | attribute | type | meaning |
//! |---|---|---|
//! | `raylab.kind` | text | `image` (a part or a whole picture) or `checkpoint` |
//! | `raylab.sceneHash` | text | `Scene::content_hash`, 16 hex digits |
//! | `raylab.settings` | text | everything else that decides the pixels: `key=value` entries (size, camera, integrator, seed, sampler, filter, ...) separated by `; ` |
//! | `raylab.samples` | int | samples per pixel reached |
//! | `raylab.command` | bytes | checkpoints only: the command line to resume, as JSON |
//!
//! An `image` part holds the mean of its pixels' samples: channels `R`, `G`, `B`, and any extra
//! layers (`albedo.R`, `depth.Z`, ...). [`merge`] puts parts back together and refuses parts that
//! do not belong together: another scene, settings, image size or sample count, overlapping
//! regions, or pixels no part covers. Because every pixel depends on (seed, pixel, sample index)
//! alone, the merge of any set of parts is the single render, bit for bit.
//!
//! A `checkpoint` holds the **sums** of the samples instead (the mean times the sample count
//! would not give the same bits back), so that a render resumed from it adds sample `samples`
//! next and ends with exactly the pixels of a render that never stopped.

use std::path::{Path, PathBuf};

use exr::prelude::*;
// The prelude's `Result` is exr's own.
use std::result::Result;

use crate::image_io::ImageIoError;
use crate::image_io::openexr as exr_file;
use crate::image_io::openexr::guarded;
pub use crate::image_io::openexr::{Channel, Compression, beauty, film_channels};
use crate::region::Region;

const KIND: &str = "raylab.kind";
const SCENE_HASH: &str = "raylab.sceneHash";
const SETTINGS: &str = "raylab.settings";
const SAMPLES: &str = "raylab.samples";
const COMMAND: &str = "raylab.command";

/// What a part's pixels are.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PartKind {
    /// Means: a picture, whole or a part of one.
    Image,
    /// Sums of samples, to resume a render from.
    Checkpoint,
}

impl PartKind {
    fn name(self) -> &'static str {
        match self {
            PartKind::Image => "image",
            PartKind::Checkpoint => "checkpoint",
        }
    }
}

/// What a part's header records (see the module documentation).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PartHeader {
    /// Means or sums.
    pub kind: PartKind,
    /// The whole image's width and height.
    pub image: (u32, u32),
    /// The pixels the part holds.
    pub region: Region,
    /// Samples per pixel reached.
    pub samples: u32,
    /// The scene's content hash (`Scene::content_hash`) as 16 hex digits.
    pub scene_hash: String,
    /// The render settings that decide the pixels, as text (ASCII).
    pub settings: String,
    /// For checkpoints: the command line to resume with (any text; stored as bytes).
    pub command: Option<String>,
}

/// A part read back: its header and channels, sorted by name.
#[derive(Clone, Debug, PartialEq)]
pub struct Part {
    /// The file it was read from.
    pub path: PathBuf,
    /// Its header.
    pub header: PartHeader,
    /// Its channels over its region, sorted by name.
    pub channels: Vec<Channel>,
}

/// Why a part cannot be read or parts cannot be merged; each message names the file.
#[derive(Debug, thiserror::Error)]
pub enum PartError {
    /// The file cannot be read or written as OpenEXR.
    #[error(transparent)]
    Io(#[from] ImageIoError),
    /// The file is an image but not a raylab part, or its header is inconsistent.
    #[error("{path}: {problem}")]
    NotAPart {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        problem: String,
    },
    /// Two parts disagree.
    #[error("{path} does not belong with {first}: {problem}")]
    Mismatch {
        /// The part that disagrees.
        path: PathBuf,
        /// The first part, which the others are compared with.
        first: PathBuf,
        /// What differs.
        problem: String,
    },
    /// Two parts cover the same pixels.
    #[error("{path} overlaps {other}: both hold pixels of {overlap}")]
    Overlap {
        /// One part.
        path: PathBuf,
        /// The other.
        other: PathBuf,
        /// The pixels both hold.
        overlap: Region,
    },
    /// Some pixels are in no part.
    #[error(
        "the parts leave {missing} of {total} pixels uncovered, the first at column {x}, row {y}"
    )]
    Holes {
        /// Pixels in no part.
        missing: u64,
        /// Pixels in the image.
        total: u64,
        /// The first such pixel's column.
        x: u32,
        /// Its row.
        y: u32,
    },
    /// Nothing to merge.
    #[error("no parts to merge")]
    NoParts,
}

/// Writes channels of `header.region` (float, lossless) to `path` atomically, with the header
/// attributes of the module documentation; `header` `None` writes a plain OpenEXR image.
///
/// # Panics
/// If a channel does not hold one value per pixel of the region, or the settings or the scene
/// hash are not ASCII.
pub fn write_exr(
    path: &Path,
    image: (u32, u32),
    region: Region,
    channels: Vec<Channel>,
    header: Option<&PartHeader>,
) -> Result<(), ImageIoError> {
    let mut attributes = Vec::new();
    if let Some(header) = header {
        debug_assert_eq!((header.image, header.region), (image, region));
        let text = |s: &str| AttributeValue::Text(Text::new_or_panic(s));
        attributes.push((Text::from(KIND), text(header.kind.name())));
        attributes.push((Text::from(SCENE_HASH), text(&header.scene_hash)));
        attributes.push((Text::from(SETTINGS), text(&header.settings)));
        attributes.push((Text::from(SAMPLES), AttributeValue::I32(header.samples as i32)));
        if let Some(command) = &header.command {
            let bytes = command.as_bytes().into();
            attributes.push((
                Text::from(COMMAND),
                AttributeValue::Bytes { type_hint: Text::from("json"), bytes },
            ));
        }
    }
    // Checkpoints are written often and read once: uncompressed, they cost the least time.
    let compression = match header.map(|h| h.kind) {
        Some(PartKind::Checkpoint) => Compression::Uncompressed,
        _ => Compression::Lossless,
    };
    exr_file::write_channels(path, image, region, channels, attributes, compression)
}

/// The most bytes of samples a part may declare (all its channels as 32-bit floats): files that
/// declare more are refused before anything is allocated for them.
pub const MAX_PART_BYTES: u64 = 4 << 30;

/// Reads a part (or a checkpoint) written by [`write_exr`] with a header.
pub fn read_part(path: &Path) -> Result<Part, PartError> {
    let file = std::fs::File::open(path).map_err(|source| ImageIoError::Io {
        action: "read",
        path: path.to_path_buf(),
        source,
    })?;
    read_part_from(path, std::io::BufReader::new(file))
}

/// [`read_part`] from any reader; `path` names it in messages. The header is read and checked
/// first ([`MAX_PART_BYTES`]), and a decoder that fails in any way, however damaged the file,
/// gives an error, never a panic.
pub fn read_part_from(
    path: &Path,
    mut reader: impl std::io::Read + std::io::Seek,
) -> Result<Part, PartError> {
    let damaged = |message: String| {
        PartError::Io(ImageIoError::Float { action: "read", path: path.to_path_buf(), message })
    };
    let not_a_part = |problem: String| PartError::NotAPart { path: path.to_path_buf(), problem };
    // The header alone, to refuse absurd sizes before the decoder allocates for them.
    let meta =
        guarded(|| exr::meta::MetaData::read_from_buffered(&mut reader, false)).map_err(damaged)?;
    let [header] = meta.headers.as_slice() else {
        return Err(not_a_part(format!(
            "{} layers, where a raylab part has one",
            meta.headers.len()
        )));
    };
    let declared = (header.layer_size.0 as u64)
        .saturating_mul(header.layer_size.1 as u64)
        .saturating_mul(header.channels.list.len() as u64)
        .saturating_mul(4);
    if declared > MAX_PART_BYTES {
        return Err(not_a_part(format!(
            "it declares {}×{} pixels of {} channels ({}), more than a part may hold ({})",
            header.layer_size.0,
            header.layer_size.1,
            header.channels.list.len(),
            crate::film::format_bytes(declared),
            crate::film::format_bytes(MAX_PART_BYTES)
        )));
    }
    reader.seek(std::io::SeekFrom::Start(0)).map_err(|e| damaged(e.to_string()))?;
    let image = guarded(|| {
        read()
            .no_deep_data()
            .largest_resolution_level()
            .all_channels()
            .all_layers()
            .all_attributes()
            .non_parallel()
            .from_buffered(reader)
    })
    .map_err(damaged)?;
    let [layer] = image.layer_data.as_slice() else {
        return Err(not_a_part(format!(
            "{} layers, where a raylab part has one",
            image.layer_data.len()
        )));
    };
    let other = &layer.attributes.other;
    let text = |name: &str| -> Result<String, PartError> {
        match other.get(&Text::from(name)) {
            Some(AttributeValue::Text(t)) => Ok(t.to_string()),
            Some(_) => Err(not_a_part(format!("its {name} attribute is not text"))),
            None => Err(not_a_part(format!("no {name} attribute: not a part raylab wrote"))),
        }
    };
    let kind = match text(KIND)?.as_str() {
        "image" => PartKind::Image,
        "checkpoint" => PartKind::Checkpoint,
        other => return Err(not_a_part(format!("unknown {KIND} '{other}'"))),
    };
    let samples = match other.get(&Text::from(SAMPLES)) {
        Some(&AttributeValue::I32(n)) if n >= 1 => n as u32,
        _ => return Err(not_a_part(format!("no valid {SAMPLES} attribute"))),
    };
    let command = match other.get(&Text::from(COMMAND)) {
        Some(AttributeValue::Bytes { bytes, .. }) => Some(
            String::from_utf8(bytes.to_vec())
                .map_err(|_| not_a_part(format!("its {COMMAND} attribute is not UTF-8")))?,
        ),
        _ => None,
    };
    let display = image.attributes.display_window;
    let fits_u32 = |v: i64| u32::try_from(v).ok();
    let (Some(width), Some(height)) =
        (fits_u32(display.size.0 as i64), fits_u32(display.size.1 as i64))
    else {
        return Err(not_a_part("its display window is too large".into()));
    };
    if display.position != Vec2(0, 0) {
        return Err(not_a_part(format!(
            "its display window starts at {:?}, not at (0, 0)",
            display.position
        )));
    }
    let position = layer.attributes.layer_position;
    let (x0, y0) = (position.0 as i64, position.1 as i64);
    let corner = [x0, y0, x0 + layer.size.0 as i64, y0 + layer.size.1 as i64].map(fits_u32);
    let [Some(x0), Some(y0), Some(x1), Some(y1)] = corner else {
        return Err(not_a_part(format!(
            "its data window at {position:?} lies outside the {width}×{height} image"
        )));
    };
    let region = Region::new([x0, y0, x1, y1], width, height)
        .map_err(|e| not_a_part(format!("its data window: {e}")))?;
    let mut channels: Vec<Channel> = layer
        .channel_data
        .list
        .iter()
        .map(|c| (c.name.to_string(), c.sample_data.values_as_f32().collect()))
        .collect();
    channels.sort_by(|a, b| a.0.cmp(&b.0));
    if ["R", "G", "B"].iter().any(|name| !channels.iter().any(|c| c.0 == *name)) {
        return Err(not_a_part("no R, G and B channels".into()));
    }
    if let Some((name, _)) = channels.iter().find(|c| c.1.len() as u64 != region.pixels()) {
        return Err(not_a_part(format!("its channel {name} does not hold a value per pixel")));
    }
    let header = PartHeader {
        kind,
        image: (width, height),
        region,
        samples,
        scene_hash: text(SCENE_HASH)?,
        settings: text(SETTINGS)?,
        command,
    };
    Ok(Part { path: path.to_path_buf(), header, channels })
}

/// Puts parts together into the whole image's channels (row by row over the image), checking
/// that they belong together, do not overlap and leave no hole (see the module documentation).
/// Returns the header the whole image shares (its region the whole image) and the channels.
///
/// Each part is dropped as soon as its pixels are copied, so that the parts and the whole image
/// are not all in memory at once.
pub fn merge(parts: Vec<Part>) -> Result<(PartHeader, Vec<Channel>), PartError> {
    let first = parts.first().ok_or(PartError::NoParts)?;
    let mismatch = |part: &Part, problem: String| PartError::Mismatch {
        path: part.path.clone(),
        first: first.path.clone(),
        problem,
    };
    let names: Vec<&String> = first.channels.iter().map(|c| &c.0).collect();
    for part in &parts {
        let (h, f) = (&part.header, &first.header);
        if h.kind != PartKind::Image {
            return Err(PartError::NotAPart {
                path: part.path.clone(),
                problem: "a checkpoint, not a finished part: resume it with \
                          `raylab render --resume` first"
                    .into(),
            });
        }
        if h.scene_hash != f.scene_hash {
            return Err(mismatch(
                part,
                format!("another scene (hash {} against {})", h.scene_hash, f.scene_hash),
            ));
        }
        if h.image != f.image {
            return Err(mismatch(
                part,
                format!(
                    "another image size ({}×{} against {}×{})",
                    h.image.0, h.image.1, f.image.0, f.image.1
                ),
            ));
        }
        if h.settings != f.settings {
            let (these, first_entries) =
                (setting_entries(&h.settings), setting_entries(&f.settings));
            let differ: Vec<String> = these
                .iter()
                .zip(&first_entries)
                .filter(|(a, b)| a != b)
                .map(|(a, b)| format!("{a} against {b}"))
                .collect();
            let problem = if differ.is_empty() || these.len() != first_entries.len() {
                format!("other settings ('{}' against '{}')", h.settings, f.settings)
            } else {
                format!("other settings ({})", differ.join(", "))
            };
            return Err(mismatch(part, problem));
        }
        if h.samples != f.samples {
            return Err(mismatch(
                part,
                format!(
                    "another sample count ({} samples per pixel against {}; an interrupted \
                     part must be resumed or rendered again)",
                    h.samples, f.samples
                ),
            ));
        }
        let these: Vec<&String> = part.channels.iter().map(|c| &c.0).collect();
        if these != names {
            return Err(mismatch(part, format!("other channels ({these:?} against {names:?})")));
        }
    }
    for (i, part) in parts.iter().enumerate() {
        for other in &parts[..i] {
            let (a, b) = (part.header.region, other.header.region);
            if part.path == other.path {
                return Err(PartError::NotAPart {
                    path: part.path.clone(),
                    problem: "given twice".into(),
                });
            }
            if a.overlaps(&b) {
                let overlap = Region {
                    x0: a.x0.max(b.x0),
                    y0: a.y0.max(b.y0),
                    x1: a.x1.min(b.x1),
                    y1: a.y1.min(b.y1),
                };
                return Err(PartError::Overlap {
                    path: part.path.clone(),
                    other: other.path.clone(),
                    overlap,
                });
            }
        }
    }
    let (width, height) = first.header.image;
    let total = width as u64 * height as u64;
    let covered: u64 = parts.iter().map(|p| p.header.region.pixels()).sum();
    if covered != total {
        // Regions do not overlap, so fewer pixels than the image means holes: find the first,
        // row by row, from the parts' spans on that row.
        let (x, y) = (0..height)
            .find_map(|y| {
                let mut spans: Vec<(u32, u32)> = parts
                    .iter()
                    .map(|p| p.header.region)
                    .filter(|r| (r.y0..r.y1).contains(&y))
                    .map(|r| (r.x0, r.x1))
                    .collect();
                spans.sort_unstable();
                let mut x = 0;
                for (x0, x1) in spans {
                    if x0 > x {
                        return Some((x, y));
                    }
                    x = x1;
                }
                (x < width).then_some((x, y))
            })
            .unwrap_or((0, 0));
        return Err(PartError::Holes { missing: total - covered, total, x, y });
    }
    let mut channels: Vec<Channel> = Vec::new();
    for name in &names {
        let mut values = Vec::new();
        if values.try_reserve_exact(total as usize).is_err() {
            return Err(PartError::NotAPart {
                path: first.path.clone(),
                problem: format!(
                    "its {width}×{height} image does not fit in memory ({} per channel)",
                    crate::film::format_bytes(total.saturating_mul(4))
                ),
            });
        }
        values.resize(total as usize, 0.0);
        channels.push(((*name).clone(), values));
    }
    let header = PartHeader { region: Region::full(width, height), ..first.header.clone() };
    for part in parts {
        let r = part.header.region;
        for ((_, whole), (_, values)) in channels.iter_mut().zip(&part.channels) {
            for (row, y) in values.chunks_exact(r.width() as usize).zip(r.y0..r.y1) {
                // In usize: an image may hold more than 2³² pixels.
                let start = y as usize * width as usize + r.x0 as usize;
                whole[start..start + row.len()].copy_from_slice(row);
            }
        }
    }
    Ok((header, channels))
}

/// The entries of a part's settings as `key=value` texts, to name the ones that differ: the
/// top-level fields of a JSON object (a render identity, from the `session` module), or `key=value`
/// entries separated by "; " in any other text.
fn setting_entries(settings: &str) -> Vec<String> {
    match serde_json::from_str::<serde_json::Value>(settings) {
        Ok(serde_json::Value::Object(fields)) => {
            fields.iter().map(|(key, value)| format!("{key}={value}")).collect()
        }
        _ => settings.split("; ").map(str::to_string).collect(),
    }
}

#[cfg(test)]
mod tests;
