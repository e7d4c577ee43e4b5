//! A chi-square goodness-of-fit test for sampling routines (after Mitsuba 3's `chi2.py`).
//!
//! Draw many samples, histogram them on a grid over the domain, integrate the claimed density
//! over each cell to get the expected counts, pool cells whose expectation is small, and reject
//! the routine if Pearson's statistic is improbably large under the null hypothesis that the
//! samples follow the density. A second check integrates the density over the whole domain: it
//! must equal the fraction of attempts that produced a sample (1 for a warp; less for a BSDF that
//! absorbs or transmits part of the time).

use glam::{DVec2, Vec2, Vec3};

use super::Pcg32;

/// Significance level of each test, before the Šidák correction for the number of tests run.
pub const SIGNIFICANCE: f64 = 0.01;

/// The result of a test, with the numbers behind it for the failure message.
#[derive(Debug)]
#[allow(dead_code)] // The fields are read through Debug, in failure messages.
pub struct Outcome {
    /// Pearson's statistic.
    pub statistic: f64,
    /// Degrees of freedom after pooling.
    pub degrees_of_freedom: usize,
    /// Probability of a statistic at least this large if the samples follow the density.
    pub p_value: f64,
    /// The density's integral over the domain.
    pub pdf_integral: f64,
    /// The fraction of attempts that produced a sample.
    pub sampled_fraction: f64,
}

/// A rectangular domain mapped onto the unit square for histogramming.
pub trait Domain {
    /// The cell coordinates in `[0, 1)²` of a sample, or `None` outside the domain.
    fn to_unit(&self, sample: Vec3) -> Option<DVec2>;
    /// The sample at unit-square coordinates (for integrating the density).
    fn point_at(&self, u: DVec2) -> Vec3;
    /// The domain's measure per unit of unit-square area (the Jacobian).
    fn measure_per_unit(&self) -> f64;
}

/// Directions on the sphere, in `(cos θ, φ)`: solid angle is `d(cos θ) dφ`.
pub struct Sphere;

impl Domain for Sphere {
    fn to_unit(&self, w: Vec3) -> Option<DVec2> {
        let w = w.as_dvec3().normalize();
        let cos_theta = w.z.clamp(-1.0, 1.0);
        let mut phi = w.y.atan2(w.x);
        if phi < 0.0 {
            phi += 2.0 * std::f64::consts::PI;
        }
        Some(DVec2::new((cos_theta + 1.0) / 2.0, phi / (2.0 * std::f64::consts::PI)))
    }
    fn point_at(&self, u: DVec2) -> Vec3 {
        let cos_theta = 2.0 * u.x - 1.0;
        let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
        let phi = 2.0 * std::f64::consts::PI * u.y;
        Vec3::new((sin_theta * phi.cos()) as f32, (sin_theta * phi.sin()) as f32, cos_theta as f32)
    }
    fn measure_per_unit(&self) -> f64 {
        4.0 * std::f64::consts::PI
    }
}

/// Points of the plane `z = 0` in `[x0, x1] × [y0, y1]`.
pub struct Rectangle(pub Vec2, pub Vec2);

impl Domain for Rectangle {
    fn to_unit(&self, p: Vec3) -> Option<DVec2> {
        let (lo, hi) = (self.0.as_dvec2(), self.1.as_dvec2());
        let u = (DVec2::new(p.x as f64, p.y as f64) - lo) / (hi - lo);
        (u.cmpge(DVec2::ZERO).all() && u.cmple(DVec2::ONE).all()).then_some(u)
    }
    fn point_at(&self, u: DVec2) -> Vec3 {
        let p = self.0.as_dvec2() + u * (self.1 - self.0).as_dvec2();
        Vec3::new(p.x as f32, p.y as f32, 0.0)
    }
    fn measure_per_unit(&self) -> f64 {
        let d = (self.1 - self.0).as_dvec2();
        d.x * d.y
    }
}

