use super::*;
use crate::sampling::Pcg32;
use crate::sampling::chi2::{self, Sphere};

/// A map of `width × height` texels with values `f(x, y)`.
fn map(width: u32, height: u32, f: impl Fn(u32, u32) -> Vec3) -> EnvironmentMap {
    let pixels = (0..height).flat_map(|y| (0..width).map(move |x| (x, y))).map(|(x, y)| f(x, y));
    let film = Film::from_pixels(width, height, pixels.collect());
    EnvironmentMap::new("test", film, 1.0, Mat3::IDENTITY).unwrap()
}

fn close(a: Vec3, b: Vec3, tolerance: f32) -> bool {
    (a - b).abs().max_element() <= tolerance
}

/// Mitsuba's convention at known points: the top row is +y, the left edge −z, a quarter of the
/// way +x, half way +z; and `uv_to_direction` inverts `direction_to_uv`.
#[test]
fn the_convention_is_mitsubas() {
    let known = [
        (Vec2::new(0.3, 0.0), Vec3::Y),
        (Vec2::new(0.7, 1.0), -Vec3::Y),
        (Vec2::new(0.0, 0.5), -Vec3::Z),
        (Vec2::new(0.25, 0.5), Vec3::X),
        (Vec2::new(0.5, 0.5), Vec3::Z),
        (Vec2::new(0.75, 0.5), -Vec3::X),
    ];
    for (uv, d) in known {
        assert!(close(uv_to_direction(uv), d, 1e-6), "{uv}: {}", uv_to_direction(uv));
        if uv.y > 0.0 && uv.y < 1.0 {
            assert!((direction_to_uv(d) - uv).abs().max_element() < 1e-6, "{d}");
        }
    }
    let mut rng = Pcg32::new(7, 1);
    for _ in 0..1000 {
        let uv = Vec2::new(rng.next_f32(), 0.01 + 0.98 * rng.next_f32());
        let back = direction_to_uv(uv_to_direction(uv));
        let du = (back.x - uv.x).abs();
        assert!(du.min(1.0 - du) < 1e-5 && (back.y - uv.y).abs() < 1e-5, "{uv} -> {back}");
    }
    // The lab's frame is the scene files' world turned half a turn about x: the map's top (+y
    // in the world) is the lab's −y, its left edge (−z in the world) the lab's +z.
    let m = map(4, 3, |_, y| Vec3::splat([1.0, 2.0, 3.0][y as usize]));
    assert_eq!(m.eval(-Vec3::Y), Vec3::splat(1.0));
    assert_eq!(m.eval(Vec3::Y), Vec3::splat(3.0));
    assert!(close(m.direction(Vec2::new(0.0, 0.5)), Vec3::Z, 1e-6));
}

/// Texel (x, y) is at u = (x + ½)/w, v = y/(h − 1); between centres the lookup is bilinear, and
/// the columns wrap around.
#[test]
fn the_lookup_is_bilinear_between_texel_centres() {
    let value = |x: u32, y: u32| Vec3::new(x as f32, y as f32, (x * 10 + y) as f32);
    let m = map(4, 3, value);
    for y in 0..3 {
        for x in 0..4 {
            let uv = Vec2::new((x as f32 + 0.5) / 4.0, y as f32 / 2.0);
            assert!(close(m.lookup(uv), value(x, y), 1e-5), "({x}, {y}): {}", m.lookup(uv));
        }
    }
    // Half way between columns 1 and 2 and a quarter of the way from row 0 to row 1.
    let got = m.lookup(Vec2::new(0.5, 0.125));
    assert!(
        close(
            got,
            0.75 * (value(1, 0) + value(2, 0)) / 2.0 + 0.25 * (value(1, 1) + value(2, 1)) / 2.0,
            1e-5
        ),
        "{got}"
    );
    // u = 0 lies half way between the last column and the first.
    let got = m.lookup(Vec2::new(0.0, 0.0));
    assert!(close(got, (value(3, 0) + value(0, 0)) / 2.0, 1e-5), "{got}");
    // A one-row image is constant across rows.
    let row = map(3, 1, |x, _| Vec3::splat(x as f32));
    assert_eq!(row.size(), (3, 2));
    assert_eq!(row.lookup(Vec2::new(0.5, 0.7)), Vec3::splat(1.0));
}

