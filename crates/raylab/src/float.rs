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
