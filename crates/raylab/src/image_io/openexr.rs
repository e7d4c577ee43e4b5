//! OpenEXR files: linear radiance and extra layers as named float channels.
//!
//! A picture is a list of [`Channel`]s, each a name and one value per pixel, row by row from the
//! top: the beauty image's `R`, `G`, `B`, and each extra layer's `NAME.R`, `NAME.G`, `NAME.B`
//! (the layer convention of Nuke and Blender), or `NAME.Z` alone for a layer named `depth`. A
//! file may hold one region of a larger image: its data window is the region, its display
//! window the whole image (the OpenEXR way of saying where a crop belongs). The render-farm
//! parts (the `parts` module) are such files with attributes of their own in the header.

use std::path::Path;

use exr::prelude::*;
// The prelude's `Result` is exr's own.
use std::result::Result;

use super::file::{ImageIoError, write_atomically};
use crate::film::Film;
use crate::region::Region;

/// One channel of an image: its name and its value at each pixel, row by row from the top.
pub type Channel = (String, Vec<f32>);

/// How a file's pixels are stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Compression {
    /// Lossless ZIP compression: the smallest files.
    Lossless,
    /// Uncompressed: the fastest to write (checkpoints, written often and read once).
    Uncompressed,
}

/// The channels of `film` as `R`, `G`, `B`, and of each extra film as `NAME.R`, `NAME.G`,
/// `NAME.B` (Nuke's and Blender's layer convention), or `NAME.Z` alone for a film named `depth`.
///
/// # Panics
/// If an extra film's size is not the beauty's.
pub fn film_channels(beauty: &Film, layers: &[(&str, &Film)]) -> Vec<Channel> {
    let mut channels = Vec::new();
    let mut add = |name: String, film: &Film, axis: usize| {
        assert_eq!(
            (film.width(), film.height()),
            (beauty.width(), beauty.height()),
            "{name}: a layer of the image's size"
        );
        channels.push((name, film.pixels().iter().map(|p| p[axis]).collect()));
    };
    for (axis, channel) in ["R", "G", "B"].into_iter().enumerate() {
        add(channel.to_string(), beauty, axis);
    }
    for (name, film) in layers {
        if *name == "depth" {
            add("depth.Z".to_string(), film, 0);
        } else {
            for (axis, channel) in ["R", "G", "B"].into_iter().enumerate() {
                add(format!("{name}.{channel}"), film, axis);
            }
        }
    }
    channels.sort_by(|a, b| a.0.cmp(&b.0));
    channels
}

/// The beauty image of channels `R`, `G`, `B` of a `width×height` region, if they are there
/// with a value for each pixel.
pub fn beauty(channels: &[Channel], width: u32, height: u32) -> Option<Film> {
    let pixels = width as usize * height as usize;
    let find = |name: &str| channels.iter().find(|c| c.0 == name && c.1.len() == pixels);
    let (r, g, b) = (&find("R")?.1, &find("G")?.1, &find("B")?.1);
    let pixels = r.iter().zip(g).zip(b).map(|((&r, &g), &b)| glam::Vec3::new(r, g, b)).collect();
    Some(Film::from_pixels(width, height, pixels))
}

/// Writes `channels` of `region` of an `image`-sized picture (float, lossless) to `path`
/// atomically, with extra header `attributes`.
///
/// # Panics
/// If a channel does not hold one value per pixel of the region.
pub fn write_channels(
    path: &Path,
    image: (u32, u32),
    region: Region,
    channels: Vec<Channel>,
    attributes: Vec<(Text, AttributeValue)>,
    compression: Compression,
) -> Result<(), ImageIoError> {
    let list: Vec<AnyChannel<FlatSamples>> = channels
        .into_iter()
        .map(|(name, values)| {
            assert_eq!(values.len() as u64, region.pixels(), "{name}: a value per pixel");
            AnyChannel::new(name.as_str(), FlatSamples::F32(values))
        })
        .collect();
    let mut layer_attributes = LayerAttributes::named("rgb");
    layer_attributes.layer_position = Vec2(region.x0 as i32, region.y0 as i32);
    layer_attributes.other.extend(attributes);
    let encoding = match compression {
        Compression::Lossless => Encoding::SMALL_LOSSLESS,
        Compression::Uncompressed => Encoding::UNCOMPRESSED,
    };
    let layer = Layer::new(
        (region.width() as usize, region.height() as usize),
        layer_attributes,
        encoding,
        AnyChannels::sort(list.into()),
    );
    let display = IntegerBounds::new((0, 0), (image.0 as usize, image.1 as usize));
    let file = Image::new(ImageAttributes::new(display), layer);
    write_atomically(path, |out| {
        file.write().to_buffered(out).map_err(|e| ImageIoError::Float {
            action: "write",
            path: path.to_path_buf(),
            message: e.to_string(),
        })
    })
}

