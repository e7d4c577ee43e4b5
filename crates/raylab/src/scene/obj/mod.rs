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
//! **How.** Parsing is done by the `tobj` crate, fed by [`ObjLines`], a reader that hands it
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

use std::borrow::Cow;
use std::cell::{Cell, RefCell};
use std::collections::HashSet;
use std::io::{self, BufRead, Read};
use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};

use super::mesh_file::{LoadError, LoadedMesh, Location, mesh_name, quoted, read_bytes};
use super::mtl::{TextureFiles, parse_mtl};
use crate::mesh::{CornerAttribute, Mesh, MeshMaterial};

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

/// Finds and reads the material library that an `mtllib` line names: its path and content.
pub(crate) type ReadLibrary<'a> = dyn Fn(&str) -> Result<(PathBuf, Vec<u8>), LoadError> + 'a;

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

/// State shared by the line reader and the material library loader, which tobj holds apart.
struct Shared<'a> {
    /// The OBJ file, for messages.
    obj_path: &'a Path,
    read_library: &'a ReadLibrary<'a>,
    /// The line the reader is on.
    line: Cell<u64>,
    /// The first error found by us rather than by tobj; the reader stops tobj once it is set.
    failure: RefCell<Option<LoadError>>,
    /// Every library's materials, in the order tobj numbers them.
    materials: RefCell<Vec<MeshMaterial>>,
    warnings: RefCell<Vec<String>>,
    /// The texture files read so far.
    textures: RefCell<TextureFiles>,
    /// Whether some library could not be read (then unknown material names are expected).
    library_missing: Cell<bool>,
}

impl Shared<'_> {
    /// tobj's material loader: reads the libraries that an `mtllib` line names.
    fn load_library(&self, requested: &Path) -> tobj::MTLLoadResult {
        let mut result: tobj::MTLLoadResult = Ok((Vec::new(), Default::default()));
        let requested = requested.to_string_lossy();
        let line = self.line.get();
        let ignored = |error: LoadError| {
            self.library_missing.set(true);
            self.warnings.borrow_mut().push(format!(
                "line {line}: material library ignored, the surfaces get the default grey: {error}"
            ));
        };
        // A name may contain spaces; if no file has the whole name, it is a list of names.
        match self.read_one(&requested) {
            Ok(library) => self.add_library(library, &mut result),
            Err(error) if requested.split_whitespace().nth(1).is_none() => ignored(error),
            Err(_) => {
                for name in requested.split_whitespace() {
                    match self.read_one(name) {
                        Ok(library) => self.add_library(library, &mut result),
                        Err(error) => ignored(error),
                    }
                }
            }
        }
        result
    }

    /// Reads one library, trying `\` as a folder separator if the name as written is not found.
    fn read_one(&self, name: &str) -> Result<(PathBuf, Vec<u8>), LoadError> {
        if name.is_empty() {
            return Err(LoadError::Invalid {
                path: self.obj_path.into(),
                message: "`mtllib` names no file".into(),
            });
        }
        match (self.read_library)(name) {
            Err(error) if name.contains('\\') => {
                (self.read_library)(&name.replace('\\', "/")).map_err(|_| error)
            }
            found => found,
        }
    }

    fn add_library(&self, (path, bytes): (PathBuf, Vec<u8>), result: &mut tobj::MTLLoadResult) {
        match parse_mtl(&bytes) {
            Ok((library, ignored)) => {
                for (line, message) in ignored {
                    self.warnings
                        .borrow_mut()
                        .push(format!("{}:{line}: ignored: {message}", path.display()));
                }
                let mut materials = Vec::with_capacity(library.len());
                for (mut material, texture) in library {
                    if let Some(line) = texture {
                        match self.textures.borrow_mut().load(&path, &line) {
                            Ok(texture) => material.textures.base_color = Some(texture),
                            Err(error) => self.warnings.borrow_mut().push(format!(
                                "{}:{}: the texture of material {} is ignored: {error}",
                                path.display(),
                                line.line,
                                quoted(&material.name)
                            )),
                        }
                    }
                    materials.push(material);
                }
                if let Ok((list, names)) = result {
                    for material in &materials {
                        names.insert(material.name.clone(), list.len());
                        list.push(tobj::Material {
                            name: material.name.clone(),
                            ..Default::default()
                        });
                    }
                }
                self.materials.borrow_mut().extend(materials);
            }
            Err((line, message)) => {
                let error = LoadError::Syntax { path, location: Location::Line(line), message };
                self.failure.borrow_mut().get_or_insert(error);
            }
        }
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

/// What the reader hands to tobj for a line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Serving {
    /// The line as it is in the file.
    Text,
    /// The line as rewritten into the scratch buffer.
    Scratch,
    /// Nothing: the end of the file, or a line tobj would ignore or misread.
    Nothing,
}

