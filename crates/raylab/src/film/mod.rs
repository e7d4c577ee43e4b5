//! The film: a linear RGB image that renders write into, and its conversion for display
//! ([`Display`]: exposure, tone mapping, sRGB, 8 bits).

use glam::Vec3;
#[cfg(feature = "io")]
use image::RgbImage;

mod display;

pub(crate) use display::to_8bit_clamped_lane;
pub use display::{Display, ToneMap, to_8bit_clamped};

/// Why a film cannot be made.
#[derive(Clone, Debug, thiserror::Error, PartialEq, Eq)]
pub enum FilmError {
    /// Width or height is zero.
    #[error("image size {width}×{height} is empty: width and height must be at least 1")]
    Empty {
        /// Width asked for.
        width: u32,
        /// Height asked for.
        height: u32,
    },
    /// The memory for the pixels could not be had.
    #[error("image size {width}×{height} needs {} of memory, which cannot be allocated", format_bytes(*.bytes))]
    OutOfMemory {
        /// Width asked for.
        width: u32,
        /// Height asked for.
        height: u32,
        /// Bytes needed.
        bytes: u64,
    },
}

/// `bytes` in the largest binary unit that keeps a number above one: `"1.5 GiB"`.
pub fn format_bytes(bytes: u64) -> String {
    const UNITS: [&str; 6] = ["bytes", "KiB", "MiB", "GiB", "TiB", "PiB"];
    let mut value = bytes as f64;
    let mut unit = 0;
    while value >= 1024.0 && unit + 1 < UNITS.len() {
        value /= 1024.0;
        unit += 1;
    }
    if unit == 0 { format!("{bytes} bytes") } else { format!("{value:.1} {}", UNITS[unit]) }
}

/// A `width×height` grid of linear RGB values, row by row from the top-left.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    width: u32,
    height: u32,
    pixels: Vec<Vec3>,
}

impl Film {
    /// Bytes of memory a render of this size needs: the film and its 8-bit copy for output.
    pub fn bytes_needed(width: u32, height: u32) -> u64 {
        (width as u64 * height as u64).saturating_mul(size_of::<Vec3>() as u64 + 3)
    }

    /// A black film. Fails cleanly, rather than aborting, when the memory is not there.
    pub fn new(width: u32, height: u32) -> Result<Film, FilmError> {
        if width == 0 || height == 0 {
            return Err(FilmError::Empty { width, height });
        }
        let count = width as u64 * height as u64;
        let out_of_memory =
            FilmError::OutOfMemory { width, height, bytes: Film::bytes_needed(width, height) };
        let count = usize::try_from(count).map_err(|_| out_of_memory.clone())?;
        let mut pixels = Vec::new();
        pixels.try_reserve_exact(count).map_err(|_| out_of_memory)?;
        pixels.resize(count, Vec3::ZERO);
        Ok(Film { width, height, pixels })
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The value of pixel `(x, y)`.
    #[inline]
    pub fn pixel(&self, x: u32, y: u32) -> Vec3 {
        self.pixels[y as usize * self.width as usize + x as usize]
    }

    /// All pixels, row by row.
    pub fn pixels(&self) -> &[Vec3] {
        &self.pixels
    }

    /// All pixels, mutable, row by row.
    pub fn pixels_mut(&mut self) -> &mut [Vec3] {
        &mut self.pixels
    }

    #[cfg(feature = "io")]
    /// 8-bit RGB through a [`Display`] transform.
    pub fn to_rgb8(&self, display: &Display) -> Result<RgbImage, FilmError> {
        let mut bytes = Vec::new();
        bytes.try_reserve_exact(self.pixels.len() * 3).map_err(|_| FilmError::OutOfMemory {
            width: self.width,
            height: self.height,
            bytes: Film::bytes_needed(self.width, self.height),
        })?;
        bytes.extend(self.pixels.iter().flat_map(|p| p.to_array().map(|v| display.level(v))));
        Ok(RgbImage::from_raw(self.width, self.height, bytes)
            .expect("buffer has width×height×3 bytes"))
    }

    /// A film from linear pixels, row by row from the top-left.
    ///
    /// # Panics
    /// If `pixels` does not hold `width×height` values.
    pub fn from_pixels(width: u32, height: u32, pixels: Vec<Vec3>) -> Film {
        assert_eq!(pixels.len(), width as usize * height as usize, "a value per pixel");
        Film { width, height, pixels }
    }

    /// The pixels, row by row from the top-left, without copying them.
    pub fn into_pixels(self) -> Vec<Vec3> {
        self.pixels
    }

    #[cfg(feature = "io")]
    /// 8-bit RGB as the lab displays it: each channel clamped to `[0, 1]`, times 255, rounded to
    /// the nearest level, no gamma.
    pub fn to_rgb8_clamped(&self) -> Result<RgbImage, FilmError> {
        self.to_rgb8(&Display::LAB)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_and_huge_films_are_errors_not_panics() {
        assert_eq!(Film::new(0, 10), Err(FilmError::Empty { width: 0, height: 10 }));
        assert!(matches!(Film::new(u32::MAX, u32::MAX), Err(FilmError::OutOfMemory { .. })));
        let message = Film::new(u32::MAX, u32::MAX).unwrap_err().to_string();
        assert!(message.contains("EiB") || message.contains("PiB"), "{message}");
    }

    #[test]
    fn conversion_clamps_without_gamma() {
        assert_eq!(to_8bit_clamped(-1.0), 0);
        assert_eq!(to_8bit_clamped(0.5), 128);
        assert_eq!(to_8bit_clamped(0.2), 51);
        assert_eq!(to_8bit_clamped(7.0), 255);
        assert_eq!(to_8bit_clamped(f32::NAN), 0);
        let mut film = Film::new(2, 1).unwrap();
        film.pixels_mut()[1] = Vec3::new(1.5, 0.75, 0.0);
        let rgb = film.to_rgb8_clamped().unwrap();
        assert_eq!(rgb.get_pixel(1, 0).0, [255, 191, 0]);
        assert_eq!(rgb.get_pixel(0, 0).0, [0, 0, 0]);
    }

    #[test]
    fn bytes_are_formatted_readably() {
        assert_eq!(format_bytes(12), "12 bytes");
        assert_eq!(format_bytes(1536), "1.5 KiB");
        assert_eq!(format_bytes(3 << 30), "3.0 GiB");
    }
}
