//! `roughconductor`: a rough metal, GGX microfacets with the conductor's Fresnel reflectance
//! (Mitsuba's `roughconductor`; Walter et al. 2007), sampled by visible normals.

use glam::{Vec2, Vec3};

use super::BsdfSample;
use super::conductor::Conductor;
use super::fresnel::reflect;
use super::microfacet::Ggx;

/// A rough conductor.
#[derive(Clone, Debug, PartialEq)]
pub struct RoughConductor {
    /// The metal's optical constants and tint.
    pub conductor: Conductor,
    /// Its microfacets.
    pub distribution: Ggx,
}

impl RoughConductor {
    /// `F(wi·m) D(m) G(wi, wo) / (4 cos θi)` with `m` the half vector: the BSDF times `cos θo`.
    #[inline(always)]
    pub fn eval(&self, wi: Vec3, wo: Vec3) -> Vec3 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return Vec3::ZERO;
        }
        let m = (wi + wo).normalize();
        let d = self.distribution.d(m);
        let g = self.distribution.g(wi, wo, m);
        self.conductor.reflectance(wi.dot(m)) * (d * g / (4.0 * wi.z))
    }

    /// The visible-normal density of the half vector, times the reflection's Jacobian
    /// `1/(4 wi·m)`.
    #[inline(always)]
    pub fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return 0.0;
        }
        let m = (wi + wo).normalize();
        let dot = wi.dot(m);
        if dot <= 0.0 {
            return 0.0;
        }
        self.distribution.visible_pdf(wi, m) / (4.0 * dot)
    }

    /// A visible normal, and the mirror direction about it.
    #[inline(always)]
    pub fn sample(&self, wi: Vec3, _u1: f32, u2: Vec2) -> Option<BsdfSample> {
        if wi.z <= 0.0 {
            return None;
        }
        let m = self.distribution.sample_visible(wi, u2);
        let wo = reflect(wi, m);
        let dot = wi.dot(m);
        if wo.z <= 0.0 || dot <= 0.0 {
            return None;
        }
        let pdf = self.distribution.visible_pdf(wi, m) / (4.0 * dot);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        // eval / pdf = F · G1(wo): the rest cancels.
        let weight = self.conductor.reflectance(dot) * self.distribution.g1(wo, m);
        Some(BsdfSample { wo, pdf, weight, delta: false, eta: 1.0 })
    }
}
