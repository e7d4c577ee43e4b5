//! Scenes: geometry, materials, lights.
//!
//! A scene is plain data: [`Geometry`] (triangle meshes, each triangle with a material), the
//! [`Material`]s they name, and the lights that are not surfaces (point lights and a constant
//! environment; emissive materials make area lights of their triangles). Build an accelerator
//! over [`Scene::vertices`] to ask ray queries, and give both to an integrator to make pictures;
//! [`Scene::interaction`] says what a ray sees at a hit.
//!
//! Scenes live in the lab's frame: x right, **y down**, z forward. Model and scene files are
//! y-up; loaders turn them with [`model_to_lab`], a half turn about x that keeps handedness.

mod built_in;
mod camera_settings;
mod cornell;
#[cfg(feature = "io")]
mod finite;
#[cfg(feature = "io")]
mod formats;
#[cfg(feature = "io")]
pub(crate) mod gltf;
mod keyframes;
#[cfg(feature = "io")]
mod load_options;
#[cfg(feature = "io")]
mod mesh_file;
mod model;
#[cfg(feature = "io")]
mod mtl;
#[cfg(feature = "io")]
pub(crate) mod obj;
#[cfg(feature = "io")]
mod open;
#[cfg(feature = "io")]
pub(crate) mod ply;
#[cfg(feature = "io")]
mod scene_file;
pub mod terrain;

use glam::Vec3;

pub use crate::settings::RenderSettings;
pub use camera_settings::{CameraSettings, FovAxis};
pub use cornell::{CORNELL_BOX_SIZE, cornell_box};
#[cfg(feature = "io")]
pub use formats::load_mesh;
pub use keyframes::Keyframe;
#[cfg(feature = "io")]
pub use load_options::{AUTO_FLATTEN_TRIANGLES, Instancing, LoadOptions};
#[cfg(feature = "bench")]
pub(crate) use mesh_file::read_file_bytes;
#[cfg(feature = "io")]
pub use mesh_file::{
    InstancedMesh, LoadError, LoadedMesh, Location, SUPPORTED_EXTENSIONS, read_limit_bytes,
};
pub use model::model_to_lab;
#[cfg(feature = "io")]
pub use open::{OpenError, OpenedScene};
#[cfg(feature = "io")]
pub use scene_file::{
    SceneFileError, load_scene_file, load_scene_file_with, parse_scene, parse_scene_with,
    parse_scene_with_meshes,
};

use crate::accel::Hit;
use crate::geometry::Geometry;
use crate::interaction::SurfaceInteraction;
use crate::light::{EnvironmentMap, Light, PointLight};
use crate::material::Material;
use crate::ray::Ray;

/// Why a scene cannot be used.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum SceneError {
    /// No built-in scene has this name.
    #[error("unknown scene '{name}': the built-in scenes are {}", BUILT_IN_SCENES.join(", "))]
    UnknownScene {
        /// The name asked for.
        name: String,
    },
    /// A built-in scene's parameters are out of range (`terrain:N`).
    #[error("scene '{name}': {problem}")]
    InvalidBuiltIn {
        /// The name asked for.
        name: String,
        /// What is wrong with it.
        problem: String,
    },
    /// A material, a light or a triangle's material id is out of its range.
    #[error("scene '{scene}': {what}: {problem}")]
    Invalid {
        /// The scene's name.
        scene: String,
        /// Which part, e.g. "material 'gold'".
        what: String,
        /// What is wrong with it.
        problem: String,
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
pub const BUILT_IN_SCENES: &[&str] = &["cornell", "terrain", "terrain:N"];

/// Geometry, materials, lights, and the camera and render settings a scene file gives.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Scene {
    /// A short name, used in messages.
    pub name: String,
    /// Every triangle, with its material.
    pub geometry: Geometry,
    /// The materials that [`Geometry::material_id`] indexes.
    pub materials: Vec<Material>,
    /// Lights that are not surfaces: point lights and the environment.
    pub lights: Vec<Light>,
    /// The camera a scene file sets up, if any.
    pub camera: Option<CameraSettings>,
    /// The camera's keyframes for an animation, sorted by frame, each frame once (empty: none).
    pub keyframes: Vec<Keyframe>,
    /// The render settings a scene file gives; the command line overrides them.
    pub settings: RenderSettings,
    /// Problems that did not stop the load (a model's texture that could not be read), one
    /// line each naming the file: for the caller to show.
    pub warnings: Vec<String>,
}