/// The OBJ file, handed to tobj one line at a time (see the module documentation for why).
struct ObjLines<'a> {
    path: &'a Path,
    text: &'a [u8],
    shared: &'a Shared<'a>,
    /// Where the next line starts.
    next_line: usize,
    /// The number of the current line.
    line: u64,
    /// The current line's bytes in `text` (at the end of the file, still the last line's).
    current: (usize, usize),
    /// What tobj is given for the current line.
    serving: Serving,
    scratch: Vec<u8>,
    /// How much of the current line tobj has consumed.
    consumed: usize,
    /// How many `v`, `vt` and `vn` lines came so far.
    positions: usize,
    texcoords: usize,
    normals: usize,
    /// Corners of the faces kept, and how many of them have a texture coordinate or normal.
    corners: u64,
    corners_with_uv: u64,
    corners_with_normal: u64,
    short_faces: u64,
    polylines: u64,
    /// Each name `usemtl` uses, with the first line that uses it.
    material_uses: Vec<(String, u64)>,
    material_names: HashSet<String>,
}

impl<'a> ObjLines<'a> {
    fn new(path: &'a Path, text: &'a [u8], shared: &'a Shared<'a>) -> Self {
        ObjLines {
            path,
            text,
            shared,
            next_line: 0,
            line: 0,
            current: (0, 0),
            serving: Serving::Nothing,
            scratch: Vec::new(),
            consumed: 0,
            positions: 0,
            texcoords: 0,
            normals: 0,
            corners: 0,
            corners_with_uv: 0,
            corners_with_normal: 0,
            short_faces: 0,
            polylines: 0,
            material_uses: Vec::new(),
            material_names: HashSet::new(),
        }
    }

    fn served(&self) -> &[u8] {
        match self.serving {
            Serving::Text => &self.text[self.current.0..self.current.1],
            Serving::Scratch => &self.scratch,
            Serving::Nothing => &[],
        }
    }