/// Runs the test: `attempts` draws of `sample` (which may return `None`: no sample), a
/// `resolution.0 × resolution.1` grid, and `pdf` integrated over each cell by a `sub×sub`
/// midpoint rule.
pub fn run(
    domain: &impl Domain,
    resolution: (usize, usize),
    attempts: usize,
    seed: u64,
    mut sample: impl FnMut(&mut Pcg32) -> Option<Vec3>,
    pdf: impl Fn(Vec3) -> f32,
) -> Outcome {
    let (nx, ny) = resolution;
    let mut observed = vec![0f64; nx * ny];
    let mut rng = Pcg32::new(seed, 0x5eed);
    let mut produced = 0usize;
    for _ in 0..attempts {
        let Some(s) = sample(&mut rng) else { continue };
        produced += 1;
        let Some(u) = domain.to_unit(s) else {
            panic!("a sample {s} lies outside the domain");
        };
        let x = ((u.x * nx as f64) as usize).min(nx - 1);
        let y = ((u.y * ny as f64) as usize).min(ny - 1);
        observed[y * nx + x] += 1.0;
    }
    let measure = domain.measure_per_unit();
    let mut expected = vec![0f64; nx * ny];
    let mut pdf_integral = 0.0;
    for y in 0..ny {
        for x in 0..nx {
            let (x0, y0) = (x as f64 / nx as f64, y as f64 / ny as f64);
            let cell = [x0, x0 + 1.0 / nx as f64, y0, y0 + 1.0 / ny as f64];
            let integral = integrate(&|u| pdf(domain.point_at(u)) as f64, cell, 0) * measure;
            pdf_integral += integral;
            expected[y * nx + x] = integral * attempts as f64;
        }
    }
    let (statistic, degrees_of_freedom) = pearson(&observed, &expected);
    Outcome {
        statistic,
        degrees_of_freedom,
        p_value: 1.0 - regularized_gamma_p(degrees_of_freedom as f64 / 2.0, statistic / 2.0),
        pdf_integral,
        sampled_fraction: produced as f64 / attempts as f64,
    }
}

impl Outcome {
    /// Panics with the numbers unless the samples fit the density (at [`SIGNIFICANCE`], Šidák-
    /// corrected for `tests` tests) and the density integrates to the sampled fraction within
    /// `integral_tolerance`.
    pub fn assert_fits(&self, name: &str, tests: usize, integral_tolerance: f64) {
        let alpha = 1.0 - (1.0 - SIGNIFICANCE).powf(1.0 / tests as f64);
        assert!(
            self.p_value >= alpha,
            "{name}: the samples do not follow the density: {self:?} (alpha {alpha:.2e})"
        );
        assert!(
            (self.pdf_integral - self.sampled_fraction).abs() <= integral_tolerance,
            "{name}: the density integrates to {} but {} of the attempts gave a sample",
            self.pdf_integral,
            self.sampled_fraction
        );
    }
}

/// The integral of `f` over the rectangle `[x0, x1] × [y0, y1]` of the unit square, by a 6×6
/// midpoint rule refined adaptively: where it disagrees with the sum over the four quarters,
/// each quarter is integrated again (peaked densities, such as smooth microfacets, need it).
fn integrate(f: &impl Fn(DVec2) -> f64, [x0, x1, y0, y1]: [f64; 4], depth: u32) -> f64 {
    let rule = |[x0, x1, y0, y1]: [f64; 4]| {
        const N: usize = 6;
        let mut sum = 0.0;
        for j in 0..N {
            for i in 0..N {
                let u = DVec2::new(
                    x0 + (x1 - x0) * (i as f64 + 0.5) / N as f64,
                    y0 + (y1 - y0) * (j as f64 + 0.5) / N as f64,
                );
                sum += f(u);
            }
        }
        sum / (N * N) as f64 * (x1 - x0) * (y1 - y0)
    };
    let (xm, ym) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
    let quarters = [[x0, xm, y0, ym], [xm, x1, y0, ym], [x0, xm, ym, y1], [xm, x1, ym, y1]];
    let whole = rule([x0, x1, y0, y1]);
    let parts: f64 = quarters.iter().map(|&q| rule(q)).sum();
    let area = (x1 - x0) * (y1 - y0);
    if depth >= 7 || (whole - parts).abs() <= 1e-4 * area.sqrt() * parts.abs().max(1e-3) {
        return parts;
    }
    quarters.iter().map(|&q| integrate(f, q, depth + 1)).sum()
}

