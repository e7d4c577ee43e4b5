//! Every warp against its density (chi-square), and the helpers' known values.

use glam::{Vec2, Vec3};

use super::chi2::{self, Rectangle, Sphere};
use super::*;

const ATTEMPTS: usize = 400_000;
/// Warp tests in this file (for the Šidák correction).
const TESTS: usize = 14;

fn uniform(rng: &mut Pcg32) -> Vec2 {
    Vec2::new(rng.next_f32(), rng.next_f32())
}

#[test]
fn cosine_hemisphere_fits_its_density() {
    chi2::run(
        &Sphere,
        (16, 32),
        ATTEMPTS,
        1,
        |r| Some(square_to_cosine_hemisphere(uniform(r))),
        cosine_hemisphere_pdf,
    )
    .assert_fits("cosine hemisphere", TESTS, 1e-3);
}

#[test]
fn uniform_hemisphere_and_sphere_fit_their_densities() {
    chi2::run(
        &Sphere,
        (16, 32),
        ATTEMPTS,
        2,
        |r| Some(square_to_uniform_hemisphere(uniform(r))),
        uniform_hemisphere_pdf,
    )
    .assert_fits("uniform hemisphere", TESTS, 1e-3);
    chi2::run(
        &Sphere,
        (16, 32),
        ATTEMPTS,
        3,
        |r| Some(square_to_uniform_sphere(uniform(r))),
        uniform_sphere_pdf,
    )
    .assert_fits("uniform sphere", TESTS, 1e-3);
}

/// Cones, a wide one and one the sun's size, through the projection onto the plane across
/// their axis, scaled to the square `[−1, 1]²`: a direction at `θ` projects to
/// `sin θ (cos φ, sin φ)`, where solid angle is `dA / cos θ`, so the projected density is
/// `pdf / cos θ` (times `sin² α` for the scaling).
#[test]
fn uniform_cones_fit_their_density() {
    let sun_radius = 0.5338f32.to_radians() / 2.0;
    for (test, alpha) in [(0u64, 1.0f32), (1, sun_radius)] {
        let one_minus_cos = 2.0 * (0.5 * alpha).sin().powi(2);
        let sin_alpha = alpha.sin();
        let domain = Rectangle(Vec2::splat(-1.0), Vec2::splat(1.0));
        chi2::run(
            &domain,
            (24, 24),
            ATTEMPTS,
            20 + test,
            |r| {
                let w = square_to_uniform_cone(uniform(r), one_minus_cos);
                assert!((w.length() - 1.0).abs() < 1e-5, "{w}");
                Some(Vec3::new(w.x / sin_alpha, w.y / sin_alpha, 0.0))
            },
            |p| {
                let sin2 = (p.x * p.x + p.y * p.y) * sin_alpha * sin_alpha;
                if p.x * p.x + p.y * p.y > 1.0 {
                    return 0.0;
                }
                let cos_theta = (1.0 - sin2).sqrt();
                uniform_cone_pdf(one_minus_cos) / cos_theta * sin_alpha * sin_alpha
            },
        )
        .assert_fits(&format!("uniform cone of {alpha} rad"), TESTS, 2e-3);
    }
}

/// Bilinear densities over the square, one with a zero corner and one steep, and their lines.
#[test]
fn bilinear_and_linear_samples_fit_their_densities() {
    let domain = Rectangle(Vec2::ZERO, Vec2::ONE);
    for (test, f) in [(0u64, [1.0f32, 0.0, 2.0, 5.0]), (1, [0.01, 3.0, 0.2, 0.0])] {
        chi2::run(
            &domain,
            (16, 16),
            ATTEMPTS,
            30 + test,
            |r| {
                let p = sample_bilinear(uniform(r), f);
                Some(Vec3::new(p.x, p.y, 0.0))
            },
            |p| bilinear_pdf(Vec2::new(p.x, p.y), f),
        )
        .assert_fits(&format!("bilinear {f:?}"), TESTS, 1e-3);
    }
    // A line from 0 to 1 and one from 3 to 0.5, along x.
    for (a, b) in [(0.0f32, 1.0f32), (3.0, 0.5)] {
        chi2::run(
            &domain,
            (32, 1),
            ATTEMPTS,
            40,
            |r| Some(Vec3::new(sample_linear(r.next_f32(), a, b), 0.5, 0.0)),
            |p| linear_pdf(p.x, a, b),
        )
        .assert_fits(&format!("linear {a} to {b}"), TESTS, 1e-3);
    }
}

