//! Every BSDF against itself: samples against the density (chi-square), the density's integral
//! against the fraction sampled, `weight = eval / pdf`, reciprocity and energy conservation.

use glam::{Vec2, Vec3};

use super::*;
use crate::sampling::Pcg32;
use crate::sampling::chi2::{self, Sphere};

/// Incident directions the tests use: head on, oblique, grazing and from behind.
pub(crate) fn incident_directions() -> Vec<Vec3> {
    [(0.0f32, 0.0f32), (35.0, 20.0), (70.0, 200.0), (88.0, 45.0), (130.0, 10.0)]
        .map(|(theta, phi)| {
            let (st, ct) = theta.to_radians().sin_cos();
            let (sp, cp) = phi.to_radians().sin_cos();
            Vec3::new(st * cp, st * sp, ct)
        })
        .to_vec()
}

/// The BSDFs under test, with names.
pub(crate) fn bsdfs() -> Vec<(&'static str, Bsdf)> {
    let gold = Conductor {
        eta: Vec3::new(0.183, 0.421, 1.373),
        k: Vec3::new(3.424, 2.346, 1.770),
        specular_reflectance: Vec3::ONE,
    };
    vec![
        ("diffuse", Bsdf::Diffuse(Diffuse { reflectance: Vec3::new(0.8, 0.5, 0.2) })),
        ("conductor", Bsdf::Conductor(gold.clone())),
        (
            "roughconductor 0.3",
            Bsdf::RoughConductor(RoughConductor {
                conductor: gold.clone(),
                distribution: Ggx::new(0.3, 0.3),
            }),
        ),
        (
            "roughconductor anisotropic",
            Bsdf::RoughConductor(RoughConductor {
                conductor: gold,
                distribution: Ggx::new(0.5, 0.1),
            }),
        ),
        ("dielectric", Bsdf::Dielectric(Dielectric { eta: 1.5 })),
        (
            "roughdielectric 0.3",
            Bsdf::RoughDielectric(RoughDielectric { eta: 1.5, distribution: Ggx::new(0.3, 0.3) }),
        ),
        (
            "roughdielectric 0.1 water",
            Bsdf::RoughDielectric(RoughDielectric { eta: 1.33, distribution: Ggx::new(0.1, 0.2) }),
        ),
        ("plastic", Bsdf::Plastic(Plastic::new(Vec3::new(0.5, 0.3, 0.1), Vec3::ONE, 1.49, false))),
        (
            "plastic nonlinear",
            Bsdf::Plastic(Plastic::new(Vec3::new(0.9, 0.3, 0.1), Vec3::ONE, 1.49, true)),
        ),
        (
            "pbr dielectric 0.5",
            Bsdf::Pbr(Pbr { base_color: Vec3::new(0.8, 0.4, 0.1), metallic: 0.0, roughness: 0.5 }),
        ),
        (
            "pbr metal 0.3",
            Bsdf::Pbr(Pbr { base_color: Vec3::new(1.0, 0.8, 0.3), metallic: 1.0, roughness: 0.3 }),
        ),
        (
            "pbr half metal 0.8",
            Bsdf::Pbr(Pbr { base_color: Vec3::new(0.2, 0.9, 0.5), metallic: 0.5, roughness: 0.8 }),
        ),
        (
            "pbr dielectric 0.1",
            Bsdf::Pbr(Pbr { base_color: Vec3::new(0.9, 0.9, 0.9), metallic: 0.0, roughness: 0.1 }),
        ),
    ]
}

fn draw(bsdf: &Bsdf, wi: Vec3, rng: &mut Pcg32) -> Option<BsdfSample> {
    let u1 = rng.next_f32();
    let u2 = Vec2::new(rng.next_f32(), rng.next_f32());
    bsdf.sample(wi, u1, u2)
}

#[test]
fn samples_follow_the_density_and_it_integrates_to_the_sampled_fraction() {
    let cases = bsdfs();
    let tests = cases.len() * incident_directions().len();
    for (name, bsdf) in &cases {
        for wi in incident_directions() {
            // Delta samples have no density to test: leave them out of both sides.
            let outcome = chi2::run(
                &Sphere,
                (16, 32),
                300_000,
                7,
                |rng| draw(bsdf, wi, rng).filter(|s| !s.delta).map(|s| s.wo),
                |wo| bsdf.pdf(wi, wo),
            );
            outcome.assert_fits(&format!("{name} at wi {wi}"), tests, 2e-3);
        }
    }
}

#[test]
fn sample_weights_are_eval_over_pdf_and_pdf_matches() {
    for (name, bsdf) in bsdfs() {
        let mut rng = Pcg32::new(3, 4);
        for wi in incident_directions() {
            for _ in 0..2000 {
                let Some(s) = draw(&bsdf, wi, &mut rng) else { continue };
                assert!(s.weight.is_finite() && s.weight.min_element() >= 0.0, "{name}: {s:?}");
                if s.delta {
                    continue;
                }
                let pdf = bsdf.pdf(wi, s.wo);
                assert!((pdf - s.pdf).abs() <= 1e-4 * pdf.max(1.0), "{name}: pdf {pdf} vs {s:?}");
                let expected = bsdf.eval(wi, s.wo) / s.pdf;
                assert!(
                    (expected - s.weight).abs().max_element()
                        <= 1e-4 * expected.max_element().max(1.0),
                    "{name}: weight {} vs eval/pdf {expected}",
                    s.weight
                );
            }
        }
    }
}

