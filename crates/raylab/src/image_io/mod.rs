//! Writing and reading images, safely.
//!
//! The format comes from the file's extension: `.png` (8-bit RGB) or `.ppm` (binary P6, which any
//! image viewer and the lab's own tools read) for pictures, and `.exr` (OpenEXR, 32-bit float,
//! lossless ZIP compression) or `.pfm` (Portable Float Map) for linear radiance. Files are written to a temporary file in the same
//! folder, synced and renamed into place, so a failed write never leaves a partial image behind
//! and never destroys the previous one. (Only a kill in the moment of writing can leave a hidden
//! `.NAME.*.tmp` file; the image itself is always whole or absent.)

use std::fs;
use std::io::{self, Write};
use std::path::Path;

use glam::Vec3;
use image::{ImageEncoder, RgbImage};

mod file;
pub mod openexr;

use crate::film::{Display, Film};
use file::temporary_file_beside;
pub use file::{ImageIoError, MAX_FLOAT_IMAGE_PIXELS, write_atomically};
pub use openexr::{load_exr_channels, save_exr_layers};

/// Image file formats raylab writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// PNG, 8-bit RGB.
    Png,
    /// Binary PPM (P6), 8-bit RGB.
    Ppm,
    /// OpenEXR, linear 32-bit float RGB.
    Exr,
    /// Portable Float Map, linear 32-bit float RGB.
    Pfm,
}

impl ImageFormat {
    /// Whether the format keeps linear radiance (rather than 8-bit display levels).
    pub fn is_float(self) -> bool {
        matches!(self, ImageFormat::Exr | ImageFormat::Pfm)
    }
}

impl ImageFormat {
    /// The format named by `path`'s extension (case-insensitive).
    pub fn from_path(path: &Path) -> Result<Self, ImageIoError> {
        let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
        match ext.as_deref() {
            Some("png") => Ok(ImageFormat::Png),
            Some("ppm") => Ok(ImageFormat::Ppm),
            Some("exr") => Ok(ImageFormat::Exr),
            Some("pfm") => Ok(ImageFormat::Pfm),
            _ => Err(ImageIoError::UnknownFormat { path: path.to_path_buf() }),
        }
    }
}

/// The format to write `path` in, refusing a path that names a folder.
fn output_format(path: &Path) -> Result<ImageFormat, ImageIoError> {
    let format = ImageFormat::from_path(path)?;
    if path.is_dir() {
        return Err(ImageIoError::IsAFolder { path: path.to_path_buf() });
    }
    Ok(format)
}

/// Checks, before any work is done, that an image can be written to `path`: a known extension,
/// an existing folder that accepts new files, and not a folder or read-only file in the way.
pub fn check_writable(path: &Path) -> Result<ImageFormat, ImageIoError> {
    let format = output_format(path)?;
    if let Ok(meta) = fs::metadata(path)
        && meta.permissions().readonly()
    {
        return Err(ImageIoError::Io {
            action: "write",
            path: path.to_path_buf(),
            source: io::Error::new(io::ErrorKind::PermissionDenied, "the file is read-only"),
        });
    }
    // Creating (and at once deleting) a file is the only reliable test of permission.
    drop(temporary_file_beside(path)?);
    Ok(format)
}

/// Writes a film to `path` in the format its extension names, atomically: linear values for
/// `.exr` and `.pfm`, through `display` for `.png` and `.ppm`.
pub fn save_film(path: &Path, film: &Film, display: &Display) -> Result<(), ImageIoError> {
    let format = output_format(path)?;
    let float_error = |message: String| ImageIoError::Float {
        action: "write",
        path: path.to_path_buf(),
        message,
    };
    match format {
        ImageFormat::Exr => save_exr_layers(path, film, &[]),
        ImageFormat::Pfm => write_atomically(path, |out| {
            let write_error = |source: io::Error| ImageIoError::Io {
                action: "write",
                path: path.to_path_buf(),
                source,
            };
            // Little-endian (negative scale), rows from the bottom up.
            write!(out, "PF\n{} {}\n-1.0\n", film.width(), film.height()).map_err(write_error)?;
            for row in film.pixels().chunks_exact(film.width() as usize).rev() {
                for p in row {
                    for v in p.to_array() {
                        out.write_all(&v.to_le_bytes()).map_err(write_error)?;
                    }
                }
            }
            Ok(())
        }),
        _ => save_rgb8(path, &film.to_rgb8(display).map_err(|e| float_error(e.to_string()))?),
    }
}

