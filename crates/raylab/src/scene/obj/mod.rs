//! Wavefront OBJ, with the MTL material libraries it names.
//!
//! **What it reads.** Positions (`v x y z`, with an optional weight `w` that divides them;
//! vertex colours `v x y z r g b` are dropped), texture coordinates (`vt u v`), normals
//! (`vn x y z`) and faces (`f v`, `f v/vt`, `f v//vn`, `f v/vt/vn`, indices from 1 or negative
//! for "counted back from the last one defined"). Polygons are fan-triangulated as
//! `(p0, pk, pk+1)` and triangles keep file order across `o`, `g` and `usemtl`. Faces with
//! fewer than 3 corners and polylines (`l`) are skipped with a warning. Normals and texture
//! coordinates are kept only when every face corner has them (a warning says otherwise).
//!
//! **Materials.** Each `mtllib` is read relative to the OBJ's folder (a Windows path such as
//! `.\scene.mtl` works too, and so does a list of names on one line). From an MTL file we keep
//! each material's name, `Kd` (diffuse, [`MeshMaterial::DEFAULT_DIFFUSE`] if absent) and `Ke`
//! (emission, zero if absent); `Kd r` alone means grey, as the MTL specification allows.
//! A library that cannot be read is a warning: the surfaces that name its materials get the
//! default grey. A library that is malformed is an error naming the library and its line.
//! `usemtl` with a name no library defines is a warning.
//!
//! **How.** Parsing is done by the `tobj` crate, fed by `ObjLines` (`obj/lines.rs`), a reader that hands it
//! the file one line at a time. That reader counts lines, so that tobj's errors (which carry no
//! position) can name the line; it checks every face's indices against what is defined before
//! it (tobj checks them only at the end of a group, without saying where, and can overflow
//! on hostile indices); it hides what tobj would misread (it turns `l` polylines into
//! triangles, and partly coloured vertices into an error); and it hands lines in other text
//! encodings on as UTF-8 with replacement characters. tobj keeps each group's triangles in
//! file order, groups in file order, and triangulates polygons as fans from their first
//! corner, which is our convention; it numbers vertices per group in order of first use, so a
//! vertex shared by two groups appears twice in [`Mesh::positions`] and unused vertices not at
//! all. The MTL reader is ours: tobj's panics on `Kd 0.5`.
//!
//! NaN or infinite values are errors naming the line of the offending `v`, `vt` or `vn`; that
//! line is found by scanning the file again, which costs nothing unless the file is bad.

use std::cell::{Cell, RefCell};
use std::collections::HashSet;
use std::path::Path;

use glam::{Vec2, Vec3};

mod libraries;
mod lines;

pub(crate) use libraries::ReadLibrary;
use libraries::Shared;
use lines::ObjLines;

use super::mesh_file::{LoadError, LoadedMesh, Location, mesh_name, quoted, read_bytes};
use super::mtl::TextureFiles;
use crate::mesh::{CornerAttribute, Mesh};

/// The largest material library we read. Real ones are a few kilobytes.
const LIBRARY_LIMIT_BYTES: u64 = 256 << 20;

/// At most this many warnings about unknown material names, then a count.
const MAX_NAMED_WARNINGS: usize = 5;

/// Reads the OBJ file `text`, found at `path`, with the material libraries beside it.
pub(crate) fn parse_obj(path: &Path, text: &[u8]) -> Result<LoadedMesh, LoadError> {
    let folder = path.parent().unwrap_or(Path::new(""));
    parse_obj_with(path, text, &|name| {
        let library = folder.join(name);
        read_bytes(&library, false, LIBRARY_LIMIT_BYTES).map(|bytes| (library, bytes))
    })
}