/// A map's `(u, v)` square as a chi-square domain, for densities over it: a histogram whose
/// cells lie each within one bilinear patch (twice as many as the patches across and down,
/// the patches starting half a texel in) integrates a piecewise-constant density exactly, which
/// a small, very bright sun needs.
struct MapSquare<'a>(&'a EnvironmentMap);

impl chi2::Domain for MapSquare<'_> {
    fn to_unit(&self, d: Vec3) -> Option<glam::DVec2> {
        Some(direction_to_uv(self.0.to_local * d).as_dvec2())
    }
    fn point_at(&self, u: glam::DVec2) -> Vec3 {
        self.0.direction(u.as_vec2())
    }
    fn measure_per_unit(&self) -> f64 {
        1.0
    }
}

/// The density over the map's square of a density per solid angle at `d`: times the Jacobian
/// `2π² sin θ`, with `sin θ` found from the direction in the map's frame.
fn per_square(m: &EnvironmentMap, d: Vec3) -> f32 {
    let local = m.to_local * d.normalize();
    m.pdf(d.normalize()) * 2.0 * PI * PI * (local.x * local.x + local.z * local.z).sqrt()
}

/// The samples follow their density (chi-square), the density matches `pdf`, and it integrates
/// to one, for maps with a small bright sun, black regions and a gradient, turned by a
/// `to_world`: over the map's square (cells within patches), and for maps without a sun over
/// the sphere too (the density per solid angle, in a frame of the test's own).
#[test]
fn sampling_fits_its_density() {
    let sky = |_: u32, y: u32| Vec3::new(0.2, 0.4, 1.0) * (1.0 - y as f32 / 32.0);
    let sun = move |x: u32, y: u32| {
        if (x, y) == (11, 9) {
            Vec3::splat(2000.0)
        } else if y > 20 {
            Vec3::ZERO
        } else {
            sky(x, y)
        }
    };
    let stripes = |x: u32, y: u32| {
        if x % 7 < 3 { Vec3::new(1.0, 0.0, 0.0) * (y + 1) as f32 } else { Vec3::ZERO }
    };
    let turned = Mat3::from_axis_angle(Vec3::new(1.0, 2.0, 0.5).normalize(), 0.8);
    let image = |f: &dyn Fn(u32, u32) -> Vec3| {
        Film::from_pixels(
            48,
            33,
            (0..33).flat_map(|y| (0..48).map(move |x| (x, y))).map(|(x, y)| f(x, y)).collect(),
        )
    };
    let maps = [
        ("sun", map(48, 33, sun), false),
        ("stripes", map(28, 17, stripes), true),
        ("turned sun", EnvironmentMap::new("turned", image(&sun), 3.0, turned).unwrap(), false),
        ("turned sky", EnvironmentMap::new("turned", image(&sky), 1.0, turned).unwrap(), true),
        ("one texel", map(1, 1, |_, _| Vec3::ONE), true),
    ];
    let tests = maps.len() + maps.iter().filter(|m| m.2).count();
    for (name, m, smooth) in &maps {
        let (mut drawn, mut mismatches) = (0u32, 0u32);
        let mut sample = |rng: &mut Pcg32| {
            let sample = m.sample(Vec2::new(rng.next_f32(), rng.next_f32()))?;
            let (d, radiance, pdf) = (sample.direction, sample.radiance, sample.pdf);
            assert!((d.length() - 1.0).abs() < 1e-5);
            // The radiance found looking along the sampled direction, but for the rounding
            // of the direction (beside the sun, the map climbs by 6000 across a texel).
            let tolerance = 1e-5 * 6000.0;
            assert!(
                close(radiance, m.eval(d), tolerance),
                "{name}: {radiance} against {}",
                m.eval(d)
            );
            // Sampled on a patch's edge, a direction may round into the next patch: a few in
            // 10⁴ are allowed to differ.
            drawn += 1;
            if (pdf - m.pdf(d)).abs() > 1e-3 * pdf {
                mismatches += 1;
            }
            Some(d)
        };
        let (w, h) = m.size();
        chi2::run(&MapSquare(m), (2 * w, 2 * (h - 1)), 400_000, 11, &mut sample, |d| {
            per_square(m, d)
        })
        .assert_fits(&format!("{name} over the square"), tests, 1e-4);
        if *smooth {
            chi2::run(&Sphere, (20, 40), 400_000, 12, &mut sample, |d| m.pdf(d.normalize()))
                .assert_fits(&format!("{name} over the sphere"), tests, 2e-3);
        }
        assert!(
            mismatches * 10_000 <= 3 * drawn,
            "{name}: {mismatches} of {drawn} sampled densities differ from pdf()"
        );
    }
}

