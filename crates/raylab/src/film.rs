//! The film: a linear RGB image that renders write into, and its conversion for display.

use glam::Vec3;
use image::RgbImage;

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

    /// 8-bit RGB as the lab displays it: each channel clamped to `[0, 1]`, times 255, rounded to
    /// the nearest level, no gamma.
    pub fn to_rgb8_clamped(&self) -> Result<RgbImage, FilmError> {
        self.to_rgb8(&Display::LAB)
    }
}

/// How a film's linear radiance becomes 8-bit pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Display {
    /// Radiance is multiplied by `2^exposure` first.
    pub exposure: f32,
    /// How values above 1 are brought into range.
    pub tone_map: ToneMap,
    /// sRGB-encode (the standard for PNG), or show linear values as the lab does.
    pub srgb: bool,
}

impl Display {
    /// The lab's display: clamped, linear, no exposure.
    pub const LAB: Display = Display { exposure: 0.0, tone_map: ToneMap::Clamp, srgb: false };
    /// Physically based renders: clamped, sRGB-encoded (what Mitsuba and pbrt write to PNG).
    pub const SRGB: Display = Display { exposure: 0.0, tone_map: ToneMap::Clamp, srgb: true };

    /// The 8-bit level of one linear channel ([`Display::LAB`]: exactly [`to_8bit_clamped`]).
    #[inline]
    pub fn level(&self, value: f32) -> u8 {
        if *self == Display::LAB {
            return to_8bit_clamped(value);
        }
        let value = value * self.exposure.exp2();
        let value = match self.tone_map {
            ToneMap::Clamp => value,
            ToneMap::Reinhard => value / (1.0 + value.max(0.0)),
            ToneMap::Aces => aces_filmic(value),
        };
        to_8bit_clamped(if self.srgb { srgb_encode(value) } else { value })
    }
}

/// Tone mapping operators.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ToneMap {
    /// Values above 1 are clipped.
    #[default]
    Clamp,
    /// `x / (1 + x)` per channel (Reinhard et al. 2002): nothing clips.
    Reinhard,
    /// Narkowicz's fit of the ACES filmic curve (2015): a film-like shoulder.
    Aces,
}

impl std::str::FromStr for ToneMap {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "clamp" => Ok(ToneMap::Clamp),
            "reinhard" => Ok(ToneMap::Reinhard),
            "aces" => Ok(ToneMap::Aces),
            _ => Err(format!("unknown tone mapping '{s}': expected clamp, reinhard or aces")),
        }
    }
}

/// Narkowicz's ACES filmic fit, `x(2.51x + 0.03) / (x(2.43x + 0.59) + 0.14)`.
#[inline]
fn aces_filmic(x: f32) -> f32 {
    let x = x.max(0.0);
    (x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)
}

/// The sRGB transfer function (IEC 61966-2-1) of a linear value in `[0, 1]` (clamped).
#[inline]
pub fn srgb_encode(linear: f32) -> f32 {
    let x = linear.clamp(0.0, 1.0);
    if x <= 0.003_130_8 { 12.92 * x } else { 1.055 * x.powf(1.0 / 2.4) - 0.055 }
}

/// One channel as the lab shows it: clamp to `[0, 1]`, ×255, round. NaN shows as 0.
#[inline]
pub fn to_8bit_clamped(value: f32) -> u8 {
    // NaN stays NaN here and `as` maps it to 0 (and NaN ≥ 0.5 is false).
    let scaled = value.clamp(0.0, 1.0) * 255.0;
    // Rounding half away from zero, as `f32::round`, without its library call (no SSE4.1 in the
    // baseline x86-64): the fraction `scaled − trunc(scaled)` is exact below 2²³.
    let whole = scaled as u8;
    whole + (scaled - whole as f32 >= 0.5) as u8
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
    fn conversion_rounds_exactly_as_f32_round() {
        // Every value whose ×255 is near a half, and a sweep of the whole range.
        let mut values: Vec<f32> = (0..=255 * 4).map(|i| (i as f32 + 0.5) / 4.0 / 255.0).collect();
        for level in 0..=255u32 {
            let half = (level as f32 + 0.5) / 255.0;
            let mut v = half;
            for _ in 0..4 {
                values.extend([v, f32::from_bits(v.to_bits() + 1)]);
                v = f32::from_bits(v.to_bits() - 1);
            }
        }
        values.extend((0..100_000).map(|i| i as f32 / 99_999.0));
        for v in values {
            let expected = (v.clamp(0.0, 1.0) * 255.0).round() as u8;
            assert_eq!(to_8bit_clamped(v), expected, "{v:e}");
        }
        assert_eq!(to_8bit_clamped(f32::INFINITY), 255);
        assert_eq!(to_8bit_clamped(f32::NEG_INFINITY), 0);
    }

    #[test]
    fn srgb_and_tone_maps_match_known_values() {
        assert_eq!(srgb_encode(0.0), 0.0);
        assert!((srgb_encode(1.0) - 1.0).abs() < 1e-6);
        // 18 % grey is sRGB level 118 (0.4614).
        assert!((srgb_encode(0.18) - 0.461_356).abs() < 1e-5, "{}", srgb_encode(0.18));
        assert!((srgb_encode(0.002) - 0.025_84).abs() < 1e-6);
        let d = Display { exposure: 1.0, tone_map: ToneMap::Clamp, srgb: false };
        assert_eq!(d.level(0.25), 128, "one stop up doubles");
        let reinhard = Display { tone_map: ToneMap::Reinhard, ..Display::LAB };
        assert_eq!(reinhard.level(1.0), 128);
        assert!(reinhard.level(100.0) < 255);
        let aces = Display { tone_map: ToneMap::Aces, ..Display::LAB };
        assert!(aces.level(0.0) == 0 && aces.level(100.0) == 255 && aces.level(0.5) > 100);
        assert_eq!(Display::SRGB.level(0.18), 118);
        assert_eq!("aces".parse::<ToneMap>(), Ok(ToneMap::Aces));
        assert!("filmic".parse::<ToneMap>().unwrap_err().contains("reinhard"));
    }

    #[test]
    fn bytes_are_formatted_readably() {
        assert_eq!(format_bytes(12), "12 bytes");
        assert_eq!(format_bytes(1536), "1.5 KiB");
        assert_eq!(format_bytes(3 << 30), "3.0 GiB");
    }
}