/// Reads the OBJ file `text` (named `path` in messages), reading material libraries with
/// `read_library`.
pub(crate) fn parse_obj_with(
    path: &Path,
    text: &[u8],
    read_library: &ReadLibrary,
) -> Result<LoadedMesh, LoadError> {
    let shared = Shared {
        obj_path: path,
        read_library,
        line: Cell::new(0),
        failure: RefCell::new(None),
        materials: RefCell::new(Vec::new()),
        warnings: RefCell::new(Vec::new()),
        textures: RefCell::new(TextureFiles::default()),
        library_missing: Cell::new(false),
    };
    let mut lines = ObjLines::new(path, text, &shared);
    // The update fills the fields that tobj's optional features add (`merging`, `reordering`).
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let result = tobj::load_obj_buf(&mut lines, &options, |library| shared.load_library(library));
    if let Some(failure) = shared.failure.take() {
        return Err(failure);
    }
    let (models, _) = result.map_err(|error| LoadError::Syntax {
        path: path.into(),
        location: Location::Line(lines.line),
        message: format!("{}, found {}", describe(error), quoted(lines.last_line_text().trim())),
    })?;

    let mut warnings = shared.warnings.take();
    let materials = shared.materials.take();
    let mut keep_normals = lines.corners_with_normal == lines.corners;
    let mut keep_uvs = lines.corners_with_uv == lines.corners;
    for (kept, with, what) in [
        (keep_normals, lines.corners_with_normal, "normals"),
        (keep_uvs, lines.corners_with_uv, "texture coordinates"),
    ] {
        if !kept && with > 0 {
            warnings.push(format!(
                "{what} ignored: {} of the {} face corners have none",
                lines.corners - with,
                lines.corners
            ));
        }
    }
    let mut mesh = Mesh { name: mesh_name(path), ..Mesh::default() };
    let mut normals = CornerAttribute::<Vec3>::default();
    let mut uvs = CornerAttribute::<Vec2>::default();
    // The index of the first value appended, if every value appended has a 32-bit index.
    let first_index = |before: usize, after: usize, what: &str| match u32::try_from(after) {
        Ok(_) => Ok(before as u32),
        Err(_) => Err(LoadError::Invalid {
            path: path.into(),
            message: format!("more {what} than 32-bit indices can address"),
        }),
    };
    for model in models {
        // tobj numbers each group's values from 0, so its indices are below the group's count
        // and `first + index` below the total, which fits a u32.
        let group = model.mesh;
        let before = mesh.positions.len();
        mesh.positions.extend(group.positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])));
        let first = first_index(before, mesh.positions.len(), "vertices")?;
        let corners = |indices: &[u32], first: u32| -> Vec<[u32; 3]> {
            indices.chunks_exact(3).map(|t| [first + t[0], first + t[1], first + t[2]]).collect()
        };
        let triangles = corners(&group.indices, first);
        // tobj gives each corner an attribute index when every corner has one; anything else
        // would be a tobj we do not know, and dropping the attribute is the safe answer.
        keep_normals &= group.normal_indices.len() == group.indices.len();
        keep_uvs &= group.texcoord_indices.len() == group.indices.len();
        if keep_normals {
            let before = normals.values.len();
            normals
                .values
                .extend(group.normals.chunks_exact(3).map(|n| Vec3::new(n[0], n[1], n[2])));
            let first = first_index(before, normals.values.len(), "normals")?;
            normals.triangles.extend(corners(&group.normal_indices, first));
        }
        if keep_uvs {
            let before = uvs.values.len();
            uvs.values.extend(group.texcoords.chunks_exact(2).map(|t| Vec2::new(t[0], t[1])));
            let first = first_index(before, uvs.values.len(), "texture coordinates")?;
            uvs.triangles.extend(corners(&group.texcoord_indices, first));
        }
        let material = group.material_id.filter(|&id| id < materials.len()).map(|id| id as u32);
        mesh.material_ids.extend(std::iter::repeat_n(material, triangles.len()));
        mesh.triangles.extend(triangles);
    }
    if keep_normals && !mesh.triangles.is_empty() {
        mesh.normals = Some(normals);
    }
    if keep_uvs && !mesh.triangles.is_empty() {
        mesh.uvs = Some(uvs);
    }
    if materials.is_empty() {
        mesh.material_ids.clear();
    }
    check_finite(path, text, &mesh)?;

    if !shared.library_missing.get() {
        let defined: HashSet<&str> = materials.iter().map(|m| m.name.as_str()).collect();
        let unknown: Vec<&(String, u64)> = lines
            .material_uses
            .iter()
            .filter(|(name, _)| !defined.contains(name.as_str()))
            .collect();
        for (name, line) in unknown.iter().take(MAX_NAMED_WARNINGS) {
            warnings.push(format!(
                "line {line}: usemtl {}: no material library defines it; the surfaces get the default grey",
                quoted(name)
            ));
        }
        if unknown.len() > MAX_NAMED_WARNINGS {
            warnings.push(format!(
                "{} more unknown material names",
                unknown.len() - MAX_NAMED_WARNINGS
            ));
        }
    }
    if lines.short_faces > 0 {
        warnings.push(format!("skipped {} faces with fewer than 3 corners", lines.short_faces));
    }
    if lines.polylines > 0 {
        warnings.push(format!("skipped {} polylines (`l`)", lines.polylines));
    }
    mesh.materials = materials;
    let warnings = warnings.into_iter().map(|w| format!("{}: {w}", path.display())).collect();
    Ok(LoadedMesh { mesh, warnings, ..LoadedMesh::default() })
}