/// A map's mean is ∫ L dω / 4π of the interpolated map: a constant map's is its value; a map
/// bright down to the equator (row 4 of 9) and black from row 5 has the upper hemisphere's 2π
/// plus the ramp between them.
#[test]
fn the_mean_is_the_radiance_over_the_sphere() {
    use std::f64::consts::PI;
    let constant = map(16, 9, |_, _| Vec3::new(0.5, 1.0, 2.0));
    assert!(close(constant.mean(), Vec3::new(0.5, 1.0, 2.0), 1e-6), "{}", constant.mean());
    let upper = map(16, 9, |_, y| if y <= 4 { Vec3::ONE } else { Vec3::ZERO });
    // The ramp falls linearly in θ from 1 at π/2 to 0 at 5π/8: midpoint rule, 10⁵ steps.
    let n = 100_000;
    let ramp: f64 = (0..n)
        .map(|i| {
            let t = (i as f64 + 0.5) / n as f64;
            (1.0 - t) * (PI * (0.5 + t / 8.0)).sin() * 2.0 * PI * (PI / 8.0) / n as f64
        })
        .sum();
    let expected = (2.0 * PI + ramp) / (4.0 * PI);
    assert!((upper.mean().x as f64 - expected).abs() < 1e-6, "{} against {expected}", upper.mean());
}

#[test]
fn bad_maps_are_refused_with_their_reasons() {
    let film = || Film::from_pixels(2, 2, vec![Vec3::ONE; 4]);
    let problem = |film: Film, scale: f32, to_world: Mat3| {
        EnvironmentMap::new("sky.hdr", film, scale, to_world).unwrap_err().to_string()
    };
    assert!(problem(film(), -1.0, Mat3::IDENTITY).contains("scale -1"));
    assert!(problem(film(), f32::NAN, Mat3::IDENTITY).contains("scale NaN"));
    let stretched = Mat3::from_diagonal(Vec3::new(2.0, 1.0, 1.0));
    assert!(problem(film(), 1.0, stretched).contains("rotation"));
    let mut pixels = vec![Vec3::ONE; 6];
    pixels[4] = Vec3::new(1.0, f32::NAN, 0.0);
    let message = problem(Film::from_pixels(3, 2, pixels), 1.0, Mat3::IDENTITY);
    assert!(message.starts_with("sky.hdr: texel (1, 1)"), "{message}");
    // No texels, or taller than wide: no map of the sphere.
    assert!(problem(Film::from_pixels(0, 0, vec![]), 1.0, Mat3::IDENTITY).contains("0×0"));
    assert!(
        problem(Film::from_pixels(1, 3, vec![Vec3::ONE; 3]), 1.0, Mat3::IDENTITY).contains("1×3")
    );
    // Too bright once scaled.
    let message =
        problem(Film::from_pixels(2, 2, vec![Vec3::splat(1e30); 4]), 10.0, Mat3::IDENTITY);
    assert!(message.contains("texel (0, 0) times scale 10"), "{message}");
    // A mirror is a rotation's kin: allowed.
    assert!(
        EnvironmentMap::new("m", film(), 1.0, Mat3::from_diagonal(Vec3::new(-1.0, 1.0, 1.0)))
            .is_ok()
    );
    // Negative texels are black.
    let negative = Film::from_pixels(2, 2, vec![Vec3::new(-1.0, 2.0, 0.0); 4]);
    let m = EnvironmentMap::new("m", negative, 1.0, Mat3::IDENTITY).unwrap();
    assert_eq!(m.eval(Vec3::X), Vec3::new(0.0, 2.0, 0.0));
}

