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

use super::file::{LoadError, LoadedMesh, Location, mesh_name, quoted};
use crate::mesh::{CornerAttribute, Mesh};

/// A PLY scalar type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    Int8,
    Uint8,
    Int16,
    Uint16,
    Int32,
    Uint32,
    Float32,
    Float64,
}

impl Scalar {
    fn from_name(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::Int8,
            "uchar" | "uint8" => Scalar::Uint8,
            "short" | "int16" => Scalar::Int16,
            "ushort" | "uint16" => Scalar::Uint16,
            "int" | "int32" => Scalar::Int32,
            "uint" | "uint32" => Scalar::Uint32,
            "float" | "float32" => Scalar::Float32,
            "double" | "float64" => Scalar::Float64,
            _ => return None,
        })
    }

    fn size_bytes(self) -> u64 {
        match self {
            Scalar::Int8 | Scalar::Uint8 => 1,
            Scalar::Int16 | Scalar::Uint16 => 2,
            Scalar::Int32 | Scalar::Uint32 | Scalar::Float32 => 4,
            Scalar::Float64 => 8,
        }
    }

    /// The range of an integer type, `None` for floating-point types.
    fn integer_range(self) -> Option<(i64, i64)> {
        match self {
            Scalar::Int8 => Some((i8::MIN.into(), i8::MAX.into())),
            Scalar::Uint8 => Some((0, u8::MAX.into())),
            Scalar::Int16 => Some((i16::MIN.into(), i16::MAX.into())),
            Scalar::Uint16 => Some((0, u16::MAX.into())),
            Scalar::Int32 => Some((i32::MIN.into(), i32::MAX.into())),
            Scalar::Uint32 => Some((0, u32::MAX.into())),
            Scalar::Float32 | Scalar::Float64 => None,
        }
    }

    fn name(self) -> &'static str {
        match self {
            Scalar::Int8 => "char",
            Scalar::Uint8 => "uchar",
            Scalar::Int16 => "short",
            Scalar::Uint16 => "ushort",
            Scalar::Int32 => "int",
            Scalar::Uint32 => "uint",
            Scalar::Float32 => "float",
            Scalar::Float64 => "double",
        }
    }
}

/// A value read from the file. Integers of every PLY type fit an `i64`.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Value {
    Integer(i64),
    Real(f64),
}

impl Value {
    /// The value as `f32`, correctly rounded (`as` rounds to nearest).
    fn to_f32(self) -> f32 {
        match self {
            Value::Integer(i) => i as f32,
            Value::Real(r) => r as f32,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Clone, Debug)]
struct Property {
    name: String,
    kind: Kind,
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: u64,
    properties: Vec<Property>,
    /// The header line that declares it.
    line: u64,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Encoding {
    Ascii,
    BinaryLittleEndian,
    BinaryBigEndian,
}

#[derive(Debug)]
struct Header {
    encoding: Encoding,
    elements: Vec<Element>,
    /// The offset of the first byte after `end_header`'s line.
    data_start: usize,
    /// The number of header lines, `end_header`'s included.
    lines: u64,
}

/// A parse error before the path is attached.
#[derive(Debug)]
struct Failure {
    location: Location,
    message: String,
}

fn fail<T>(location: Location, message: impl Into<String>) -> Result<T, Failure> {
    Err(Failure { location, message: message.into() })
}

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

/// The header's lines, each without its line ending, with their numbers and the offset after.
fn header_lines(bytes: &[u8]) -> impl Iterator<Item = (u64, &[u8], usize)> {
    let mut start = 0;
    let mut number = 0;
    std::iter::from_fn(move || {
        if start >= bytes.len() {
            return None;
        }
        let rest = &bytes[start..];
        let length = rest.iter().position(|&b| b == b'\n');
        let line = &rest[..length.unwrap_or(rest.len())];
        start += length.map_or(rest.len(), |n| n + 1);
        number += 1;
        Some((number, line.strip_suffix(b"\r").unwrap_or(line), start))
    })
}

fn parse_header(bytes: &[u8]) -> Result<Header, Failure> {
    let mut lines = header_lines(bytes);
    match lines.next() {
        Some((_, b"ply", _)) => {}
        _ => return fail(Location::Line(1), "expected `ply` on the first line: not a PLY file"),
    }
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut last_line = 1;
    for (number, line, next) in lines {
        last_line = number;
        let at = Location::Line(number);
        // Lossy, so that a comment in another encoding does no harm.
        let text = String::from_utf8_lossy(line);
        let words: Vec<&str> = text.split_ascii_whitespace().collect();
        match words.as_slice() {
            [] | ["comment", ..] | ["obj_info", ..] => {}
            ["format", format, version] => {
                if encoding.is_some() {
                    return fail(at, "a second `format` line");
                }
                encoding = Some(match *format {
                    "ascii" => Encoding::Ascii,
                    "binary_little_endian" => Encoding::BinaryLittleEndian,
                    "binary_big_endian" => Encoding::BinaryBigEndian,
                    _ => {
                        return fail(
                            at,
                            format!(
                                "expected format ascii, binary_little_endian or \
                                 binary_big_endian, found {}",
                                quoted(format)
                            ),
                        );
                    }
                });
                if *version != "1.0" {
                    return fail(at, format!("expected version 1.0, found {}", quoted(version)));
                }
            }
            ["element", name, count] => {
                let Ok(count) = count.parse::<u64>() else {
                    return fail(
                        at,
                        format!("expected a count of {name} elements, found {}", quoted(count)),
                    );
                };
                if elements.iter().any(|e| e.name == *name) {
                    return fail(at, format!("a second `element {name}`"));
                }
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    properties: Vec::new(),
                    line: number,
                });
            }
            ["format", ..] => return fail(at, "expected `format <encoding> 1.0`"),
            ["element", ..] => return fail(at, "expected `element <name> <count>`"),
            ["property", ..] => {
                let Some(element) = elements.last_mut() else {
                    return fail(at, "a property before any element");
                };
                let (kind, name) =
                    parse_property(&words).map_err(|m| Failure { location: at, message: m })?;
                if element.properties.iter().any(|p| p.name == name) {
                    return fail(
                        at,
                        format!("a second property {name} in element {}", element.name),
                    );
                }
                element.properties.push(Property { name: name.to_string(), kind });
            }
            ["end_header"] => {
                let Some(encoding) = encoding else {
                    return fail(at, "end of the header without a `format` line");
                };
                return Ok(Header { encoding, elements, data_start: next, lines: number });
            }
            _ => {
                return fail(
                    at,
                    format!(
                        "expected a header line (format, element, property, comment, obj_info or \
                         end_header), found {}",
                        quoted(&text)
                    ),
                );
            }
        }
    }
    fail(Location::Line(last_line + 1), "the file ends inside the header (no `end_header` line)")
}

