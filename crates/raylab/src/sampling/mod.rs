//! Sampling: warps from the unit square to the shapes a renderer samples, each beside its
//! density, and the [`Sampler`] that feeds them.
//!
//! The shape follows pbrt-v4's `util/sampling.h`: every warp is a small pure function
//! `square_to_*(u) -> point` with its `*_pdf(point)` right below it, so that the pair can be read
//! and tested together (the chi-square tests in this module's tests check every warp against its
//! density). Densities are per unit solid angle for directions and per unit area for points.
//!
//! - [`sample_offset`]: where sample `k` of a pixel goes through it (the lab's centre, then R₂).
//! - [`Sampler`]: the numbers behind every random decision of a path, derived from
//!   (seed, pixel, sample index) alone, so pictures do not depend on threads or tiling.

mod multijitter;
mod pcg;
mod piecewise;
mod sampler;
mod sobol;

#[cfg(test)]
pub(crate) mod chi2;

use std::f32::consts::{FRAC_1_PI, FRAC_PI_2, FRAC_PI_4, PI};

use glam::{DVec3, Vec2, Vec3};

pub use multijitter::Grid;
pub use pcg::{Pcg32, mix64};
pub use piecewise::{PiecewiseConstant1D, PiecewiseConstant2D};
pub use sampler::{Sampler, SamplerKind, VertexNumbers};

/// Where sample `index` of pixel `(x, y)` goes through the pixel, in `[0, 1)²` from its top-left
/// corner: the lab's pixel sampling.
///
/// Sample 0 is the centre `(½, ½)`. Later samples follow the R₂ low-discrepancy sequence
/// (Roberts 2018: `{s + k·(1/φ₂, 1/φ₂²)}` with φ₂ the plastic number), shifted per pixel by a
/// hash of its coordinates so that neighbouring pixels do not share one pattern. Any prefix of
/// the sequence covers the pixel evenly, so a picture refined one sample at a time improves at
/// every step.
pub fn sample_offset(x: u32, y: u32, index: u32) -> Vec2 {
    if index == 0 {
        return Vec2::splat(0.5);
    }
    // 1/φ₂ and 1/φ₂², where φ₂ ≈ 1.3247 solves x³ = x + 1.
    const ALPHA: [f64; 2] = [0.754_877_666_246_692_7, 0.569_840_290_998_053_3];
    let hash = pixel_hash(x, y);
    let shift = [
        (hash >> 40) as f64 / (1u64 << 24) as f64,
        (hash & 0xff_ffff) as f64 / (1u64 << 24) as f64,
    ];
    let k = index as f64;
    let coordinate = |i: usize| {
        let value = (shift[i] + k * ALPHA[i]).fract() as f32;
        // Rounding to f32 can give exactly 1.0; keep the sample inside its pixel.
        value.min(ONE_MINUS_EPSILON)
    };
    Vec2::new(coordinate(0), coordinate(1))
}

/// The largest `f32` below 1: samples live in `[0, 1)`.
pub const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// A well-mixed 64-bit hash of a pixel's coordinates (SplitMix64's finalizer).
pub fn pixel_hash(x: u32, y: u32) -> u64 {
    mix64(((x as u64) << 32 | y as u64).wrapping_add(0x9e37_79b9_7f4a_7c15))
}

// ---------------------------------------------------------------------------------------------
// Disks and hemispheres.

/// A point on the unit disk, uniform by area: Shirley & Chiu's concentric map, which keeps
/// strata compact (a stratified square gives a stratified disk).
#[inline]
pub fn square_to_uniform_disk_concentric(u: Vec2) -> Vec2 {
    let offset = 2.0 * u - Vec2::ONE;
    if offset == Vec2::ZERO {
        return Vec2::ZERO;
    }
    // θ = π/4·(y/x) about the x axis, π/2 − π/4·(x/y) about the y axis: both from the sine
    // and cosine of an angle within ±π/4, whose polynomials are exact to a float or two.
    if offset.x.abs() > offset.y.abs() {
        let (sin, cos) = sin_cos_within_quarter_pi(FRAC_PI_4 * (offset.y / offset.x));
        offset.x * Vec2::new(cos, sin)
    } else {
        let (sin, cos) = sin_cos_within_quarter_pi(FRAC_PI_4 * (offset.x / offset.y));
        offset.y * Vec2::new(sin, cos)
    }
}

