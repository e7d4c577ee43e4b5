//! What every mesh reader (OBJ, PLY, glTF; [`load_mesh`](super::load_mesh) picks one) gives
//! and says: the mesh as loaded ([`LoadedMesh`]), a place in a file ([`Location`]), why a load
//! failed ([`LoadError`]), and the file's bytes, read within a limit.
//!
//! **Errors** are one line each and name the file, the place in it and what was expected:
//! `bunny.ply: line 12: vertex 9: expected 3 values (x y z), found 2`, or for binary data
//! `dragon.ply: byte 1048: file ends inside face 17 (expected 3 indices)`. Line numbers start
//! at 1; byte offsets count from the start of the (decompressed) file.
//!
//! **Warnings** are problems that do not stop the load: a missing material library, faces with
//! fewer than 3 vertices, normals given for only some corners. They come back with the mesh in
//! [`LoadedMesh::warnings`], one line each, for the caller to show.
//!
//! **Memory.** The whole file is read into memory before parsing. A file (or a gzip stream once
//! decompressed) larger than [`read_limit_bytes`] is refused, so that a small gzip bomb cannot
//! exhaust the machine: the limit is half of the memory the system reports as available
//! (`MemAvailable` in `/proc/meminfo`), at most 16 GiB and at least 256 MiB; 16 GiB where the
//! system does not say. Half, because the parsed mesh needs room too.

use std::fmt;
use std::path::{Path, PathBuf};

use crate::file_bytes::ReadError;
pub use crate::file_bytes::read_limit_bytes;
pub use crate::mesh::InstancedMesh;
use crate::mesh::Mesh;

/// The file name endings [`load_mesh`](super::load_mesh) accepts, in any case.
pub const SUPPORTED_EXTENSIONS: &[&str] = &[".obj", ".obj.gz", ".ply", ".ply.gz", ".gltf", ".glb"];

/// A mesh as loaded, with the warnings the loader has for the caller.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LoadedMesh {
    /// The triangles drawn once, in file order, in the model's space; its `materials` are the
    /// file's, for these and for [`instanced`](Self::instanced).
    pub mesh: Mesh,
    /// Meshes the file draws in several places (glTF nodes that share a mesh), each once.
    pub instanced: Vec<InstancedMesh>,
    /// Problems that did not stop the load, one line each, each naming the file (and the line
    /// where there is one), e.g. `spider.obj: line 3: material library spider.mtl ignored: …`.
    pub warnings: Vec<String>,
    /// The file's camera (glTF), in the lab's frame.
    pub camera: Option<super::CameraSettings>,
    /// The file's lights (glTF's `KHR_lights_punctual`: point, spot and directional), in the
    /// lab's frame.
    pub lights: Vec<crate::light::Light>,
}

impl LoadedMesh {
    /// The number of triangles drawn, each copy of an instanced mesh counted.
    pub fn triangle_count(&self) -> usize {
        let copies = self.instanced.iter().map(|m| m.mesh.triangles.len() * m.transforms.len());
        self.mesh.triangles.len() + copies.sum::<usize>()
    }

    /// The number of triangles stored: an instanced mesh's once.
    pub fn stored_triangle_count(&self) -> usize {
        let instanced = self.instanced.iter().map(|m| m.mesh.triangles.len());
        self.mesh.triangles.len() + instanced.sum::<usize>()
    }

    /// Every triangle drawn, each copy placed, as one mesh in the model's space (with the
    /// file's materials): what a loader that does not instance gives. A mirroring copy has its
    /// corners turned so that its front side stays outside.
    pub fn flattened(&self) -> Mesh {
        let mut all = self.clone();
        all.flatten_within(usize::MAX);
        all.mesh
    }

    /// Copies instanced meshes into [`mesh`](Self::mesh), each copy placed (as
    /// [`flattened`](Self::flattened) does), the meshes whose copies beyond their first add the
    /// fewest triangles first, while those extra triangles total at most `budget`; the rest
    /// stay instanced. Returns how many meshes it copied. The triangles drawn are the same.
    pub fn flatten_within(&mut self, budget: usize) -> usize {
        let extra = |part: &InstancedMesh| {
            part.mesh.triangles.len().saturating_mul(part.transforms.len().saturating_sub(1))
        };
        let mut order: Vec<usize> = (0..self.instanced.len()).collect();
        order.sort_by_key(|&k| extra(&self.instanced[k]));
        let (mut spent, mut copy) = (0usize, vec![false; self.instanced.len()]);
        for k in order {
            let cost = extra(&self.instanced[k]);
            if cost > budget - spent {
                break;
            }
            spent += cost;
            copy[k] = true;
        }
        let parts = std::mem::take(&mut self.instanced);
        let mut copied = 0;
        for (part, copy) in parts.into_iter().zip(copy) {
            if copy {
                for transform in &part.transforms {
                    self.mesh.append_transformed(&part.mesh, transform);
                }
                copied += 1;
            } else {
                self.instanced.push(part);
            }
        }
        copied
    }

