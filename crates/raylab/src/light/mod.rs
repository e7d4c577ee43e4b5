//! Lights that are not surfaces: the lab's point light, Mitsuba 3's `directional`, `spot` and
//! `envmap`, a sun disc, and a constant environment.
//!
//! Area lights are triangles whose material emits (see `Material::emission`);
//! the path integrator gathers every light, these and the area lights, into one set that it
//! samples by power, the environments half the time beside other lights
//! (`integrator::LightSet`). The lab's integrator knows only the point light (its light model
//! is the lab's).
//!
//! Every direction and position here is in the lab's frame (y down); scene files and glTF
//! give them y-up and their loaders turn them.

use std::f32::consts::PI;
use std::sync::Arc;

use glam::Vec3;

mod envmap;
mod error;
mod punctual;

pub use envmap::{EnvironmentMap, direction_to_uv, uv_to_direction};
pub use error::LightError;
pub use punctual::{DirectionalLight, SpotLight, SpotProfile, SunLight};

/// A light of the scene that is not a surface.
#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// The lab's point light.
    Point(PointLight),
    /// Radiance arriving equally from every direction that leaves the scene.
    Environment {
        /// The radiance, per channel.
        radiance: Vec3,
    },
    /// Radiance arriving from every direction that leaves the scene, as an HDR image says.
    EnvironmentMap(Arc<EnvironmentMap>),
    /// Parallel light from infinitely far away (a delta light).
    Directional(DirectionalLight),
    /// A point light shining in a cone.
    Spot(SpotLight),
    /// A disc of constant radiance infinitely far away, as the sun.
    Sun(SunLight),
}

impl Light {
    /// What kind of light this is, in a scene file's words.
    pub fn kind(&self) -> &'static str {
        match self {
            Light::Point(_) => "point",
            Light::Environment { .. } => "environment",
            Light::EnvironmentMap(_) => "envmap",
            Light::Directional(_) => "directional",
            Light::Spot(_) => "spot",
            Light::Sun(_) => "sun",
        }
    }
}

/// An isotropic point light of power `P` (watts per channel).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLight {
    /// Where the light is.
    pub position: Vec3,
    /// Power `P` per colour channel.
    pub power: Vec3,
}

impl PointLight {
    /// The lab's light: at (0, −0.5, −0.7), power 14 in every channel.
    pub fn lab() -> Self {
        PointLight { position: Vec3::new(0.0, -0.5, -0.7), power: Vec3::splat(14.0) }
    }

    /// The radiant intensity `I = P/4π` (watts per steradian per channel).
    #[inline]
    pub fn intensity(&self) -> Vec3 {
        self.power / (4.0 * PI)
    }

    /// Power per unit area arriving at `point` on a surface with unit normal `normal`, ignoring
    /// occlusion. Lab eq. (27): `D = P·max(r̂·n̂, 0) / (4πr²)`.
    #[inline]
    pub fn direct(&self, point: Vec3, normal: Vec3) -> Vec3 {
        let to_light = self.position - point;
        let r2 = to_light.length_squared();
        if r2 == 0.0 {
            return Vec3::ZERO;
        }
        // max(r̂·n̂, 0)/(4πr²) = max(r·n, 0)/(4πr³): one square root and one division.
        let r_dot_n = to_light.dot(normal).max(0.0);
        self.power * (r_dot_n / (4.0 * PI * r2 * r2.sqrt()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn direct_light_falls_off_with_the_square_of_distance_and_the_cosine() {
        let light = PointLight { position: Vec3::new(0.0, 2.0, 0.0), power: Vec3::splat(4.0 * PI) };
        // r = 2, head on: D = 4π / (4π·4) = 1/4.
        assert!((light.direct(Vec3::ZERO, Vec3::Y) - Vec3::splat(0.25)).length() < 1e-6);
        // Tilted by 60°: half of it.
        let n = Vec3::new(3f32.sqrt() / 2.0, 0.5, 0.0);
        assert!((light.direct(Vec3::ZERO, n) - Vec3::splat(0.125)).length() < 1e-6);
        // Facing away: nothing.
        assert_eq!(light.direct(Vec3::ZERO, -Vec3::Y), Vec3::ZERO);
        // At the light itself: nothing rather than infinity.
        assert_eq!(light.direct(light.position, Vec3::Y), Vec3::ZERO);
    }
}
