//! Floating-point error analysis helpers.
//!
//! Robust ray tracing needs to know how far a computed value can be from the exact one. These are
//! the tools of Pharr, Jakob & Humphreys, *Physically Based Rendering* (4th ed.), §6.8 "Managing
//! Rounding Error": the unit roundoff, the `γ(n)` bound on `n` successive roundings, and stepping to
//! the neighbouring representable float.

/// Unit roundoff of `f32`: half the distance from 1 to the next float (2⁻²⁴).
pub const MACHINE_EPSILON: f32 = f32::EPSILON * 0.5;

/// Bound on the relative error of `n` successive floating-point operations:
/// `γ(n) = n·ε / (1 − n·ε)` (PBR 4th ed., eq. 6.16).
#[inline]
pub const fn gamma(n: u32) -> f32 {
    let n_eps = n as f32 * MACHINE_EPSILON;
    n_eps / (1.0 - n_eps)
}

/// `v.floor()`, bit for bit for every number (−0.0 stays −0.0; a NaN stays a NaN, its payload
/// unchanged, where a rounding instruction may quiet a signalling one), without a call: x86-64's
/// baseline has no rounding instruction (SSE4.1's `roundss`), so `f32::floor` there calls the C
/// library's `floorf`, which costs texture lookups a call per coordinate. A float of magnitude
/// 2²³ or more is an integer already; below, truncation through `i32` is exact, one less where it
/// rounded a negative value up, and the sign of `v` restores a zero's. Where the target has the
/// instruction, it is `f32::floor` itself.
#[inline(always)]
pub fn floor(v: f32) -> f32 {
    if cfg!(any(not(target_arch = "x86_64"), target_feature = "sse4.1")) {
        return v.floor();
    }
    // (NaN too.)
    if v.abs() >= 8_388_608.0 || v.is_nan() {
        return v;
    }
    let t = v as i32 as f32;
    let f = if t > v { t - 1.0 } else { t };
    f.copysign(v)
}

/// The smallest float greater than `v` (`+∞` stays `+∞`, NaN stays NaN).
#[inline]
pub fn next_float_up(v: f32) -> f32 {
    if v.is_infinite() && v > 0.0 || v.is_nan() {
        return v;
    }
    // −0.0 and +0.0 both step to the smallest positive subnormal.
    let v = if v == -0.0 { 0.0 } else { v };
    let bits = v.to_bits();
    let bits = if v >= 0.0 { bits + 1 } else { bits - 1 };
    f32::from_bits(bits)
}

/// The largest float less than `v` (`−∞` stays `−∞`, NaN stays NaN).
#[inline]
pub fn next_float_down(v: f32) -> f32 {
    if v.is_infinite() && v < 0.0 || v.is_nan() {
        return v;
    }
    let v = if v == 0.0 { -0.0 } else { v };
    let bits = v.to_bits();
    let bits = if v > 0.0 { bits - 1 } else { bits + 1 };
    f32::from_bits(bits)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `floor` is `f32::floor` to the bit, at every float near the edges (zeros, halves,
    /// integers, 2²³, the extremes, subnormals, infinities) and across the range; a NaN's floor
    /// is a NaN (whose payload a rounding instruction may change).
    #[test]
    fn floor_is_f32_floor_bit_for_bit() {
        let mut values = vec![
            0.0f32,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            1.5,
            -1.5,
            0.999_999_9,
            -0.999_999_9,
            8_388_607.5,
            -8_388_607.5,
            8_388_608.0,
            -8_388_608.0,
            8_388_609.0,
            -8_388_609.0,
            2_147_483_648.0,
            -2_147_483_648.0,
            f32::MAX,
            f32::MIN,
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
            1e-45,
            -1e-45,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            -f32::NAN,
        ];
        for base in [1.0f32, 7.0, 255.0, 4096.0, 1e6, 8_388_607.0, 1e7] {
            for v in [base, -base] {
                values.extend([v, next_float_up(v), next_float_down(v)]);
            }
        }
        let mut bits = 0x9e37_79b9u32;
        for _ in 0..100_000 {
            bits = bits.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            values.push(f32::from_bits(bits));
        }
        for v in values {
            match v.is_nan() {
                true => assert!(floor(v).is_nan()),
                false => assert_eq!(floor(v).to_bits(), v.floor().to_bits(), "floor({v:e})"),
            }
        }
    }

    #[test]
    fn next_float_steps_one_ulp() {
        assert_eq!(next_float_up(1.0), 1.0 + f32::EPSILON);
        assert_eq!(next_float_down(1.0), 1.0 - f32::EPSILON / 2.0);
        assert_eq!(next_float_up(-1.0), -1.0 + f32::EPSILON / 2.0);
        assert_eq!(next_float_down(-1.0), -1.0 - f32::EPSILON);
        assert_eq!(next_float_up(0.0), f32::from_bits(1));
        assert_eq!(next_float_up(-0.0), f32::from_bits(1));
        assert_eq!(next_float_down(0.0), -f32::from_bits(1));
        assert_eq!(next_float_down(-0.0), -f32::from_bits(1));
        assert_eq!(next_float_up(f32::INFINITY), f32::INFINITY);
        assert_eq!(next_float_down(f32::NEG_INFINITY), f32::NEG_INFINITY);
        assert_eq!(next_float_up(f32::MAX), f32::INFINITY);
    }

    #[test]
    fn gamma_bounds_grow_with_n() {
        assert!(gamma(1) > MACHINE_EPSILON && gamma(1) < 1.01 * MACHINE_EPSILON);
        assert!(gamma(3) > 3.0 * MACHINE_EPSILON);
        assert!(gamma(7) < 8.0 * MACHINE_EPSILON);
    }
}
