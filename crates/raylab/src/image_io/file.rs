//! Writing a file whole or not at all ([`write_atomically`]), and why an image could not be
//! written or read ([`ImageIoError`], whose every message names the file), and the largest
//! float image a file may declare ([`MAX_FLOAT_IMAGE_PIXELS`]).

use std::fs;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

/// The most pixels a float image read from a file may declare (an environment map of
/// 16k × 8k is 2²⁷): refused before anything is allocated for them.
pub const MAX_FLOAT_IMAGE_PIXELS: u64 = 1 << 28;

/// Why an image could not be written or read. Every message names the file.
#[derive(Debug, thiserror::Error)]
pub enum ImageIoError {
    /// The extension is not one raylab writes.
    #[error("cannot write '{}': unknown image format {}; use .png, .ppm, .exr or .pfm", .path.display(), describe_extension(.path))]
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
    /// The OpenEXR decoder or encoder failed, or a float image is malformed.
    #[error("cannot {action} '{}': {message}", .path.display())]
    Float {
        /// "write" or "read".
        action: &'static str,
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
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

/// The folder a file named `path` lives in (`.` for a bare file name).
fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent,
        _ => Path::new("."),
    }
}

/// A new empty temporary file next to `path`, readable like any file the user creates.
pub(super) fn temporary_file_beside(path: &Path) -> Result<tempfile::NamedTempFile, ImageIoError> {
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