/// Whether `path` names a Radiance HDR (RGBE) file, `.hdr` (case-insensitive).
fn is_hdr(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("hdr"))
}

/// Reads a float image, `.pfm`, `.exr` (its first RGB layer) or `.hdr` (Radiance RGBE, the
/// format most HDRI libraries publish), as a film.
pub fn load_film(path: &Path) -> Result<Film, ImageIoError> {
    let error =
        |message: String| ImageIoError::Float { action: "read", path: path.to_path_buf(), message };
    if is_hdr(path) {
        let bytes = fs::read(path).map_err(|source| ImageIoError::Io {
            action: "read",
            path: path.to_path_buf(),
            source,
        })?;
        return parse_hdr(&bytes).map_err(error);
    }
    match ImageFormat::from_path(path) {
        Ok(ImageFormat::Exr) => {
            let bytes = fs::read(path).map_err(|source| ImageIoError::Io {
                action: "read",
                path: path.to_path_buf(),
                source,
            })?;
            openexr::read_exr_film(&bytes).map_err(error)
        }
        Ok(ImageFormat::Pfm) => {
            let bytes = fs::read(path).map_err(|source| ImageIoError::Io {
                action: "read",
                path: path.to_path_buf(),
                source,
            })?;
            parse_pfm(&bytes).map_err(error)
        }
        _ => Err(error("not a float image: expected .pfm, .exr or .hdr".into())),
    }
}

/// Parses a Radiance HDR file (RGBE, flat or run-length encoded; top row first, as films are).
/// Its size is checked against [`MAX_FLOAT_IMAGE_PIXELS`] before the pixels are read.
pub fn parse_hdr(bytes: &[u8]) -> Result<Film, String> {
    use image::ImageDecoder;
    let decoder = image::codecs::hdr::HdrDecoder::new(std::io::Cursor::new(bytes))
        .map_err(|e| format!("not a Radiance HDR file: {e}"))?;
    let (width, height) = decoder.dimensions();
    let pixels = u64::from(width) * u64::from(height);
    if pixels > MAX_FLOAT_IMAGE_PIXELS {
        return Err(format!(
            "it declares {width}×{height} pixels, more than an image may have ({MAX_FLOAT_IMAGE_PIXELS})"
        ));
    }
    if pixels == 0 {
        return Err(format!("it declares {width}×{height} pixels: no image"));
    }
    // The decoder writes RGB triples of native-endian f32, a `Vec3`'s layout: straight into the
    // film's pixels, without a second copy (an 8k × 4k map's pixels are 384 MiB). Zeroed
    // memory is only committed as the decoder writes it: a short file that declares a huge
    // image fails at its first missing row, not after filling gigabytes.
    let mut pixels: Vec<Vec3> = bytemuck::allocation::try_zeroed_vec(pixels_needed(width, height)?)
        .map_err(|()| format!("not enough memory for {width}×{height} pixels"))?;
    let bytes: &mut [u8] = bytemuck::cast_slice_mut(&mut pixels);
    if decoder.total_bytes() != bytes.len() as u64 {
        return Err(format!("{} bytes of pixels for {width}×{height} RGB", decoder.total_bytes()));
    }
    decoder.read_image(bytes).map_err(|e| format!("damaged pixel data: {e}"))?;
    Ok(Film::from_pixels(width, height, pixels))
}

/// How many pixels `width × height` is, as a length.
fn pixels_needed(width: u32, height: u32) -> Result<usize, String> {
    usize::try_from(u64::from(width) * u64::from(height))
        .map_err(|_| format!("{width}×{height} pixels do not fit in memory"))
}

