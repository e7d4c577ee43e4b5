//! Known answers for the lights beyond the lab's:
//!
//! - a constant environment map is the constant `environment` (a white sphere in it vanishes);
//! - a map with one bright texel lights a surface from the direction Mitsuba 3's convention
//!   gives, also when `to_world` turns it;
//! - a directional light gives a diffuse floor `ρ E cos θ / π`; a sun disc gives
//!   `ρ E cos θ (1 + cos α) / 2π` (the mean direction over a cap), converging to the
//!   directional light as it shrinks, and half of it on a shadow's edge;
//! - a spot light lights a floor as `ρ I f(θ) cos³θ / (π h²)` with Mitsuba's profile `f`,
//!   and not at all beyond its cutoff;
//! - importance sampling a sky with a sun pays: at equal samples its error is less than a
//!   fifth of uniform sampling's.
//!
//! Every radiance but the last test's is computed by both path tracers, the scalar and the
//! wavefront, which must agree to the bit.

use std::f32::consts::PI;
use std::sync::Arc;

use glam::{Mat3, Vec3};
use raylab::Scene;
use raylab::integrator::{EnvironmentSampling, Integrator, Path};
use raylab::light::{DirectionalLight, EnvironmentMap, SpotLight, SpotProfile, SunLight};
use raylab::{
    Bvh, Film, Geometry, Light, Material, PathScalar, PathSettings, Ray, Sampler, SamplerKind,
};

/// The diffuse reflectance of every surface here.
const ALBEDO: f32 = 0.8;

/// The mean radiance along each ray over `spp` samples, by the scalar path tracer and the
/// wavefront, which must agree to the bit.
fn radiance(scene: &Scene, rays: &[Ray], spp: u32) -> Vec<Vec3> {
    radiance_with(scene, rays, spp, PathSettings::default())
}

/// [`radiance`] with `settings`.
fn radiance_with(scene: &Scene, rays: &[Ray], spp: u32, settings: PathSettings) -> Vec<Vec3> {
    let accel = Bvh::new(&scene.vertices());
    let scalar = PathScalar::new(scene, &accel, settings);
    let wavefront = Path::new(scene, &accel, settings);
    let [by_path, by_wavefront] = [&scalar as &dyn Integrator, &wavefront]
        .map(|integrator| mean_radiance(integrator, rays, spp, SamplerKind::Independent));
    let bits = |v: &[Vec3]| -> Vec<[u32; 3]> {
        v.iter().map(|c| c.to_array().map(f32::to_bits)).collect()
    };
    assert!(bits(&by_path) == bits(&by_wavefront), "the wavefront's radiance is the scalar path's");
    by_path
}

/// The mean of `spp` samples of `integrator` along each ray.
fn mean_radiance(
    integrator: &dyn Integrator,
    rays: &[Ray],
    spp: u32,
    kind: SamplerKind,
) -> Vec<Vec3> {
    let mut sum = vec![Vec3::ZERO; rays.len()];
    let mut out = vec![Vec3::ZERO; rays.len()];
    for index in 0..spp {
        let mut samplers: Vec<Sampler> =
            (0..rays.len()).map(|i| Sampler::new(kind, 9, (i as u32, 0), index)).collect();
        integrator.radiance_each(rays, &mut samplers, &mut out);
        for (s, o) in sum.iter_mut().zip(&out) {
            *s += *o;
        }
    }
    sum.into_iter().map(|s| s / spp as f32).collect()
}

/// A square of half-width `half` about `centre` whose front faces `normal` (its triangles
/// counter-clockwise about it), in `material`.
fn square(centre: Vec3, normal: Vec3, half: f32, material: u32) -> Vec<([Vec3; 3], u32)> {
    let (s, t) = raylab::sampling::orthonormal_basis(normal);
    let corner = |a: f32, b: f32| centre + half * (a * s + b * t);
    let [a, b, c, d] = [corner(-1.0, -1.0), corner(1.0, -1.0), corner(1.0, 1.0), corner(-1.0, 1.0)];
    vec![([a, b, c], material), ([a, c, d], material)]
}

