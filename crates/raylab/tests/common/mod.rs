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

/// The bumps of the normal-map test: `z = −A (sin kx + sin ky)` over the wall `x, y ∈ [−1, 1]`
/// (toward the camera at the lab's −z), and its unit normal `(cx, cy, −1)/len` with
/// `cx = −Ak cos kx`, `cy = −Ak cos ky`, on the camera's side.
pub const BUMP_A: f32 = 0.02;
pub const BUMP_K: f32 = 2.0 * std::f32::consts::PI;

pub fn bump_normal(x: f32, y: f32) -> Vec3 {
    let (cx, cy) = (-BUMP_A * BUMP_K * (BUMP_K * x).cos(), -BUMP_A * BUMP_K * (BUMP_K * y).cos());
    Vec3::new(cx, cy, -1.0).normalize()
}

/// A wall lit by a point light, seen by the path tracer (direct light only), its materials
/// diffuse.
pub fn wall_scene(geometry: raylab::Geometry, material: Material) -> Scene {
    let light =
        raylab::PointLight { position: Vec3::new(0.4, -0.6, -2.0), power: Vec3::splat(60.0) };
    Scene::new("wall", geometry, vec![material], light)
}

/// The flat wall with the bumps in a normal map (256², floats), its tangents from MikkTSpace:
/// along +u (the +x here) and the bitangent along +v (+y), so the map holds the bump normal's
/// x, y and −z, encoded as (n + 1)/2.
pub fn normal_mapped_wall() -> Scene {
    let m = 256u32;
    let texels = (0..m * m)
        .map(|k| {
            let (i, j) = (k % m, k / m);
            let (u, v) = ((i as f32 + 0.5) / m as f32, (j as f32 + 0.5) / m as f32);
            let n = bump_normal(2.0 * u - 1.0, 2.0 * v - 1.0);
            let local = Vec3::new(n.x, n.y, -n.z);
            let encoded = (local + Vec3::ONE) * 0.5;
            [encoded.x, encoded.y, encoded.z, 1.0]
        })
        .collect();
    let image = TextureImage::from_rgba_f32("bumps", m, m, texels);
    let corners = [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)];
    let triangles = vec![[0, 1, 2], [2, 1, 3]];
    let mut mesh = Mesh {
        name: "flat".into(),
        positions: corners.iter().map(|&(x, y)| Vec3::new(x, y, 0.0)).collect(),
        uvs: Some(CornerAttribute {
            values: corners
                .iter()
                .map(|&(x, y)| Vec2::new((x + 1.0) / 2.0, (y + 1.0) / 2.0))
                .collect(),
            triangles: triangles.clone(),
        }),
        triangles,
        ..Mesh::default()
    };
    assert!(mesh.generate_tangents());
    let mut geometry = raylab::Geometry::new();
    geometry.add_mesh(&mesh, &glam::Affine3A::IDENTITY, |_| 0);
    let mut material = Material::diffuse("wall", Vec3::splat(0.8));
    let texture = Texture::Image(ImageTexture::new(Arc::new(image)));
    material.textures.normal = Some(raylab::material::NormalMap { texture, scale: 1.0 });
    wall_scene(geometry, material)
}