/// Parses a colour Portable Float Map.
fn parse_pfm(bytes: &[u8]) -> Result<Film, String> {
    // Three whitespace-separated header tokens after "PF", then one whitespace byte.
    let mut tokens = Vec::new();
    let mut i = 0;
    while tokens.len() < 4 {
        while i < bytes.len() && bytes[i].is_ascii_whitespace() {
            i += 1;
        }
        let start = i;
        while i < bytes.len() && !bytes[i].is_ascii_whitespace() {
            i += 1;
        }
        if start == i {
            return Err("the header ends early: expected PF, width, height and scale".into());
        }
        tokens.push(String::from_utf8_lossy(&bytes[start..i]).into_owned());
    }
    i += 1;
    if tokens[0] != "PF" {
        return Err(format!("expected 'PF' (colour PFM), found '{}'", tokens[0]));
    }
    let dimension = |t: &str| t.parse::<u32>().ok().filter(|&d| d > 0 && d <= 1 << 16);
    let (Some(width), Some(height)) = (dimension(&tokens[1]), dimension(&tokens[2])) else {
        return Err(format!("bad size '{} {}'", tokens[1], tokens[2]));
    };
    let scale: f32 = tokens[3].parse().map_err(|_| format!("bad scale '{}'", tokens[3]))?;
    let data = bytes.get(i..).unwrap_or_default();
    let needed = width as usize * height as usize * 12;
    if data.len() != needed {
        return Err(format!("expected {needed} bytes of pixels, found {}", data.len()));
    }
    let value = |k: usize| {
        let b = [data[4 * k], data[4 * k + 1], data[4 * k + 2], data[4 * k + 3]];
        if scale < 0.0 { f32::from_le_bytes(b) } else { f32::from_be_bytes(b) }
    };
    let mut pixels = vec![Vec3::ZERO; width as usize * height as usize];
    for y in 0..height as usize {
        let file_row = height as usize - 1 - y;
        for x in 0..width as usize {
            let k = 3 * (file_row * width as usize + x);
            pixels[y * width as usize + x] = Vec3::new(value(k), value(k + 1), value(k + 2));
        }
    }
    Ok(Film::from_pixels(width, height, pixels))
}

/// Writes `image` to `path` in the format its extension names, atomically: the file appears
/// complete or not at all.
pub fn save_rgb8(path: &Path, image: &RgbImage) -> Result<(), ImageIoError> {
    let format = output_format(path)?;
    write_atomically(path, |out| {
        let write_error = |source: io::Error| ImageIoError::Io {
            action: "write",
            path: path.to_path_buf(),
            source,
        };
        match format {
            ImageFormat::Png => image::codecs::png::PngEncoder::new(out)
                .write_image(
                    image.as_raw(),
                    image.width(),
                    image.height(),
                    image::ExtendedColorType::Rgb8,
                )
                .map_err(|source| ImageIoError::Image {
                    action: "write",
                    path: path.to_path_buf(),
                    source,
                }),
            ImageFormat::Ppm => {
                write!(out, "P6\n{} {}\n255\n", image.width(), image.height())
                    .map_err(write_error)?;
                out.write_all(image.as_raw()).map_err(write_error)
            }
            ImageFormat::Exr | ImageFormat::Pfm => {
                let film = Film::from_pixels(
                    image.width(),
                    image.height(),
                    image
                        .pixels()
                        .map(|p| Vec3::from_array(p.0.map(|v| v as f32 / 255.0)))
                        .collect(),
                );
                save_film(path, &film, &Display::LAB)
            }
        }
    })
}

