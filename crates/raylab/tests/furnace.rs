//! Known answers of the path tracer (furnace tests): inside a closed surface of uniform diffuse
//! albedo `a` that emits `Le` everywhere, the radiance is `Le/(1 − a)` in every direction, and
//! a path of at most `d` segments sees `Le·(1 − aᵈ)/(1 − a)`.
//!
//! Each picture is made by both path tracers, the wavefront (`path`) and the scalar twin
//! (`path-scalar`), which must agree to the bit; the known answers are then checked once.

use glam::Vec3;
use raylab::integrator::{Integrator, Path};
use raylab::{
    Accumulator, BruteForce, Camera, Geometry, Material, PathScalar, PathSettings, SampleSettings,
    SamplerKind, Scene, TriangleSampling,
};

/// A closed UV sphere of radius 1 about the origin whose triangles face inward (their
/// counter-clockwise side toward the centre), all of material 0.
fn inward_sphere(rings: u32, segments: u32) -> Geometry {
    let point = |ring: u32, segment: u32| {
        let theta = std::f32::consts::PI * ring as f32 / rings as f32;
        let phi = 2.0 * std::f32::consts::PI * (segment % segments) as f32 / segments as f32;
        Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin())
    };
    let mut triangles = Vec::new();
    for ring in 0..rings {
        for segment in 0..segments {
            let (a, b) = (point(ring, segment), point(ring, segment + 1));
            let (c, d) = (point(ring + 1, segment), point(ring + 1, segment + 1));
            for t in [[a, b, d], [a, d, c]] {
                let normal = (t[1] - t[0]).cross(t[2] - t[0]);
                if normal.length_squared() == 0.0 {
                    continue; // The poles' zero-area triangles.
                }
                // Inward: the normal points toward the centre.
                let centroid = (t[0] + t[1] + t[2]) / 3.0;
                let corners = if normal.dot(centroid) < 0.0 { t } else { [t[0], t[2], t[1]] };
                triangles.push((corners, 0));
            }
        }
    }
    let mut geometry = Geometry::new();
    geometry.add_triangles("sphere", triangles);
    geometry
}

fn furnace(albedo: f32, emission: f32) -> Scene {
    let material = Material {
        emission: Vec3::splat(emission),
        ..Material::diffuse("inside", Vec3::splat(albedo))
    };
    Scene {
        name: "furnace".into(),
        geometry: inward_sphere(12, 24),
        materials: vec![material],
        ..Scene::default()
    }
}

/// `spp` passes of `scene` by the scalar path tracer and by the wavefront, which must give the
/// same bits: the film.
fn render_both<A: raylab::Accelerator>(
    scene: &Scene,
    accel: &A,
    settings: PathSettings,
    camera: &Camera,
    samples: SampleSettings,
    spp: u32,
) -> raylab::Film {
    let scalar = PathScalar::new(scene, accel, settings);
    let wavefront = Path::new(scene, accel, settings);
    let [by_path, by_wavefront] = [&scalar as &dyn Integrator, &wavefront].map(|integrator| {
        let mut accumulator = Accumulator::new(camera.width, camera.height).unwrap();
        accumulator.settings = samples;
        for _ in 0..spp {
            accumulator.add_sample(camera, integrator);
        }
        accumulator.mean().unwrap()
    });
    let bits = |film: &raylab::Film| -> Vec<[u32; 3]> {
        film.pixels().iter().map(|p| p.to_array().map(f32::to_bits)).collect()
    };
    assert!(bits(&by_path) == bits(&by_wavefront), "the wavefront's pixels are the scalar path's");
    by_path
}

/// The mean radiance over a small image from the centre, and its standard error (from the
/// spread of the pixels).
fn mean_radiance(
    scene: &Scene,
    settings: PathSettings,
    spp: u32,
    kind: SamplerKind,
) -> (Vec3, f32) {
    let accel = BruteForce::new(&scene.vertices());
    let camera = Camera { position: Vec3::new(0.1, -0.2, 0.05), yaw: 0.7, ..Camera::lab(24, 24) };
    let samples = SampleSettings { seed: 5, sampler: Some(kind), ..SampleSettings::default() };
    let film = render_both(scene, &accel, settings, &camera, samples, spp);
    let n = film.pixels().len() as f32;
    let mean = film.pixels().iter().sum::<Vec3>() / n;
    let variance = film.pixels().iter().map(|p| (p.x - mean.x).powi(2)).sum::<f32>() / (n - 1.0);
    (mean, (variance / n).sqrt())
}

#[test]
fn a_closed_emitting_sphere_shines_le_over_one_minus_a() {
    for (albedo, emission) in [(0.5f32, 0.5f32), (0.8, 0.2), (0.0, 1.5)] {
        let scene = furnace(albedo, emission);
        let expected = emission / (1.0 - albedo);
        let (mean, error) = mean_radiance(&scene, PathSettings::default(), 16, SamplerKind::Sobol);
        // The same by solid-angle sampling of the emitting triangles.
        let solid = PathSettings {
            light_sampling: TriangleSampling::SolidAngle,
            ..PathSettings::default()
        };
        let (mean_solid, error_solid) = mean_radiance(&scene, solid, 16, SamplerKind::Sobol);
        assert!(
            (mean_solid.x - expected).abs() <= (4.0 * error_solid).max(0.01 * expected),
            "solid angle: a = {albedo}: {mean_solid} vs {expected}"
        );
        // Every channel is the same; within four standard errors and 1 %.
        assert!(mean.max_element() - mean.min_element() < 1e-6, "{mean}");
        assert!(
            (mean.x - expected).abs() <= (4.0 * error).max(0.01 * expected),
            "a = {albedo}, Le = {emission}: {mean} vs {expected} (standard error {error})"
        );
    }
}