/// Pearson's statistic over cells, pooling cells with an expectation below 5 (in increasing
/// order of expectation) into one. Cells whose integrated density is zero join the pool too (a
/// density that is discontinuous at a shape's edge can integrate to zero over a cell the edge
/// barely crosses), but samples in them beyond one in ten thousand are an outright failure
/// (infinite statistic): samples outside the density's support.
fn pearson(observed: &[f64], expected: &[f64]) -> (f64, usize) {
    let total: f64 = observed.iter().sum();
    let outside: f64 =
        observed.iter().zip(expected).filter(|(_, e)| **e == 0.0).map(|(o, _)| o).sum();
    if outside > 1e-4 * total {
        return (f64::INFINITY, 1);
    }
    let mut order: Vec<usize> = (0..observed.len()).collect();
    order.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]));
    let mut statistic = 0.0;
    let mut cells = 0;
    let (mut pooled_observed, mut pooled_expected) = (0.0, 0.0);
    for i in order {
        if expected[i] < 5.0 || pooled_expected > 0.0 && pooled_expected < 5.0 {
            pooled_observed += observed[i];
            pooled_expected += expected[i];
            continue;
        }
        statistic += (observed[i] - expected[i]).powi(2) / expected[i];
        cells += 1;
    }
    if pooled_expected > 0.0 {
        statistic += (pooled_observed - pooled_expected).powi(2) / pooled_expected;
        cells += 1;
    }
    (statistic, cells.max(2) - 1)
}

/// The regularized lower incomplete gamma function `P(a, x)` (Numerical Recipes §6.2: its series
/// below `x < a + 1`, Lentz's continued fraction for the complement above).
pub fn regularized_gamma_p(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if x.is_infinite() {
        return 1.0;
    }
    let log_prefactor = a * x.ln() - x - ln_gamma(a);
    if x < a + 1.0 {
        let (mut term, mut sum, mut n) = (1.0 / a, 1.0 / a, a);
        for _ in 0..10_000 {
            n += 1.0;
            term *= x / n;
            sum += term;
            if term.abs() < sum.abs() * 1e-15 {
                break;
            }
        }
        sum * log_prefactor.exp()
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            d = if d.abs() < tiny { tiny } else { d };
            c = b + an / c;
            c = if c.abs() < tiny { tiny } else { c };
            d = 1.0 / d;
            let delta = d * c;
            h *= delta;
            if (delta - 1.0).abs() < 1e-15 {
                break;
            }
        }
        1.0 - log_prefactor.exp() * h
    }
}

/// `ln Γ(x)` for `x > 0` (Lanczos, g = 7, n = 9).
pub fn ln_gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const COEFFICIENTS: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut sum = COEFFICIENTS[0];
    for (i, c) in COEFFICIENTS.iter().enumerate().skip(1) {
        sum += c / (x + i as f64);
    }
    let t = x + G + 0.5;
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + sum.ln()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gamma_functions_match_known_values() {
        assert!((ln_gamma(5.0) - 24f64.ln()).abs() < 1e-12);
        assert!((ln_gamma(0.5) - std::f64::consts::PI.sqrt().ln()).abs() < 1e-12);
        // P(1, x) = 1 − e^−x; the chi-square distribution with 2 dof at 5.991 is 0.95.
        assert!((regularized_gamma_p(1.0, 2.0) - (1.0 - (-2f64).exp())).abs() < 1e-12);
        assert!((regularized_gamma_p(1.0, 5.991_464_5 / 2.0) - 0.95).abs() < 1e-6);
        // 10 dof: the 99th percentile is 23.209.
        assert!((regularized_gamma_p(5.0, 23.209_251 / 2.0) - 0.99).abs() < 1e-6);
        // 100 dof: the median is 99.334.
        assert!((regularized_gamma_p(50.0, 99.334_129 / 2.0) - 0.5).abs() < 1e-5);
    }

    #[test]
    fn the_test_rejects_a_wrong_density() {
        // Uniform hemisphere samples against the cosine density: must fail.
        let outcome = run(
            &Sphere,
            (10, 20),
            200_000,
            1,
            |rng| {
                Some(super::super::square_to_uniform_hemisphere(Vec2::new(
                    rng.next_f32(),
                    rng.next_f32(),
                )))
            },
            super::super::cosine_hemisphere_pdf,
        );
        assert!(outcome.p_value < 1e-6, "{outcome:?}");
    }
}