/// Parses `property <type> <name>` or `property list <count type> <item type> <name>`.
fn parse_property<'a>(words: &[&'a str]) -> Result<(Kind, &'a str), String> {
    let scalar = |word: &str| {
        Scalar::from_name(word).ok_or_else(|| {
            format!(
                "expected a type (char uchar short ushort int uint float double, or int8 … \
                 float64), found {}",
                quoted(word)
            )
        })
    };
    match words {
        ["property", "list", count, item, name] => {
            let count = scalar(count)?;
            if count.integer_range().is_none() {
                return Err(format!(
                    "the count of list {name} must have an integer type, not {}",
                    count.name()
                ));
            }
            Ok((Kind::List { count, item: scalar(item)? }, name))
        }
        ["property", "list", ..] => {
            Err("expected `property list <count type> <item type> <name>`".to_string())
        }
        ["property", ty, name] => Ok((Kind::Scalar(scalar(ty)?), name)),
        _ => Err("expected `property <type> <name>`".to_string()),
    }
}

/// The fewest bytes one instance of `element` can take.
fn min_bytes_per_element(element: &Element, encoding: Encoding) -> u64 {
    element
        .properties
        .iter()
        .map(|p| match (encoding, p.kind) {
            // A value and a separator (or the line's end).
            (Encoding::Ascii, _) => 2,
            (_, Kind::Scalar(s)) => s.size_bytes(),
            // The count; the list may be empty.
            (_, Kind::List { count, .. }) => count.size_bytes(),
        })
        .sum()
}

/// Refuses a header that declares more than the rest of the file can hold, before anything is
/// allocated for it.
fn check_declared_counts(header: &Header, data_bytes: u64) -> Result<(), Failure> {
    // ASCII: the last value of the file needs no separator after it.
    let available =
        if header.encoding == Encoding::Ascii { data_bytes.saturating_add(1) } else { data_bytes };
    let mut needed: u64 = 0;
    for element in &header.elements {
        let each = min_bytes_per_element(element, header.encoding);
        needed = needed.saturating_add(element.count.saturating_mul(each));
        if needed > available {
            return fail(
                Location::Line(element.line),
                format!(
                    "element {} declares {} of them, which take at least {} bytes with what \
                     comes before, but only {data_bytes} bytes follow the header",
                    element.name,
                    element.count,
                    if needed == u64::MAX {
                        "18446744073709551615".into()
                    } else {
                        needed.to_string()
                    },
                ),
            );
        }
    }
    Ok(())
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
            .then(|| CornerAttribute { values: self.normals, triangles: self.triangles.clone() });
        let uvs = (!self.uvs.is_empty())
            .then(|| CornerAttribute { values: self.uvs, triangles: self.triangles.clone() });
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

/// What the reader was about to read, for messages.
#[derive(Clone, Copy)]
enum Expected<'a> {
    Value(&'a Property),
    Count(&'a Property),
    Items(&'a Property, u64),
}

impl Expected<'_> {
    fn describe(self) -> String {
        match self {
            Expected::Value(p) => match p.kind {
                Kind::Scalar(s) => format!("{} ({})", p.name, s.name()),
                Kind::List { .. } => p.name.clone(),
            },
            Expected::Count(p) => format!("the length of list {}", p.name),
            Expected::Items(p, 1) if is_index_list(p) => "1 index".into(),
            Expected::Items(p, count) if is_index_list(p) => format!("{count} indices"),
            Expected::Items(p, 1) => format!("1 value of list {}", p.name),
            Expected::Items(p, count) => format!("{count} values of list {}", p.name),
        }
    }
}

fn is_index_list(property: &Property) -> bool {
    matches!(property.name.as_str(), "vertex_indices" | "vertex_index")
}

/// The element instance being read, for messages.
#[derive(Clone, Copy)]
struct Place<'a> {
    element: &'a Element,
    index: u64,
}

impl std::fmt::Display for Place<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} {}", self.element.name, self.index)
    }
}

