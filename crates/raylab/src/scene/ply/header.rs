//! The PLY header: the format line, elements and their properties, and the check that the
//! data can hold what the header declares before anything is allocated.

use super::failure::{Failure, fail};
use crate::scene::mesh_file::{Location, quoted};

/// A PLY scalar type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Scalar {
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
    pub(super) fn from_name(name: &str) -> Option<Scalar> {
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

    pub(super) fn size_bytes(self) -> u64 {
        match self {
            Scalar::Int8 | Scalar::Uint8 => 1,
            Scalar::Int16 | Scalar::Uint16 => 2,
            Scalar::Int32 | Scalar::Uint32 | Scalar::Float32 => 4,
            Scalar::Float64 => 8,
        }
    }

    /// The range of an integer type, `None` for floating-point types.
    pub(super) fn integer_range(self) -> Option<(i64, i64)> {
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

    pub(super) fn name(self) -> &'static str {
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
pub(super) enum Value {
    Integer(i64),
    Real(f64),
}

impl Value {
    /// The value as `f32`, correctly rounded (`as` rounds to nearest).
    pub(super) fn to_f32(self) -> f32 {
        match self {
            Value::Integer(i) => i as f32,
            Value::Real(r) => r as f32,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Clone, Debug)]
pub(super) struct Property {
    pub(super) name: String,
    pub(super) kind: Kind,
}

#[derive(Clone, Debug)]
pub(super) struct Element {
    pub(super) name: String,
    pub(super) count: u64,
    pub(super) properties: Vec<Property>,
    /// The header line that declares it.
    pub(super) line: u64,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Encoding {
    Ascii,
    BinaryLittleEndian,
    BinaryBigEndian,
}

#[derive(Debug)]
pub(super) struct Header {
    pub(super) encoding: Encoding,
    pub(super) elements: Vec<Element>,
    /// The offset of the first byte after `end_header`'s line.
    pub(super) data_start: usize,
    /// The number of header lines, `end_header`'s included.
    pub(super) lines: u64,
}

/// The header's lines, each without its line ending, with their numbers and the offset after.
pub(super) fn header_lines(bytes: &[u8]) -> impl Iterator<Item = (u64, &[u8], usize)> {
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

pub(super) fn parse_header(bytes: &[u8]) -> Result<Header, Failure> {
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
pub(super) fn parse_property<'a>(words: &[&'a str]) -> Result<(Kind, &'a str), String> {
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
pub(super) fn min_bytes_per_element(element: &Element, encoding: Encoding) -> u64 {
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
pub(super) fn check_declared_counts(header: &Header, data_bytes: u64) -> Result<(), Failure> {
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
