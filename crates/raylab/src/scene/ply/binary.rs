//! PLY's binary encodings, little- and big-endian: values back to back, no separators.

use super::failure::Failure;
use super::header::Scalar;
use super::header::Value;
use super::reader::{Expected, Place, Reader};
use crate::scene::mesh_file::Location;

/// Reads the binary encodings; `BIG_ENDIAN` picks the byte order.
pub(super) struct BinaryReader<'a, const BIG_ENDIAN: bool> {
    pub(super) bytes: &'a [u8],
    pub(super) position: usize,
    pub(super) value_start: usize,
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

    pub(super) fn trailing_bytes(&self) -> Option<String> {
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