    /// The bounding box of every triangle drawn, or `None` without triangles.
    pub fn bounds(&self) -> Option<(glam::Vec3, glam::Vec3)> {
        let placed = self.instanced.iter().flat_map(|part| {
            part.transforms.iter().flat_map(move |t| {
                part.mesh
                    .triangles
                    .iter()
                    .flatten()
                    .map(move |&v| t.transform_point3(part.mesh.positions[v as usize]))
            })
        });
        let own = self.mesh.triangles.iter().flatten().map(|&v| self.mesh.positions[v as usize]);
        crate::mesh::bounds_of(own.chain(placed))
    }
}

/// A place in a file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Location {
    /// A line of a text file, counted from 1.
    Line(u64),
    /// A byte offset into a binary file (after decompression), counted from 0.
    Byte(u64),
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::Line(line) => write!(f, "line {line}"),
            Location::Byte(offset) => write!(f, "byte {offset}"),
        }
    }
}

/// Why a mesh file cannot be loaded. Every message is one line and starts with the file's path.
///
/// Variants that wrap an [`std::io::Error`] include its text in their message and do not report it
/// again as [`std::error::Error::source`], so that printing the chain (`{:#}` with `anyhow`)
/// says it once.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// The file cannot be read, is not valid gzip, or is larger than [`read_limit_bytes`].
    #[error(transparent)]
    File(#[from] ReadError),
    /// The path names a folder.
    #[error("{}: is a folder, not a mesh file", .path.display())]
    Folder {
        /// The folder.
        path: PathBuf,
    },
    /// The file name has none of the [`SUPPORTED_EXTENSIONS`].
    #[error(
        "{}: unknown mesh file type; the supported extensions are {} (in any case)",
        .path.display(),
        SUPPORTED_EXTENSIONS.join(", ")
    )]
    UnsupportedExtension {
        /// The file.
        path: PathBuf,
    },
    /// The content is malformed at a known place.
    #[error("{}: {location}: {message}", .path.display())]
    Syntax {
        /// The file (for a broken material library, the library).
        path: PathBuf,
        /// Where in the file.
        location: Location,
        /// What was wrong, or what was expected and what was found.
        message: String,
    },
    /// The content is unusable as a whole, e.g. more vertices than 32-bit indices can address.
    #[error("{}: {message}", .path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What was wrong.
        message: String,
    },
    /// The file is well formed but has no triangles.
    #[error("{}: no triangles (an empty mesh)", .path.display())]
    NoTriangles {
        /// The file.
        path: PathBuf,
    },
}

/// Reads the whole file, decompressing it if `gzip`, within [`read_limit_bytes`]: for other
/// readers of untrusted files (the ray-set files).
#[cfg(feature = "bench")]
pub(crate) fn read_file_bytes(path: &Path, gzip: bool) -> Result<Vec<u8>, LoadError> {
    read_bytes(path, gzip, read_limit_bytes())
}

/// Reads the whole file, decompressing it if `gzip`, refusing more than `limit` bytes.
pub(crate) fn read_bytes(path: &Path, gzip: bool, limit: u64) -> Result<Vec<u8>, LoadError> {
    Ok(crate::file_bytes::read_bytes(path, gzip, limit)?)
}

/// `text` quoted for an error message: escaped so that it stays on one line, and cut after
/// 40 characters.
pub(crate) fn quoted(text: &str) -> String {
    const MAX_CHARS: usize = 40;
    match text.char_indices().nth(MAX_CHARS) {
        Some((cut, _)) => format!("{:?}…", &text[..cut]),
        None => format!("{text:?}"),
    }
}

/// The name a mesh gets from its path: the file name.
pub(crate) fn mesh_name(path: &Path) -> String {
    path.file_name().map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into())
}

#[cfg(test)]
mod tests {
    use std::io::Write;

    use super::*;

    /// A mesh of `n` triangles (all in one plane, each its own corners).
    fn strip(n: usize) -> Mesh {
        let positions = (0..3 * n).map(|k| glam::Vec3::new(k as f32, (k % 3) as f32, 0.0));
        let triangles = (0..n as u32).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
        Mesh { positions: positions.collect(), triangles, ..Mesh::default() }
    }