/// A scene of `triangles` in white diffuse (material 0), lit by `lights`.
fn scene(triangles: Vec<([Vec3; 3], u32)>, lights: Vec<Light>) -> Scene {
    let mut geometry = Geometry::new();
    geometry.add_triangles("squares", triangles);
    Scene {
        name: "lights".into(),
        geometry,
        materials: vec![Material::diffuse("white", Vec3::splat(ALBEDO))],
        lights,
        ..Scene::default()
    }
}

/// A ray from one unit in front of `point` (along `normal`) straight at it.
fn ray_at(point: Vec3, normal: Vec3) -> Ray {
    Ray::new(point + normal, -normal)
}

fn map(width: u32, height: u32, f: impl Fn(u32, u32) -> Vec3, to_world: Mat3) -> Light {
    let pixels = (0..height).flat_map(|y| (0..width).map(move |x| (x, y))).map(|(x, y)| f(x, y));
    let film = Film::from_pixels(width, height, pixels.collect());
    Light::EnvironmentMap(Arc::new(EnvironmentMap::new("test", film, 1.0, to_world).unwrap()))
}

/// The scene files' y-up world to the lab's frame (`raylab::scene::model_to_lab`).
fn lab(v: Vec3) -> Vec3 {
    raylab::scene::model_to_lab(v)
}

/// A white sphere in a constant map shines the map's radiance (it reflects all of it, and
/// nothing else lights it), as in the constant `environment`, which it equals; rays that miss
/// see the map.
#[test]
fn a_constant_map_is_the_constant_environment() {
    let value = Vec3::new(0.3, 0.6, 0.9);
    let text = "[materials.m]\ntype = \"diffuse\"\nreflectance = [1, 1, 1]\n\n[[shapes]]\n\
                type = \"sphere\"\nradius = 1\nmaterial = \"m\"\n";
    let mut sphere = raylab::scene::parse_scene(text, std::path::Path::new("s.toml")).unwrap();
    let rays: Vec<Ray> = [(0.0, 0.0), (0.3, -0.2), (-0.5, 0.4), (0.1, 0.7), (3.0, 0.0)]
        .into_iter()
        .map(|(x, y)| Ray::new(Vec3::new(x, y, -3.0), Vec3::Z))
        .collect();
    sphere.lights = vec![map(8, 5, |_, _| value, Mat3::IDENTITY)];
    let mapped = radiance(&sphere, &rays, 4096);
    sphere.lights = vec![Light::Environment { radiance: value }];
    let constant = radiance(&sphere, &rays, 4096);
    for (i, (m, c)) in mapped.iter().zip(&constant).enumerate() {
        assert!((*m - value).abs().max_element() < 0.01 * value.max_element(), "ray {i}: {m}");
        assert!((*c - value).abs().max_element() < 0.01 * value.max_element(), "ray {i}: {c}");
    }
    // The ray that misses sees the map itself (but for the rounding of its interpolation).
    assert!((mapped[4] - value).abs().max_element() < 1e-4, "{}", mapped[4]);
}

/// Mitsuba's direction of texel `(x, y)` of a `w × h` map, in the map's frame: `u = (x + ½)/w`,
/// `v = y/(h − 1)`, `d = (sin φ sin θ, cos θ, −cos φ sin θ)`.
fn mitsuba_direction(x: u32, y: u32, w: u32, h: u32) -> Vec3 {
    let phi = 2.0 * std::f64::consts::PI * (x as f64 + 0.5) / w as f64;
    let theta = std::f64::consts::PI * y as f64 / (h - 1) as f64;
    Vec3::new(
        (phi.sin() * theta.sin()) as f32,
        theta.cos() as f32,
        (-phi.cos() * theta.sin()) as f32,
    )
}

