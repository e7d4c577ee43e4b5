//! What a light gives the path tracer: a sampled direction toward it with the shadow ray that
//! tests it ([`LightSample`]), a direction toward an infinite light alone
//! ([`DirectionSample`]), and what a ray that finds a light sees ([`Emission`]).

use glam::Vec3;

use crate::ray::{Ray, SurfacePoint};

/// A point sampled on a light, seen from a shading point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// The unit direction from the shading point toward the light.
    pub direction: Vec3,
    /// The radiance arriving from it (unoccluded).
    pub radiance: Vec3,
    /// The density per unit solid angle of this direction; for a delta light (point, spot,
    /// directional), 1. From a light set (the path tracer's `LightSet`), times
    /// the probability of having picked the light.
    pub pdf: f32,
    /// A delta light: no other strategy can find it.
    pub delta: bool,
    /// The ray to test visibility with (from the shading point, ending just before the light).
    pub shadow_ray: Ray,
}

/// A direction toward an infinite light (a sun, an environment map), the radiance arriving
/// along it and its density per unit solid angle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectionSample {
    /// The unit direction toward the light.
    pub direction: Vec3,
    /// The radiance arriving along it.
    pub radiance: Vec3,
    /// The density per unit solid angle with which it was picked.
    pub pdf: f32,
}

impl DirectionSample {
    /// The sample seen from `point`: its shadow ray leaves the surface toward the light and
    /// has no end (an infinite light is not a delta light).
    #[inline]
    pub fn seen_from(self, point: &SurfacePoint) -> LightSample {
        let DirectionSample { direction, radiance, pdf } = self;
        LightSample {
            direction,
            radiance,
            pdf,
            delta: false,
            shadow_ray: point.spawn_ray(direction),
        }
    }
}

/// What a ray that finds a light sees: the radiance, and the density per unit solid angle
/// with which sampling the light would have picked that direction (for the MIS weight).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Emission {
    /// The radiance arriving along the ray.
    pub radiance: Vec3,
    /// The density of the ray's direction under light sampling (times the light's selection
    /// probability, from a light set).
    pub pdf: f32,
}

impl Emission {
    /// Nothing: no light, or a light seen from behind.
    pub const NONE: Emission = Emission { radiance: Vec3::ZERO, pdf: 0.0 };
}

/// The fraction of a shadow ray toward a point on a surface light that is tested: the rest
/// (a relative 10⁻⁴) keeps the light's own triangle out of the test (PBR 4th ed.'s
/// `ShadowEpsilon`).
pub const SHADOW_RAY_LENGTH: f32 = 1.0 - 1e-4;