#[test]
fn concentric_disk_fits_its_density() {
    let domain = Rectangle(Vec2::splat(-1.0), Vec2::splat(1.0));
    chi2::run(
        &domain,
        (24, 24),
        ATTEMPTS,
        4,
        |r| {
            let p = square_to_uniform_disk_concentric(uniform(r));
            Some(Vec3::new(p.x, p.y, 0.0))
        },
        |p| uniform_disk_pdf(Vec2::new(p.x, p.y)),
    )
    // The disk's edge crosses cells: the midpoint rule's error there.
    .assert_fits("concentric disk", TESTS, 2e-3);
}

#[test]
fn triangle_points_fit_the_uniform_area_density() {
    // The triangle (0,0), (2,0), (0.5,1.5): area 1.5.
    let [a, b, c] = [Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.5, 1.5, 0.0)];
    let inside = |p: Vec3| {
        let edge = |p0: Vec3, p1: Vec3| (p1 - p0).cross(p - p0).z >= 0.0;
        edge(a, b) && edge(b, c) && edge(c, a)
    };
    chi2::run(
        &Rectangle(Vec2::ZERO, Vec2::new(2.0, 1.5)),
        (24, 24),
        ATTEMPTS,
        5,
        |r| {
            let [b0, b1, b2] = square_to_uniform_triangle(uniform(r));
            Some(b0 * a + b1 * b + b2 * c)
        },
        |p| if inside(p) { uniform_triangle_pdf(1.5) } else { 0.0 },
    )
    .assert_fits("uniform triangle", TESTS, 5e-3);
}

#[test]
fn truncated_gaussian_fits_its_density() {
    let (sigma, radius) = (0.5f32, 2.0f32);
    let edge = erf(radius / (sigma * std::f32::consts::SQRT_2));
    let density_1d =
        |x: f32| (-x * x / (2.0 * sigma * sigma)).exp() / (sigma * (2.0 * PI).sqrt()) / edge;
    chi2::run(
        &Rectangle(Vec2::splat(-radius), Vec2::splat(radius)),
        (20, 20),
        ATTEMPTS,
        6,
        |r| {
            let p = square_to_truncated_gaussian(uniform(r), sigma, radius);
            Some(Vec3::new(p.x, p.y, 0.0))
        },
        |p| density_1d(p.x) * density_1d(p.y),
    )
    .assert_fits("truncated gaussian", TESTS, 1e-3);
}

#[test]
fn erf_and_its_inverse_match_known_values() {
    for (x, expected) in [
        (0.0f32, 0.0f32),
        (0.5, 0.520_499_9),
        (1.0, 0.842_700_8),
        (2.0, 0.995_322_3),
        (3.0, 0.999_977_9),
    ] {
        assert!((erf(x) - expected).abs() < 1e-6, "erf({x}) = {}", erf(x));
        assert!((erf(-x) + expected).abs() < 1e-6);
    }
    for y in [-0.999f32, -0.5, 0.0, 0.1, 0.9, 0.999_9] {
        assert!((erf(erf_inv(y)) - y).abs() < 1e-6, "{y}");
    }
}

#[test]
fn warps_stay_in_their_domains_at_the_square_s_corners() {
    let corners = [
        Vec2::ZERO,
        Vec2::new(ONE_MINUS_EPSILON, 0.0),
        Vec2::splat(ONE_MINUS_EPSILON),
        Vec2::new(0.0, ONE_MINUS_EPSILON),
        Vec2::splat(0.5),
    ];
    for u in corners {
        let w = square_to_cosine_hemisphere(u);
        assert!(w.z >= 0.0 && (w.length() - 1.0).abs() < 1e-6, "{u}: {w}");
        let [b0, b1, b2] = square_to_uniform_triangle(u);
        assert!(b0 >= 0.0 && b1 >= 0.0 && b2 >= 0.0 && ((b0 + b1 + b2) - 1.0).abs() < 1e-6, "{u}");
        assert!(square_to_uniform_disk_concentric(u).length() <= 1.0 + 1e-6);
        assert!((square_to_uniform_sphere(u).length() - 1.0).abs() < 1e-6);
    }
}

