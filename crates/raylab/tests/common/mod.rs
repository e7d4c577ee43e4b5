//! Scenes that more than one test file builds.

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