/// `(sin a, cos a)` for `|a| ≤ π/4`, by the minimax polynomials of Cephes' `sinf` and `cosf`
/// (Moshier, *Methods and Programs for Mathematical Functions*, 1989) without their range
/// reduction:
///
/// `sin a ≈ a + a³(−1.6666654611·10⁻¹ + a²(8.3321608736·10⁻³ − 1.9515295891·10⁻⁴a²))`,
/// `cos a ≈ 1 − a²/2 + a⁴(4.166664568298827·10⁻² + a²(−1.388731625493765·10⁻³ +
/// 2.443315711809948·10⁻⁵a²))`,
///
/// within 2·10⁻⁷ of the true values (`tests.rs` checks every float of the range against double
/// precision). Straight-line arithmetic, so a loop over lanes runs it sixteen lanes per
/// instruction, and the path tracer's lanes and its scalar twin get the same bits.
#[inline(always)]
pub fn sin_cos_within_quarter_pi(a: f32) -> (f32, f32) {
    let z = a * a;
    let sin = ((-1.951_529_6e-4 * z + 8.332_161e-3) * z - 1.666_665_5e-1) * z * a + a;
    let cos = ((2.443_315_7e-5 * z - 1.388_731_6e-3) * z + 4.166_664_6e-2) * z * z - 0.5 * z + 1.0;
    (sin, cos)
}

/// `(sin 2πt, cos 2πt)` for a number of turns `t` in `[0, 1]` (the samplers' numbers): the
/// nearest quarter turn `q` is split off exactly (`4t − q` is exact), the polynomials of
/// [`sin_cos_within_quarter_pi`] take the rest (within ±π/4, give or take an ulp at the
/// eighths), and the quarter turns swap and negate the pair. Within 3·10⁻⁷ of double
/// precision over `[0, 1]` (`tests.rs`); straight-line arithmetic, so the lanes of the path
/// tracer run it sixteen at a time with the scalar code's bits (where `f32::sin_cos`, a call
/// into the C library, would keep a loop scalar). Negative, huge or NaN `t` give a pair that
/// is not the sine and cosine (the integer conversion truncates toward zero and saturates).
#[inline(always)]
pub fn sin_cos_turns(t: f32) -> (f32, f32) {
    let quarters = 4.0 * t;
    // `floor` by truncation (the same for `t ≥ −1/8`): a plain conversion even on the
    // baseline instruction set, where `floor` is a call into the C library.
    let quadrant = (quarters + 0.5) as i32;
    let q = quadrant as f32;
    let (sin, cos) = sin_cos_within_quarter_pi((quarters - q) * FRAC_PI_2);
    let (sin, cos) = if quadrant & 1 != 0 { (cos, -sin) } else { (sin, cos) };
    if quadrant & 2 != 0 { (-sin, -cos) } else { (sin, cos) }
}

/// `atan2(y, x)` in `[−π, π]` by a polynomial, within 3·10⁻⁷ of double precision (`tests.rs`
/// checks every octant): the octant's reduction to `atan(a)`, `a = min/max ∈ [0, 1]`, and there
/// `a·p(a²)` with `p` of degree 7, fitted for least maximum error. About five times as fast as
/// the C library's `atan2f`, which environment maps call twice for every ray that leaves the
/// scene. `(0, 0)` gives 0; NaN gives NaN.
#[inline]
pub fn atan2_polynomial(y: f32, x: f32) -> f32 {
    const C: [f32; 8] = [
        0.999_999_34,
        -0.333_298_6,
        0.199_465_66,
        -0.139_086_3,
        0.096_421_96,
        -0.055_912_3,
        0.021_862_935,
        -0.004_054_56,
    ];
    let (ax, ay) = (x.abs(), y.abs());
    let (small, large) = if ay > ax { (ax, ay) } else { (ay, ax) };
    let a = if large > 0.0 { small / large } else { small };
    let z = a * a;
    let mut p = C[7];
    for &c in C[..7].iter().rev() {
        p = p * z + c;
    }
    let mut r = a * p;
    if ay > ax {
        r = FRAC_PI_2 - r;
    }
    if x < 0.0 {
        r = PI - r;
    }
    if y < 0.0 { -r } else { r }
}

