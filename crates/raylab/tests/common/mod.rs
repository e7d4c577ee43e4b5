//! Scenes that more than one test file builds.

// Each test file that includes this module uses only part of it.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Vec2, Vec3};
use raylab::material::AlphaMask;
use raylab::mesh::CornerAttribute;
use raylab::texture::{ImageTexture, Texture, TextureImage};
use raylab::{Material, Mesh, Scene};

/// A white quad (material 0) in front of a red wall (material 1), cut out by its texture's
/// alpha in a 2 × 2 checker (glTF's `alphaMode: MASK`; texels (0, 0) and (1, 1) opaque, the
/// other two holes), lit by a point light at (0, 0, −1.5): camera rays and shadow rays pass the
/// holes and stop at the rest. The quad spans ±1 at z = 0, the wall ±3 at z = 1.
pub fn cut_out_scene() -> Scene {
    let quad = |z: f32, half: f32| Mesh {
        name: "quad".into(),
        positions: [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)]
            .iter()
            .map(|&(x, y)| Vec3::new(x * half, y * half, z))
            .collect(),
        triangles: vec![[0, 1, 2], [2, 1, 3]],
        uvs: Some(CornerAttribute {
            values: vec![Vec2::new(0.0, 0.0), Vec2::new(0.0, 1.0), Vec2::new(1.0, 0.0), Vec2::ONE],
            triangles: vec![[0, 1, 2], [2, 1, 3]],
        }),
        ..Mesh::default()
    };
    let texels = vec![[255; 4], [255, 255, 255, 0], [255, 255, 255, 0], [255; 4]];
    let image = Arc::new(TextureImage::from_rgba8("mask", 2, 2, texels, false));
    let mut cut = Material::diffuse("cut", Vec3::ONE);
    cut.textures.base_color = Some(Texture::Image(ImageTexture::new(image)));
    cut.textures.alpha_mask = Some(AlphaMask { cutoff: 0.5, factor: 1.0 });
    let wall = Material::diffuse("wall", Vec3::new(0.8, 0.0, 0.0));
    let mut geometry = raylab::Geometry::new();
    geometry.add_mesh(&quad(0.0, 1.0), &glam::Affine3A::IDENTITY, |_| 0);
    geometry.add_mesh(&quad(1.0, 3.0), &glam::Affine3A::IDENTITY, |_| 1);
    let light =
        raylab::PointLight { position: Vec3::new(0.0, 0.0, -1.5), power: Vec3::splat(20.0) };
    Scene::new("cut-out", geometry, vec![cut, wall], light)
}

/// The repository's root.
pub fn repository() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The scenes to render in whole-pipeline tests: the built-in lab box, every `scenes/*.toml`
/// (sorted), and `models`, paths under `crates/raylab/tests/data/meshes`.
pub fn scene_names(models: &[&str]) -> Vec<String> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(repository().join("scenes"))
        .unwrap()
        .map(|entry| entry.unwrap().path())
        .filter(|path| path.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    assert!(files.len() >= 3, "the scenes folder: {files:?}");
    let meshes = repository().join("crates/raylab/tests/data/meshes");
    files.extend(models.iter().map(|name| meshes.join(name)));
    std::iter::once("cornell".to_string())
        .chain(files.iter().map(|p| p.display().to_string()))
        .collect()
}
