//! `conductor`: a smooth metal, a perfect mirror tinted by the Fresnel reflectance of its
//! complex index of refraction `eta + i·k` (Mitsuba's `conductor`).

use glam::{Vec2, Vec3};

use super::BsdfSample;
use super::fresnel::fresnel_conductor;

/// A smooth conductor.
#[derive(Clone, Debug, PartialEq)]
pub struct Conductor {
    /// Real part of the index of refraction, per channel.
    pub eta: Vec3,
    /// Imaginary part (absorption), per channel.
    pub k: Vec3,
    /// A tint multiplied in (Mitsuba's `specular_reflectance`; physically 1).
    pub specular_reflectance: Vec3,
}

impl Conductor {
    /// The reflectance for the incident cosine.
    #[inline(always)]
    pub fn reflectance(&self, cos_theta_i: f32) -> Vec3 {
        self.specular_reflectance * fresnel_conductor(cos_theta_i, self.eta, self.k)
    }

    /// The mirror direction, weighted by the Fresnel reflectance.
    #[inline(always)]
    pub fn sample(&self, wi: Vec3, _u1: f32, _u2: Vec2) -> Option<BsdfSample> {
        if wi.z <= 0.0 {
            return None;
        }
        Some(BsdfSample {
            wo: Vec3::new(-wi.x, -wi.y, wi.z),
            pdf: 1.0,
            weight: self.reflectance(wi.z),
            delta: true,
            eta: 1.0,
        })
    }
}

/// Indices of refraction of common metals at the sRGB primaries' wavelengths (about 650, 550
/// and 450 nm; the values many renderers' scene libraries use), as `(name, eta, k)`. Mitsuba
/// integrates measured spectra instead, so its colours differ slightly.
pub const METALS: [(&str, [f32; 3], [f32; 3]); 5] = [
    ("Au", [0.183, 0.421, 1.373], [3.424, 2.346, 1.770]),
    ("Ag", [0.159, 0.145, 0.135], [3.929, 3.190, 2.381]),
    ("Cu", [0.271, 0.677, 1.316], [3.609, 2.625, 2.292]),
    ("Al", [1.657, 0.880, 0.521], [9.224, 6.270, 4.837]),
    // Mitsuba's `none`: a perfect mirror (eta 0, k 1 reflects everything).
    ("none", [0.0, 0.0, 0.0], [1.0, 1.0, 1.0]),
];