/// Density of [`square_to_uniform_disk_concentric`] per unit area: `1/π` inside the disk.
#[inline]
pub fn uniform_disk_pdf(p: Vec2) -> f32 {
    if p.length_squared() <= 1.0 { FRAC_1_PI } else { 0.0 }
}

/// A direction in the hemisphere `z > 0` with density `cos θ / π` (Malley's method: a
/// concentric disk point lifted to the hemisphere).
#[inline]
pub fn square_to_cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = square_to_uniform_disk_concentric(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

/// Density of [`square_to_cosine_hemisphere`] per unit solid angle: `cos θ / π` for `z > 0`.
#[inline]
pub fn cosine_hemisphere_pdf(w: Vec3) -> f32 {
    if w.z > 0.0 { w.z * FRAC_1_PI } else { 0.0 }
}

/// A direction in the hemisphere `z ≥ 0`, uniform by solid angle.
#[inline]
pub fn square_to_uniform_hemisphere(u: Vec2) -> Vec3 {
    let z = u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (sin, cos) = (2.0 * PI * u.y).sin_cos();
    Vec3::new(r * cos, r * sin, z)
}

/// Density of [`square_to_uniform_hemisphere`]: `1/2π` for `z ≥ 0`.
#[inline]
pub fn uniform_hemisphere_pdf(w: Vec3) -> f32 {
    if w.z >= 0.0 { 0.5 * FRAC_1_PI } else { 0.0 }
}

/// A direction on the unit sphere, uniform by solid angle.
#[inline]
pub fn square_to_uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    // The polynomial sine and cosine (the path tracer's lanes sample the environment too).
    let (sin, cos) = sin_cos_turns(u.y);
    Vec3::new(r * cos, r * sin, z)
}

/// Density of [`square_to_uniform_sphere`]: `1/4π` everywhere.
#[inline]
pub fn uniform_sphere_pdf(_w: Vec3) -> f32 {
    0.25 * FRAC_1_PI
}

/// A direction within angle `α` of +z, uniform by solid angle, given `1 − cos α` (which a
/// small cone, the sun's, needs without cancellation): `1 − cos θ = u.x·(1 − cos α)`, and
/// `sin θ` from it without cancellation either.
#[inline]
pub fn square_to_uniform_cone(u: Vec2, one_minus_cos_alpha: f32) -> Vec3 {
    let one_minus_cos = u.x * one_minus_cos_alpha;
    let sin_theta = (one_minus_cos * (2.0 - one_minus_cos)).max(0.0).sqrt();
    let (sin, cos) = sin_cos_turns(u.y);
    Vec3::new(sin_theta * cos, sin_theta * sin, 1.0 - one_minus_cos)
}

/// Density of [`square_to_uniform_cone`] inside its cone: `1 / (2π (1 − cos α))`.
#[inline]
pub fn uniform_cone_pdf(one_minus_cos_alpha: f32) -> f32 {
    1.0 / (2.0 * PI * one_minus_cos_alpha)
}

/// A point of `[0, 1)` with density proportional to the line from `a` at 0 to `b` at 1 (both
/// not negative, not both zero): the root of the CDF's quadratic, in the form without
/// cancellation (pbrt-v4's `SampleLinear`, PBR 4th ed.'s "Sampling a Linear Function").
#[inline]
pub fn sample_linear(u: f32, a: f32, b: f32) -> f32 {
    if u == 0.0 && a == 0.0 {
        return 0.0;
    }
    let x = u * (a + b) / (a + (a * a + u * (b * b - a * a)).max(0.0).sqrt());
    x.min(ONE_MINUS_EPSILON)
}