/// Writes an OpenEXR file with the beauty image as its `R`, `G`, `B` channels and each extra
/// film as channels `NAME.R`, `NAME.G`, `NAME.B` (the layer convention of Nuke and Blender), or
/// `NAME.Z` alone for a film named `depth`. Atomic, as every write.
///
/// # Panics
/// If a film's size is not the beauty's.
pub fn save_exr_layers(
    path: &Path,
    beauty: &Film,
    layers: &[(&str, &Film)],
) -> Result<(), ImageIoError> {
    let (width, height) = (beauty.width(), beauty.height());
    let channels = film_channels(beauty, layers);
    let region = Region::full(width, height);
    write_channels(path, (width, height), region, channels, Vec::new(), Compression::Lossless)
}

/// Reads every channel of an OpenEXR file's first layer by name, row by row from the top.
pub fn load_exr_channels(path: &Path) -> Result<Vec<Channel>, ImageIoError> {
    let error =
        |message: String| ImageIoError::Float { action: "read", path: path.to_path_buf(), message };
    let image = read_all_flat_layers_from_file(path).map_err(|e| error(e.to_string()))?;
    let layer = image.layer_data.first().ok_or_else(|| error("no layer".into()))?;
    Ok(layer
        .channel_data
        .list
        .iter()
        .map(|c| (c.name.to_string(), c.sample_data.values_as_f32().collect()))
        .collect())
}

/// Runs an OpenEXR decoding step, turning a panic inside the decoder (a damaged file it does
/// not expect) into an error.
///
/// The panic is not printed: the caller reports the error in one line. (Decoding runs on this
/// thread only, `non_parallel`, so the hook's per-thread switch covers it.)
pub(crate) fn guarded<T>(decode: impl FnOnce() -> exr::error::Result<T>) -> Result<T, String> {
    match crate::quiet_panic::catch_quietly(decode) {
        Some(result) => result.map_err(|e| e.to_string()),
        None => Err("damaged beyond what the OpenEXR decoder can read".into()),
    }
}

/// Reads an OpenEXR file's first RGB layer as a film (`load_film`'s `.exr`): its headers are
/// read and checked against [`MAX_FLOAT_IMAGE_PIXELS`](super::MAX_FLOAT_IMAGE_PIXELS) before
/// any pixel is decoded, and a decoder that fails in any way gives an error, never a panic.
pub fn read_exr_film(bytes: &[u8]) -> Result<Film, String> {
    let meta =
        guarded(|| exr::meta::MetaData::read_from_buffered(std::io::Cursor::new(bytes), false))?;
    if let Some(header) = meta.headers.iter().find(|h| {
        (h.layer_size.0 as u64).saturating_mul(h.layer_size.1 as u64)
            > super::file::MAX_FLOAT_IMAGE_PIXELS
    }) {
        return Err(format!(
            "it declares {}×{} pixels, more than an image may have ({})",
            header.layer_size.0,
            header.layer_size.1,
            super::file::MAX_FLOAT_IMAGE_PIXELS
        ));
    }
    let image = guarded(|| {
        read()
            .no_deep_data()
            .largest_resolution_level()
            .rgba_channels(
                |resolution, _| {
                    (
                        resolution.width(),
                        vec![glam::Vec3::ZERO; resolution.width() * resolution.height()],
                    )
                },
                |(width, pixels): &mut (usize, Vec<glam::Vec3>),
                 position,
                 (r, g, b, _a): (f32, f32, f32, f32)| {
                    pixels[position.y() * *width + position.x()] = glam::Vec3::new(r, g, b);
                },
            )
            .first_valid_layer()
            .all_attributes()
            .non_parallel()
            .from_buffered(std::io::Cursor::new(bytes))
    })?;
    let size = image.layer_data.size;
    let (_, pixels) = image.layer_data.channel_data.pixels;
    Ok(Film::from_pixels(size.width() as u32, size.height() as u32, pixels))
}