#[test]
fn orthonormal_bases_are_orthonormal_and_right_handed() {
    for n in [
        Vec3::Z,
        -Vec3::Z,
        Vec3::X,
        Vec3::new(0.3, -0.4, 0.866).normalize(),
        Vec3::new(0.0, 0.0, -1e-9).normalize_or(Vec3::Z),
    ] {
        let (t, b) = orthonormal_basis(n);
        assert!((t.length() - 1.0).abs() < 1e-6 && (b.length() - 1.0).abs() < 1e-6);
        assert!(t.dot(n).abs() < 1e-6 && b.dot(n).abs() < 1e-6 && t.dot(b).abs() < 1e-6);
        assert!((t.cross(b) - n).length() < 1e-5, "{n}");
    }
}

#[test]
fn the_power_heuristic_weights_sum_to_one() {
    for (f, g) in [(1.0f32, 1.0f32), (0.2, 3.0), (5.0, 0.0), (0.0, 0.0)] {
        let sum = power_heuristic(f, g) + power_heuristic(g, f);
        assert!(sum == 0.0 && f == 0.0 && g == 0.0 || (sum - 1.0).abs() < 1e-6, "{f} {g}");
    }
    assert_eq!(power_heuristic(f32::INFINITY, 1.0), 1.0);
}

#[test]
fn sample_zero_is_the_pixel_centre_and_the_rest_stay_inside_the_pixel() {
    assert_eq!(sample_offset(3, 4, 0), Vec2::splat(0.5));
    for (x, y) in [(0, 0), (1, 0), (499, 499), (u32::MAX, 7)] {
        for k in [1, 2, 3, 100, 65_535, u32::MAX] {
            let o = sample_offset(x, y, k);
            assert!(o.cmpge(Vec2::ZERO).all() && o.cmplt(Vec2::ONE).all(), "{o}");
        }
    }
    // Neighbouring pixels do not share a pattern.
    assert_ne!(sample_offset(0, 0, 1), sample_offset(1, 0, 1));
    assert_ne!(sample_offset(0, 0, 1), sample_offset(0, 1, 1));
}

#[test]
fn samples_cover_the_pixel_evenly() {
    // n² consecutive samples leave at most a fifth of the pixel's n×n cells empty and put at
    // most 3 in any; n² uniform random points would leave about n²/e (37 %) of them empty.
    for (x, y) in [(0, 0), (17, 230), (499, 3)] {
        for n in [4usize, 8] {
            let mut cells = vec![0u32; n * n];
            for k in 1..=(n * n) as u32 {
                let o = sample_offset(x, y, k) * n as f32;
                cells[o.y as usize * n + o.x as usize] += 1;
            }
            let empty = cells.iter().filter(|&&c| c == 0).count();
            assert!(empty <= n * n / 5 && cells.iter().all(|&c| c <= 3), "{n}: {cells:?}");
        }
        let mean = (1..=1024).map(|k| sample_offset(x, y, k)).sum::<Vec2>() / 1024.0;
        assert!((mean - Vec2::splat(0.5)).abs().max_element() < 0.01, "{mean}");
    }
}

