//! What a render job tells its caller as it goes ([`Event`]): passes begun and rows done, a
//! frame found already rendered or resumed from a checkpoint, a checkpoint not written.

use std::path::Path;
use std::time::Duration;

use crate::image_io::ImageIoError;

/// What a job tells its caller as it goes.
#[derive(Debug)]
pub enum Event<'a> {
    /// A frame's passes begin: `rows` rows of `row_pixels` pixels to render in all (for a
    /// progress bar), within `time_limit` if there is one.
    Started {
        /// Rows in all passes.
        rows: u64,
        /// Pixels per row.
        row_pixels: u64,
        /// The render's time limit.
        time_limit: Option<Duration>,
    },
    /// Rows just finished (called from the render threads).
    Rows(u32),
    /// The frame's passes are over.
    Finished,
    /// The output is already rendered, by an earlier run of the same render: it is kept.
    AlreadyRendered(&'a Path),
    /// Going on from a checkpoint at `samples` samples per pixel.
    Resumed {
        /// The checkpoint.
        checkpoint: &'a Path,
        /// Samples per pixel it holds.
        samples: u32,
    },
    /// A checkpoint could not be written (a full disk, say); the render goes on.
    CheckpointNotWritten(&'a ImageIoError),
}
