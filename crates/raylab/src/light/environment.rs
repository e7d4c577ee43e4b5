//! The environments as lights: a constant radiance from every direction that leaves the
//! scene ([`ConstantEnvironment`], sampled uniformly over the sphere), and an environment map
//! sampled as [`EnvironmentSampling`] says ([`MapLight`]).

use std::sync::Arc;

use glam::{Vec2, Vec3};

use super::envmap::EnvironmentMap;
use super::sample::{DirectionSample, Emission, LightSample};
use crate::ray::SurfacePoint;
use crate::sampling::{square_to_uniform_sphere, uniform_sphere_pdf};

/// Radiance arriving equally from every direction that leaves the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConstantEnvironment {
    /// The radiance, per channel.
    pub radiance: Vec3,
}

impl ConstantEnvironment {
    /// A direction that `u` picks uniformly over the sphere, seen from `point`.
    #[inline]
    pub fn sample(&self, point: &SurfacePoint, u: Vec2) -> LightSample {
        let direction = square_to_uniform_sphere(u);
        LightSample {
            direction,
            radiance: self.radiance,
            pdf: uniform_sphere_pdf(direction),
            delta: false,
            shadow_ray: point.spawn_ray(direction),
        }
    }

    /// Its mean radiance (the mean of its channels), by which several environments share
    /// their picks.
    pub fn mean_radiance(&self) -> f32 {
        self.radiance.element_sum() / 3.0
    }

    /// What a ray leaving the scene along `direction` sees, and its density under
    /// [`sample`](Self::sample).
    #[inline]
    pub fn eval_pdf(&self, direction: Vec3) -> Emission {
        Emission { radiance: self.radiance, pdf: uniform_sphere_pdf(direction) }
    }
}

/// How directions toward an environment map are chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum EnvironmentSampling {
    /// In proportion to its luminance ([`EnvironmentMap::sample`]): what renders use.
    #[default]
    Importance,
    /// Uniformly over the sphere, whatever the map holds: only to measure what importance
    /// sampling is worth.
    Uniform,
}

/// An environment map as a light: the map, and how directions toward it are chosen.
#[derive(Clone, Debug)]
pub struct MapLight {
    /// The map.
    pub map: Arc<EnvironmentMap>,
    /// How directions toward it are chosen.
    pub sampling: EnvironmentSampling,
}

impl MapLight {
    /// A direction toward the map that `u` picks, seen from `point`; `None` where the
    /// map's density is not finite (its poles).
    #[inline]
    pub fn sample(&self, point: &SurfacePoint, u: Vec2) -> Option<LightSample> {
        let DirectionSample { direction, radiance, pdf } = match self.sampling {
            EnvironmentSampling::Importance => self.map.sample(u)?,
            EnvironmentSampling::Uniform => {
                let direction = square_to_uniform_sphere(u);
                DirectionSample {
                    direction,
                    radiance: self.map.eval(direction),
                    pdf: uniform_sphere_pdf(direction),
                }
            }
        };
        Some(DirectionSample { direction, radiance, pdf }.seen_from(point))
    }

    /// [`eval_pdf`](Self::eval_pdf) for each of `directions`, to the bit.
    ///
    /// # Panics
    /// If the slices differ in length.
    #[inline]
    pub fn eval_pdf_each(&self, directions: &[Vec3], out: &mut [Emission]) {
        match self.sampling {
            EnvironmentSampling::Importance => self.map.eval_pdf_each(directions, out),
            EnvironmentSampling::Uniform => {
                for (direction, slot) in directions.iter().zip(out) {
                    *slot = self.eval_pdf(*direction);
                }
            }
        }
    }

    /// The map's mean radiance (the mean of its channels), by which several environments share
    /// their picks.
    pub fn mean_radiance(&self) -> f32 {
        self.map.mean().element_sum() / 3.0
    }

    /// What a ray leaving the scene along the unit `direction` sees, and the density with which
    /// [`sample`](Self::sample) picks that direction.
    #[inline]
    pub fn eval_pdf(&self, direction: Vec3) -> Emission {
        match self.sampling {
            EnvironmentSampling::Importance => self.map.eval_pdf(direction),
            EnvironmentSampling::Uniform => {
                Emission { radiance: self.map.eval(direction), pdf: uniform_sphere_pdf(direction) }
            }
        }
    }
}