#[test]
fn discrete_distributions_pick_by_weight_and_skip_zeros() {
    let d = DiscreteDistribution::new(&[1.0, 0.0, 3.0, 0.0]).unwrap();
    assert_eq!(d.len(), 4);
    assert_eq!((d.pmf(0), d.pmf(1), d.pmf(2)), (0.25, 0.0, 0.75));
    assert_eq!(d.sample(0.0).0, 0);
    assert_eq!(d.sample(0.2499).0, 0);
    assert_eq!(d.sample(0.25).0, 2);
    assert_eq!(d.sample(ONE_MINUS_EPSILON).0, 2);
    let (i, pmf, reused) = d.sample(0.625);
    assert_eq!((i, pmf), (2, 0.75));
    assert!((reused - 0.5).abs() < 1e-6);
    let mut counts = [0usize; 4];
    let mut rng = Pcg32::new(1, 2);
    for _ in 0..100_000 {
        counts[d.sample(rng.next_f32()).0] += 1;
    }
    assert_eq!((counts[1], counts[3]), (0, 0));
    assert!((counts[2] as f64 / 100_000.0 - 0.75).abs() < 0.01, "{counts:?}");
    // Small distributions count the CDF entries at most `u`, large ones search: the same item.
    for n in [1, 2, 3, 7, 15, 16, 40] {
        let weights: Vec<f32> =
            (0..n).map(|i| if i % 3 == 1 { 0.0 } else { rng.next_f32() + 0.01 }).collect();
        let d = DiscreteDistribution::new(&weights).unwrap();
        let search = |u: f32| d.cdf.partition_point(|&c| c <= u);
        let edges = d.cdf.iter().flat_map(|&c| [c, c.next_down(), c.next_up()]);
        let numbers = (0..2000).map(|_| rng.next_f32()).chain(edges).chain([f32::NAN, -1.0, 2.0]);
        for u in numbers {
            assert_eq!(d.below_or_at(u), search(u), "{n} items, u = {u}");
        }
    }
    assert!(DiscreteDistribution::new(&[0.0, 0.0]).is_none());
    assert!(DiscreteDistribution::new(&[]).is_none());
    assert!(DiscreteDistribution::new(&[f32::INFINITY]).is_none());
}

#[test]
fn spherical_triangles_are_sampled_uniformly_in_solid_angle() {
    // Seen from the origin: a large nearby triangle and a small oblique one.
    let triangles = [
        [Vec3::new(-1.0, -1.0, 1.0), Vec3::new(2.0, -0.5, 0.6), Vec3::new(0.0, 1.5, 1.2)],
        [Vec3::new(3.0, 0.2, 0.5), Vec3::new(3.5, 0.9, 0.4), Vec3::new(2.8, 0.6, 1.4)],
    ];
    for v in triangles {
        let omega = spherical_triangle_area(v, Vec3::ZERO);
        let hits = |w: Vec3| {
            // Whether the ray from the origin along w meets the triangle (Möller–Trumbore in f64).
            let [a, b, c] = v.map(|x| x.as_dvec3());
            let w = w.as_dvec3();
            let (e1, e2) = (b - a, c - a);
            let h = w.cross(e2);
            let det = e1.dot(h);
            let s = -a;
            let u = s.dot(h) / det;
            let q = s.cross(e1);
            let t_v = w.dot(q) / det;
            det != 0.0 && u >= 0.0 && t_v >= 0.0 && u + t_v <= 1.0 && e2.dot(q) / det > 0.0
        };
        chi2::run(
            &Sphere,
            (24, 48),
            ATTEMPTS,
            8,
            |r| {
                let (b, pdf) = sample_spherical_triangle(v, Vec3::ZERO, uniform(r))?;
                assert!((pdf - 1.0 / omega).abs() < 1e-3 * pdf, "{pdf} vs {}", 1.0 / omega);
                Some((b[0] * v[0] + b[1] * v[1] + b[2] * v[2]).normalize())
            },
            |w| if hits(w) { 1.0 / omega } else { 0.0 },
        )
        .assert_fits("spherical triangle", TESTS, 5e-3);
    }
    // In the triangle's plane nothing is subtended.
    let flat = [Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, 0.0)];
    assert!(sample_spherical_triangle(flat, Vec3::ZERO, Vec2::splat(0.5)).is_none());
}

/// The sine and cosine of whole turns are within 3·10⁻⁷ of double precision's over a turn
/// (every 997th float of `[0, 1]` and the quarter turns' ends), and exact at the quarter turns.
#[test]
fn sin_cos_turns_is_accurate() {
    let mut worst: (f64, f32) = (0.0, 0.0);
    let mut bits = 0u32;
    let mut check = |t: f32| {
        let (sin, cos) = sin_cos_turns(t);
        let (sin_exact, cos_exact) = (std::f64::consts::TAU * t as f64).sin_cos();
        let error = (sin as f64 - sin_exact).abs().max((cos as f64 - cos_exact).abs());
        if error > worst.0 {
            worst = (error, t);
        }
    };
    while f32::from_bits(bits) <= 1.0 {
        check(f32::from_bits(bits));
        bits += 997;
    }
    for q in [0.125f32, 0.375, 0.625, 0.875] {
        for t in [q.next_down(), q, q.next_up()] {
            check(t);
        }
    }
    assert!(worst.0 < 3e-7, "{worst:?}");
    assert_eq!(sin_cos_turns(0.0), (0.0, 1.0));
    assert_eq!(sin_cos_turns(0.25), (1.0, 0.0));
    assert_eq!(sin_cos_turns(0.5), (0.0, -1.0));
    assert_eq!(sin_cos_turns(0.75), (-1.0, 0.0));
}

