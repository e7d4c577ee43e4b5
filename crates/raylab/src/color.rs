//! The sRGB transfer function (IEC 61966-2-1), both ways: how 8-bit images store light.
//!
//! Textures decode their sRGB texels to linear light with [`srgb_to_linear`]; the film encodes
//! linear radiance for PNG output with [`linear_to_srgb`]. Every colour inside the renderer is
//! linear.

/// Decodes an sRGB-encoded value in `[0, 1]` to linear light.
#[inline]
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
}

/// Encodes linear light in `[0, 1]` as sRGB.
#[inline]
pub fn linear_to_srgb(c: f32) -> f32 {
    if c <= 0.003_130_8 { c * 12.92 } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 }
}

/// The luminance `Y` of a linear sRGB (Rec. 709) colour: `0.2126 r + 0.7152 g + 0.0722 b`
/// (Mitsuba 3's `luminance`, which weighs an environment map's texels for sampling).
#[inline]
pub fn luminance(c: glam::Vec3) -> f32 {
    0.212671 * c.x + 0.715160 * c.y + 0.072169 * c.z
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_matches_known_values() {
        assert_eq!(linear_to_srgb(0.0), 0.0);
        assert!((linear_to_srgb(1.0) - 1.0).abs() < 1e-6);
        // 18 % grey is sRGB level 118 (0.4614).
        assert!((linear_to_srgb(0.18) - 0.461_356).abs() < 1e-5, "{}", linear_to_srgb(0.18));
        assert!((linear_to_srgb(0.002) - 0.025_84).abs() < 1e-6);
        // The two halves meet where the standard joins them, both ways.
        assert!((srgb_to_linear(0.040_45) - 0.040_45 / 12.92).abs() < 1e-9);
        assert!((srgb_to_linear(0.5) - 0.214_041).abs() < 1e-6);
    }
}