/// The ASCII and the binary encodings, behind one interface.
trait Reader {
    /// Starts element instance `place`.
    fn begin(&mut self, place: Place) -> Result<(), Failure>;
    /// Reads a scalar of type `ty`.
    fn value(&mut self, ty: Scalar, place: Place, expected: Expected) -> Result<Value, Failure>;
    /// Checks that `count` items of type `ty` can follow (a binary file may be cut short).
    fn expect_items(
        &mut self,
        count: u64,
        ty: Scalar,
        place: Place,
        expected: Expected,
    ) -> Result<(), Failure>;
    /// Skips `count` items of type `ty`.
    fn skip_items(
        &mut self,
        count: u64,
        ty: Scalar,
        place: Place,
        expected: Expected,
    ) -> Result<(), Failure>;
    /// Ends element instance `place`.
    fn end(&mut self, place: Place) -> Result<(), Failure>;
    /// Where the last value read starts.
    fn location(&self) -> Location;
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

/// Reads the ASCII encoding: one element per line, values separated by spaces.
struct AsciiReader<'a> {
    bytes: &'a [u8],
    /// Where the next line starts.
    next_line: usize,
    /// The number of the current line.
    line: u64,
    /// The current line and the position of the next value in it.
    current: &'a [u8],
    cursor: usize,
    /// How many values of the current line have been read.
    values_read: usize,
}

impl<'a> AsciiReader<'a> {
    fn new(bytes: &'a [u8], data_start: usize, header_lines: u64) -> Self {
        AsciiReader {
            bytes,
            next_line: data_start,
            line: header_lines,
            current: &[],
            cursor: 0,
            values_read: 0,
        }
    }

    /// Moves to the next line, if there is one.
    fn advance(&mut self) -> bool {
        let Some(rest) = self.bytes.get(self.next_line..).filter(|rest| !rest.is_empty()) else {
            return false;
        };
        let length = rest.iter().position(|&b| b == b'\n').unwrap_or(rest.len());
        self.current = &rest[..length];
        self.next_line += (length + 1).min(rest.len());
        self.line += 1;
        self.cursor = 0;
        self.values_read = 0;
        true
    }

    fn token(&mut self) -> Option<&'a [u8]> {
        let line = self.current;
        let start =
            self.cursor + line.get(self.cursor..)?.iter().position(|b| !b.is_ascii_whitespace())?;
        let length = line[start..]
            .iter()
            .position(|b| b.is_ascii_whitespace())
            .unwrap_or(line.len() - start);
        self.cursor = start + length;
        self.values_read += 1;
        Some(&line[start..start + length])
    }

    fn values_on_line(&self) -> usize {
        self.current.split(|b| b.is_ascii_whitespace()).filter(|t| !t.is_empty()).count()
    }

    /// The number of the first non-blank line after the current one, if any.
    fn trailing_line(&mut self) -> Option<u64> {
        while self.advance() {
            if self.current.iter().any(|b| !b.is_ascii_whitespace()) {
                return Some(self.line);
            }
        }
        None
    }

    fn missing(&self, place: Place, expected: Expected) -> Failure {
        let found = self.values_on_line();
        let element = place.element;
        let message = if element.properties.iter().all(|p| matches!(p.kind, Kind::Scalar(_))) {
            let names: Vec<&str> = element.properties.iter().map(|p| p.name.as_str()).collect();
            format!("{place}: expected {} values ({}), found {found}", names.len(), names.join(" "))
        } else {
            format!("{place}: the line ends before {} (it has {found} values)", expected.describe())
        };
        Failure { location: Location::Line(self.line), message }
    }
}

