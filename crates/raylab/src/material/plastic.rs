//! `plastic`: a diffuse base under a smooth dielectric coating (Mitsuba's `plastic`): a sharp
//! specular reflection by the coating's Fresnel reflectance, and the light that enters,
//! scatters diffusely in the base, and leaves again (with the internal reflections the coating
//! causes, `1/(1 − ρ·Fdr)` in closed form).

use std::f32::consts::FRAC_1_PI;

use glam::{Vec2, Vec3};

use super::BsdfSample;
use super::fresnel::{fresnel_dielectric, fresnel_diffuse_reflectance};
use crate::sampling::{cosine_hemisphere_pdf, square_to_cosine_hemisphere};

/// A smooth plastic.
#[derive(Clone, Debug, PartialEq)]
pub struct Plastic {
    /// The base's reflectance.
    pub diffuse_reflectance: Vec3,
    /// The coating's specular tint (physically 1).
    pub specular_reflectance: Vec3,
    /// Relative index of refraction of the coating, inside over outside.
    pub eta: f32,
    /// Mitsuba's `nonlinear`: internal scattering that saturates colours.
    pub nonlinear: bool,
    /// The diffuse Fresnel reflectance of the coating seen from inside.
    pub(super) internal_reflectance: f32,
    /// The probability of sampling the specular lobe, before the Fresnel factor.
    pub(super) specular_weight: f32,
}

impl Plastic {
    /// A plastic with Mitsuba's parameters.
    pub fn new(diffuse: Vec3, specular: Vec3, eta: f32, nonlinear: bool) -> Plastic {
        let (d_mean, s_mean) = (diffuse.element_sum() / 3.0, specular.element_sum() / 3.0);
        Plastic {
            diffuse_reflectance: diffuse,
            specular_reflectance: specular,
            eta,
            nonlinear,
            internal_reflectance: fresnel_diffuse_reflectance(1.0 / eta),
            specular_weight: if d_mean + s_mean > 0.0 { s_mean / (d_mean + s_mean) } else { 0.5 },
        }
    }

    /// The probability of sampling the specular lobe for `cos θi`.
    #[inline(always)]
    fn specular_probability(&self, cos_theta_i: f32) -> f32 {
        let f = fresnel_dielectric(cos_theta_i, self.eta);
        let specular = f * self.specular_weight;
        let diffuse = (1.0 - f) * (1.0 - self.specular_weight);
        if specular + diffuse > 0.0 { specular / (specular + diffuse) } else { 0.0 }
    }

    /// The diffuse lobe times `cos θo` (the specular lobe is a delta).
    #[inline(always)]
    pub fn eval(&self, wi: Vec3, wo: Vec3) -> Vec3 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return Vec3::ZERO;
        }
        let (f_i, f_o) = (fresnel_dielectric(wi.z, self.eta), fresnel_dielectric(wo.z, self.eta));
        let diffuse = if self.nonlinear {
            self.diffuse_reflectance
                / (Vec3::ONE - self.diffuse_reflectance * self.internal_reflectance)
        } else {
            self.diffuse_reflectance / (1.0 - self.internal_reflectance)
        };
        diffuse * (FRAC_1_PI / (self.eta * self.eta) * wo.z * (1.0 - f_i) * (1.0 - f_o))
    }

    /// The diffuse lobe's share of the cosine density.
    #[inline(always)]
    pub fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return 0.0;
        }
        (1.0 - self.specular_probability(wi.z)) * cosine_hemisphere_pdf(wo)
    }

    /// The coating's mirror reflection or the base's cosine-weighted scattering.
    #[inline(always)]
    pub fn sample(&self, wi: Vec3, u1: f32, u2: Vec2) -> Option<BsdfSample> {
        if wi.z <= 0.0 {
            return None;
        }
        let p_specular = self.specular_probability(wi.z);
        if u1 < p_specular {
            let f = fresnel_dielectric(wi.z, self.eta);
            return Some(BsdfSample {
                wo: Vec3::new(-wi.x, -wi.y, wi.z),
                pdf: p_specular,
                weight: self.specular_reflectance * (f / p_specular),
                delta: true,
                eta: 1.0,
            });
        }
        let wo = square_to_cosine_hemisphere(u2);
        let pdf = (1.0 - p_specular) * cosine_hemisphere_pdf(wo);
        if pdf.is_nan() || pdf <= 0.0 {
            return None;
        }
        Some(BsdfSample { wo, pdf, weight: self.eval(wi, wo) / pdf, delta: false, eta: 1.0 })
    }
}