/// Density of [`sample_linear`] at `x ∈ [0, 1]`: `2 ((1 − x) a + x b) / (a + b)`.
#[inline]
pub fn linear_pdf(x: f32, a: f32, b: f32) -> f32 {
    2.0 * ((1.0 - x) * a + x * b) / (a + b)
}

/// A point of `[0, 1)²` with density proportional to the bilinear interpolant of corner values
/// `[f(0, 0), f(1, 0), f(0, 1), f(1, 1)]` (not negative, not all zero): `y` from the
/// marginal, a line, then `x` from the line at that `y` (pbrt-v4's `SampleBilinear`; Mitsuba 3
/// samples environment maps within texels so).
#[inline]
pub fn sample_bilinear(u: Vec2, f: [f32; 4]) -> Vec2 {
    let y = sample_linear(u.y, f[0] + f[1], f[2] + f[3]);
    let x = sample_linear(u.x, (1.0 - y) * f[0] + y * f[2], (1.0 - y) * f[1] + y * f[3]);
    Vec2::new(x, y)
}

/// Density of [`sample_bilinear`] at `p ∈ [0, 1]²`.
#[inline]
pub fn bilinear_pdf(p: Vec2, f: [f32; 4]) -> f32 {
    let sum = f[0] + f[1] + f[2] + f[3];
    if sum <= 0.0 {
        return 0.0;
    }
    let (x, y) = (p.x, p.y);
    4.0 * ((1.0 - x) * (1.0 - y) * f[0]
        + x * (1.0 - y) * f[1]
        + (1.0 - x) * y * f[2]
        + x * y * f[3])
        / sum
}

// ---------------------------------------------------------------------------------------------
// Triangles.

/// Barycentric coordinates `(b0, b1, b2)` of a point uniform by area on a triangle (Heitz 2019,
/// "A Low-Distortion Map Between Triangle and Square": no square root, and it keeps strata).
#[inline]
pub fn square_to_uniform_triangle(u: Vec2) -> [f32; 3] {
    let (b0, b1) = if u.x < u.y {
        let b0 = u.x / 2.0;
        (b0, u.y - b0)
    } else {
        let b1 = u.y / 2.0;
        (u.x - b1, b1)
    };
    [b0, b1, 1.0 - b0 - b1]
}

/// Density of a point uniform on a triangle of `area`, per unit area: `1/area`.
#[inline]
pub fn uniform_triangle_pdf(area: f32) -> f32 {
    if area > 0.0 { 1.0 / area } else { 0.0 }
}

