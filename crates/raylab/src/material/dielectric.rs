//! `dielectric`: smooth glass or water, reflecting and refracting by the Fresnel equations
//! (Mitsuba's `dielectric`; both sides: `wi.z < 0` is light arriving from inside).
//!
//! Radiance is scaled by `1/η'²` when it crosses into a medium of relative index `η'` (the
//! solid angle compresses), and the sample reports `η'` so that Russian roulette can undo that
//! scale (PBR 4th ed. §9.5.2).

use glam::{Vec2, Vec3};

use super::BsdfSample;
use super::fresnel::{fresnel_dielectric, refract};

/// A smooth dielectric interface.
#[derive(Clone, Debug, PartialEq)]
pub struct Dielectric {
    /// Relative index of refraction, inside over outside (`int_ior / ext_ior`).
    pub eta: f32,
}

impl Dielectric {
    /// Reflection with the probability `F`, refraction otherwise.
    #[inline(always)]
    pub fn sample(&self, wi: Vec3, u1: f32, _u2: Vec2) -> Option<BsdfSample> {
        let reflectance = fresnel_dielectric(wi.z, self.eta);
        if u1 < reflectance {
            return Some(BsdfSample {
                wo: Vec3::new(-wi.x, -wi.y, wi.z),
                pdf: reflectance,
                weight: Vec3::ONE,
                delta: true,
                eta: 1.0,
            });
        }
        let (wo, etap) = refract(wi, Vec3::Z, self.eta)?;
        Some(BsdfSample {
            wo,
            pdf: 1.0 - reflectance,
            weight: Vec3::splat(1.0 / (etap * etap)),
            delta: true,
            eta: etap,
        })
    }
}
