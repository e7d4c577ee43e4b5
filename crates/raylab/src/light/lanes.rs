//! The lights as the wavefront's lanes take them: one record for every kind ([`LaneLight`]),
//! and the sampling of the kinds the lanes sample themselves, as straight-line arithmetic a
//! loop over sixteen lanes turns into vector code: a triangle by area with a constant
//! radiance ([`sample_triangle`]), and the constant environment ([`sample_environment`]).
//! Each is its scalar twin's arithmetic ([`TriangleLight::sample`],
//! [`ConstantEnvironment::sample`]) operation for operation, so a lane's sample is the scalar
//! one to the bit; where an offset point is not finite the lane says so and the scalar code
//! decides. Every other light ([`LaneRole::Other`]) the scalar code samples for the lanes,
//! which take its sample from there.
//!
//! [`TriangleLight::sample`]: super::TriangleLight::sample
//! [`ConstantEnvironment::sample`]: super::ConstantEnvironment::sample

use glam::{Vec2, Vec3};

use super::emitter::Emitter;
use super::sample::SHADOW_RAY_LENGTH;
use super::triangle::TriangleSampling;
use crate::ray::{SurfacePoint, offset_ray_origin_finite};
use crate::sampling::{square_to_uniform_sphere, square_to_uniform_triangle, uniform_sphere_pdf};

/// How the lanes take a light ([`LaneLight::role`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) enum LaneRole {
    /// No light: nothing to sample.
    #[default]
    Nothing,
    /// A triangle the lanes sample uniformly by area, with a constant radiance.
    Triangle,
    /// The constant environment, which the lanes sample by [`square_to_uniform_sphere`].
    Environment,
    /// A light the scalar code samples for the lanes (`LightSet::sample_each`).
    Other,
}

/// A light as the lanes copy it into their rows, whatever its kind: a triangle's corners,
/// normal, rounding bound, area and radiance; the environment's radiance (its other fields
/// zero); and its role. One record for every kind, so that a lane takes its light without a
/// branch on the kind: the lights a chunk's lanes pick are random, and where they are of
/// several kinds a branch on each lane's kind goes the wrong way often.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct LaneLight {
    pub corners: [Vec3; 3],
    pub normal: Vec3,
    pub error: Vec3,
    pub area: f32,
    pub radiance: Vec3,
    pub role: LaneRole,
}

impl LaneLight {
    /// No light.
    pub(crate) const NONE: LaneLight = LaneLight {
        corners: [Vec3::ZERO; 3],
        normal: Vec3::ZERO,
        error: Vec3::ZERO,
        area: 0.0,
        radiance: Vec3::ZERO,
        role: LaneRole::Nothing,
    };
}

impl Emitter {
    /// Its record for the lanes: a triangle sampled by area without an emission texture, and
    /// the constant environment, take their own roles; every other light is
    /// [`LaneRole::Other`].
    pub(crate) fn lane_light(&self) -> LaneLight {
        match self {
            Emitter::Triangle(light)
                if light.sampling == TriangleSampling::Area && light.pattern.is_none() =>
            {
                LaneLight {
                    corners: light.corners,
                    normal: light.normal,
                    error: light.error,
                    area: light.area,
                    radiance: light.radiance,
                    role: LaneRole::Triangle,
                }
            }
            Emitter::Environment(light) => LaneLight {
                radiance: light.radiance,
                role: LaneRole::Environment,
                ..LaneLight::default()
            },
            _ => LaneLight { role: LaneRole::Other, ..LaneLight::default() },
        }
    }
}

/// A light sampled in a lane: the direction toward it, its density (without the light's
/// selection probability), whether the shading point sees its front, and the shadow ray
/// (a segment to `shadow_origin + shadow_direction`, `shadow_t_max` of it), `finite` where
/// every offset point was finite.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LaneSample {
    pub direction: Vec3,
    pub pdf: f32,
    pub faces: bool,
    pub shadow_origin: Vec3,
    pub shadow_direction: Vec3,
    pub shadow_t_max: f32,
    pub finite: bool,
}

/// A point on the triangle `corners` (unit `normal`, rounding bound `error`, `area`) that `u`
/// picks uniformly by area, seen from `point`: `TriangleLight::sample` by area.
#[inline(always)]
pub(crate) fn sample_triangle(
    corners: [Vec3; 3],
    normal: Vec3,
    error: Vec3,
    area: f32,
    point: &SurfacePoint,
    u: Vec2,
) -> LaneSample {
    let [b0, b1, b2] = square_to_uniform_triangle(u);
    let target = b0 * corners[0] + b1 * corners[1] + b2 * corners[2];
    let to_light = target - point.p;
    let distance_squared = to_light.length_squared();
    let direction = to_light / distance_squared.sqrt();
    let cos_light = -direction.dot(normal);
    // The scalar test's very words: a NaN cosine passes it, as it passes the scalar one.
    #[allow(clippy::nonminimal_bool, clippy::neg_cmp_op_on_partial_ord)]
    let faces = !(cos_light <= 0.0 || !distance_squared.is_normal());
    let end = SurfacePoint { p: target, error, normal };
    let (end, end_finite) = offset_ray_origin_finite(&end, point.p - target);
    let (to_end, to_end_finite) = offset_ray_origin_finite(point, end - point.p);
    LaneSample {
        direction,
        pdf: distance_squared / (cos_light * area),
        faces,
        shadow_origin: to_end,
        shadow_direction: end - to_end,
        shadow_t_max: SHADOW_RAY_LENGTH,
        finite: end_finite && to_end_finite,
    }
}

/// A direction that `u` picks uniformly over the sphere, seen from `point`:
/// `ConstantEnvironment::sample`.
#[inline(always)]
pub(crate) fn sample_environment(point: &SurfacePoint, u: Vec2) -> LaneSample {
    let direction = square_to_uniform_sphere(u);
    let (origin, finite) = offset_ray_origin_finite(point, direction);
    LaneSample {
        direction,
        pdf: uniform_sphere_pdf(direction),
        faces: true,
        shadow_origin: origin,
        shadow_direction: direction,
        shadow_t_max: f32::INFINITY,
        finite,
    }
}