/// One bright texel lights a white square facing it with `ρ Φ / π` (Φ its power per unit
/// area, `∫ L dω`), a square turned 60° from it with half that, and one turned away not at
/// all: the light comes from Mitsuba's direction, in the map's frame turned by `to_world`.
#[test]
fn one_bright_texel_lights_from_mitsubas_direction() {
    let (w, h, x0, y0, value) = (64u32, 33u32, 23u32, 12u32, 1000.0f32);
    // Φ: the bilinear hat around the texel integrates to 2π/w across and to ∫ hat(θ) sin θ dθ
    // down (θ₀ ± π/(h − 1)).
    let step = std::f64::consts::PI / (h - 1) as f64;
    let theta0 = y0 as f64 * step;
    let n = 10_000;
    let down: f64 = (0..n)
        .map(|i| {
            let t = -1.0 + 2.0 * (i as f64 + 0.5) / n as f64;
            (1.0 - t.abs()) * (theta0 + t * step).sin() * step * 2.0 / n as f64
        })
        .sum();
    let phi_power = value as f64 * 2.0 * std::f64::consts::PI / w as f64 * down;
    let facing = (ALBEDO as f64 * phi_power / std::f64::consts::PI) as f32;
    let turns = [
        Mat3::IDENTITY,
        Mat3::from_rotation_y(90f32.to_radians()),
        Mat3::from_axis_angle(Vec3::new(1.0, 2.0, -0.5).normalize(), 1.1),
    ];
    for to_world in turns {
        let light = map(
            w,
            h,
            |x, y| if (x, y) == (x0, y0) { Vec3::splat(value) } else { Vec3::ZERO },
            to_world,
        );
        let d = lab(to_world * mitsuba_direction(x0, y0, w, h));
        let (s, t) = raylab::sampling::orthonormal_basis(d);
        let tilted = |towards: Vec3| (0.5 * d + 0.75f32.sqrt() * towards).normalize();
        let normals = [d, tilted(s), tilted(-t), -d];
        let expected = [facing, 0.5 * facing, 0.5 * facing, 0.0];
        for (normal, expected) in normals.into_iter().zip(expected) {
            let lit = scene(square(Vec3::ZERO, normal, 0.1, 0), vec![light.clone()]);
            let got = radiance(&lit, &[ray_at(Vec3::ZERO, normal)], 512)[0];
            assert!(
                (got.x - expected).abs() <= 0.02 * facing,
                "to_world {to_world}: a square facing {normal} (the light at {d}): {got} against {expected}"
            );
        }
    }
}

/// Light that comes straight from the lights, without bounces (the roof would light the floor's
/// shadow).
fn direct(scene: &Scene, rays: &[Ray], spp: u32) -> Vec<Vec3> {
    radiance_with(scene, rays, spp, PathSettings { max_depth: Some(2), ..PathSettings::default() })
}

/// A white floor facing up (the lab's −y), its light from 30° off the zenith toward +x.
fn floor_and_light(light: Light, occluder: bool) -> Scene {
    let mut triangles = square(Vec3::ZERO, -Vec3::Y, 10.0, 0);
    if occluder {
        // A roof one unit above, from x = 1 on: its edge shadows the floor along
        // x = 1 − tan 30°.
        triangles.extend(square(Vec3::new(11.0, -1.0, 0.0), Vec3::Y, 10.0, 0));
    }
    scene(triangles, vec![light])
}

const SUN_ZENITH_DEG: f32 = 30.0;

/// The way the light travels, in the lab's frame: down and toward −x.
fn sunlight() -> Vec3 {
    let zenith = SUN_ZENITH_DEG.to_radians();
    lab(-Vec3::new(zenith.sin(), zenith.cos(), 0.0))
}