/// The polynomial sine and cosine are within 2·10⁻⁷ of double precision's over ±π/4 (every
/// 1,009th float of the range, both signs, and the ends), and odd and even as they should be.
#[test]
fn sin_cos_within_quarter_pi_is_accurate() {
    let end = std::f32::consts::FRAC_PI_4;
    let mut worst: (f64, f32) = (0.0, 0.0);
    let mut bits = 0u32;
    while f32::from_bits(bits) <= end {
        for a in [f32::from_bits(bits), -f32::from_bits(bits)] {
            let (sin, cos) = sin_cos_within_quarter_pi(a);
            let (sin_exact, cos_exact) = (a as f64).sin_cos();
            let error = (sin as f64 - sin_exact).abs().max((cos as f64 - cos_exact).abs());
            if error > worst.0 {
                worst = (error, a);
            }
            assert_eq!(sin_cos_within_quarter_pi(-a), (-sin, cos), "odd sine, even cosine at {a}");
        }
        bits += 1009;
    }
    for a in [0.0, end, -end] {
        let (sin, cos) = sin_cos_within_quarter_pi(a);
        let (sin_exact, cos_exact) = (a as f64).sin_cos();
        worst.0 = worst.0.max((sin as f64 - sin_exact).abs()).max((cos as f64 - cos_exact).abs());
    }
    assert!(worst.0 <= 2e-7, "worst error {:e} at {}", worst.0, worst.1);
    assert_eq!(sin_cos_within_quarter_pi(0.0), (0.0, 1.0));
}

/// A table with an empty row, an empty column, negative and NaN values, a bright spot (a sun)
/// and a smooth rest: `width × height` values.
fn sky_table(width: usize, height: usize) -> Vec<f32> {
    let mut rng = Pcg32::new(11, 3);
    let mut values: Vec<f32> = (0..width * height).map(|_| 0.2 + rng.next_f32()).collect();
    if height > 2 {
        values[2 * width..3 * width].fill(0.0);
    }
    for row in 0..height {
        values[row * width + 5] = 0.0;
    }
    values[7] = -1.0;
    values[8] = f32::NAN;
    values[(height - 1).min(4) * width + 9] = 60.0;
    values
}

#[test]
fn piecewise_1d_fits_its_density() {
    let table = sky_table(12, 1);
    let density = PiecewiseConstant1D::new(&table);
    chi2::run(
        &Rectangle(Vec2::ZERO, Vec2::ONE),
        (24, 1),
        ATTEMPTS,
        21,
        |r| Some(Vec3::new(density.sample(r.next_f32()).0, 0.5, 0.0)),
        |p| density.pdf(p.x),
    )
    .assert_fits("piecewise-constant 1D", TESTS, 1e-4);
    // The density is the table's, normalized: the empty and negative bins are never sampled.
    let mean = table.iter().map(|&f| if f > 0.0 { f as f64 } else { 0.0 }).sum::<f64>() / 12.0;
    assert!((density.integral() - mean).abs() < 1e-6);
    for (i, &f) in table.iter().enumerate() {
        let want = if f > 0.0 { f as f64 / mean } else { 0.0 };
        let got = density.pdf((i as f32 + 0.5) / 12.0) as f64;
        assert!((got - want).abs() < 1e-5 * want.max(1.0), "bin {i}: {got} against {want}");
    }
    let mut rng = Pcg32::new(5, 5);
    for _ in 0..10_000 {
        let (x, pdf, bin) = density.sample(rng.next_f32());
        assert!((0.0..1.0).contains(&x) && bin == (x * 12.0) as usize && pdf > 0.0, "{x} {bin}");
    }
}