/// What tobj's error means, as "expected …".
fn describe(error: tobj::LoadError) -> String {
    use tobj::LoadError as E;
    match error {
        E::PositionParseError => {
            "expected `v x y z` with 3 numbers (and an optional weight)".into()
        }
        E::ScalingByZeroError => "the vertex weight w is 0".into(),
        E::ColorParseError => "expected `v x y z`, `v x y z w` or `v x y z r g b`".into(),
        E::NormalParseError => "expected `vn x y z` with 3 numbers".into(),
        E::TexcoordParseError => "expected `vt u v` with 2 numbers".into(),
        E::FaceParseError => "expected face corners like 1, 1/2, 1//3 or 1/2/3".into(),
        E::MaterialParseError => "expected `usemtl <name>`".into(),
        other => format!("cannot read this line ({other})"),
    }
}

/// Refuses NaN and infinite positions, normals and texture coordinates, naming the line.
fn check_finite(path: &Path, text: &[u8], mesh: &Mesh) -> Result<(), LoadError> {
    let bad_position =
        mesh.positions.iter().find(|p| !p.is_finite()).map(|p| p.to_array().to_vec());
    let bad_normal = mesh.normals.as_ref().and_then(|n| n.values.iter().find(|n| !n.is_finite()));
    let bad_uv = mesh.uvs.as_ref().and_then(|t| t.values.iter().find(|t| !t.is_finite()));
    let (keyword, what, bad) = match (bad_position, bad_normal, bad_uv) {
        (Some(p), _, _) => ("v", "vertex", p),
        (None, Some(n), _) => ("vn", "normal", n.to_array().to_vec()),
        (None, None, Some(t)) => ("vt", "texture coordinate", t.to_array().to_vec()),
        (None, None, None) => return Ok(()),
    };
    let show = |values: &[f32]| values.iter().map(|v| v.to_string()).collect::<Vec<_>>().join(", ");
    let (line, ordinal, values) =
        find_non_finite(text, keyword, &bad).ok_or_else(|| LoadError::Invalid {
            path: path.into(),
            message: format!("a {what} is not finite ({})", show(&bad)),
        })?;
    Err(LoadError::Syntax {
        path: path.into(),
        location: Location::Line(line),
        message: format!("{what} {ordinal} is not finite ({})", show(&values)),
    })
}

/// The line number, ordinal and values of the `keyword` line that gives `bad` (bit for bit),
/// or else of the first one with a value that is not finite.
fn find_non_finite(text: &[u8], keyword: &str, bad: &[f32]) -> Option<(u64, usize, Vec<f32>)> {
    let mut first = None;
    let mut ordinal = 0;
    for (index, raw) in text.split(|&b| b == b'\n').enumerate() {
        let line = String::from_utf8_lossy(raw);
        let mut words = line.split_whitespace();
        if words.next() != Some(keyword) {
            continue;
        }
        ordinal += 1;
        let numbers: Vec<f32> = words.map_while(|w| w.parse().ok()).collect();
        let mut values: Vec<f32> = numbers.iter().take(bad.len()).copied().collect();
        // As tobj does: a fourth number on a `v` line is a weight that divides the others.
        if let (true, &[_, _, _, w]) = (keyword == "v", numbers.as_slice()) {
            values.iter_mut().for_each(|v| *v /= w);
        }
        if values.iter().all(|v| v.is_finite()) {
            continue;
        }
        let found = (index as u64 + 1, ordinal, values);
        let same = found.2.len() == bad.len()
            && found.2.iter().zip(bad).all(|(a, b)| a.to_bits() == b.to_bits());
        if same {
            return Some(found);
        }
        first.get_or_insert(found);
    }
    first
}

#[cfg(test)]
mod tests;
