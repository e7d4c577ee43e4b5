//! Scenes: triangles with their colours, and a light.
//!
//! A scene is plain data. Give its triangles to an [`Accelerator`](crate::Accelerator) to ask ray
//! queries, and both to an integrator to make pictures.

mod cornell;
mod file;
mod model;
mod obj;
mod ply;

use glam::Vec3;

pub use cornell::{CORNELL_BOX_SIZE, cornell_box};
pub(crate) use file::read_file_bytes;
pub use file::{
    LoadError, LoadedMesh, Location, SUPPORTED_EXTENSIONS, load_mesh, read_limit_bytes,
};
pub use model::model_to_lab;

use crate::light::PointLight;
use crate::triangle::Triangle;

/// Why a scene cannot be used.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum SceneError {
    /// No built-in scene has this name.
    #[error("unknown scene '{name}': the built-in scenes are {}", BUILT_IN_SCENES.join(", "))]
    UnknownScene {
        /// The name asked for.
        name: String,
    },
    /// A vertex, colour or light value is NaN or infinite.
    #[error("scene '{scene}': {what} is not a finite number ({value:?})")]
    NotFinite {
        /// The scene's name.
        scene: String,
        /// Which value, e.g. "triangle 3, vertex 1".
        what: String,
        /// The offending value.
        value: Vec3,
    },
}

/// Names accepted by [`Scene::built_in`].
pub const BUILT_IN_SCENES: &[&str] = &["cornell"];

/// Triangles and a light.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// A short name, used in messages.
    pub name: String,
    /// Every triangle, with its normal and colour.
    pub triangles: Vec<Triangle>,
    /// The point light.
    pub light: PointLight,
}

impl Scene {
    /// A built-in scene by name: `cornell`, the lab's Cornell box.
    pub fn built_in(name: &str) -> Result<Scene, SceneError> {
        match name {
            "cornell" => Ok(cornell_box()),
            _ => Err(SceneError::UnknownScene { name: name.to_string() }),
        }
    }

    /// Checks that every number in the scene is finite.
    pub fn validate(&self) -> Result<(), SceneError> {
        let not_finite = |what: String, value: Vec3| SceneError::NotFinite {
            scene: self.name.clone(),
            what,
            value,
        };
        for (i, t) in self.triangles.iter().enumerate() {
            for (name, v) in [("vertex 0", t.v0), ("vertex 1", t.v1), ("vertex 2", t.v2)] {
                if !v.is_finite() {
                    return Err(not_finite(format!("triangle {i}, {name}"), v));
                }
            }
            if !t.albedo.is_finite() {
                return Err(not_finite(format!("triangle {i}, colour"), t.albedo));
            }
        }
        if !self.light.position.is_finite() {
            return Err(not_finite("the light's position".into(), self.light.position));
        }
        if !self.light.power.is_finite() {
            return Err(not_finite("the light's power".into(), self.light.power));
        }
        Ok(())
    }

    /// The same scene with every length multiplied by `factor`, and the light's power by
    /// `factor²` so that the picture stays the same (lab eq. 27 falls off as 1/r²).
    pub fn scaled(&self, factor: f32) -> Scene {
        let triangles = self
            .triangles
            .iter()
            .map(|t| Triangle::new(t.v0 * factor, t.v1 * factor, t.v2 * factor, t.albedo))
            .collect();
        Scene {
            name: format!("{} ×{factor}", self.name),
            triangles,
            light: PointLight {
                position: self.light.position * factor,
                power: self.light.power * factor * factor,
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn built_in_names_resolve_and_unknown_names_are_listed() {
        assert_eq!(Scene::built_in("cornell").unwrap().triangles.len(), 30);
        let err = Scene::built_in("sponza").unwrap_err();
        assert_eq!(err.to_string(), "unknown scene 'sponza': the built-in scenes are cornell");
    }

    #[test]
    fn validate_names_the_bad_value() {
        let mut scene = cornell_box();
        assert_eq!(scene.validate(), Ok(()));
        scene.triangles[7].v1.y = f32::NAN;
        let message = scene.validate().unwrap_err().to_string();
        assert!(message.contains("triangle 7, vertex 1"), "{message}");
        let mut scene = cornell_box();
        scene.light.position.x = f32::INFINITY;
        assert!(scene.validate().unwrap_err().to_string().contains("light's position"));
    }
}