impl Scene {
    /// The camera at `frame` of the animation its keyframes describe (see `keyframes.rs`), or
    /// `None` when it has none.
    pub fn camera_at(&self, frame: f32) -> Option<CameraSettings> {
        keyframes::camera_at(&self.keyframes, frame)
    }

    /// A hash of everything in the scene that decides what a ray sees: every triangle (its
    /// vertices, normals, texture coordinates and material), the materials and the lights, by
    /// their bits (XXH3, 64 bits). Not the name, the camera or the render settings. Parts of one
    /// render carry it, so that `raylab merge` can refuse parts of another scene.
    pub fn content_hash(&self) -> u64 {
        let mut hasher = xxhash_rust::xxh3::Xxh3::new();
        self.geometry.hash_into(&mut hasher);
        // `Debug` writes every float as the shortest text that reads back as the same bits.
        hasher.update(format!("{:?}\n{:?}", self.materials, self.lights).as_bytes());
        hasher.digest()
    }

    /// A scene lit by one point light.
    pub fn new(
        name: &str,
        geometry: Geometry,
        materials: Vec<Material>,
        light: PointLight,
    ) -> Scene {
        Scene {
            name: name.to_string(),
            geometry,
            materials,
            lights: vec![Light::Point(light)],
            ..Scene::default()
        }
    }

    /// Every triangle's corners, in order: build an accelerator over them.
    pub fn vertices(&self) -> Vec<[Vec3; 3]> {
        self.geometry.vertices()
    }

    /// What `ray` sees at `hit`, which an accelerator over [`vertices`](Self::vertices) found.
    #[inline]
    pub fn interaction(&self, ray: &Ray, hit: &Hit) -> SurfaceInteraction {
        self.geometry.interaction(ray, hit)
    }

    /// The material of an interaction.
    #[inline]
    pub fn material(&self, interaction: &SurfaceInteraction) -> &Material {
        &self.materials[interaction.material as usize]
    }

    /// The bytes its texture images take, each image counted once however many materials use
    /// it, and how many images there are.
    pub fn texture_bytes(&self) -> (u64, usize) {
        use crate::texture::Texture;
        let mut seen: Vec<*const crate::texture::TextureImage> = Vec::new();
        let mut bytes = 0;
        for material in &self.materials {
            let t = &material.textures;
            let normal = t.normal.as_ref().map(|n| &n.texture);
            for texture in [&t.base_color, &t.metallic_roughness, &t.roughness]
                .into_iter()
                .flatten()
                .chain(normal)
            {
                if let Texture::Image(image) = texture {
                    let pointer = std::sync::Arc::as_ptr(&image.image);
                    if !seen.contains(&pointer) {
                        seen.push(pointer);
                        bytes += image.image.bytes();
                    }
                }
            }
        }
        (bytes, seen.len())
    }

    /// Whether some material has cut-out holes (an alpha mask): rays must then be traced past
    /// them (`integrator::closest_opaque_hit`).
    #[inline]
    pub fn has_cut_outs(&self) -> bool {
        self.materials.iter().any(|m| m.textures.alpha_mask.is_some())
    }

    /// Whether `hit` (found by `ray`) is on a hole of its material's alpha mask.
    #[inline]
    pub fn is_cut_out(&self, ray: &Ray, hit: &Hit) -> bool {
        let material = &self.materials[self.geometry.material_id(hit.triangle as usize) as usize];
        material.textures.alpha_mask.is_some()
            && material.is_cut_out(&self.geometry.texture_query(ray, hit, 0.0))
    }

