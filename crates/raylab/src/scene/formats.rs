//! Loading a triangle mesh from a file: [`load_mesh`] picks the reader by the file's extension.
//!
//! | extension | reader |
//! | --- | --- |
//! | `.obj` | Wavefront OBJ, with the MTL material libraries it names (`scene::obj`) |
//! | `.ply` | Stanford PLY: `ascii`, `binary_little_endian` and `binary_big_endian` (`scene::ply`) |
//! | `.obj.gz`, `.ply.gz` | the same, gzip-compressed (decompressed in memory as they are read) |
//! | `.gltf`, `.glb` | glTF 2.0, its nodes' shared meshes kept as instances (`scene::gltf`) |
//!
//! Extensions are matched without regard to case (`BUNNY.OBJ.GZ` is fine). Errors, warnings
//! and the memory limit are the same for every reader (`mesh_file.rs`).

use std::path::Path;

use super::mesh_file::{LoadError, LoadedMesh, read_bytes, read_limit_bytes};
use super::{gltf, obj, ply};
use crate::file_bytes::ReadError;

/// The mesh formats, as chosen by the file name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Obj,
    Ply,
    Gltf,
}

/// The format and whether the file is gzip-compressed, from the file name's ending (any case).
fn format_of(path: &Path) -> Option<(Format, bool)> {
    let name = path.file_name()?.to_string_lossy().to_ascii_lowercase();
    let (stem, gzip) = match name.strip_suffix(".gz") {
        Some(stem) => (stem, true),
        None => (name.as_str(), false),
    };
    if stem.ends_with(".obj") {
        Some((Format::Obj, gzip))
    } else if stem.ends_with(".ply") {
        Some((Format::Ply, gzip))
    } else if !gzip && (stem.ends_with(".gltf") || stem.ends_with(".glb")) {
        Some((Format::Gltf, false))
    } else {
        None
    }
}

/// Loads the triangle mesh in `path`, choosing the reader by the extension (see the module
/// documentation for the formats, and `mesh_file.rs` for the error messages and the memory
/// limit).
///
/// A file that parses but has no triangles is an error ([`LoadError::NoTriangles`]).
pub fn load_mesh(path: &Path) -> Result<LoadedMesh, LoadError> {
    let metadata = std::fs::metadata(path)
        .map_err(|error| LoadError::File(ReadError::Read { path: path.into(), error }))?;
    if metadata.is_dir() {
        return Err(LoadError::Folder { path: path.into() });
    }
    let (format, gzip) =
        format_of(path).ok_or_else(|| LoadError::UnsupportedExtension { path: path.into() })?;
    let bytes = read_bytes(path, gzip, read_limit_bytes())?;
    let loaded = match format {
        Format::Obj => obj::parse_obj(path, &bytes)?,
        Format::Ply => ply::parse_ply(path, &bytes)?,
        Format::Gltf => gltf::parse_gltf(path, &bytes)?,
    };
    if loaded.triangle_count() == 0 {
        return Err(LoadError::NoTriangles { path: path.into() });
    }
    Ok(loaded)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn extensions_are_matched_in_any_case() {
        assert_eq!(format_of(Path::new("a/b.obj")), Some((Format::Obj, false)));
        assert_eq!(format_of(Path::new("B.OBJ.GZ")), Some((Format::Obj, true)));
        assert_eq!(format_of(Path::new("x.Ply")), Some((Format::Ply, false)));
        assert_eq!(format_of(Path::new("x.ply.Gz")), Some((Format::Ply, true)));
        assert_eq!(format_of(Path::new("x.gz")), None);
        assert_eq!(format_of(Path::new("x.stl")), None);
        assert_eq!(format_of(Path::new("obj")), None);
        assert_eq!(format_of(Path::new("")), None);
    }
}