/// A direction from `p` toward the triangle `v`, uniform in the solid angle the triangle
/// subtends (Arvo, "Stratified Sampling of Spherical Triangles", SIGGRAPH 1995; in the form of
/// PBR 4th ed. §6.5.4), with the barycentric coordinates of the point it points at and the
/// density `1/Ω`. `None` when the triangle subtends no solid angle from `p` (degenerate, or `p`
/// in its plane). Computed in double precision.
pub fn sample_spherical_triangle(v: [Vec3; 3], p: Vec3, u: Vec2) -> Option<([f32; 3], f32)> {
    let [v0, v1, v2] = v.map(|v| v.as_dvec3());
    let p = p.as_dvec3();
    let (a, b, c) = ((v0 - p).normalize(), (v1 - p).normalize(), (v2 - p).normalize());
    let (n_ab, n_bc, n_ca) = (a.cross(b), b.cross(c), c.cross(a));
    if n_ab.length_squared() == 0.0 || n_bc.length_squared() == 0.0 || n_ca.length_squared() == 0.0
    {
        return None;
    }
    let (n_ab, n_bc, n_ca) = (n_ab.normalize(), n_bc.normalize(), n_ca.normalize());
    let alpha = angle_between(n_ab, -n_ca);
    let beta = angle_between(n_bc, -n_ab);
    let gamma = angle_between(n_ca, -n_bc);
    let area_plus_pi = alpha + beta + gamma;
    let area = area_plus_pi - std::f64::consts::PI;
    if area.is_nan() || area <= 0.0 || !area.is_finite() {
        return None;
    }
    // The sub-triangle's area, uniform in [0, area], fixes the point c' on the arc from a to c.
    let sampled = std::f64::consts::PI + u.x as f64 * area;
    let (sin_alpha, cos_alpha) = alpha.sin_cos();
    let (sin_s, cos_s) = sampled.sin_cos();
    let sin_phi = sin_s * cos_alpha - cos_s * sin_alpha;
    let cos_phi = cos_s * cos_alpha + sin_s * sin_alpha;
    let k1 = cos_phi + cos_alpha;
    let k2 = sin_phi - sin_alpha * a.dot(b);
    let cos_bp = ((k2 + (k2 * cos_phi - k1 * sin_phi) * cos_alpha)
        / ((k2 * sin_phi + k1 * cos_phi) * sin_alpha))
        .clamp(-1.0, 1.0);
    let sin_bp = (1.0 - cos_bp * cos_bp).max(0.0).sqrt();
    let cp = cos_bp * a + sin_bp * (c - c.dot(a) * a).normalize();
    // Then a point on the arc from b to c', uniform in the remaining area.
    let cos_theta = 1.0 - u.y as f64 * (1.0 - cp.dot(b));
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let w = cos_theta * b + sin_theta * (cp - cp.dot(b) * b).normalize();
    // The barycentric coordinates where the direction meets the triangle.
    let (e1, e2) = (v1 - v0, v2 - v0);
    let s1 = w.cross(e2);
    let divisor = s1.dot(e1);
    if divisor == 0.0 || !w.is_finite() {
        return None;
    }
    let s = p - v0;
    let mut b1 = (s.dot(s1) / divisor).clamp(0.0, 1.0);
    let mut b2 = (w.dot(s.cross(e1)) / divisor).clamp(0.0, 1.0);
    if b1 + b2 > 1.0 {
        let sum = b1 + b2;
        b1 /= sum;
        b2 /= sum;
    }
    Some(([(1.0 - b1 - b2) as f32, b1 as f32, b2 as f32], (1.0 / area) as f32))
}

/// The solid angle a triangle subtends from `p` (Van Oosterom and Strackee 1983).
pub fn spherical_triangle_area(v: [Vec3; 3], p: Vec3) -> f32 {
    let [a, b, c] = v.map(|v| (v.as_dvec3() - p.as_dvec3()).normalize());
    let numerator = a.dot(b.cross(c)).abs();
    let denominator = 1.0 + a.dot(b) + b.dot(c) + c.dot(a);
    (2.0 * numerator.atan2(denominator)) as f32
}

/// The angle between two unit vectors, accurate near 0 and π.
fn angle_between(v1: DVec3, v2: DVec3) -> f64 {
    if v1.dot(v2) < 0.0 {
        std::f64::consts::PI - 2.0 * ((v1 + v2).length() / 2.0).min(1.0).asin()
    } else {
        2.0 * ((v2 - v1).length() / 2.0).min(1.0).asin()
    }
}

// ---------------------------------------------------------------------------------------------
// Filters.

/// An offset from a pixel's centre distributed as a Gaussian of standard deviation `sigma`,
/// truncated at `radius` on each axis (by inverting the truncated normal's distribution per axis).
pub fn square_to_truncated_gaussian(u: Vec2, sigma: f32, radius: f32) -> Vec2 {
    let axis = |u: f32| {
        let edge = erf(radius / (sigma * std::f32::consts::SQRT_2));
        sigma * std::f32::consts::SQRT_2 * erf_inv((2.0 * u - 1.0) * edge)
    };
    Vec2::new(axis(u.x), axis(u.y))
}

/// The error function, to about 1e-7 (Abramowitz & Stegun 7.1.26 is too coarse; this is the
/// rational approximation of W. J. Cody as used by many numeric libraries, evaluated in `f64`).
pub fn erf(x: f32) -> f32 {
    libm_erf(x as f64) as f32
}

