//! `roughdielectric`: rough glass, GGX microfacets that reflect and refract (Mitsuba's
//! `roughdielectric`; Walter et al. 2007, "Microfacet Models for Refraction through Rough
//! Surfaces"), sampled by visible normals. Both sides, as the smooth one.

use glam::{Vec2, Vec3};

use super::BsdfSample;
use super::fresnel::{fresnel_dielectric, reflect, refract};
use super::microfacet::Ggx;

/// A rough dielectric interface.
#[derive(Clone, Debug, PartialEq)]
pub struct RoughDielectric {
    /// Relative index of refraction, inside over outside.
    pub eta: f32,
    /// Its microfacets.
    pub distribution: Ggx,
}

/// The generalized half vector of `wi` and `wo`, in the upper hemisphere, and the relative
/// index `η'` (transmitted over incident side; 1 for a reflection).
#[inline(always)]
fn half_vector(wi: Vec3, wo: Vec3, eta: f32) -> Option<(Vec3, f32, bool)> {
    let reflection = wi.z * wo.z > 0.0;
    let etap = if reflection {
        1.0
    } else if wi.z > 0.0 {
        eta
    } else {
        1.0 / eta
    };
    let m = wi + wo * etap;
    if wi.z == 0.0 || wo.z == 0.0 || m.length_squared() == 0.0 {
        return None;
    }
    let m = m.normalize();
    let m = if m.z < 0.0 { -m } else { m };
    // Microfacets seen from behind by either direction do not scatter.
    if m.dot(wi) * wi.z <= 0.0 || m.dot(wo) * wo.z <= 0.0 {
        return None;
    }
    Some((m, etap, reflection))
}

impl RoughDielectric {
    /// The BSDF times `|cos θo|`.
    #[inline(always)]
    pub fn eval(&self, wi: Vec3, wo: Vec3) -> Vec3 {
        let Some((m, etap, reflection)) = half_vector(wi, wo, self.eta) else {
            return Vec3::ZERO;
        };
        let f = fresnel_dielectric(wi.dot(m), self.eta);
        let (d, g) = (self.distribution.d(m), self.distribution.g(wi, wo, m));
        let value = if reflection {
            f * d * g / (4.0 * wi.z.abs())
        } else {
            let denominator = (wi.dot(m) + wo.dot(m) * etap).powi(2) * wi.z.abs();
            // Radiance crossing into η' is scaled by 1/η'².
            (1.0 - f) * d * g * (wi.dot(m) * wo.dot(m)).abs() * etap * etap
                / denominator
                / (etap * etap)
        };
        Vec3::splat(if value.is_finite() { value } else { 0.0 })
    }

    /// The density of [`sample`](Self::sample).
    #[inline(always)]
    pub fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        let Some((m, etap, reflection)) = half_vector(wi, wo, self.eta) else {
            return 0.0;
        };
        let f = fresnel_dielectric(wi.dot(m), self.eta);
        let flipped = if wi.z < 0.0 { -wi } else { wi };
        let pdf_m = self.distribution.visible_pdf(flipped, m);
        let pdf = if reflection {
            f * pdf_m / (4.0 * wi.dot(m).abs())
        } else {
            let denominator = (wi.dot(m) + wo.dot(m) * etap).powi(2);
            (1.0 - f) * pdf_m * etap * etap * wo.dot(m).abs() / denominator
        };
        if pdf.is_finite() { pdf } else { 0.0 }
    }

    /// A visible normal, then reflection with probability `F(wi·m)` or refraction.
    #[inline(always)]
    pub fn sample(&self, wi: Vec3, u1: f32, u2: Vec2) -> Option<BsdfSample> {
        if wi.z == 0.0 {
            return None;
        }
        let flipped = if wi.z < 0.0 { -wi } else { wi };
        let m = self.distribution.sample_visible(flipped, u2);
        let f = fresnel_dielectric(wi.dot(m), self.eta);
        let wo = if u1 < f {
            let wo = reflect(wi, m);
            if wo.z * wi.z <= 0.0 {
                return None;
            }
            wo
        } else {
            let (wo, _) = refract(wi, m, self.eta)?;
            if wo.z * wi.z >= 0.0 {
                return None;
            }
            wo
        };
        let pdf = self.pdf(wi, wo);
        let value = self.eval(wi, wo);
        if pdf.is_nan() || pdf <= 0.0 || value == Vec3::ZERO {
            return None;
        }
        let reflection = wo.z * wi.z > 0.0;
        let etap = if reflection {
            1.0
        } else if wi.z > 0.0 {
            self.eta
        } else {
            1.0 / self.eta
        };
        Some(BsdfSample { wo, pdf, weight: value / pdf, delta: false, eta: etap })
    }
}