/// `Debug` (which `Scene::content_hash` hashes) tells maps apart by their texels and
/// orientation, not their names, and stays short however large the map.
#[test]
fn debug_names_the_content_not_the_file() {
    let film = |value: f32| Film::from_pixels(64, 32, vec![Vec3::splat(value); 64 * 32]);
    let debug = |name: &str, value: f32, to_world: Mat3| {
        format!("{:?}", EnvironmentMap::new(name, film(value), 1.0, to_world).unwrap())
    };
    let a = debug("a.hdr", 1.0, Mat3::IDENTITY);
    assert_eq!(a, debug("elsewhere/b.hdr", 1.0, Mat3::IDENTITY));
    assert_ne!(a, debug("a.hdr", 1.5, Mat3::IDENTITY));
    assert_ne!(a, debug("a.hdr", 1.0, Mat3::from_rotation_y(0.5)));
    assert!(a.len() < 200, "{a}");
}

/// The lanes' picks (`sample_each`, their searches in step) are `sample`'s to the bit, for
/// numbers at 0, just below 1 and at random, on maps with black rows and columns, a bright
/// texel at the seam and the poles, and a single texel; in groups of every size up to sixteen.
#[test]
fn sampling_in_step_is_sampling_one_by_one() {
    let below_one = 1.0 - f32::EPSILON / 2.0;
    let maps = [
        map(16, 9, |x, y| if x == 15 && y == 4 { Vec3::splat(500.0) } else { Vec3::splat(0.1) }),
        map(12, 7, |_, y| if y == 0 || y == 6 { Vec3::new(9.0, 1.0, 0.0) } else { Vec3::ZERO }),
        map(64, 33, |x, y| if x % 5 == 0 || y % 7 == 0 { Vec3::ZERO } else { Vec3::ONE }),
        map(1, 1, |_, _| Vec3::ONE),
    ];
    let mut rng = Pcg32::new(48, 1);
    let mut compared = 0;
    for m in &maps {
        for size in 1..=crate::sampling::SEARCH_LANES {
            for _ in 0..40 {
                let number = |rng: &mut Pcg32| match rng.next_u32() % 6 {
                    0 => 0.0,
                    1 => below_one,
                    _ => rng.next_f32(),
                };
                let us: Vec<Vec2> =
                    (0..size).map(|_| Vec2::new(number(&mut rng), number(&mut rng))).collect();
                let mut each = vec![None; size];
                m.sample_each(&us, &mut each);
                for (u, got) in us.iter().zip(&each) {
                    let want = m.sample(*u);
                    let bits = |s: &Option<DirectionSample>| {
                        s.map(|s| (s.direction.to_array(), s.radiance.to_array(), s.pdf)).map(
                            |(d, r, p)| (d.map(f32::to_bits), r.map(f32::to_bits), p.to_bits()),
                        )
                    };
                    assert_eq!(bits(got), bits(&want), "{u}");
                    compared += 1;
                }
            }
        }
    }
    assert_eq!(compared, maps.len() * 40 * (1..=16).sum::<usize>());
}

