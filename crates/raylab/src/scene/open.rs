//! Opening any scene by name: a built-in scene, a TOML scene file or a model file.

use std::path::Path;

use super::{LoadError, LoadOptions, Scene, SceneError, SceneFileError};

/// A scene as [`Scene::open`] found it.
#[derive(Debug)]
pub struct OpenedScene {
    /// The scene; problems that did not stop the load are in its `warnings`.
    pub scene: Scene,
    /// A model file without a camera of its own: a camera should frame its bounding box
    /// ([`Camera::framing`](crate::Camera::framing)) rather than stand where the lab's does.
    pub is_model: bool,
}

/// Why a scene could not be opened. Every message names the scene or the file.
#[derive(Debug, thiserror::Error)]
pub enum OpenError {
    /// An unknown built-in name, or a built-in scene's parameters out of range.
    #[error(transparent)]
    BuiltIn(#[from] SceneError),
    /// A TOML scene file that cannot be read or is malformed.
    #[error(transparent)]
    SceneFile(#[from] SceneFileError),
    /// A model file that cannot be read or is malformed.
    #[error(transparent)]
    Model(#[from] LoadError),
}

impl Scene {
    /// Opens `name`: a built-in scene (`cornell`, `terrain`, `terrain:N`), a scene file
    /// (`.toml`, see `docs/scene-format.md`) or a model file (`.obj`, `.ply`, either optionally
    /// `.gz`, `.gltf`, `.glb`). A name that is neither a built-in scene nor looks like a file
    /// (it exists, or has a `/` or a `.`) is an unknown scene, and the error lists the built-in
    /// ones. A model's instanced meshes, and those of a scene file's mesh files, are copied or
    /// kept as `options.instancing` says.
    pub fn open(name: &str, options: &LoadOptions) -> Result<OpenedScene, OpenError> {
        let path = Path::new(name);
        let looks_like_a_file = path.exists() || name.contains('/') || name.contains('.');
        match Scene::built_in(name) {
            Ok(scene) => return Ok(OpenedScene { scene, is_model: false }),
            Err(unknown) if !looks_like_a_file => return Err(unknown.into()),
            Err(_) => {}
        }
        if name.to_ascii_lowercase().ends_with(".toml") {
            let scene = super::load_scene_file_with(path, options)?;
            return Ok(OpenedScene { scene, is_model: false });
        }
        let mut loaded = super::load_mesh(path)?;
        options.instancing.apply(&mut loaded);
        let mut scene = Scene::from_loaded(&loaded);
        scene.warnings.extend(loaded.warnings.iter().cloned());
        // A file with its own camera (glTF) is seen through it; other models are framed.
        Ok(OpenedScene { scene, is_model: loaded.camera.is_none() })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Instancing;

    #[test]
    fn every_kind_of_scene_opens_and_unknown_names_list_the_built_in_ones() {
        let options = LoadOptions::default();
        let lab = Scene::open("cornell", &options).unwrap();
        assert_eq!((lab.scene.geometry.len(), lab.is_model), (30, false));
        let error = Scene::open("sponza", &options).unwrap_err().to_string();
        assert!(error.starts_with("unknown scene 'sponza': the built-in scenes are"), "{error}");
        let folder = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");
        let model = format!("{folder}/crates/raylab/tests/data/meshes/bunny_lowres.obj");
        let bunny = Scene::open(&model, &options).unwrap();
        assert!(bunny.is_model && bunny.scene.geometry.len() > 100);
        let file = format!("{folder}/scenes/cornell-lab.toml");
        let toml = Scene::open(&file, &options).unwrap();
        assert!(!toml.is_model && toml.scene.has_area_lights());
        let missing = Scene::open("missing.obj", &options).unwrap_err().to_string();
        assert!(missing.starts_with("missing.obj: cannot read"), "{missing}");
    }

    /// The glTF boxes (one 12-triangle box drawn 18 times), as a model and through a scene
    /// file: `auto` copies so small a mesh, `keep` keeps it instanced, `flatten` copies it; the
    /// same 216 triangles drawn every way.
    #[test]
    fn instancing_is_chosen_for_models_and_scene_files() {
        let folder = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/mitsuba-gltf");
        for (name, others) in [("boxes.gltf", 0), ("boxes.toml", 4)] {
            for (instancing, instanced) in
                [(Instancing::Auto, false), (Instancing::Keep, true), (Instancing::Flatten, false)]
            {
                let opened =
                    Scene::open(&format!("{folder}/{name}"), &LoadOptions { instancing }).unwrap();
                let geometry = &opened.scene.geometry;
                assert_eq!(geometry.is_instanced(), instanced, "{name} {instancing:?}");
                assert_eq!(geometry.len(), 216 + others, "{name} {instancing:?}");
            }
        }
        assert_eq!("keep".parse(), Ok(Instancing::Keep));
        let error = "some".parse::<Instancing>().unwrap_err().to_string();
        assert_eq!(error, "unknown instancing 'some': expected auto, keep or flatten");
    }
}
