//! PLY's ASCII encoding: one element per line, values separated by white space.

use super::failure::{Failure, fail};
use super::header::Value;
use super::header::{Kind, Scalar};
use super::reader::{Expected, Place, Reader};
use crate::scene::mesh_file::{Location, quoted};

/// Reads the ASCII encoding: one element per line, values separated by spaces.
pub(super) struct AsciiReader<'a> {
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
    pub(super) fn new(bytes: &'a [u8], data_start: usize, header_lines: u64) -> Self {
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
    pub(super) fn trailing_line(&mut self) -> Option<u64> {
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