/// What a ray leaving the scene sees and its density, read the plain way (`lookup`, the
/// density's `rem_euclid`, checked indexing): the twin `eval_pdf_inline` must match.
fn eval_pdf_plain(m: &EnvironmentMap, direction: Vec3) -> Emission {
    let local = m.to_local * direction;
    let uv = direction_to_uv(local);
    let radiance = m.lookup(uv);
    let sin_theta = (local.x * local.x + local.z * local.z).sqrt();
    if sin_theta <= 0.0 {
        return Emission { radiance, pdf: 0.0 };
    }
    let (columns, rows) = (m.width, m.height - 1);
    let x = (uv.x * columns as f32 - 0.5).rem_euclid(columns as f32);
    let y = uv.y * rows as f32;
    let (column, row) = ((x as usize).min(columns - 1), (y as usize).min(rows - 1));
    let within = Vec2::new(x - column as f32, y - row as f32).clamp(Vec2::ZERO, Vec2::ONE);
    let f = m.corners(column, row);
    let pdf_uv =
        m.patches.probability(column, row) * (columns * rows) as f32 * bilinear_pdf(within, f);
    Emission { radiance, pdf: pdf_uv / (2.0 * PI * PI * sin_theta) }
}

/// On every instruction set this CPU has, the lookups in lanes (`eval_pdf_each_on`) and the
/// scalar `eval_pdf` give the plain reading's bits: at the poles, on the seam (either side and
/// both zeros), all around, for directions of any length, zero and NaN, on maps turned or not,
/// one texel wide or a single texel.
#[test]
fn lookups_in_lanes_are_the_plain_readings_bits() {
    let turned = Mat3::from_rotation_y(0.7) * Mat3::from_rotation_x(0.3);
    let image = |w: u32, h: u32| {
        let pixels = (0..w * h).map(|i| Vec3::new((i % 11) as f32, 0.5, (i % 5) as f32)).collect();
        Film::from_pixels(w, h, pixels)
    };
    let maps = [
        map(16, 9, |x, y| Vec3::new(x as f32, y as f32, 1.0)),
        EnvironmentMap::new("turned", image(24, 13), 2.0, turned).unwrap(),
        map(3, 2, |x, _| Vec3::splat(x as f32)),
        map(1, 1, |_, _| Vec3::ONE),
    ];
    let mut rng = Pcg32::new(48, 5);
    let mut directions = vec![
        Vec3::Y,
        -Vec3::Y,
        Vec3::Z,
        -Vec3::Z,
        Vec3::new(0.0, 0.3, 1.0),
        Vec3::new(-0.0, 0.3, 1.0),
        Vec3::new(1e-30, 0.3, 1.0),
        Vec3::new(-1e-30, 0.3, 1.0),
        Vec3::new(0.0, -0.2, -1.0),
        Vec3::ZERO,
        Vec3::splat(f32::NAN),
        Vec3::new(1e-20, 1.0, 0.0),
    ];
    for _ in 0..3000 {
        let v = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
        let length = [1.0, 1e-3, 7.0][rng.next_u32() as usize % 3];
        directions.push(v.normalize_or_zero() * length);
    }
    let bits = |e: &Emission| (e.radiance.to_array().map(f32::to_bits), e.pdf.to_bits());
    let same = |a: &Emission, b: &Emission| {
        bits(a) == bits(b)
            || (a.radiance.is_nan() && b.radiance.is_nan() && a.pdf.is_nan() && b.pdf.is_nan())
    };
    for m in &maps {
        let plain: Vec<Emission> = directions.iter().map(|&d| eval_pdf_plain(m, d)).collect();
        for (d, want) in directions.iter().zip(&plain) {
            assert!(same(&m.eval_pdf(*d), want), "{d}");
        }
        for isa in crate::cpu::Isa::ALL.into_iter().filter(|isa| isa.is_supported()) {
            let mut out = vec![Emission::NONE; directions.len()];
            m.eval_pdf_each_on(isa, &directions, &mut out);
            for ((d, got), want) in directions.iter().zip(&out).zip(&plain) {
                assert!(same(got, want), "{isa:?} {d}: {got:?} against {want:?}");
            }
        }
    }
}