impl Reader for AsciiReader<'_> {
    fn begin(&mut self, place: Place) -> Result<(), Failure> {
        loop {
            if !self.advance() {
                return fail(
                    Location::Line(self.line + 1),
                    format!(
                        "the file ends before {place} (the header declares {} of them)",
                        place.element.count
                    ),
                );
            }
            if self.current.iter().any(|b| !b.is_ascii_whitespace()) {
                return Ok(());
            }
        }
    }

    fn value(&mut self, ty: Scalar, place: Place, expected: Expected) -> Result<Value, Failure> {
        let Some(token) = self.token() else {
            return Err(self.missing(place, expected));
        };
        let text = std::str::from_utf8(token).unwrap_or("");
        let value = match ty.integer_range() {
            Some((lo, hi)) => {
                text.parse::<i64>().ok().filter(|i| (lo..=hi).contains(i)).map(Value::Integer)
            }
            // Straight to f32, so that decimal text is correctly rounded once.
            None => text.parse::<f32>().ok().map(|r| Value::Real(r.into())),
        };
        value.ok_or_else(|| Failure {
            location: Location::Line(self.line),
            message: format!(
                "{place}: expected {}, found {}",
                match (expected, ty.integer_range()) {
                    (Expected::Items(..), Some((lo, hi))) =>
                        format!("{} as integers from {lo} to {hi}", expected.describe()),
                    (_, Some((lo, hi))) =>
                        format!("{} as an integer from {lo} to {hi}", expected.describe()),
                    (_, None) => format!("{} as a number", expected.describe()),
                },
                quoted(&String::from_utf8_lossy(token))
            ),
        })
    }

    fn expect_items(&mut self, _: u64, _: Scalar, _: Place, _: Expected) -> Result<(), Failure> {
        Ok(())
    }

    fn skip_items(
        &mut self,
        count: u64,
        ty: Scalar,
        place: Place,
        expected: Expected,
    ) -> Result<(), Failure> {
        for _ in 0..count {
            self.value(ty, place, expected)?;
        }
        Ok(())
    }

    fn end(&mut self, place: Place) -> Result<(), Failure> {
        let read = self.values_read;
        match self.token() {
            None => Ok(()),
            Some(extra) => fail(
                Location::Line(self.line),
                format!(
                    "{place}: expected {read} values, found {} (the first extra one is {})",
                    self.values_on_line(),
                    quoted(&String::from_utf8_lossy(extra))
                ),
            ),
        }
    }

    fn location(&self) -> Location {
        Location::Line(self.line)
    }
}

/// Reads the binary encodings; `BIG_ENDIAN` picks the byte order.
struct BinaryReader<'a, const BIG_ENDIAN: bool> {
    bytes: &'a [u8],
    position: usize,
    value_start: usize,
}

impl<const BIG_ENDIAN: bool> BinaryReader<'_, BIG_ENDIAN> {
    fn take<const N: usize>(&mut self) -> Option<[u8; N]> {
        let chunk = *self.bytes.get(self.position..)?.first_chunk::<N>()?;
        self.position += N;
        Some(chunk)
    }

    fn cut_short(&self, place: Place, expected: Expected) -> Failure {
        Failure {
            location: Location::Byte(self.bytes.len() as u64),
            message: format!("the file ends inside {place} (expected {})", expected.describe()),
        }
    }

    fn remaining(&self) -> u64 {
        self.bytes.len().saturating_sub(self.position) as u64
    }

    fn trailing_bytes(&self) -> Option<String> {
        let extra = self.remaining();
        (extra > 0).then(|| {
            format!("byte {}: ignored {extra} bytes after the last element", self.position)
        })
    }
}

/// Decodes a `$ty` from `$reader`'s next bytes in its byte order.
macro_rules! decode {
    ($reader:expr, $ty:ty) => {{
        let bytes = $reader.take::<{ std::mem::size_of::<$ty>() }>();
        bytes.map(|b| if BIG_ENDIAN { <$ty>::from_be_bytes(b) } else { <$ty>::from_le_bytes(b) })
    }};
}

