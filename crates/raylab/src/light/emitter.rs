//! [`Emitter`]: any light, as a light sampler holds it. Each kind owns its sampling, its
//! evaluation and its power (`sample`, `eval_pdf`, `power`, in its own file); an emitter says
//! which kind it is and passes the call on, so that a light sampler chooses among lights
//! without knowing how each is sampled. (The lanes' form of each, `lane_light`, is in
//! `lanes.rs`.)

use glam::{Vec2, Vec3};

use super::environment::{ConstantEnvironment, MapLight};
use super::punctual::{DirectionalLight, PointLight, SpotLight, SunLight};
use super::sample::{Emission, LightSample};
use super::triangle::TriangleLight;
use crate::ray::SurfacePoint;

/// A light, whatever its kind, ready to be sampled.
#[derive(Clone, Debug)]
pub enum Emitter {
    /// A point light.
    Point(PointLight),
    /// An emitting triangle.
    Triangle(TriangleLight),
    /// The constant environment.
    Environment(ConstantEnvironment),
    /// An environment map.
    EnvironmentMap(MapLight),
    /// A directional light.
    Directional(DirectionalLight),
    /// A spot light.
    Spot(SpotLight),
    /// A sun disc.
    Sun(SunLight),
}

impl Emitter {
    /// A direction toward it that `u` picks, seen from `point`, with its radiance, density
    /// (1 for a delta light) and shadow ray; `None` where `point` sees nothing of it.
    #[inline]
    pub fn sample(&self, point: &SurfacePoint, u: Vec2) -> Option<LightSample> {
        match self {
            Emitter::Point(light) => light.sample(point),
            Emitter::Triangle(light) => light.sample(point, u),
            Emitter::Environment(light) => Some(light.sample(point, u)),
            Emitter::EnvironmentMap(light) => light.sample(point, u),
            Emitter::Directional(light) => Some(light.sample(point)),
            Emitter::Spot(light) => light.sample(point),
            Emitter::Sun(light) => Some(light.sample(point, u)),
        }
    }

    /// Whether rays that leave the scene find it: the environments and the sun.
    pub fn is_infinite(&self) -> bool {
        matches!(self, Emitter::Environment(_) | Emitter::EnvironmentMap(_) | Emitter::Sun(_))
    }

    /// What a ray leaving the scene along the unit `direction` finds of it, with the density of
    /// [`sample`](Self::sample); [`Emission::NONE`] for a light that is not infinite.
    #[inline]
    pub fn escaped(&self, direction: Vec3) -> Emission {
        match self {
            Emitter::Environment(light) => light.eval_pdf(direction),
            Emitter::EnvironmentMap(light) => light.eval_pdf(direction),
            Emitter::Sun(light) => light.eval_pdf(direction),
            _ => Emission::NONE,
        }
    }

    /// [`escaped`](Self::escaped) for each of `directions`, to the bit (an environment map's
    /// lookups in one loop).
    ///
    /// # Panics
    /// If the slices differ in length.
    #[inline]
    pub fn escaped_each(&self, directions: &[Vec3], out: &mut [Emission]) {
        match self {
            Emitter::EnvironmentMap(light) => light.eval_pdf_each(directions, out),
            _ => {
                for (direction, slot) in directions.iter().zip(out) {
                    *slot = self.escaped(*direction);
                }
            }
        }
    }

    /// Its power, for choosing among lights; a light from infinitely far away sends its
    /// power through a disk of area `through_scene` (PBR 4th ed. §12.5). The environments have
    /// none here: a light sampler gives them their share ([`environment_power`]).
    ///
    /// [`environment_power`]: Self::environment_power
    pub fn power(&self, through_scene: f32) -> f32 {
        match self {
            Emitter::Point(light) => light.mean_power(),
            Emitter::Triangle(light) => light.power(),
            Emitter::Directional(light) => light.power(through_scene),
            Emitter::Sun(light) => light.power(through_scene),
            Emitter::Spot(light) => light.power(),
            Emitter::Environment(_) | Emitter::EnvironmentMap(_) => 0.0,
        }
    }

    /// For an environment, its mean radiance (the mean of its channels), by which several
    /// environments share their picks; `None` for any other light.
    pub fn environment_power(&self) -> Option<f32> {
        match self {
            Emitter::Environment(light) => Some(light.mean_radiance()),
            Emitter::EnvironmentMap(light) => Some(light.mean_radiance()),
            _ => None,
        }
    }
}
