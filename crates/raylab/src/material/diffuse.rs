//! `diffuse`: Lambertian reflection, `f = ρ/π` (one-sided, as Mitsuba's).

use std::f32::consts::FRAC_1_PI;

use glam::{Vec2, Vec3};

use super::{BsdfSample, cos_theta};
use crate::sampling::{cosine_hemisphere_pdf, square_to_cosine_hemisphere};

/// A Lambertian reflector.
#[derive(Clone, Debug, PartialEq)]
pub struct Diffuse {
    /// Reflectance ρ per channel, in `[0, 1]`.
    pub reflectance: Vec3,
}

impl Diffuse {
    /// `ρ/π · cos θo` on the front side, zero elsewhere.
    #[inline(always)]
    pub fn eval(&self, wi: Vec3, wo: Vec3) -> Vec3 {
        if cos_theta(wi) <= 0.0 || cos_theta(wo) <= 0.0 {
            return Vec3::ZERO;
        }
        self.reflectance * (FRAC_1_PI * cos_theta(wo))
    }

    /// The cosine-weighted hemisphere's density.
    #[inline(always)]
    pub fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        if cos_theta(wi) <= 0.0 { 0.0 } else { cosine_hemisphere_pdf(wo) }
    }

    /// A cosine-weighted direction: the weight is ρ exactly.
    #[inline(always)]
    pub fn sample(&self, wi: Vec3, _u1: f32, u2: Vec2) -> Option<BsdfSample> {
        if cos_theta(wi) <= 0.0 {
            return None;
        }
        let wo = square_to_cosine_hemisphere(u2);
        let pdf = cosine_hemisphere_pdf(wo);
        (pdf > 0.0).then_some(BsdfSample {
            wo,
            pdf,
            weight: self.reflectance,
            delta: false,
            eta: 1.0,
        })
    }
}
