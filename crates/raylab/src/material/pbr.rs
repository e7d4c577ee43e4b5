//! `pbr`: glTF 2.0's metallic-roughness material (the glTF 2.0 specification, appendix B), as
//! glTF files describe surfaces.
//!
//! A GGX specular lobe (α = roughness², sampled by visible normals as the rough conductor) with
//! Schlick's Fresnel term `F(c) = F0 + (1 − F0)(1 − c)⁵`, over a Lambertian base:
//!
//! ```text
//! F0       = lerp(0.04, base_color, metallic)
//! f cos θo = F(wi·m) D G / (4 cos θi)  +  (1 − F(min(cos θi, cos θo))) (1 − metallic) base_color/π · cos θo
//! ```
//!
//! A metal (`metallic` 1) is the specular lobe tinted by its base colour; a dielectric
//! (`metallic` 0) a diffuse base under a clear coat of index 1.5 (F0 = 0.04).
//!
//! **One departure from the specification.** Its diffuse base is weighted by `1 − F(wi·m)`, at
//! the half vector. That gains energy at grazing angles: seen at 88°, a smooth white dielectric
//! would reflect 1.6 times the light that arrives, and a path tracer shows bright rims. Here
//! the base is weighted by the Fresnel term of the more grazing of the two directions, so that
//! what the coat reflects toward `wi` is never also passed to the base. Head on it is the
//! specification's `1 − F0`. Both lobes are symmetric in `wi` and `wo`, so the BSDF stays
//! reciprocal.
//!
//! **Sampling** picks the specular lobe with the probability of its share of the Fresnel
//! weights seen from `wi` (`F(cos θi)` against `(1 − F(cos θi))(1 − metallic) base_color`), the
//! diffuse lobe otherwise (cosine-weighted); the density is the mixture of both, and the weight
//! `eval / pdf`.

use std::f32::consts::FRAC_1_PI;

use glam::{Vec2, Vec3};

use super::BsdfSample;
use super::fresnel::reflect;
use super::microfacet::Ggx;
use crate::sampling::{cosine_hemisphere_pdf, square_to_cosine_hemisphere};

/// The smallest α: glTF's roughness 0 is a mirror, which the GGX lobe approaches.
const MIN_ALPHA: f32 = 1e-3;

/// glTF's metallic-roughness material.
#[derive(Clone, Debug, PartialEq)]
pub struct Pbr {
    /// The base colour (linear), in `[0, 1]`.
    pub base_color: Vec3,
    /// How metallic, in `[0, 1]`.
    pub metallic: f32,
    /// Perceptual roughness, in `[0, 1]`: α = roughness².
    pub roughness: f32,
}

impl Pbr {
    /// The GGX distribution of its roughness.
    #[inline(always)]
    fn distribution(&self) -> Ggx {
        let alpha = (self.roughness * self.roughness).max(MIN_ALPHA);
        Ggx::new(alpha, alpha)
    }

    /// Schlick's Fresnel reflectance at `cos` between the direction and the microfacet normal.
    #[inline(always)]
    fn fresnel(&self, cos: f32) -> Vec3 {
        let f0 = Vec3::splat(0.04).lerp(self.base_color, self.metallic);
        let x = (1.0 - cos).clamp(0.0, 1.0);
        let x5 = x * x * x * x * x;
        f0 + (Vec3::ONE - f0) * x5
    }

    /// The diffuse base's colour, before the Fresnel term.
    #[inline(always)]
    fn diffuse(&self) -> Vec3 {
        self.base_color * (1.0 - self.metallic)
    }

    /// The probability of sampling the specular lobe, seen from `wi`.
    #[inline(always)]
    fn specular_probability(&self, wi: Vec3) -> f32 {
        let f = self.fresnel(wi.z);
        let specular = f.element_sum();
        let diffuse = ((Vec3::ONE - f) * self.diffuse()).element_sum();
        if diffuse <= 0.0 { 1.0 } else { specular / (specular + diffuse) }
    }

    /// Both lobes, times `cos θo`, on the front side.
    #[inline(always)]
    pub fn eval(&self, wi: Vec3, wo: Vec3) -> Vec3 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return Vec3::ZERO;
        }
        let m = (wi + wo).normalize();
        let distribution = self.distribution();
        let f = self.fresnel(wi.dot(m));
        let specular = f * (distribution.d(m) * distribution.g(wi, wo, m) / (4.0 * wi.z));
        let coat = Vec3::ONE - self.fresnel(wi.z.min(wo.z));
        let diffuse = coat * self.diffuse() * (FRAC_1_PI * wo.z);
        specular + diffuse
    }

    /// The mixture of the visible-normal density (times the reflection's Jacobian) and the
    /// cosine-weighted density.
    #[inline(always)]
    pub fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return 0.0;
        }
        let p = self.specular_probability(wi);
        let m = (wi + wo).normalize();
        let dot = wi.dot(m);
        let specular =
            if dot > 0.0 { self.distribution().visible_pdf(wi, m) / (4.0 * dot) } else { 0.0 };
        p * specular + (1.0 - p) * cosine_hemisphere_pdf(wo)
    }

    /// `u1` picks the lobe, `u2` its direction.
    #[inline(always)]
    pub fn sample(&self, wi: Vec3, u1: f32, u2: Vec2) -> Option<BsdfSample> {
        if wi.z <= 0.0 {
            return None;
        }
        let wo = if u1 < self.specular_probability(wi) {
            reflect(wi, self.distribution().sample_visible(wi, u2))
        } else {
            square_to_cosine_hemisphere(u2)
        };
        if wo.z <= 0.0 {
            return None;
        }
        let pdf = self.pdf(wi, wo);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        Some(BsdfSample { wo, pdf, weight: self.eval(wi, wo) / pdf, delta: false, eta: 1.0 })
    }
}
