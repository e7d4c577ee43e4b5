//! A PLY parse error before the file's path is attached ([`Failure`]).

use crate::scene::mesh_file::Location;

/// A parse error before the path is attached.
#[derive(Debug)]
pub(super) struct Failure {
    pub(super) location: Location,
    pub(super) message: String,
}

/// Fails at `location` with `message`.
pub(super) fn fail<T>(location: Location, message: impl Into<String>) -> Result<T, Failure> {
    Err(Failure { location, message: message.into() })
}