/// A directional light gives the floor exactly `ρ E cos θ / π`; a sun of the same irradiance
/// gives `ρ E cos θ (1 + cos α)/(2π)` (its mean direction is its centre's, shortened by
/// `(1 + cos α)/2`), which converges to it as the disc shrinks; on a roof's shadow edge the
/// sun gives half, and the directional light is all or nothing either side.
#[test]
fn a_shrinking_sun_becomes_the_directional_light_and_shadows_softly() {
    let irradiance = Vec3::new(2.0, 3.0, 4.0);
    let cos_theta = SUN_ZENITH_DEG.to_radians().cos();
    let up = -Vec3::Y;
    let directional = Light::Directional(DirectionalLight { direction: sunlight(), irradiance });
    let exact = ALBEDO * irradiance * cos_theta / PI;
    let got = direct(&floor_and_light(directional.clone(), false), &[ray_at(Vec3::ZERO, up)], 4)[0];
    assert!(
        (got - exact).abs().max_element() < 1e-5 * exact.max_element(),
        "{got} against {exact}"
    );
    let mut previous = f32::INFINITY;
    for radius_deg in [5.0f32, 1.0, SunLight::EARTH_APERTURE_DEG / 2.0, 0.01] {
        let radius = radius_deg.to_radians();
        let sun = SunLight::with_irradiance(sunlight(), radius, irradiance).unwrap();
        let got =
            direct(&floor_and_light(Light::Sun(sun), false), &[ray_at(Vec3::ZERO, up)], 256)[0];
        let expected = exact * (1.0 + radius.cos()) / 2.0;
        assert!(
            (got - expected).abs().max_element() < 2e-3 * expected.max_element(),
            "sun of {radius_deg}°: {got} against {expected}"
        );
        let off = (got - exact).abs().max_element();
        assert!(
            off <= previous.max(1e-4 * exact.max_element()),
            "{radius_deg}°: {off} after {previous}"
        );
        previous = off;
    }
    // The roof's edge at x = 1 shadows the floor's points with x > 1 − tan 30° from the sun's
    // centre.
    let edge = 1.0 - SUN_ZENITH_DEG.to_radians().tan();
    let points = [edge - 0.2, edge, edge + 0.2];
    let rays: Vec<Ray> = points.iter().map(|&x| ray_at(Vec3::new(x, 0.0, 0.0), 0.5 * up)).collect();
    let hard = direct(&floor_and_light(directional, true), &[rays[0], rays[2]], 4);
    assert!((hard[0] - exact).abs().max_element() < 1e-5 && hard[1] == Vec3::ZERO, "{hard:?}");
    let sun = SunLight::with_irradiance(sunlight(), 1f32.to_radians(), irradiance).unwrap();
    let unshadowed = exact * (1.0 + 1f32.to_radians().cos()) / 2.0;
    let soft = direct(&floor_and_light(Light::Sun(sun), true), &rays, 1024);
    assert!((soft[0] - unshadowed).abs().max_element() < 3e-3 * exact.max_element(), "{soft:?}");
    assert!(
        (soft[1] - 0.5 * unshadowed).abs().max_element() < 0.02 * exact.max_element(),
        "{soft:?}"
    );
    assert_eq!(soft[2], Vec3::ZERO, "{soft:?}");
}

/// A spot two units above a white floor, pointing down (cutoff 30°, beam 20°): at `θ` from
/// its axis the floor's radiance is `ρ I f(θ) cos³θ / (π h²)`, with Mitsuba's profile `f` (1 in
/// the beam, linear in the angle to 0 at the cutoff), and nothing beyond.
#[test]
fn a_spot_light_lights_its_cone_with_mitsubas_profile() {
    let intensity = Vec3::new(10.0, 20.0, 5.0);
    let height = 2.0f32;
    let spot = SpotLight::new(
        Vec3::new(0.0, -height, 0.0),
        Vec3::Y,
        intensity,
        30f32.to_radians(),
        20f32.to_radians(),
        SpotProfile::Mitsuba,
    )
    .unwrap();
    let lit = scene(square(Vec3::ZERO, -Vec3::Y, 10.0, 0), vec![Light::Spot(spot)]);
    let angles = [0.0f32, 10.0, 19.0, 22.0, 25.0, 28.0, 31.0, 45.0];
    let profile = [1.0, 1.0, 1.0, 0.8, 0.5, 0.2, 0.0, 0.0];
    let rays: Vec<Ray> = angles
        .iter()
        .map(|a| ray_at(Vec3::new(height * a.to_radians().tan(), 0.0, 0.0), -0.5 * Vec3::Y))
        .collect();
    let got = radiance(&lit, &rays, 4);
    for ((angle, f), got) in angles.iter().zip(profile).zip(got) {
        let cos = angle.to_radians().cos();
        let expected = ALBEDO * intensity * f * cos.powi(3) / (PI * height * height);
        assert!(
            (got - expected).abs().max_element() <= 1e-4 * intensity.max_element(),
            "{angle}°: {got} against {expected}"
        );
    }
}