impl<const BIG_ENDIAN: bool> Reader for BinaryReader<'_, BIG_ENDIAN> {
    fn begin(&mut self, _: Place) -> Result<(), Failure> {
        Ok(())
    }

    fn value(&mut self, ty: Scalar, place: Place, expected: Expected) -> Result<Value, Failure> {
        self.value_start = self.position;
        let value = match ty {
            Scalar::Int8 => decode!(self, i8).map(|v| Value::Integer(v.into())),
            Scalar::Uint8 => decode!(self, u8).map(|v| Value::Integer(v.into())),
            Scalar::Int16 => decode!(self, i16).map(|v| Value::Integer(v.into())),
            Scalar::Uint16 => decode!(self, u16).map(|v| Value::Integer(v.into())),
            Scalar::Int32 => decode!(self, i32).map(|v| Value::Integer(v.into())),
            Scalar::Uint32 => decode!(self, u32).map(|v| Value::Integer(v.into())),
            Scalar::Float32 => decode!(self, f32).map(|v| Value::Real(v.into())),
            Scalar::Float64 => decode!(self, f64).map(Value::Real),
        };
        value.ok_or_else(|| self.cut_short(place, expected))
    }

    fn expect_items(
        &mut self,
        count: u64,
        ty: Scalar,
        place: Place,
        expected: Expected,
    ) -> Result<(), Failure> {
        match count.checked_mul(ty.size_bytes()) {
            Some(needed) if needed <= self.remaining() => Ok(()),
            _ => Err(self.cut_short(place, expected)),
        }
    }

    fn skip_items(
        &mut self,
        count: u64,
        ty: Scalar,
        place: Place,
        expected: Expected,
    ) -> Result<(), Failure> {
        self.expect_items(count, ty, place, expected)?;
        // At most `remaining`, so it fits a usize.
        self.position += (count * ty.size_bytes()) as usize;
        Ok(())
    }

    fn end(&mut self, _: Place) -> Result<(), Failure> {
        Ok(())
    }

    fn location(&self) -> Location {
        Location::Byte(self.value_start as u64)
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    fn parse(bytes: &[u8]) -> Result<LoadedMesh, LoadError> {
        parse_ply(Path::new("test.ply"), bytes)
    }

    fn error(bytes: &[u8]) -> String {
        let message = parse(bytes).expect_err("the file is malformed").to_string();
        assert!(message.starts_with("test.ply: "), "{message}");
        assert!(!message.contains('\n'), "{message}");
        message
    }

    /// A header for `encoding` with the given element and property lines.
    fn header(encoding: &str, body: &str) -> String {
        format!("ply\nformat {encoding} 1.0\ncomment made by hand\n{body}end_header\n")
    }

    const SQUARE_HEADER: &str = "element vertex 4\nproperty float x\nproperty float y\n\
        property float z\nelement face 1\nproperty list uchar int vertex_indices\n";

    #[test]
    fn an_ascii_polygon_is_a_fan_in_file_order() {
        let text = header("ascii", &SQUARE_HEADER.replace("face 1", "face 2"))
            + "0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n3 3 2 1\n";
        let mesh = parse(text.as_bytes()).unwrap().mesh;
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3], [3, 2, 1]]);
        assert_eq!(mesh.positions[2], Vec3::new(1.0, 1.0, 0.0));
        assert_eq!((mesh.normals, mesh.uvs), (None, None));
        assert_eq!(mesh.name, "test.ply");
    }

    #[test]
    fn every_type_name_and_alias_is_read() {
        let types = [
            ("char", "int8"),
            ("uchar", "uint8"),
            ("short", "int16"),
            ("ushort", "uint16"),
            ("int", "int32"),
            ("uint", "uint32"),
            ("float", "float32"),
            ("double", "float64"),
        ];
        for (name, alias) in types {
            for ty in [name, alias] {
                let body = format!(
                    "element vertex 3\nproperty {ty} x\nproperty {ty} y\nproperty {ty} z\n\
                     element face 1\nproperty list {} {} vertex_indices\n",
                    if ty.contains("float") || ty == "double" { "uchar" } else { ty },
                    if ty.contains("float") || ty == "double" { "int" } else { ty },
                );
                let text = header("ascii", &body) + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
                let mesh = parse(text.as_bytes()).unwrap_or_else(|e| panic!("{ty}: {e}")).mesh;
                assert_eq!(mesh.triangles, vec![[0, 1, 2]], "{ty}");
                assert_eq!(mesh.positions[1], Vec3::X, "{ty}");
            }
        }
    }

    /// The same mesh in the three encodings: a vertex with `x y z nx ny nz s t` and an unused
    /// list, faces with an extra scalar and the index list second, and an unknown element with
    /// a list between them.
    fn rich_file(encoding: Encoding) -> Vec<u8> {
        let name = match encoding {
            Encoding::Ascii => "ascii",
            Encoding::BinaryLittleEndian => "binary_little_endian",
            Encoding::BinaryBigEndian => "binary_big_endian",
        };
        let mut bytes = header(
            name,
            "element vertex 4\nproperty double x\nproperty float y\nproperty float z\n\
             property list uchar short junk\nproperty float nx\nproperty float ny\n\
             property float nz\nproperty float s\nproperty float t\n\
             element edge 2\nproperty list ushort uint ends\nproperty uchar red\n\
             obj_info skip me\n\
             element face 2\nproperty short flags\nproperty list uchar uint vertex_indices\n",
        )
        .into_bytes();
        let vertices: [[f64; 8]; 4] = [
            [0.1, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0],
            [1.0, 0.0, -2.5, 0.0, 0.0, 1.0, 1.0, 0.0],
            [1.0, 1.0, 3e-5, 0.0, 1.0, 0.0, 1.0, 1.0],
            [0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
        ];
        if encoding == Encoding::Ascii {
            for v in vertices {
                let [x, y, z, nx, ny, nz, s, t] = v;
                bytes.extend(format!("{x} {y} {z} 2 -7 8 {nx} {ny} {nz} {s} {t}\n").bytes());
            }
            bytes.extend(b"3 0 1 2 255\n\n0 9\n  7 4 0 1 2 3\n-1 3 3 2 1\r\n");
            return bytes;
        }
        let big = encoding == Encoding::BinaryBigEndian;
        fn put<const N: usize>(bytes: &mut Vec<u8>, big: bool, le: [u8; N], be: [u8; N]) {
            bytes.extend(if big { be } else { le });
        }
        for v in vertices {
            put(&mut bytes, big, v[0].to_le_bytes(), v[0].to_be_bytes());
            for c in [v[1], v[2]] {
                put(&mut bytes, big, (c as f32).to_le_bytes(), (c as f32).to_be_bytes());
            }
            bytes.push(2);
            for j in [-7i16, 8] {
                put(&mut bytes, big, j.to_le_bytes(), j.to_be_bytes());
            }
            for c in &v[3..] {
                put(&mut bytes, big, (*c as f32).to_le_bytes(), (*c as f32).to_be_bytes());
            }
        }
        for (ends, red) in [(&[0u32, 1, 2][..], 255u8), (&[], 9)] {
            let n = ends.len() as u16;
            put(&mut bytes, big, n.to_le_bytes(), n.to_be_bytes());
            for e in ends {
                put(&mut bytes, big, e.to_le_bytes(), e.to_be_bytes());
            }
            bytes.push(red);
        }
        for (flags, face) in [(7i16, &[0u32, 1, 2, 3][..]), (-1, &[3, 2, 1])] {
            put(&mut bytes, big, flags.to_le_bytes(), flags.to_be_bytes());
            bytes.push(face.len() as u8);
            for i in face {
                put(&mut bytes, big, i.to_le_bytes(), i.to_be_bytes());
            }
        }
        bytes
    }

    #[test]
    fn the_three_encodings_give_the_same_mesh() {
        let ascii = parse(&rich_file(Encoding::Ascii)).unwrap();
        assert_eq!(ascii.warnings, Vec::<String>::new());
        let mesh = &ascii.mesh;
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3], [3, 2, 1]]);
        assert_eq!(mesh.positions[0], Vec3::new(0.1, 0.0, 0.0));
        assert_eq!(mesh.positions[2], Vec3::new(1.0, 1.0, 3e-5));
        let normals = mesh.normals.as_ref().expect("normals");
        assert_eq!(normals.values[3], Vec3::X);
        assert_eq!(normals.triangles, mesh.triangles);
        let uvs = mesh.uvs.as_ref().expect("uvs from s t");
        assert_eq!(uvs.values[2], Vec2::ONE);
        for encoding in [Encoding::BinaryLittleEndian, Encoding::BinaryBigEndian] {
            let binary = parse(&rich_file(encoding)).unwrap();
            assert_eq!(binary, ascii, "{encoding:?}");
        }
    }

    #[test]
    fn texture_coordinate_names_are_recognised() {
        for (u, v) in
            [("u", "v"), ("s", "t"), ("texture_u", "texture_v"), ("texture_s", "texture_t")]
        {
            let body = SQUARE_HEADER.replace(
                "property float z\n",
                &format!("property float z\nproperty float {u}\nproperty float {v}\n"),
            );
            let text =
                header("ascii", &body) + "0 0 0 0 0\n1 0 0 1 0\n1 1 0 1 .5\n0 1 0 0 1\n3 0 1 2\n";
            let mesh = parse(text.as_bytes()).unwrap().mesh;
            assert_eq!(mesh.uvs.unwrap().values[2], Vec2::new(1.0, 0.5), "{u} {v}");
        }
    }

    #[test]
    fn ascii_floats_are_correctly_rounded_to_f32() {
        // 1.00000005960464477539062500000001 is just above the midpoint between 1 and the next
        // f32, so it rounds up; through f64 it would round to 1.0.
        let body = SQUARE_HEADER.replace("property float x", "property double x");
        let text = header("ascii", &body)
            + "1.00000005960464477539062500000001 0 0\n0 0 0\n0 1 0\n1 1 0\n3 0 1 2\n";
        let mesh = parse(text.as_bytes()).unwrap().mesh;
        assert_eq!(mesh.positions[0].x, 1.0 + f32::EPSILON);
    }

    #[test]
    fn header_errors_name_the_line_and_what_was_expected() {
        let cases: &[(&str, &str)] = &[
            ("PLY\n", "line 1: expected `ply` on the first line"),
            ("", "line 1: expected `ply`"),
            (
                "ply\nformat ascii 1.0\nelement vertex 0\n",
                "line 4: the file ends inside the header",
            ),
            ("ply\nformat ascii 2.0\nend_header\n", "line 2: expected version 1.0, found \"2.0\""),
            ("ply\nformat text 1.0\nend_header\n", "line 2: expected format ascii"),
            ("ply\nelement vertex 1\nend_header\n", "line 3: end of the header without a `format`"),
            (
                "ply\nformat ascii 1.0\nproperty float x\nend_header\n",
                "line 3: a property before any",
            ),
            (
                "ply\nformat ascii 1.0\nelement vertex -1\nend_header\n",
                "line 3: expected a count of vertex elements, found \"-1\"",
            ),
            (
                "ply\nformat ascii 1.0\nelement vertex 1\nproperty real x\nend_header\n",
                "line 4: expected a type",
            ),
            (
                "ply\nformat ascii 1.0\nelement f 1\nproperty list float int i\nend_header\n",
                "line 4: the count of list i must have an integer type, not float",
            ),
            (
                "ply\nformat ascii 1.0\nelemnt vertex 1\nend_header\n",
                "line 3: expected a header line",
            ),
            (
                "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nend_header\n",
                "line 3: element vertex has no property z",
            ),
            (
                "ply\nformat ascii 1.0\nelement face 0\nend_header\n",
                "line 4: the header declares no `element vertex`",
            ),
            (
                &header(
                    "ascii",
                    "element vertex 0\nproperty float x\nproperty float y\nproperty float z\nelement face 0\nproperty list uchar float vertex_indices\n",
                ),
                "line 8: face indices must have an integer type, not float",
            ),
            (
                &header(
                    "ascii",
                    "element vertex 0\nproperty float x\nproperty float y\nproperty float z\nelement face 0\nproperty int vertex_indices\n",
                ),
                "line 8: face property vertex_indices must be a list",
            ),
            (
                &header("ascii", "element vertex 0\nproperty float x\nproperty float x\n"),
                "line 6: a second property x in element vertex",
            ),
        ];
        for (text, expected) in cases {
            let message = error(text.as_bytes());
            assert!(message.contains(expected), "{message}\n  expected: {expected}");
        }
    }

    #[test]
    fn absurd_counts_are_refused_before_reading() {
        // 4e9 vertices of 12 bytes each in a 24-byte body.
        let text =
            header("binary_little_endian", &SQUARE_HEADER.replace("vertex 4", "vertex 4000000000"));
        let message = error(&[text.as_bytes(), &[0; 24]].concat());
        assert!(message.contains("line 4: element vertex declares 4000000000 of them, which take at least 48000000000 bytes"), "{message}");
        assert!(message.contains("only 24 bytes follow the header"), "{message}");
        // A face's list needs at least its count byte; an ASCII value at least 2 bytes.
        let text = header(
            "binary_little_endian",
            &SQUARE_HEADER.replace("face 1", "face 18446744073709551615"),
        );
        let message = error(&[text.as_bytes(), &[0; 60]].concat());
        assert!(
            message.contains("line 8: element face declares 18446744073709551615 of them"),
            "{message}"
        );
        let text = header("ascii", &SQUARE_HEADER.replace("vertex 4", "vertex 5")) + "0 0 0\n";
        assert!(error(text.as_bytes()).contains("line 4: element vertex declares 5"));
        // A file that is exactly long enough passes this check: 4 vertices and a face of
        // "3 0 1 2" written as tightly as possible, with no final line ending.
        let text = header("ascii", SQUARE_HEADER) + "0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2";
        assert_eq!(parse(text.as_bytes()).unwrap().mesh.triangles.len(), 1);
    }

    #[test]
    fn cut_ascii_files_name_the_line() {
        // 10 header lines; the vertices are lines 11 to 14, the face line 15. (Where the rest
        // of the file is too short for what the header declares, the count check comes first:
        // see `absurd_counts_are_refused_before_reading`.)
        let whole = header("ascii", SQUARE_HEADER) + "0 0 0\n1 0 0\n1 1\n0 1 0\n4 0 1 2 3\n";
        let message = error(whole.as_bytes());
        assert!(
            message.contains("line 13: vertex 2: expected 3 values (x y z), found 2"),
            "{message}"
        );
        let whole = header("ascii", SQUARE_HEADER) + "0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
        let cut = &whole[..whole.len() - 3];
        let message = error(cut.as_bytes());
        assert!(
            message.contains("line 15: face 0: the line ends before 4 indices (it has 4 values)"),
            "{message}"
        );
        let cut = header("ascii", &SQUARE_HEADER.replace("face 1", "face 2"))
            + "0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n";
        let message = error(cut.as_bytes());
        assert!(
            message
                .contains("line 16: the file ends before face 1 (the header declares 2 of them)"),
            "{message}"
        );
    }

    #[test]
    fn cut_binary_files_name_the_byte() {
        for encoding in [Encoding::BinaryLittleEndian, Encoding::BinaryBigEndian] {
            let whole = rich_file(encoding);
            // The last face: flags (2), count (1), three 4-byte indices.
            for cut in 1..=14 {
                let bytes = &whole[..whole.len() - cut];
                let message = error(bytes);
                let at = format!("byte {}: the file ends inside face 1 (expected ", bytes.len());
                assert!(message.contains(&at), "{message}");
                let what = match cut {
                    1..=12 => "3 indices)",
                    13 => "the length of list vertex_indices)",
                    _ => "flags (short))",
                };
                assert!(message.ends_with(what), "{message}");
            }
        }
    }

    #[test]
    fn bad_values_are_errors_with_their_place() {
        let file = |vertices: &str, face: &str| {
            let text = header("ascii", SQUARE_HEADER) + vertices + face;
            error(text.as_bytes())
        };
        let good = "0 0 0\n1 0 0\n1 1 0\n0 1 0\n";
        let cases = [
            (
                file(good, "4 0 1 2 4\n"),
                "line 15: face 0: vertex index 4 is out of range (the file has 4 vertices)",
            ),
            (file(good, "4 0 -1 2 3\n"), "line 15: face 0: negative vertex index -1"),
            (
                file(good, "3 0 1 2 3\n"),
                "line 15: face 0: expected 4 values, found 5 (the first extra one is \"3\")",
            ),
            (
                file(good, "3 0 1 x\n"),
                "line 15: face 0: expected 3 indices as integers from -2147483648 to 2147483647, found \"x\"",
            ),
            (
                file(good, "256 0 1 2\n"),
                "line 15: face 0: expected the length of list vertex_indices as an integer from 0 to 255, found \"256\"",
            ),
            (
                file("0 0 0\n1 nan 0\n1 1 0\n0 1 0\n", "3 0 1 2\n"),
                "line 12: vertex 1: y is not finite (NaN)",
            ),
            (
                file("0 0 0\n1 0 0\n1 1 -inf\n0 1 0\n", "3 0 1 2\n"),
                "line 13: vertex 2: z is not finite (-inf)",
            ),
            (
                file("0 0 0\n1 0 0\n1 1 1e39\n0 1 0\n", "3 0 1 2\n"),
                "line 13: vertex 2: z is not finite (inf)",
            ),
            (
                file("0 0 0\n1 0 0\n1 1 0,5\n0 1 0\n", "3 0 1 2\n"),
                "line 13: vertex 2: expected z (float) as a number, found \"0,5\"",
            ),
        ];
        for (message, expected) in cases {
            assert!(message.contains(expected), "{message}\n  expected: {expected}");
        }
        // Binary: the offset is the value's.
        let mut bytes = rich_file(Encoding::BinaryLittleEndian);
        let last = bytes.len() - 4;
        bytes[last..].copy_from_slice(&4u32.to_le_bytes());
        let message = error(&bytes);
        assert!(
            message.contains(&format!("byte {last}: face 1: vertex index 4 is out of range")),
            "{message}"
        );
        let mut bytes = rich_file(Encoding::BinaryBigEndian);
        let start = String::from_utf8_lossy(&bytes).find("end_header\n").unwrap() + 11;
        bytes[start..start + 8].copy_from_slice(&f64::NAN.to_be_bytes());
        let message = error(&bytes);
        assert!(
            message.contains(&format!("byte {start}: vertex 0: x is not finite (NaN)")),
            "{message}"
        );
        // A negative list length in a signed count type.
        let body = SQUARE_HEADER.replace("list uchar", "list char");
        let mut bytes = header("binary_little_endian", &body).into_bytes();
        bytes.extend([0u8; 48]);
        let at = bytes.len();
        bytes.extend([0xff, 0, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0]);
        let message = error(&bytes);
        assert!(
            message.contains(&format!(
                "byte {at}: face 0: list vertex_indices has a negative length -1"
            )),
            "{message}"
        );
    }

    #[test]
    fn short_faces_and_trailing_data_are_warnings() {
        let text = header("ascii", &SQUARE_HEADER.replace("face 1", "face 3"))
            + "0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 1\n0\n3 0 1 2\n\n9 9 9\n";
        let loaded = parse(text.as_bytes()).unwrap();
        assert_eq!(loaded.mesh.triangles, vec![[0, 1, 2]]);
        assert_eq!(
            loaded.warnings,
            [
                "test.ply: line 19: ignored text after the last element",
                "test.ply: skipped 2 faces with fewer than 3 vertices"
            ]
        );
        let mut bytes = rich_file(Encoding::BinaryLittleEndian);
        let end = bytes.len();
        bytes.extend(b"\n");
        let loaded = parse(&bytes).unwrap();
        assert_eq!(
            loaded.warnings,
            [format!("test.ply: byte {end}: ignored 1 bytes after the last element")]
        );
    }

    #[test]
    fn partial_normals_are_ignored_with_a_warning() {
        let body =
            SQUARE_HEADER.replace("property float z\n", "property float z\nproperty float nx\n");
        let text = header("ascii", &body) + "0 0 0 1\n1 0 0 1\n1 1 0 1\n0 1 0 1\n3 0 1 2\n";
        let loaded = parse(text.as_bytes()).unwrap();
        assert_eq!(loaded.mesh.normals, None);
        assert_eq!(
            loaded.warnings,
            ["test.ply: line 4: normals ignored: element vertex lacks some of nx, ny and nz"]
        );
    }

    /// Deterministic pseudo-random bytes, for hostile inputs without a seed from the entropy.
    fn mutate(bytes: &mut [u8], seed: u64, flips: usize) {
        let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        for _ in 0..flips {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            if !bytes.is_empty() {
                let at = (state % bytes.len() as u64) as usize;
                bytes[at] = (state >> 32) as u8;
            }
        }
    }

    proptest! {
        #[test]
        fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
            let _ = parse(&bytes);
            let _ = parse(&[b"ply\nformat binary_little_endian 1.0\n".as_slice(), &bytes].concat());
        }

        #[test]
        fn cut_or_damaged_files_never_panic(which in 0..3usize, cut in 0.0..1.0f64, seed in any::<u64>(), flips in 0..4usize) {
            let encoding = [Encoding::Ascii, Encoding::BinaryLittleEndian, Encoding::BinaryBigEndian][which];
            let mut bytes = rich_file(encoding);
            bytes.truncate((bytes.len() as f64 * cut) as usize);
            let _ = parse(&bytes);
            let mut bytes = rich_file(encoding);
            mutate(&mut bytes, seed, flips);
            if let Ok(loaded) = parse(&bytes) {
                let n = loaded.mesh.positions.len() as u32;
                prop_assert!(loaded.mesh.triangles.iter().flatten().all(|&v| v < n));
                prop_assert!(loaded.mesh.positions.iter().all(|p| p.is_finite()));
            }
        }
    }
}