    /// The bounding box `(min, max)` of every triangle, or `None` for an empty scene.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        self.geometry.bounds()
    }

    /// The lab's point light: the scene's first point light, or [`default_light`](Self::default_light)
    /// for scenes lit only by surfaces.
    pub fn lab_light(&self) -> PointLight {
        self.lights
            .iter()
            .find_map(|light| match light {
                Light::Point(point) => Some(*point),
                _ => None,
            })
            .unwrap_or_else(|| self.default_light())
    }

    /// The first point light, added (as [`default_light`](Self::default_light)) if there is none:
    /// for the command line's `--light` and `--light-power`.
    pub fn point_light_mut(&mut self) -> &mut PointLight {
        let index = match self.lights.iter().position(|l| matches!(l, Light::Point(_))) {
            Some(index) => index,
            None => {
                self.lights.insert(0, Light::Point(self.default_light()));
                0
            }
        };
        match &mut self.lights[index] {
            Light::Point(point) => point,
            _ => unreachable!("found a point light above"),
        }
    }

    /// Whether any material emits: the scene has area lights.
    pub fn has_area_lights(&self) -> bool {
        self.materials.iter().any(Material::is_emissive)
    }

    /// The kinds of its lights that the lab's light model ignores (every kind but the point
    /// light), each once, in the order they come: the `lab` integrator warns of them.
    pub fn lights_the_lab_ignores(&self) -> Vec<&'static str> {
        let mut kinds = Vec::new();
        for light in &self.lights {
            if !matches!(light, Light::Point(_)) && !kinds.contains(&light.kind()) {
                kinds.push(light.kind());
            }
        }
        kinds
    }

    /// Whether only the path tracer sees all of its light: some surface emits, or some light is
    /// not a point light.
    pub fn needs_path_tracing(&self) -> bool {
        self.has_area_lights() || self.lights.iter().any(|l| !matches!(l, Light::Point(_)))
    }

    /// Lights the scene with `map` instead of its environments (constant or mapped); a model
    /// (`is_model`) lit only by its [`default_light`](Self::default_light) loses that light
    /// too, so that the map alone lights it.
    pub fn light_with_environment_map(&mut self, map: EnvironmentMap, is_model: bool) {
        let only_default =
            matches!(&self.lights[..], [Light::Point(p)] if *p == self.default_light());
        if is_model && only_default {
            self.lights.clear();
        }
        self.lights.retain(|l| !matches!(l, Light::Environment { .. } | Light::EnvironmentMap(_)));
        self.lights.push(Light::EnvironmentMap(std::sync::Arc::new(map)));
    }

    /// Checks that every number in the scene is finite and every material id and parameter
    /// valid.
    pub fn validate(&self) -> Result<(), SceneError> {
        let not_finite = |what: String, value: Vec3| SceneError::NotFinite {
            scene: self.name.clone(),
            what,
            value,
        };
        for (i, p) in self.geometry.positions().iter().enumerate() {
            if !p.is_finite() {
                return Err(not_finite(format!("vertex {i}"), *p));
            }
        }
        let ids = self.geometry.material_ids();
        if let Some(i) = ids.iter().position(|&m| m as usize >= self.materials.len()) {
            // (`material_ids` holds the stored triangles' ids: one per instanced mesh's
            // triangle, not per scene triangle.)
            let what = if self.geometry.is_instanced() { "stored triangle" } else { "triangle" };
            return Err(SceneError::Invalid {
                scene: self.name.clone(),
                what: format!("{what} {i}"),
                problem: format!("names material {} of {}", ids[i], self.materials.len()),
            });
        }
        for material in &self.materials {
            material.validate().map_err(|problem| SceneError::Invalid {
                scene: self.name.clone(),
                what: format!("material '{}'", material.name),
                problem: problem.to_string(),
            })?;
        }
        let non_negative = |light: &str, what: &str, value: Vec3| {
            if value.is_finite() && value.min_element() >= 0.0 {
                return Ok(());
            }
            Err(SceneError::Invalid {
                scene: self.name.clone(),
                what: light.into(),
                problem: format!("{what} {value} must be finite and not negative"),
            })
        };
        for light in &self.lights {
            match light {
                Light::Point(point) => {
                    if !point.position.is_finite() {
                        return Err(not_finite("the light's position".into(), point.position));
                    }
                    if !point.power.is_finite() {
                        return Err(not_finite("the light's power".into(), point.power));
                    }
                }
                Light::Environment { radiance } => {
                    non_negative("the environment", "radiance", *radiance)?
                }
                // Checked as it was made.
                Light::EnvironmentMap(_) => {}
                Light::Directional(light) => {
                    if !(light.direction.is_finite() && light.direction != Vec3::ZERO) {
                        return Err(not_finite(
                            "a directional light's direction".into(),
                            light.direction,
                        ));
                    }
                    non_negative("a directional light", "irradiance", light.irradiance)?;
                }
                Light::Spot(spot) => {
                    if !spot.position().is_finite() {
                        return Err(not_finite("a spot light's position".into(), spot.position()));
                    }
                    non_negative("a spot light", "intensity", spot.intensity())?;
                }
                Light::Sun(sun) => non_negative("a sun", "radiance", sun.radiance())?,
            }
        }
        Ok(())
    }

    /// The same scene with every length multiplied by `factor`, and point and spot lights' power
    /// by `factor²` so that the picture stays the same (lab eq. 27 falls off as 1/r²).
    pub fn scaled(&self, factor: f32) -> Scene {
        let lights = self
            .lights
            .iter()
            .map(|light| match light {
                Light::Point(point) => Light::Point(PointLight {
                    position: point.position * factor,
                    power: point.power * factor * factor,
                }),
                Light::Spot(spot) => Light::Spot(
                    spot.moved_to(spot.position() * factor)
                        .with_intensity(spot.intensity() * factor * factor),
                ),
                other => other.clone(),
            })
            .collect();
        Scene {
            name: format!("{} ×{factor}", self.name),
            geometry: self.geometry.scaled(factor),
            materials: self.materials.clone(),
            lights,
            camera: self.camera,
            keyframes: self.keyframes.clone(),
            settings: self.settings.clone(),
            warnings: self.warnings.clone(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn built_in_names_resolve_and_unknown_names_are_listed() {
        assert_eq!(Scene::built_in("cornell").unwrap().geometry.len(), 30);
        let err = Scene::built_in("sponza").unwrap_err();
        assert_eq!(
            err.to_string(),
            "unknown scene 'sponza': the built-in scenes are cornell, terrain, terrain:N"
        );
    }

    #[test]
    fn validate_names_the_bad_value() {
        let mut scene = cornell_box();
        assert_eq!(scene.validate(), Ok(()));
        scene.geometry =
            scene.geometry.map_positions(|p| if p.x == -1.0 { p * f32::NAN } else { p });
        let message = scene.validate().unwrap_err().to_string();
        assert!(message.contains("vertex"), "{message}");
        let mut scene = cornell_box();
        scene.point_light_mut().position.x = f32::INFINITY;
        assert!(scene.validate().unwrap_err().to_string().contains("light's position"));
        let mut scene = cornell_box();
        scene.materials[2] = Material::diffuse("too bright", Vec3::splat(2.0));
        let message = scene.validate().unwrap_err().to_string();
        assert!(
            message.contains("material 'too bright'") && message.contains("reflectance"),
            "{message}"
        );
        let mut scene = cornell_box();
        scene.materials.truncate(3);
        let message = scene.validate().unwrap_err().to_string();
        assert!(message.contains("names material"), "{message}");
    }
}
