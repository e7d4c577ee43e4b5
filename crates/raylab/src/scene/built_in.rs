//! The built-in scenes by name ([`Scene::built_in`]): the lab's Cornell box and the fractal
//! terrain.

use super::cornell::cornell_box;
use super::terrain::parse_terrain;
use super::{Scene, SceneError};

impl Scene {
    /// A built-in scene by name: `cornell`, the lab's Cornell box; `terrain` or `terrain:N`, a
    /// fractal landscape ([`terrain::terrain`](super::terrain::terrain)).
    pub fn built_in(name: &str) -> Result<Scene, SceneError> {
        if name == "cornell" {
            return Ok(cornell_box());
        }
        parse_terrain(name)
            .unwrap_or_else(|| Err(SceneError::UnknownScene { name: name.to_string() }))
    }
}
