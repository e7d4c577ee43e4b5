//! PLY, the Stanford polygon file format: our own reader for `ascii 1.0`,
//! `binary_little_endian 1.0` and `binary_big_endian 1.0`.
//!
//! **What it reads.** The header's `format`, `element`, `property` (scalar or `list`),
//! `comment` and `obj_info` lines; the scalar types `char uchar short ushort int uint float
//! double` and their aliases `int8 uint8 int16 uint16 int32 uint32 float32 float64`. From the
//! `vertex` element: `x y z` (required), `nx ny nz` (optional, all three) and texture
//! coordinates `u v`, `s t`, `texture_u texture_v` or `texture_s texture_t` (optional, the first
//! pair present). From the `face` element: the list `vertex_indices` (or `vertex_index`), each
//! polygon fan-triangulated as `(p0, pk, pk+1)` in file order. Everything else — other
//! elements, other properties, lists included — is skipped. Normals and texture coordinates are
//! per vertex, so their index triples equal the position triples.
//!
//! **Why our own reader.** The format is small, and we want what general readers do not give:
//! errors that say where (the line of an ASCII file, the byte offset in a binary one) and what
//! was expected, and a file that cannot hold what its header declares (say, `element vertex
//! 4000000000` in a 200-byte file) rejected before anything is allocated. Every count from the
//! header is checked against the bytes that follow it: at least one byte per binary scalar
//! (a list's count included), at least two per ASCII value (a digit and a separator).
//!
//! **Strictness.** In ASCII files each element is one line (blank lines are skipped) and must
//! hold exactly its values; integers must fit their declared type. Indices out of range,
//! NaN or infinite values and data cut short are errors. Faces with fewer than 3 vertices and
//! data after the last element are skipped with a warning.

use std::path::Path;

use glam::{Vec2, Vec3};

mod ascii;
mod binary;
mod failure;
mod header;
mod reader;

use super::mesh_file::{LoadError, LoadedMesh, Location, mesh_name};
use crate::mesh::{CornerAttribute, Mesh};
use ascii::AsciiReader;
use binary::BinaryReader;
use failure::{Failure, fail};
use header::{
    Encoding, Header, Kind, Property, Scalar, Value, check_declared_counts, parse_header,
};
use reader::{Expected, Place, Reader};

/// Reads the PLY file `bytes` (named `path` in messages).
pub(crate) fn parse_ply(path: &Path, bytes: &[u8]) -> Result<LoadedMesh, LoadError> {
    let attach = |failure: Failure| LoadError::Syntax {
        path: path.into(),
        location: failure.location,
        message: failure.message,
    };
    let header = parse_header(bytes).map_err(attach)?;
    let data_bytes = bytes.len().saturating_sub(header.data_start) as u64;
    check_declared_counts(&header, data_bytes).map_err(attach)?;
    let layout = Layout::new(&header).map_err(attach)?;
    let mut builder = Builder::new(&header, &layout, data_bytes);
    let trailing = match header.encoding {
        Encoding::Ascii => {
            let mut reader = AsciiReader::new(bytes, header.data_start, header.lines);
            read_elements(&mut reader, &header, &layout, &mut builder).map_err(attach)?;
            reader
                .trailing_line()
                .map(|line| format!("line {line}: ignored text after the last element"))
        }
        Encoding::BinaryLittleEndian => {
            let mut reader =
                BinaryReader::<false> { bytes, position: header.data_start, value_start: 0 };
            read_elements(&mut reader, &header, &layout, &mut builder).map_err(attach)?;
            reader.trailing_bytes()
        }
        Encoding::BinaryBigEndian => {
            let mut reader =
                BinaryReader::<true> { bytes, position: header.data_start, value_start: 0 };
            read_elements(&mut reader, &header, &layout, &mut builder).map_err(attach)?;
            reader.trailing_bytes()
        }
    };
    let mut warnings = layout.warnings;
    warnings.extend(trailing);
    if builder.short_faces > 0 {
        warnings.push(format!("skipped {} faces with fewer than 3 vertices", builder.short_faces));
    }
    let warnings = warnings.into_iter().map(|w| format!("{}: {w}", path.display())).collect();
    let mesh = builder.finish(mesh_name(path));
    Ok(LoadedMesh { mesh, warnings, ..LoadedMesh::default() })
}

/// What a property is used for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Role {
    Skip,
    Position(usize),
    Normal(usize),
    Uv(usize),
    Indices,
}