#[test]
fn eval_is_reciprocal() {
    // f(wi, wo) = f(wo, wi): eval carries cos θo, so compare eval/cos θo both ways.
    for (name, bsdf) in bsdfs() {
        let directions = incident_directions();
        for &a in &directions {
            for &b in &directions {
                if a.z <= 0.0 || b.z <= 0.0 {
                    continue;
                }
                let ab = bsdf.eval(a, b) / b.z;
                let ba = bsdf.eval(b, a) / a.z;
                assert!(
                    (ab - ba).abs().max_element() <= 1e-5 * ab.max_element().max(1.0),
                    "{name}: {a} {b}"
                );
            }
        }
    }
}

#[test]
fn no_bsdf_reflects_more_than_arrives() {
    // The directional albedo, the mean sample weight (a white furnace for one bounce), is at
    // most 1 in every channel, and one-sided BSDFs are black from behind.
    for (name, bsdf) in bsdfs() {
        let mut rng = Pcg32::new(11, 12);
        for wi in incident_directions() {
            let n = 100_000;
            let mut sum = Vec3::ZERO;
            for _ in 0..n {
                if let Some(s) = draw(&bsdf, wi, &mut rng) {
                    // Power, not radiance: undo the 1/η'² of a crossing.
                    sum += s.weight * s.eta * s.eta;
                }
            }
            let albedo = sum / n as f32;
            assert!(albedo.max_element() <= 1.0 + 0.01, "{name} at {wi}: albedo {albedo}");
            let two_sided = matches!(bsdf, Bsdf::Dielectric(_) | Bsdf::RoughDielectric(_));
            if wi.z < 0.0 && !two_sided {
                assert_eq!(albedo, Vec3::ZERO, "{name} is one-sided");
            }
            // Lossless interfaces keep all of it (rough ones lose a little to single scattering).
            if let Bsdf::Dielectric(_) = bsdf {
                assert!(
                    (albedo - Vec3::ONE).abs().max_element() < 0.01,
                    "{name} at {wi}: {albedo}"
                );
            }
        }
    }
}

#[test]
fn diffuse_reflects_its_reflectance() {
    let bsdf = Bsdf::Diffuse(Diffuse { reflectance: Vec3::new(0.8, 0.5, 0.2) });
    let s = bsdf.sample(Vec3::Z, 0.5, Vec2::new(0.3, 0.7)).unwrap();
    assert_eq!(s.weight, Vec3::new(0.8, 0.5, 0.2));
    let wo = Vec3::new(0.6, 0.0, 0.8);
    assert!(
        (bsdf.eval(Vec3::Z, wo) - Vec3::new(0.8, 0.5, 0.2) * 0.8 / std::f32::consts::PI).length()
            < 1e-7
    );
    assert!(bsdf.sample(-Vec3::Z, 0.5, Vec2::splat(0.5)).is_none());
    assert_eq!(bsdf.eval(Vec3::Z, -wo), Vec3::ZERO);
}

#[test]
fn invalid_parameters_are_named() {
    let mut material = Material::diffuse("wall", Vec3::new(0.5, 1.5, 0.5));
    assert!(material.validate().unwrap_err().to_string().contains("reflectance"));
    material.bsdf = Bsdf::Diffuse(Diffuse { reflectance: Vec3::splat(0.5) });
    material.emission = Vec3::new(1.0, f32::NAN, 1.0);
    assert!(material.validate().unwrap_err().to_string().contains("emission"));
    material.emission = Vec3::ONE;
    assert_eq!(material.validate(), Ok(()));
    assert!(material.is_emissive());
}

/// A texture's tint on a plastic is the plastic with the tinted diffuse reflectance, lobe
/// sampling weights included (they follow the diffuse reflectance).
#[test]
fn a_tinted_plastic_is_rebuilt_with_its_new_weights() {
    let plastic = Plastic::new(Vec3::splat(0.8), Vec3::ONE, 1.5, false);
    let tint = Vec3::new(0.1, 0.2, 0.05);
    let tinted = Bsdf::Plastic(plastic.clone()).tinted(tint);
    let expected = Plastic::new(Vec3::splat(0.8) * tint, Vec3::ONE, 1.5, false);
    assert_eq!(tinted, Bsdf::Plastic(expected));
    // Only scaling the reflectance would keep the untinted weights: not the same BSDF.
    let mut scaled = plastic;
    scaled.diffuse_reflectance *= tint;
    assert_ne!(tinted, Bsdf::Plastic(scaled));
}