    /// Copies' extra triangles, the cheapest first, within the budget: parts of 1, 2 and 3
    /// triangles drawn 11, 6 and 4 times add 10, 10 and 9 triangles beyond their first copies, one
    /// of 7 drawn once none.
    #[test]
    fn the_cheapest_instanced_meshes_are_copied_within_the_budget() {
        let shift = |k: usize| glam::Affine3A::from_translation(glam::Vec3::Z * k as f32);
        let part = |n, copies| InstancedMesh {
            mesh: strip(n),
            transforms: (1..=copies).map(shift).collect(),
        };
        let loaded = LoadedMesh {
            mesh: strip(5),
            instanced: vec![part(1, 11), part(2, 6), part(3, 4), part(7, 1)],
            ..LoadedMesh::default()
        };
        // Every triangle drawn, each copy moved by its transform by hand, as bits, sorted.
        let drawn_corners = |l: &LoadedMesh| {
            let mut corners: Vec<[u32; 9]> = l.mesh.triangle_vertices().map(bits).collect();
            for part in &l.instanced {
                for t in &part.transforms {
                    let moved =
                        part.mesh.triangle_vertices().map(|c| c.map(|v| t.transform_point3(v)));
                    corners.extend(moved.map(bits));
                }
            }
            corners.sort();
            corners
        };
        let everything = drawn_corners(&loaded);
        let drawn =
            |l: &LoadedMesh| (l.triangle_count(), l.instanced.len(), l.mesh.triangles.len());
        for (budget, copied, kept, own) in [
            (0, 1, 3, 5 + 7),
            (8, 1, 3, 5 + 7),
            (9, 2, 2, 5 + 7 + 12),
            (18, 2, 2, 5 + 7 + 12),
            (19, 3, 1, 5 + 7 + 12 + 11),
            (28, 3, 1, 5 + 7 + 12 + 11),
            (29, 4, 0, 47),
            (usize::MAX, 4, 0, 47),
        ] {
            let mut l = loaded.clone();
            assert_eq!(l.flatten_within(budget), copied, "budget {budget}");
            assert_eq!(drawn(&l), (47, kept, own), "budget {budget}");
            // The copied triangles and the kept copies draw every triangle (in another order).
            assert_eq!(drawn_corners(&l), everything, "budget {budget}");
        }
    }

    /// A triangle's corners, as bits.
    fn bits(t: [glam::Vec3; 3]) -> [u32; 9] {
        let f = t.map(|v| v.to_array()).concat();
        std::array::from_fn(|k| f[k].to_bits())
    }

    #[test]
    fn locations_read_naturally() {
        assert_eq!(Location::Line(12).to_string(), "line 12");
        assert_eq!(Location::Byte(1048).to_string(), "byte 1048");
    }

    #[test]
    fn quoting_keeps_one_line_and_cuts_long_text() {
        assert_eq!(quoted("a\nb"), r#""a\nb""#);
        let long = "é".repeat(50);
        assert_eq!(quoted(&long), format!("{:?}…", "é".repeat(40)));
    }

    #[test]
    fn the_read_limit_is_within_its_bounds() {
        let limit = read_limit_bytes();
        assert!((256 << 20..=16 << 30).contains(&limit), "{limit}");
    }

    fn gzip(bytes: &[u8]) -> Vec<u8> {
        let mut encoder = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        encoder.write_all(bytes).unwrap();
        encoder.finish().unwrap()
    }

    #[test]
    fn a_gzip_bomb_stops_at_the_limit() {
        let folder = tempfile::tempdir().unwrap();
        let path = folder.path().join("bomb.obj.gz");
        std::fs::write(&path, gzip(&vec![b'#'; 1 << 20])).unwrap();
        let error = read_bytes(&path, true, 1000).unwrap_err();
        assert!(matches!(
            error,
            LoadError::File(ReadError::TooLarge { limit_bytes: 1000, decompressed: true, .. })
        ));
        assert!(error.to_string().contains("larger than 1000 bytes once decompressed"), "{error}");
        assert_eq!(read_bytes(&path, true, 1 << 20).unwrap().len(), 1 << 20);
        let plain = folder.path().join("big.obj");
        std::fs::write(&plain, [b'#'; 1001]).unwrap();
        let error = read_bytes(&plain, false, 1000).unwrap_err();
        assert!(
            matches!(error, LoadError::File(ReadError::TooLarge { decompressed: false, .. })),
            "{error}"
        );
    }

    #[test]
    fn concatenated_gzip_members_are_read_whole() {
        let folder = tempfile::tempdir().unwrap();
        let path = folder.path().join("two.obj.gz");
        std::fs::write(&path, [gzip(b"first\n"), gzip(b"second\n")].concat()).unwrap();
        assert_eq!(read_bytes(&path, true, 1000).unwrap(), b"first\nsecond\n");
    }

    #[test]
    fn corrupt_or_cut_gzip_is_a_gzip_error() {
        let folder = tempfile::tempdir().unwrap();
        let whole = gzip(&b"v 0 0 0\n".repeat(1000));
        for (name, bytes) in [
            ("plain.obj.gz", b"v 0 0 0\n".to_vec()),
            ("cut.obj.gz", whole[..whole.len() / 2].to_vec()),
            ("no-trailer.obj.gz", whole[..whole.len() - 4].to_vec()),
        ] {
            let path = folder.path().join(name);
            std::fs::write(&path, bytes).unwrap();
            let error = read_bytes(&path, true, 1 << 20).unwrap_err();
            assert!(matches!(error, LoadError::File(ReadError::Gzip { .. })), "{name}: {error}");
            let message = error.to_string();
            assert!(message.contains(name) && !message.contains('\n'), "{message}");
        }
    }
}