/// `erf` in double precision by its Taylor series near 0 and a continued fraction for the
/// complement further out: accurate to ~1e-12 over the line.
fn libm_erf(x: f64) -> f64 {
    let a = x.abs();
    let value = if a < 2.5 {
        // erf(x) = 2/√π Σ (−1)ⁿ x^(2n+1) / (n! (2n+1))
        let mut term = a;
        let mut sum = a;
        let x2 = a * a;
        let mut n = 0.0;
        while term.abs() > 1e-17 * sum.abs() {
            n += 1.0;
            term *= -x2 / n;
            sum += term / (2.0 * n + 1.0);
        }
        sum * std::f64::consts::FRAC_2_SQRT_PI
    } else {
        // erfc(x) = exp(−x²)/√π · 1/(x + 1/2/(x + 1/(x + 3/2/(x + …)))) (Lentz's method).
        let tiny = 1e-300;
        let mut f = a;
        let mut c = a;
        let mut d = 0.0;
        for k in 1..200 {
            let coefficient = k as f64 / 2.0;
            d = a + coefficient * d;
            d = if d == 0.0 { tiny } else { d };
            c = a + coefficient / c;
            c = if c == 0.0 { tiny } else { c };
            d = 1.0 / d;
            let delta = c * d;
            f *= delta;
            if (delta - 1.0).abs() < 1e-16 {
                break;
            }
        }
        1.0 - (-a * a).exp() / (f * std::f64::consts::PI.sqrt())
    };
    value.copysign(x)
}

/// The inverse error function on `(−1, 1)`: Giles' single-precision approximation ("Approximating
/// the erfinv function", GPU Computing Gems, 2011), then two Newton steps in `f64`.
pub fn erf_inv(y: f32) -> f32 {
    let y = y.clamp(-ONE_MINUS_EPSILON, ONE_MINUS_EPSILON) as f64;
    let mut w = -((1.0 - y) * (1.0 + y)).ln();
    let mut x = if w < 5.0 {
        w -= 2.5;
        let mut p = 2.810_226_36e-08;
        for c in [
            3.432_739_39e-07,
            -3.523_387_7e-06,
            -4.391_506_54e-06,
            0.000_218_580_87,
            -0.001_253_725_03,
            -0.004_177_681_64,
            0.246_640_727,
            1.501_409_41,
        ] {
            p = c + p * w;
        }
        p * y
    } else {
        w = w.sqrt() - 3.0;
        let mut p = -0.000_200_214_257;
        for c in [
            0.000_100_950_558,
            0.001_349_343_22,
            -0.003_673_428_44,
            0.005_739_507_73,
            -0.007_622_461_3,
            0.009_438_870_47,
            1.001_674_06,
            2.832_976_82,
        ] {
            p = c + p * w;
        }
        p * y
    };
    for _ in 0..2 {
        let error = libm_erf(x) - y;
        x -= error / (std::f64::consts::FRAC_2_SQRT_PI * (-x * x).exp());
    }
    x as f32
}

// ---------------------------------------------------------------------------------------------
// Discrete choices.

/// The most CDF entries [`DiscreteDistribution`] counts rather than searches.
const SMALL_DISTRIBUTION: usize = 16;

/// A choice among `n` items with probabilities proportional to given weights, by a binary
/// search of the cumulative distribution (Mitsuba's `DiscreteDistribution`; a count for a few
/// items).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DiscreteDistribution {
    /// `cdf[i]` = the sum of the weights before item `i`, normalized; `cdf[n] = 1`. Item `i`'s
    /// probability is the step `cdf[i + 1] − cdf[i]`: exactly what sampling gives it, and no
    /// second table (an environment map's rows hold millions of items).
    cdf: Vec<f32>,
}

impl DiscreteDistribution {
    /// A distribution over weights that are finite and not negative; `None` if they sum to 0.
    pub fn new(weights: &[f32]) -> Option<DiscreteDistribution> {
        let total: f64 = weights.iter().map(|&w| w.max(0.0) as f64).sum();
        if !(total > 0.0 && total.is_finite()) {
            return None;
        }
        let mut cdf = Vec::with_capacity(weights.len() + 1);
        let mut sum = 0.0f64;
        cdf.push(0.0);
        for &w in weights {
            sum += w.max(0.0) as f64;
            cdf.push((sum / total) as f32);
        }
        *cdf.last_mut().expect("pushed") = 1.0;
        Some(DiscreteDistribution { cdf })
    }

