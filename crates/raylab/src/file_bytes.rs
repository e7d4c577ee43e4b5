//! Reading an input file whole, within a size limit, decompressing gzip as it is read.
//!
//! Every reader of untrusted files (mesh loaders, material libraries, textures, ray sets) reads
//! through [`read_bytes`], so that a huge file or a small gzip bomb is refused before it can
//! exhaust the machine. The default limit, [`read_limit_bytes`], is half of the memory the system
//! reports as available (`MemAvailable` in `/proc/meminfo`), at most 16 GiB and at least
//! 256 MiB; 16 GiB where the system does not say. Half, because what is parsed from the bytes
//! needs room too.

use std::fs::File;
use std::io::{self, BufReader, Read};
use std::path::{Path, PathBuf};

use flate2::read::MultiGzDecoder;

/// Why a file's bytes could not be had.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The file does not exist or cannot be read.
    #[error("{}: cannot read: {error}", .path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        error: io::Error,
    },
    /// The file is named `.gz` but is not a valid gzip stream (or it is cut short).
    #[error("{}: not a valid gzip file: {error}", .path.display())]
    Gzip {
        /// The file.
        path: PathBuf,
        /// What the decompressor said.
        error: io::Error,
    },
    /// The file, or its decompressed content, is larger than the limit.
    #[error(
        "{}: larger than {limit_bytes} bytes{}, more than this machine can load safely",
        .path.display(),
        if *.decompressed { " once decompressed" } else { "" }
    )]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// The limit that was exceeded.
        limit_bytes: u64,
        /// Whether the limit was reached while decompressing.
        decompressed: bool,
    },
}

/// The most bytes to read from one file, after decompression: half of the memory available now
/// (`MemAvailable` in `/proc/meminfo`), clamped to 256 MiB ..= 16 GiB; 16 GiB where the system
/// does not report it.
pub fn read_limit_bytes() -> u64 {
    const MIN: u64 = 256 << 20;
    const MAX: u64 = 16 << 30;
    crate::memory::available_bytes().map_or(MAX, |bytes| (bytes / 2).clamp(MIN, MAX))
}

/// Reads the whole file, decompressing it if `gzip`, refusing more than `limit` bytes.
pub fn read_bytes(path: &Path, gzip: bool, limit: u64) -> Result<Vec<u8>, ReadError> {
    let read_error = |error| ReadError::Read { path: path.into(), error };
    let file = File::open(path).map_err(read_error)?;
    // The size on disk is a hint only: special files report 0, and a file may grow.
    let size_on_disk = file.metadata().map(|m| m.len()).unwrap_or(0);
    if !gzip && size_on_disk > limit {
        return Err(ReadError::TooLarge {
            path: path.into(),
            limit_bytes: limit,
            decompressed: false,
        });
    }
    let mut bytes = Vec::with_capacity(usize::try_from(size_on_disk.min(limit)).unwrap_or(0));
    let result = if gzip {
        MultiGzDecoder::new(BufReader::new(file))
            .take(limit.saturating_add(1))
            .read_to_end(&mut bytes)
    } else {
        file.take(limit.saturating_add(1)).read_to_end(&mut bytes)
    };
    match result {
        Ok(_) => {}
        // The decoder reports a malformed stream as invalid input or data, a cut one as an
        // unexpected end; anything else is the operating system's.
        Err(error)
            if gzip
                && matches!(
                    error.kind(),
                    io::ErrorKind::InvalidInput
                        | io::ErrorKind::InvalidData
                        | io::ErrorKind::UnexpectedEof
                ) =>
        {
            return Err(ReadError::Gzip { path: path.into(), error });
        }
        Err(error) => return Err(read_error(error)),
    }
    if bytes.len() as u64 > limit {
        return Err(ReadError::TooLarge {
            path: path.into(),
            limit_bytes: limit,
            decompressed: gzip,
        });
    }
    Ok(bytes)
}
