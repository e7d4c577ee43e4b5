//! What sampling a BSDF gives ([`BsdfSample`]), and the local frame every BSDF works in: the
//! shading normal along `z`, so that `cos θ` is a direction's `z` ([`cos_theta`]).

use glam::Vec3;

/// One sampled direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// The sampled direction `wo`, in the local frame.
    pub wo: Vec3,
    /// Its density per unit solid angle (for a delta lobe, the lobe's discrete probability).
    pub pdf: f32,
    /// `eval(wi, wo) / pdf`: what the path's throughput is multiplied by.
    pub weight: Vec3,
    /// The sample came from a delta (perfectly specular) lobe.
    pub delta: bool,
    /// The relative index of refraction along the sampled direction (1 unless it refracted).
    pub eta: f32,
}

/// `cos θ` of a local direction.
#[inline(always)]
pub(crate) fn cos_theta(w: Vec3) -> f32 {
    w.z
}