    /// The current line of the file, as text.
    fn last_line_text(&self) -> Cow<'a, str> {
        String::from_utf8_lossy(&self.text[self.current.0..self.current.1])
    }

    /// Moves to the next line that tobj should see, or to the end of the file.
    fn advance(&mut self) -> io::Result<()> {
        loop {
            self.consumed = 0;
            self.serving = Serving::Nothing;
            if self.shared.failure.borrow().is_some() {
                return Err(io::Error::other("stopped"));
            }
            let text = self.text;
            let Some(rest) = text.get(self.next_line..).filter(|rest| !rest.is_empty()) else {
                return Ok(());
            };
            let length = rest.iter().position(|&b| b == b'\n').map_or(rest.len(), |n| n + 1);
            self.current = (self.next_line, self.next_line + length);
            self.next_line += length;
            self.line += 1;
            self.shared.line.set(self.line);
            match self.inspect(&rest[..length]) {
                Ok(Serving::Nothing) => continue,
                Ok(serving) => {
                    self.serving = serving;
                    return Ok(());
                }
                Err(message) => {
                    let location = Location::Line(self.line);
                    let error = LoadError::Syntax { path: self.path.into(), location, message };
                    self.shared.failure.borrow_mut().get_or_insert(error);
                    return Err(io::Error::other("stopped"));
                }
            }
        }
    }

    /// Decides what tobj gets for `raw`, checking faces and counting what is defined.
    fn inspect(&mut self, raw: &[u8]) -> Result<Serving, String> {
        let line = match std::str::from_utf8(raw) {
            Ok(line) => Cow::Borrowed(line),
            Err(_) => String::from_utf8_lossy(raw),
        };
        let mut words = line.split_whitespace();
        let serve = match words.next() {
            None => return Ok(Serving::Nothing),
            Some(word) if word.starts_with('#') => return Ok(Serving::Nothing),
            Some("v") => {
                self.positions += 1;
                // Seven words need six separators; counting bytes first is cheaper than splitting.
                let separators = raw.iter().filter(|b| b.is_ascii_whitespace()).count();
                if (separators >= 6 || !raw.is_ascii()) && words.clone().count() == 6 {
                    // x y z r g b: tobj wants colours on every vertex or none; we need none.
                    let xyz: Vec<&str> = words.take(3).collect();
                    self.scratch = format!("v {}\n", xyz.join(" ")).into_bytes();
                    return Ok(Serving::Scratch);
                }
                Serving::Text
            }
            Some("vt") => {
                self.texcoords += 1;
                Serving::Text
            }
            Some("vn") => {
                self.normals += 1;
                Serving::Text
            }
            Some("f") => match self.check_face(words)? {
                0 => return Err("expected face corners after `f`".into()),
                1 | 2 => {
                    self.short_faces += 1;
                    return Ok(Serving::Nothing);
                }
                _ => Serving::Text,
            },
            Some("l") => {
                self.polylines += 1;
                return Ok(Serving::Nothing);
            }
            Some("usemtl") => {
                // The name as tobj reads it: everything after the first space.
                let name = line.split_once(' ').map_or("", |(_, rest)| rest).trim();
                if !name.is_empty() && !self.material_names.contains(name) {
                    self.material_names.insert(name.to_string());
                    self.material_uses.push((name.to_string(), self.line));
                }
                Serving::Text
            }
            Some(_) => Serving::Text,
        };
        if let Cow::Owned(line) = line {
            self.scratch = line.into_bytes();
            return Ok(Serving::Scratch);
        }
        Ok(serve)
    }

    /// Checks a face's corners against what is defined so far; returns how many there are.
    fn check_face<'w>(&mut self, corners: impl Iterator<Item = &'w str>) -> Result<u64, String> {
        let (mut count, mut with_uv, mut with_normal) = (0, 0, 0);
        for corner in corners {
            count += 1;
            let mut parts = corner.split('/');
            let vertex = parts.next().unwrap_or("");
            if vertex.is_empty() {
                return Err(format!("face corner {} has no vertex index", quoted(corner)));
            }
            check_index(vertex, self.positions, ("vertex", "vertices"), corner)?;
            if let Some(uv) = parts.next().filter(|t| !t.is_empty()) {
                check_index(
                    uv,
                    self.texcoords,
                    ("texture coordinate", "texture coordinates"),
                    corner,
                )?;
                with_uv += 1;
            }
            if let Some(normal) = parts.next().filter(|n| !n.is_empty()) {
                check_index(normal, self.normals, ("normal", "normals"), corner)?;
                with_normal += 1;
            }
            if parts.any(|p| !p.is_empty()) {
                return Err(format!(
                    "expected a face corner like 1, 1/2, 1//3 or 1/2/3, found {}",
                    quoted(corner)
                ));
            }
        }
        if count >= 3 {
            self.corners += count;
            self.corners_with_uv += with_uv;
            self.corners_with_normal += with_normal;
        }
        Ok(count)
    }
}

/// Checks a face index: from 1 up to `defined`, or from -1 down to `-defined`.
fn check_index(
    text: &str,
    defined: usize,
    (what, plural): (&str, &str),
    corner: &str,
) -> Result<(), String> {
    let Ok(index) = text.parse::<isize>() else {
        return Err(format!(
            "expected a {what} index in face corner {}, found {}",
            quoted(corner),
            quoted(text)
        ));
    };
    if index == 0 {
        Err(format!("{what} index 0 in face corner {}: OBJ indices start at 1", quoted(corner)))
    } else if index > 0 && index.unsigned_abs() > defined {
        Err(format!(
            "{what} index {index} is out of range: {defined} {plural} are defined before this line"
        ))
    } else if index < 0 && index.unsigned_abs() > defined {
        Err(format!(
            "relative {what} index {index} reaches before the first one: {defined} {plural} are \
             defined before this line"
        ))
    } else {
        Ok(())
    }
}

impl Read for ObjLines<'_> {
    fn read(&mut self, buffer: &mut [u8]) -> io::Result<usize> {
        let available = self.fill_buf()?;
        let n = available.len().min(buffer.len());
        buffer[..n].copy_from_slice(&available[..n]);
        self.consume(n);
        Ok(n)
    }
}

impl BufRead for ObjLines<'_> {
    fn fill_buf(&mut self) -> io::Result<&[u8]> {
        if self.consumed >= self.served().len() {
            self.advance()?;
        }
        let served = self.served();
        Ok(&served[self.consumed.min(served.len())..])
    }

    fn consume(&mut self, amount: usize) {
        self.consumed += amount;
    }
}

#[cfg(test)]
mod tests;
