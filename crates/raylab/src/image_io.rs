//! Writing and reading images, safely.
//!
//! The format comes from the file's extension: `.png` (8-bit RGB) or `.ppm` (binary P6, which any
//! image viewer and the lab's own tools read). Files are written to a temporary file in the same
//! folder, synced and renamed into place, so a failed write never leaves a partial image behind
//! and never destroys the previous one. (Only a kill in the moment of writing can leave a hidden
//! `.NAME.*.tmp` file; the image itself is always whole or absent.)

use std::fs;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

use image::{ImageEncoder, RgbImage};

/// Why an image could not be written or read. Every message names the file.
#[derive(Debug, thiserror::Error)]
pub enum ImageIoError {
    /// The extension is not one raylab writes.
    #[error("cannot write '{}': unknown image format {}; use .png or .ppm", .path.display(), describe_extension(.path))]
    UnknownFormat {
        /// The file asked for.
        path: PathBuf,
    },
    /// The path names a folder.
    #[error("cannot write '{}': it is a folder, not a file", .path.display())]
    IsAFolder {
        /// The file asked for.
        path: PathBuf,
    },
    /// The folder that should hold the file does not exist.
    #[error("cannot write '{}': folder '{}' does not exist", .path.display(), .folder.display())]
    NoSuchFolder {
        /// The file asked for.
        path: PathBuf,
        /// Its folder.
        folder: PathBuf,
    },
    /// The operating system refused.
    #[error("cannot {action} '{}': {source}", .path.display())]
    Io {
        /// "write" or "read".
        action: &'static str,
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        source: io::Error,
    },
    /// The PNG decoder or encoder failed.
    #[error("cannot {action} '{}': {source}", .path.display())]
    Image {
        /// "write" or "read".
        action: &'static str,
        /// The file.
        path: PathBuf,
        /// What the codec said.
        source: image::ImageError,
    },
}

fn describe_extension(path: &Path) -> String {
    match path.extension() {
        Some(ext) => format!("'.{}'", ext.to_string_lossy()),
        None => "(the name has no extension)".to_string(),
    }
}

/// Image file formats raylab writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// PNG, 8-bit RGB.
    Png,
    /// Binary PPM (P6), 8-bit RGB.
    Ppm,
}

impl ImageFormat {
    /// The format named by `path`'s extension (case-insensitive).
    pub fn from_path(path: &Path) -> Result<Self, ImageIoError> {
        let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
        match ext.as_deref() {
            Some("png") => Ok(ImageFormat::Png),
            Some("ppm") => Ok(ImageFormat::Ppm),
            _ => Err(ImageIoError::UnknownFormat { path: path.to_path_buf() }),
        }
    }
}

/// The folder a file named `path` lives in (`.` for a bare file name).
fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent,
        _ => Path::new("."),
    }
}

/// A new empty temporary file next to `path`, readable like any file the user creates.
fn temporary_file_beside(path: &Path) -> Result<tempfile::NamedTempFile, ImageIoError> {
    let folder = folder_of(path);
    if !folder.is_dir() {
        return Err(ImageIoError::NoSuchFolder {
            path: path.to_path_buf(),
            folder: folder.to_path_buf(),
        });
    }
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    // Keep the temporary name within the file system's limit even for very long names.
    let short: String = name.chars().take(64).collect();
    let prefix = format!(".{short}.");
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix).suffix(".tmp");
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        // 0666 before the umask, as for any new file; tempfile's default would be 0600.
        builder.permissions(fs::Permissions::from_mode(0o666));
    }
    builder.tempfile_in(folder).map_err(|source| ImageIoError::Io {
        action: "write",
        path: path.to_path_buf(),
        source,
    })
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
        }
    })
}

/// Writes a file atomically: `write` fills a temporary file beside `path` (readable like any new
/// file), which is flushed, synced and then renamed into place. A failure at any step leaves
/// `path` as it was. Used for every file raylab writes: images and ray-set files alike.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<&fs::File>) -> Result<(), ImageIoError>,
) -> Result<(), ImageIoError> {
    if path.is_dir() {
        return Err(ImageIoError::IsAFolder { path: path.to_path_buf() });
    }
    let temporary = temporary_file_beside(path)?;
    let write_error =
        |source: io::Error| ImageIoError::Io { action: "write", path: path.to_path_buf(), source };
    {
        let mut out = BufWriter::new(temporary.as_file());
        write(&mut out)?;
        out.flush().map_err(write_error)?;
    }
    // On disk before the rename, so that even a crash cannot leave a renamed, empty file.
    temporary.as_file().sync_all().map_err(write_error)?;
    temporary.persist(path).map_err(|e| write_error(e.error))?;
    Ok(())
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