/// Which element is which, and what each of their properties is used for.
struct Layout {
    vertex: usize,
    vertex_roles: Vec<Role>,
    has_normals: bool,
    has_uvs: bool,
    face: Option<usize>,
    face_roles: Vec<Role>,
    warnings: Vec<String>,
}

impl Layout {
    fn new(header: &Header) -> Result<Layout, Failure> {
        let mut warnings = Vec::new();
        let Some(vertex) = header.elements.iter().position(|e| e.name == "vertex") else {
            return fail(Location::Line(header.lines), "the header declares no `element vertex`");
        };
        let element = &header.elements[vertex];
        let at = Location::Line(element.line);
        if element.count > u64::from(u32::MAX) {
            return fail(
                at,
                format!("{} vertices: more than 32-bit indices can address", element.count),
            );
        }
        let find_scalar = |name: &str| -> Result<Option<usize>, Failure> {
            match element.properties.iter().position(|p| p.name == name) {
                Some(i) if matches!(element.properties[i].kind, Kind::List { .. }) => {
                    fail(at, format!("vertex property {name} must be a scalar, not a list"))
                }
                found => Ok(found),
            }
        };
        let mut vertex_roles = vec![Role::Skip; element.properties.len()];
        for (axis, name) in ["x", "y", "z"].into_iter().enumerate() {
            let Some(i) = find_scalar(name)? else {
                return fail(at, format!("element vertex has no property {name}"));
            };
            vertex_roles[i] = Role::Position(axis);
        }
        let normal = [find_scalar("nx")?, find_scalar("ny")?, find_scalar("nz")?];
        let has_normals = normal.iter().all(Option::is_some);
        if has_normals {
            for (axis, i) in normal.into_iter().flatten().enumerate() {
                vertex_roles[i] = Role::Normal(axis);
            }
        } else if normal.iter().any(Option::is_some) {
            warnings.push(format!(
                "line {}: normals ignored: element vertex lacks some of nx, ny and nz",
                element.line
            ));
        }
        let mut has_uvs = false;
        for (u, v) in
            [("u", "v"), ("s", "t"), ("texture_u", "texture_v"), ("texture_s", "texture_t")]
        {
            if let (Some(u), Some(v)) = (find_scalar(u)?, find_scalar(v)?) {
                vertex_roles[u] = Role::Uv(0);
                vertex_roles[v] = Role::Uv(1);
                has_uvs = true;
                break;
            }
        }

        let face = header.elements.iter().position(|e| e.name == "face");
        let mut face_roles = Vec::new();
        if let Some(face) = face {
            let element = &header.elements[face];
            let at = Location::Line(element.line);
            let Some(i) = element
                .properties
                .iter()
                .position(|p| p.name == "vertex_indices")
                .or_else(|| element.properties.iter().position(|p| p.name == "vertex_index"))
            else {
                return fail(
                    at,
                    "element face has no list property vertex_indices (or vertex_index)",
                );
            };
            match element.properties[i].kind {
                Kind::List { item, .. } if item.integer_range().is_some() => {}
                Kind::List { item, .. } => {
                    return fail(
                        at,
                        format!("face indices must have an integer type, not {}", item.name()),
                    );
                }
                Kind::Scalar(_) => {
                    return fail(
                        at,
                        format!("face property {} must be a list", element.properties[i].name),
                    );
                }
            }
            face_roles = vec![Role::Skip; element.properties.len()];
            face_roles[i] = Role::Indices;
        }
        Ok(Layout { vertex, vertex_roles, has_normals, has_uvs, face, face_roles, warnings })
    }
}

/// The mesh as it is read.
struct Builder {
    vertex_count: u64,
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    uvs: Vec<Vec2>,
    triangles: Vec<[u32; 3]>,
    short_faces: u64,
}

impl Builder {
    fn new(header: &Header, layout: &Layout, data_bytes: u64) -> Builder {
        // The counts were checked against the file's size, so these allocations are bounded by
        // a small multiple of it.
        let vertex_count = header.elements[layout.vertex].count;
        let capacity = |wanted: bool| if wanted { vertex_count as usize } else { 0 };
        // A face that makes a triangle takes at least 4 bytes (binary: a count and 3 one-byte
        // indices; ASCII: "3 0 1 2" is longer still).
        let face_count = layout.face.map_or(0, |f| header.elements[f].count);
        Builder {
            vertex_count,
            positions: Vec::with_capacity(capacity(true)),
            normals: Vec::with_capacity(capacity(layout.has_normals)),
            uvs: Vec::with_capacity(capacity(layout.has_uvs)),
            triangles: Vec::with_capacity(face_count.min(data_bytes / 4) as usize),
            short_faces: 0,
        }
    }