/// A white sphere on a white floor under `sky.hdr` (a sun of radius 2.5° and 800 times the
/// sky's radiance, most of the light): 8 × 8 rays, each estimated at 16 samples 32 times over,
/// importance-sampled and uniformly. Both are unbiased, so each one's error is its spread about
/// its own mean (the RMSE of one estimate): importance sampling's is less than a fifth of
/// uniform sampling's; and the two means agree within four standard errors.
#[test]
fn importance_sampling_a_sky_with_a_sun_pays_fivefold() {
    let path = raylab::image_io::load_film(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mitsuba-envmap/sky.hdr"),
    )
    .unwrap();
    let sky = EnvironmentMap::new("sky.hdr", path, 1.0, Mat3::IDENTITY).unwrap();
    let mut triangles = square(Vec3::ZERO, -Vec3::Y, 5.0, 0);
    let sphere = raylab::scene::parse_scene(
        "[materials.m]\ntype = \"diffuse\"\nreflectance = [0.8, 0.8, 0.8]\n\n[[shapes]]\ntype = \"sphere\"\n\
         center = [0, 1, 0]\nradius = 1\nmaterial = \"m\"\n",
        std::path::Path::new("s.toml"),
    )
    .unwrap();
    triangles.extend((0..sphere.geometry.len()).map(|i| (sphere.geometry.triangle(i), 0)));
    let lit = scene(triangles, vec![Light::EnvironmentMap(Arc::new(sky))]);
    let camera = raylab::Camera {
        position: Vec3::new(0.0, -1.5, -4.0),
        pitch: -0.2,
        ..raylab::Camera::lab(8, 8)
    };
    let rays: Vec<Ray> = (0..64).map(|i| camera.pixel_ray(i % 8, i / 8)).collect();
    let accel = Bvh::new(&lit.vertices());
    let errors = [EnvironmentSampling::Importance, EnvironmentSampling::Uniform].map(|sampling| {
        let settings = PathSettings {
            environment_sampling: sampling,
            max_depth: Some(3),
            ..PathSettings::default()
        };
        let path = PathScalar::new(&lit, &accel, settings);
        // 32 estimates of 16 samples each: their spread about their mean.
        let estimates: Vec<Vec<Vec3>> = (0..32u32)
            .map(|k| {
                let samplers = |i: usize, s: u32| {
                    Sampler::new(SamplerKind::Independent, 100 + k as u64, (i as u32, 0), s)
                };
                let mut sum = vec![Vec3::ZERO; rays.len()];
                for s in 0..16 {
                    for (i, ray) in rays.iter().enumerate() {
                        sum[i] += path.radiance(ray, &mut samplers(i, s));
                    }
                }
                sum.into_iter().map(|v| v / 16.0).collect()
            })
            .collect();
        let mean: Vec<Vec3> = (0..rays.len())
            .map(|i| estimates.iter().map(|e| e[i]).sum::<Vec3>() / estimates.len() as f32)
            .collect();
        let squared: f64 = estimates
            .iter()
            .flat_map(|e| e.iter().zip(&mean).map(|(v, m)| (*v - *m).length_squared() as f64))
            .sum();
        let count = (estimates.len() * rays.len()) as f64;
        let rmse = (squared / count).sqrt();
        // The image's mean over every estimate, and its standard error (per channel).
        let overall = mean.iter().map(|m| m.as_dvec3()).sum::<glam::DVec3>() / rays.len() as f64;
        (rmse, overall, rmse / (3.0 * count).sqrt())
    });
    let [(importance, mean_importance, se_importance), (uniform, mean_uniform, se_uniform)] =
        errors;
    eprintln!(
        "RMSE at 16 spp: importance {importance:.4}, uniform {uniform:.4}; means \
         {mean_importance:.4} ± {se_importance:.4} and {mean_uniform:.4} ± {se_uniform:.4}"
    );
    assert!(uniform >= 5.0 * importance, "importance {importance} against uniform {uniform}");
    // Both estimate the same picture: a sampler that missed the sun would be quieter but darker.
    let allowed = 4.0 * (se_importance.powi(2) + se_uniform.powi(2)).sqrt();
    assert!(
        (mean_importance - mean_uniform).abs().max_element() <= allowed,
        "means {mean_importance} against {mean_uniform} (allowed {allowed})"
    );
}