#[test]
fn piecewise_2d_fits_its_density() {
    let (width, height) = (12, 9);
    let density = PiecewiseConstant2D::new(&sky_table(width, height), width, height);
    assert_eq!(density.size(), (12, 9));
    chi2::run(
        &Rectangle(Vec2::ZERO, Vec2::ONE),
        (24, 18),
        ATTEMPTS,
        22,
        |r| {
            let (p, pdf) = density.sample(uniform(r));
            assert!((pdf - density.pdf(p)).abs() <= 1e-5 * pdf, "sampled density {pdf} at {p}");
            Some(Vec3::new(p.x, p.y, 0.0))
        },
        |p| density.pdf(Vec2::new(p.x, p.y)),
    )
    .assert_fits("piecewise-constant 2D", TESTS, 1e-4);
}

#[test]
fn piecewise_tables_of_zeros_are_uniform() {
    let flat = PiecewiseConstant2D::new(&[0.0, -1.0, f32::NAN, 0.0, 0.0, 0.0], 3, 2);
    assert_eq!(flat.integral(), 0.0);
    let mut rng = Pcg32::new(9, 9);
    for _ in 0..1000 {
        let (p, pdf) = flat.sample(uniform(&mut rng));
        assert!((pdf - 1.0).abs() < 1e-6 && (flat.pdf(p) - 1.0).abs() < 1e-6);
    }
    // One value: its bin is the whole interval.
    let one = PiecewiseConstant1D::new(&[3.0]);
    assert_eq!(one.sample(0.25), (0.25, 1.0, 0));
    assert_eq!(one.integral(), 3.0);
}

/// Every octant, the axes, and points near them, against double precision.
#[test]
fn atan2_polynomial_is_accurate() {
    let mut rng = Pcg32::new(12, 1);
    let mut worst = 0.0f64;
    let mut check = |y: f32, x: f32| {
        let error = (atan2_polynomial(y, x) as f64 - (y as f64).atan2(x as f64)).abs();
        worst = worst.max(error);
        assert!(
            error < 3e-7,
            "atan2({y}, {x}): {} against {}",
            atan2_polynomial(y, x),
            (y as f64).atan2(x as f64)
        );
    };
    for _ in 0..1_000_000 {
        let angle = (rng.next_f32() * 2.0 - 1.0) * PI;
        let r = 1e-3 + 10.0 * rng.next_f32();
        check(r * angle.sin(), r * angle.cos());
    }
    for (y, x) in [
        (0.0, 1.0),
        (1.0, 0.0),
        (0.0, -1.0),
        (-1.0, 0.0),
        (1.0, 1.0),
        (-1.0, -1.0),
        (1e-30, 1.0),
        (1.0, -1e-30),
    ] {
        check(y, x);
    }
    assert_eq!(atan2_polynomial(0.0, 0.0), 0.0);
    assert!(atan2_polynomial(f32::NAN, 1.0).is_nan());
    eprintln!("atan2_polynomial: worst error {worst:.2e}");
}

/// The searches in step count what `partition_point` counts, on ascending tables with runs of
/// equal entries (items of probability zero), at the entries themselves, between them, below
/// the first and from the last on, for tables of 1 to 40 entries.
#[test]
fn searches_in_step_count_as_partition_point() {
    let mut rng = Pcg32::new(48, 2);
    for n in 1..=40usize {
        for _ in 0..20 {
            let tables: Vec<Vec<f32>> = (0..SEARCH_LANES)
                .map(|_| {
                    let mut sum = 0.0f32;
                    (0..n)
                        .map(|_| {
                            // A third of the steps are zero: equal entries.
                            if !rng.next_u32().is_multiple_of(3) {
                                sum += rng.next_f32();
                            }
                            sum
                        })
                        .collect()
                })
                .collect();
            let us: Vec<f32> = tables
                .iter()
                .map(|t| match rng.next_u32() % 4 {
                    0 => t[rng.next_u32() as usize % n],
                    1 => -1.0,
                    2 => t[n - 1] + 1.0,
                    _ => rng.next_f32() * (t[n - 1] + 0.5),
                })
                .collect();
            let cdfs: Vec<&[f32]> = tables.iter().map(Vec::as_slice).collect();
            let mut counts = [0usize; SEARCH_LANES];
            below_or_at_each(&cdfs, &us, &mut counts);
            for l in 0..SEARCH_LANES {
                assert_eq!(counts[l], tables[l].partition_point(|&c| c <= us[l]), "{n} {l}");
            }
        }
    }
}
