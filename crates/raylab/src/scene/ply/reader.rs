//! The ASCII and the binary encodings behind one interface ([`Reader`]), and what a reader
//! says where it fails: the element being read ([`Place`]) and what was expected there
//! ([`Expected`]).

use super::failure::Failure;
use super::header::{Element, Kind, Property, Scalar, Value};
use crate::scene::mesh_file::Location;

/// What the reader was about to read, for messages.
#[derive(Clone, Copy)]
pub(super) enum Expected<'a> {
    Value(&'a Property),
    Count(&'a Property),
    Items(&'a Property, u64),
}

impl Expected<'_> {
    pub(super) fn describe(self) -> String {
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
pub(super) struct Place<'a> {
    pub(super) element: &'a Element,
    pub(super) index: u64,
}

impl std::fmt::Display for Place<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} {}", self.element.name, self.index)
    }
}

/// The ASCII and the binary encodings, behind one interface.
pub(super) trait Reader {
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