/// Reads a PNG file as 8-bit RGB.
pub fn load_rgb8(path: &Path) -> Result<RgbImage, ImageIoError> {
    let read_error =
        |source| ImageIoError::Image { action: "read", path: path.to_path_buf(), source };
    let reader = image::ImageReader::open(path).map_err(|source| ImageIoError::Io {
        action: "read",
        path: path.to_path_buf(),
        source,
    })?;
    Ok(reader
        .with_guessed_format()
        .map_err(|e| read_error(e.into()))?
        .decode()
        .map_err(read_error)?
        .to_rgb8())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn test_image() -> RgbImage {
        RgbImage::from_fn(3, 2, |x, y| image::Rgb([x as u8 * 80, y as u8 * 200, 7]))
    }

    #[test]
    fn png_round_trips_and_ppm_has_the_p6_layout() {
        let dir = tempfile::tempdir().unwrap();
        let png = dir.path().join("a.PNG");
        save_rgb8(&png, &test_image()).unwrap();
        assert_eq!(load_rgb8(&png).unwrap(), test_image());
        let ppm = dir.path().join("a.ppm");
        save_rgb8(&ppm, &test_image()).unwrap();
        let bytes = fs::read(&ppm).unwrap();
        assert_eq!(&bytes[..11], b"P6\n3 2\n255\n");
        assert_eq!(&bytes[11..], test_image().as_raw().as_slice());
        // Nothing but the two images is left in the folder.
        assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 2);
    }

    /// A Radiance HDR file of `pixels` (`width` wide, top row first), by the `image` crate's
    /// encoder (run-length encoded rows).
    fn hdr_file(pixels: &[Vec3], width: usize) -> Vec<u8> {
        let rgb: Vec<image::Rgb<f32>> = pixels.iter().map(|p| image::Rgb(p.to_array())).collect();
        let mut bytes = Vec::new();
        image::codecs::hdr::HdrEncoder::new(&mut bytes)
            .encode(&rgb, width, pixels.len() / width)
            .unwrap();
        bytes
    }

    #[test]
    fn hdr_files_are_read_top_row_first_to_rgbe_precision() {
        let dir = tempfile::tempdir().unwrap();
        // Wide enough (≥ 8) that the encoder run-length encodes its rows.
        let (width, height) = (40, 3);
        let pixels: Vec<Vec3> = (0..width * height)
            .map(|i| Vec3::new(i as f32 * 0.37 + 0.01, 1000.0 / (i as f32 + 1.0), (i % 7) as f32))
            .collect();
        let path = dir.path().join("sky.HDR");
        fs::write(&path, hdr_file(&pixels, width)).unwrap();
        let film = load_film(&path).unwrap();
        assert_eq!((film.width(), film.height()), (width as u32, height as u32));
        for y in 0..height {
            for x in 0..width {
                let (want, got) = (pixels[y * width + x], film.pixel(x as u32, y as u32));
                // RGBE keeps 8 bits of mantissa under the largest channel's exponent.
                let tolerance = want.max_element() / 128.0;
                assert!(
                    (want - got).abs().max_element() <= tolerance,
                    "({x}, {y}): {got} for {want}"
                );
            }
        }
    }

    #[test]
    fn damaged_hdr_files_are_one_line_errors_naming_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let pixels: Vec<Vec3> = (0..64 * 32).map(|i| Vec3::splat((i % 97) as f32 + 0.5)).collect();
        let whole = hdr_file(&pixels, 64);
        let cases: [(&str, Vec<u8>, &str); 4] = [
            ("truncated.hdr", whole[..whole.len() / 2].to_vec(), "damaged pixel data"),
            ("garbage.hdr", b"#?RADIANCE\nthis is no header\n".to_vec(), "not a Radiance HDR"),
            ("empty.hdr", Vec::new(), "not a Radiance HDR"),
            (
                "huge.hdr",
                b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 100000 +X 100000\n".to_vec(),
                "declares 100000×100000 pixels, more than an image may have",
            ),
        ];
        for (name, bytes, words) in cases {
            let path = dir.path().join(name);
            fs::write(&path, bytes).unwrap();
            let message = load_film(&path).unwrap_err().to_string();
            assert!(message.contains(name) && message.contains(words), "{name}: {message}");
            assert!(!message.contains('\n'), "{name}: one line: {message}");
        }
    }

    #[test]
    fn hostile_exr_images_are_refused_with_their_reason() {
        let folder = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz/exr_part");
        let error = |name: &str| load_film(&folder.join(name)).unwrap_err().to_string();
        let huge = error("huge-data-window.exr");
        assert!(
            huge.contains("huge-data-window.exr") && huge.contains("declares 100000×100000"),
            "{huge}"
        );
        let truncated = error("truncated.exr");
        assert!(truncated.contains("truncated.exr") && !truncated.contains('\n'), "{truncated}");
    }

    #[test]
    fn float_images_round_trip_bit_for_bit() {
        let dir = tempfile::tempdir().unwrap();
        let pixels: Vec<Vec3> = (0..12)
            .map(|i| Vec3::new(i as f32 * 1.5e-3, -(i as f32), 1e6 + i as f32 * 0.125))
            .collect();
        let film = Film::from_pixels(4, 3, pixels);
        for name in ["a.exr", "a.pfm"] {
            let path = dir.path().join(name);
            save_film(&path, &film, &Display::LAB).unwrap();
            assert_eq!(load_film(&path).unwrap(), film, "{name}");
        }
        // The PFM layout: header, then rows bottom-up, little-endian.
        let bytes = fs::read(dir.path().join("a.pfm")).unwrap();
        assert_eq!(&bytes[..12], b"PF\n4 3\n-1.0\n");
        assert_eq!(&bytes[12..16], &film.pixel(0, 2).x.to_le_bytes());
        // Malformed files are named with what is wrong.
        let bad = dir.path().join("bad.pfm");
        fs::write(&bad, b"PF\n4 3\n-1.0\n1234").unwrap();
        let message = load_film(&bad).unwrap_err().to_string();
        assert!(message.contains("bad.pfm") && message.contains("expected 144 bytes"), "{message}");
        fs::write(&bad, b"Pf\n4 3\n-1.0\n").unwrap();
        assert!(load_film(&bad).unwrap_err().to_string().contains("colour PFM"));
    }

    #[test]
    fn exr_layers_keep_every_channel_by_name() {
        let dir = tempfile::tempdir().unwrap();
        let film =
            |v: f32| Film::from_pixels(3, 2, (0..6).map(|i| Vec3::new(v, i as f32, -v)).collect());
        let path = dir.path().join("aov.exr");
        save_exr_layers(&path, &film(1.0), &[("albedo", &film(2.0)), ("depth", &film(3.0))])
            .unwrap();
        let channels = load_exr_channels(&path).unwrap();
        let names: Vec<&str> = channels.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["B", "G", "R", "albedo.B", "albedo.G", "albedo.R", "depth.Z"]);
        let channel = |name: &str| &channels.iter().find(|(n, _)| n == name).unwrap().1;
        assert_eq!(channel("albedo.R"), &vec![2.0; 6]);
        assert_eq!(channel("G"), &(0..6).map(|i| i as f32).collect::<Vec<_>>());
        assert_eq!(channel("depth.Z"), &vec![3.0; 6]);
        // The beauty reads back as the film.
        assert_eq!(load_film(&path).unwrap(), film(1.0));
    }

    #[test]
    fn bad_paths_are_refused_with_the_path_named() {
        let dir = tempfile::tempdir().unwrap();
        let cases = [
            (dir.path().join("a.jpg"), "unknown image format '.jpg'"),
            (dir.path().join("noext"), "no extension"),
            (dir.path().join("missing/a.png"), "does not exist"),
        ];
        for (path, expected) in cases {
            let message = save_rgb8(&path, &test_image()).unwrap_err().to_string();
            assert!(message.contains(expected), "{message}");
            assert!(message.contains(&path.display().to_string()), "{message}");
        }
        let folder = dir.path().join("f.png");
        fs::create_dir(&folder).unwrap();
        assert!(matches!(check_writable(&folder), Err(ImageIoError::IsAFolder { .. })));
    }

    #[test]
    fn very_long_file_names_can_be_written() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(format!("{}.png", "n".repeat(250)));
        save_rgb8(&path, &test_image()).unwrap();
        assert_eq!(load_rgb8(&path).unwrap(), test_image());
    }

    #[test]
    fn a_failed_write_keeps_the_old_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("keep.png");
        save_rgb8(&path, &test_image()).unwrap();
        let before = fs::read(&path).unwrap();
        // An encoder error (zero-sized image) must not touch the existing file.
        assert!(save_rgb8(&path, &RgbImage::new(0, 0)).is_err());
        assert_eq!(fs::read(&path).unwrap(), before);
        assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 1);
    }
}