    /// The number of items.
    pub fn len(&self) -> usize {
        self.cdf.len().saturating_sub(1)
    }

    /// How many entries of the CDF are at most `u` (it ascends, so they lead): a binary search,
    /// or for a few items (a scene's handful of light triangles) a count without branches,
    /// which random numbers cannot mispredict. Both give the same number.
    #[inline]
    fn below_or_at(&self, u: f32) -> usize {
        if self.cdf.len() <= SMALL_DISTRIBUTION {
            self.cdf.iter().map(|&c| usize::from(c <= u)).sum()
        } else {
            self.cdf.partition_point(|&c| c <= u)
        }
    }

    /// Whether there are no items.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The probability of item `i`.
    #[inline]
    pub fn pmf(&self, i: usize) -> f32 {
        self.cdf[i + 1] - self.cdf[i]
    }

    /// [`pmf`](Self::pmf) without bounds checks.
    ///
    /// # Safety
    /// `i` must be below [`len`](Self::len).
    #[inline(always)]
    pub(crate) unsafe fn pmf_unchecked(&self, i: usize) -> f32 {
        // SAFETY: the caller's `i < len()`: the CDF holds `len() + 1` entries.
        unsafe { *self.cdf.get_unchecked(i + 1) - *self.cdf.get_unchecked(i) }
    }

    /// The item that `u ∈ [0, 1)` picks, its probability, and `u` rescaled to `[0, 1)` within the
    /// item's interval (so it can be used again).
    #[inline]
    pub fn sample(&self, u: f32) -> (usize, f32, f32) {
        let (i, pmf, start) = self.pick(u);
        (i, pmf, rescaled(u, start, pmf))
    }

    /// The item that `u ∈ [0, 1)` picks, its probability, and where its interval starts:
    /// [`sample`](Self::sample) without the rescaling, for callers that rescale many at once
    /// ([`rescaled`]).
    #[inline]
    pub fn pick(&self, u: f32) -> (usize, f32, f32) {
        self.pick_at(self.below_or_at(u))
    }

    /// [`pick`](Self::pick) given how many entries of the CDF are at most `u`.
    #[inline(always)]
    fn pick_at(&self, below_or_at: usize) -> (usize, f32, f32) {
        // The last i with cdf[i] <= u, skipping items of probability zero.
        let i = (below_or_at.max(1) - 1).min(self.len() - 1);
        (i, self.pmf(i), self.cdf[i])
    }

    /// The CDF: `len() + 1` ascending entries from 0 to 1.
    #[inline]
    pub(crate) fn cdf(&self) -> &[f32] {
        &self.cdf
    }

    /// [`sample`](Self::sample) for each of `us`, of several distributions of the same length
    /// (`distributions[l]` for `us[l]`): the same items, probabilities and rescaled numbers, the
    /// binary searches taken in step ([`below_or_at_each`]) so that their loads overlap.
    ///
    /// # Panics
    /// If the slices differ in length, hold more than [`SEARCH_LANES`], or the distributions
    /// differ in length.
    pub fn sample_each(
        distributions: &[&DiscreteDistribution],
        us: &[f32],
        out: &mut [(usize, f32, f32)],
    ) {
        let lanes = us.len();
        assert!(lanes <= SEARCH_LANES && distributions.len() == lanes, "a table per number");
        let (mut counts, mut cdfs) = ([0usize; SEARCH_LANES], [&[][..]; SEARCH_LANES]);
        for (cdf, distribution) in cdfs.iter_mut().zip(distributions) {
            *cdf = distribution.cdf();
        }
        below_or_at_each(&cdfs[..lanes], us, &mut counts[..lanes]);
        for (l, slot) in out.iter_mut().enumerate() {
            let (i, pmf, start) = distributions[l].pick_at(counts[l]);
            *slot = (i, pmf, rescaled(us[l], start, pmf));
        }
    }
}