#[test]
fn max_depth_counts_segments_as_mitsuba_does() {
    let (albedo, emission) = (0.6f32, 1.0f32);
    let scene = furnace(albedo, emission);
    for depth in 0..=4u32 {
        // d segments: Le·(1 + a + … + a^(d−1)).
        let expected = emission * (1.0 - albedo.powi(depth as i32)) / (1.0 - albedo);
        let settings = PathSettings { max_depth: Some(depth), ..PathSettings::default() };
        let (mean, error) = mean_radiance(&scene, settings, 8, SamplerKind::Independent);
        assert!(
            (mean.x - expected).abs() <= (4.0 * error).max(0.005 * expected.max(0.1)),
            "max depth {depth}: {mean} vs {expected}"
        );
    }
}

#[test]
fn the_sphere_is_black_from_outside_and_one_sided() {
    // Seen from outside, the triangles' back faces neither emit nor reflect.
    let scene = furnace(0.5, 1.0);
    let accel = BruteForce::new(&scene.vertices());
    let path = PathScalar::new(&scene, &accel, PathSettings::default());
    let camera = Camera { position: Vec3::new(0.0, 0.0, -3.0), ..Camera::lab(16, 16) };
    let mut accumulator = Accumulator::new(16, 16).unwrap();
    for _ in 0..4 {
        accumulator.add_sample(&camera, &path);
    }
    assert!(accumulator.mean().unwrap().pixels().iter().all(|&p| p == Vec3::ZERO));
}

/// A sphere of `material` (TOML) in a uniform white environment, seen from outside: the mean
/// radiance of the pixels on the sphere and its standard error.
fn sphere_in_white_furnace(material: &str) -> (f32, f32) {
    let text = format!(
        "[materials.m]\n{material}\n\n[[shapes]]\ntype = \"sphere\"\nradius = 1\nmaterial = \"m\"\n\n\
         [[lights]]\ntype = \"environment\"\nradiance = [1, 1, 1]\n"
    );
    let scene = raylab::scene::parse_scene(&text, std::path::Path::new("furnace.toml")).unwrap();
    let accel = raylab::Bvh::new(&scene.vertices());
    // Close enough that the sphere fills the middle of the picture.
    let camera = Camera { position: Vec3::new(0.0, 0.0, -2.5), ..Camera::lab(24, 24) };
    let samples = SampleSettings { seed: 2, ..SampleSettings::default() };
    let film = render_both(&scene, &accel, PathSettings::default(), &camera, samples, 64);
    // The central 8×8 pixels all see the sphere.
    let values: Vec<f32> = (8..16)
        .flat_map(|y| (8..16).map(move |x| (x, y)))
        .map(|(x, y)| film.pixel(x, y).y)
        .collect();
    let n = values.len() as f32;
    let mean = values.iter().sum::<f32>() / n;
    let variance = values.iter().map(|v| (v - mean).powi(2)).sum::<f32>() / (n - 1.0);
    (mean, (variance / n).sqrt())
}

#[test]
fn no_material_creates_energy_in_a_white_furnace_and_smooth_glass_disappears() {
    let materials = [
        ("diffuse white", "type = \"diffuse\"\nreflectance = [1, 1, 1]", true),
        ("mirror", "type = \"conductor\"", true),
        ("gold", "type = \"roughconductor\"\nmaterial = \"Au\"\nalpha = 0.3", false),
        ("glass", "type = \"dielectric\"", true),
        ("rough glass", "type = \"roughdielectric\"\nalpha = 0.2", false),
        ("plastic", "type = \"plastic\"\ndiffuse_reflectance = [1, 1, 1]", false),
    ];
    for (name, material, lossless) in materials {
        let (mean, error) = sphere_in_white_furnace(material);
        eprintln!("{name}: {mean} ± {error}");
        // Never more light than the furnace holds.
        assert!(mean <= 1.0 + 4.0 * error + 1e-3, "{name} creates energy: {mean} ± {error}");
        if lossless {
            // A white diffuser, a perfect mirror and smooth glass send every bit of it on: they
            // are invisible.
            assert!(
                (mean - 1.0).abs() <= 4.0 * error + 0.005,
                "{name} is visible: {mean} ± {error}"
            );
        }
    }
}

/// A sample whose radiance overflows counts as black and is counted, so that `raylab render` can
/// say so; a sound scene discards none.
#[test]
fn samples_that_overflow_are_counted_as_discarded() {
    let count = |emission: f32| {
        let scene = furnace(0.5, emission);
        let accel = BruteForce::new(&scene.vertices());
        let path = PathScalar::new(&scene, &accel, PathSettings::default());
        let wavefront = Path::new(&scene, &accel, PathSettings::default());
        let camera = Camera { position: Vec3::new(0.1, -0.2, 0.05), ..Camera::lab(8, 8) };
        let counts = [&path as &dyn Integrator, &wavefront].map(|integrator| {
            let mut accumulator = Accumulator::new(8, 8).unwrap();
            accumulator.add_sample(&camera, integrator);
            let film = accumulator.mean().unwrap();
            (integrator.discarded_samples(), film.pixels().iter().all(|p| p.is_finite()))
        });
        assert_eq!(counts[0], counts[1], "the wavefront counts as the scalar path does");
        counts[0]
    };
    // Le = f32::MAX seen directly, plus anything more, is infinite.
    assert_eq!(count(f32::MAX), (64, true));
    assert_eq!(count(1.0), (0, true));
}
