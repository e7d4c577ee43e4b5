//! Lights: the lab's point light, Mitsuba 3's `directional`, `spot`, `envmap` and `area`
//! (triangles whose material emits), a sun disc, and a constant environment.
//!
//! A scene lists the lights that are not surfaces ([`Light`]); its emitting triangles are area
//! lights (see `Material::emission`). The path tracer gathers all of them, each as an
//! [`Emitter`], into one set that picks among them by power
//! (`integrator::LightSet`). Each kind owns what is particular to it, in its own file, as in
//! pbrt-v4 and Mitsuba 3: sampling a direction toward it from a shading point (`sample`,
//! giving a [`LightSample`]), what a ray that finds it sees with the density sampling would
//! have given it (`eval_pdf`, an [`Emission`]), and its power:
//!
//! | light | file |
//! |---|---|
//! | point, directional, spot, sun | `punctual.rs` |
//! | area (an emitting triangle) | `triangle.rs` |
//! | constant environment, environment map | `environment.rs`, `envmap.rs` (the map itself) |
//! | any, as a light sampler holds it | `emitter.rs` |
//! | the lanes' form (the wavefront's) | `lanes.rs` |
//!
//! The lab's integrator knows only the point light (its light model is the lab's).
//!
//! Every direction and position here is in the lab's frame (y down); scene files and glTF
//! give them y-up and their loaders turn them.

use std::sync::Arc;

use glam::Vec3;

mod emitter;
mod environment;
mod envmap;
mod error;
pub(crate) mod lanes;
mod punctual;
mod sample;
mod triangle;

pub use emitter::Emitter;
pub use environment::{ConstantEnvironment, EnvironmentSampling, MapLight};
pub use envmap::{EnvironmentMap, direction_to_uv, uv_to_direction};
pub use error::LightError;
pub use punctual::{DirectionalLight, PointLight, SpotLight, SpotProfile, SunLight};
pub use sample::{DirectionSample, Emission, LightSample, SHADOW_RAY_LENGTH};
pub use triangle::{EmissionPattern, TriangleLight, TriangleSampling};

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