/// The most searches [`below_or_at_each`] takes in step.
pub const SEARCH_LANES: usize = 16;

/// For each `l`, how many entries of `cdfs[l]` are at most `us[l]` (each ascending, all of one
/// length): what `partition_point(|c| c <= u)` counts, by a binary search without branches
/// whose steps the lanes take together, so that their loads, which depend on the last step's,
/// overlap one another rather than each waiting for its own.
///
/// # Panics
/// If the slices differ in length, hold more than [`SEARCH_LANES`] or no entry, or the tables
/// differ in length.
#[inline]
pub fn below_or_at_each(cdfs: &[&[f32]], us: &[f32], out: &mut [usize]) {
    let lanes = us.len();
    assert!(lanes <= SEARCH_LANES && cdfs.len() == lanes && out.len() == lanes);
    let Some(n) = cdfs.first().map(|c| c.len()) else { return };
    assert!(n > 0 && cdfs.iter().all(|c| c.len() == n), "tables of one length");
    let mut base = [0usize; SEARCH_LANES];
    // Entries below `base[l]` are at most `us[l]`; those from `base[l] + size` on are above.
    let mut size = n;
    while size > 1 {
        let half = size / 2;
        for l in 0..lanes {
            let at = base[l] + half;
            base[l] = if cdfs[l][at] <= us[l] { at } else { base[l] };
        }
        size -= half;
    }
    for l in 0..lanes {
        out[l] = base[l] + usize::from(cdfs[l][base[l]] <= us[l]);
    }
}

/// `u` rescaled to `[0, 1)` within an item's interval, which starts at `start` and has
/// probability `pmf` ([`DiscreteDistribution::pick`]); 0 for an item of probability zero.
#[inline(always)]
pub fn rescaled(u: f32, start: f32, pmf: f32) -> f32 {
    if pmf > 0.0 { ((u - start) / pmf).clamp(0.0, ONE_MINUS_EPSILON) } else { 0.0 }
}

// ---------------------------------------------------------------------------------------------
// Frames and heuristics.

/// An orthonormal basis `(tangent, bitangent)` completing the unit vector `n` to a right-handed
/// frame, without a branch on a near-zero axis (Duff et al., "Building an Orthonormal Basis,
/// Revisited", JCGT 2017).
#[inline]
pub fn orthonormal_basis(n: Vec3) -> (Vec3, Vec3) {
    let s = 1f32.copysign(n.z);
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    (Vec3::new(1.0 + s * n.x * n.x * a, s * b, -s * n.x), Vec3::new(b, s + n.y * n.y * a, -n.y))
}

/// [`orthonormal_basis`] in double precision: the ray-set protocol's diffuse rays.
#[inline]
pub fn orthonormal_basis_f64(n: DVec3) -> (DVec3, DVec3) {
    let s = 1f64.copysign(n.z);
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    (DVec3::new(1.0 + s * n.x * n.x * a, s * b, -s * n.x), DVec3::new(b, s + n.y * n.y * a, -n.y))
}

/// A cosine-weighted direction about +z by polar coordinates, `r = √u₁`, `φ = 2πu₂`, in double
/// precision: the ray-set protocol's diffuse rays (§5), which must match the reference program
/// bit for bit. Renders use [`square_to_cosine_hemisphere`].
#[inline]
pub fn square_to_cosine_hemisphere_polar_f64(u1: f64, u2: f64) -> DVec3 {
    let radius = u1.sqrt();
    let phi = 2.0 * std::f64::consts::PI * u2;
    DVec3::new(radius * phi.cos(), radius * phi.sin(), (1.0 - u1).max(0.0).sqrt())
}

/// The power heuristic with β = 2 (Veach 1997): the weight of a sample drawn with density `f`
/// when another strategy would have drawn it with density `g`.
#[inline]
pub fn power_heuristic(f: f32, g: f32) -> f32 {
    let (f2, g2) = (f * f, g * g);
    if f2.is_infinite() {
        return 1.0;
    }
    if f2 + g2 == 0.0 { 0.0 } else { f2 / (f2 + g2) }
}

#[cfg(test)]
mod tests;