    fn finish(self, name: String) -> Mesh {
        // Per-vertex attributes: their corners are the positions' corners.
        let normals = (!self.normals.is_empty())
            .then(|| CornerAttribute::per_vertex(self.normals, &self.triangles));
        let uvs =
            (!self.uvs.is_empty()).then(|| CornerAttribute::per_vertex(self.uvs, &self.triangles));
        Mesh {
            name,
            positions: self.positions,
            triangles: self.triangles,
            normals,
            uvs,
            tangents: None,
            material_ids: Vec::new(),
            materials: Vec::new(),
        }
    }
}

fn read_count<R: Reader>(
    reader: &mut R,
    count: Scalar,
    place: Place,
    property: &Property,
) -> Result<u64, Failure> {
    match reader.value(count, place, Expected::Count(property))? {
        Value::Integer(n) if n >= 0 => Ok(n as u64),
        Value::Integer(n) => fail(
            reader.location(),
            format!("{place}: list {} has a negative length {n}", property.name),
        ),
        // The header admits integer count types only.
        Value::Real(r) => {
            fail(reader.location(), format!("{place}: list {} has length {r}", property.name))
        }
    }
}

fn read_elements<R: Reader>(
    reader: &mut R,
    header: &Header,
    layout: &Layout,
    builder: &mut Builder,
) -> Result<(), Failure> {
    for (element_index, element) in header.elements.iter().enumerate() {
        if element.properties.is_empty() {
            continue;
        }
        let roles: &[Role] = if element_index == layout.vertex {
            &layout.vertex_roles
        } else if Some(element_index) == layout.face {
            &layout.face_roles
        } else {
            &[]
        };
        for index in 0..element.count {
            let place = Place { element, index };
            reader.begin(place)?;
            let mut position = [0.0; 3];
            let mut normal = [0.0; 3];
            let mut uv = [0.0; 2];
            for (property_index, property) in element.properties.iter().enumerate() {
                let role = roles.get(property_index).copied().unwrap_or(Role::Skip);
                match property.kind {
                    Kind::Scalar(ty) => {
                        let value = reader.value(ty, place, Expected::Value(property))?.to_f32();
                        if role != Role::Skip && !value.is_finite() {
                            return fail(
                                reader.location(),
                                format!("{place}: {} is not finite ({value})", property.name),
                            );
                        }
                        match role {
                            Role::Position(axis) => position[axis] = value,
                            Role::Normal(axis) => normal[axis] = value,
                            Role::Uv(axis) => uv[axis] = value,
                            Role::Skip | Role::Indices => {}
                        }
                    }
                    Kind::List { count, item } => {
                        let length = read_count(reader, count, place, property)?;
                        let expected = Expected::Items(property, length);
                        if role == Role::Indices {
                            reader.expect_items(length, item, place, expected)?;
                            read_polygon(reader, item, length, place, expected, builder)?;
                        } else {
                            reader.skip_items(length, item, place, expected)?;
                        }
                    }
                }
            }
            reader.end(place)?;
            if element_index == layout.vertex {
                builder.positions.push(Vec3::from(position));
                if layout.has_normals {
                    builder.normals.push(Vec3::from(normal));
                }
                if layout.has_uvs {
                    builder.uvs.push(Vec2::from(uv));
                }
            }
        }
    }
    Ok(())
}

/// Reads one face's `length` indices and appends its fan triangulation `(p0, pk, pk+1)`.
fn read_polygon<R: Reader>(
    reader: &mut R,
    item: Scalar,
    length: u64,
    place: Place,
    expected: Expected,
    builder: &mut Builder,
) -> Result<(), Failure> {
    let (mut first, mut previous) = (0, 0);
    for k in 0..length {
        let index = match reader.value(item, place, expected)? {
            Value::Integer(i) if (0..builder.vertex_count as i64).contains(&i) => i as u32,
            Value::Integer(i) if i < 0 => {
                return fail(reader.location(), format!("{place}: negative vertex index {i}"));
            }
            value => {
                return fail(
                    reader.location(),
                    format!(
                        "{place}: vertex index {} is out of range (the file has {} vertices)",
                        match value {
                            Value::Integer(i) => i.to_string(),
                            Value::Real(r) => r.to_string(),
                        },
                        builder.vertex_count
                    ),
                );
            }
        };
        match k {
            0 => first = index,
            1 => previous = index,
            _ => {
                builder.triangles.push([first, previous, index]);
                previous = index;
            }
        }
    }
    if length < 3 {
        builder.short_faces += 1;
    }
    Ok(())
}

#[cfg(test)]
mod tests;
