//! How linear radiance becomes 8-bit pixels: exposure, a tone map, the sRGB encoding (or the
//! lab's plain clamp), and exact rounding.

use crate::color::linear_to_srgb;
use crate::unknown_name::UnknownName;

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
        to_8bit_clamped(if self.srgb { linear_to_srgb(value.clamp(0.0, 1.0)) } else { value })
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
    type Err = UnknownName;
    fn from_str(s: &str) -> Result<Self, UnknownName> {
        match s {
            "clamp" => Ok(ToneMap::Clamp),
            "reinhard" => Ok(ToneMap::Reinhard),
            "aces" => Ok(ToneMap::Aces),
            _ => Err(UnknownName::new("tone mapping", s, "clamp, reinhard or aces")),
        }
    }
}

/// Narkowicz's ACES filmic fit, `x(2.51x + 0.03) / (x(2.43x + 0.59) + 0.14)`.
#[inline]
fn aces_filmic(x: f32) -> f32 {
    let x = x.max(0.0);
    (x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)
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

/// [`to_8bit_clamped`] as a `u32`, by the same steps written without branches or saturating
/// casts, so that a loop of them is vectorized (the window's words, eight pixels at a time).
#[inline(always)]
pub(crate) fn to_8bit_clamped_lane(value: f32) -> u32 {
    // NaN and everything below 0 select 0 (NaN ≥ 0 is false), as `clamp` then `as` map them.
    let clamped = if value >= 0.0 { if value < 1.0 { value } else { 1.0 } } else { 0.0 };
    let scaled = clamped * 255.0;
    // SAFETY: `scaled` is finite and in `[0, 255]`, so truncating it fits an `i32` (the
    // truncation `as u8` makes).
    let whole = unsafe { scaled.to_int_unchecked::<i32>() };
    (whole + (scaled - whole as f32 >= 0.5) as i32) as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_lane_form_is_the_clamp_bit_for_bit() {
        let mut values = vec![
            f32::NAN,
            -f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            -0.0,
            0.0,
            1.0,
            -1.0,
            f32::MIN_POSITIVE,
            f32::MAX,
            1.0 + f32::EPSILON,
        ];
        // Around every level's half and across the range, with neighbours one bit away.
        for level in 0..=256u32 {
            let half = (level as f32 - 0.5) / 255.0;
            for k in -3i32..=3 {
                values.push(f32::from_bits((half.to_bits() as i32 + k) as u32));
            }
        }
        values.extend((0..100_000).map(|i| i as f32 / 90_000.0 - 0.05));
        for v in values {
            assert_eq!(to_8bit_clamped_lane(v), to_8bit_clamped(v) as u32, "{v:e}");
        }
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
    fn tone_maps_match_known_values() {
        let d = Display { exposure: 1.0, tone_map: ToneMap::Clamp, srgb: false };
        assert_eq!(d.level(0.25), 128, "one stop up doubles");
        let reinhard = Display { tone_map: ToneMap::Reinhard, ..Display::LAB };
        assert_eq!(reinhard.level(1.0), 128);
        assert!(reinhard.level(100.0) < 255);
        let aces = Display { tone_map: ToneMap::Aces, ..Display::LAB };
        assert!(aces.level(0.0) == 0 && aces.level(100.0) == 255 && aces.level(0.5) > 100);
        assert_eq!(Display::SRGB.level(0.18), 118);
        assert_eq!("aces".parse::<ToneMap>(), Ok(ToneMap::Aces));
        assert!("filmic".parse::<ToneMap>().unwrap_err().to_string().contains("reinhard"));
    }
}
