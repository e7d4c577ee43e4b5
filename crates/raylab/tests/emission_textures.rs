//! Emission textures: an emitter that shines in a pattern lights the scene as the same pattern
//! cut into geometry would, whether the light is found by light sampling (the floor) or by a
//! ray that hits it (the ceiling seen directly).

use std::sync::Arc;

use glam::{Affine3A, Vec2, Vec3, Vec4};
use raylab::material::MaterialTextures;
use raylab::mesh::CornerAttribute;
use raylab::texture::{ImageTexture, Texture, TextureImage, Wrap};
use raylab::{
    Camera, Film, Geometry, Material, Mesh, PathScalar, PathSettings, Scene, SceneBvh,
    render_samples,
};

/// A quad over `x ∈ [x0, x1]`, `z ∈ [−1, 3]` at height `y`, facing `facing` (±y), with
/// texture coordinates `u` along x (0 at x = −1, 1 at x = 1) and `v` along z.
fn quad(x0: f32, x1: f32, y: f32, facing: f32) -> Mesh {
    let positions = vec![
        Vec3::new(x0, y, -1.0),
        Vec3::new(x1, y, -1.0),
        Vec3::new(x1, y, 3.0),
        Vec3::new(x0, y, 3.0),
    ];
    // (v1 − v0) × (v3 − v0) = x × z = −y: flip the winding to face +y.
    let triangles =
        if facing < 0.0 { vec![[0, 1, 2], [0, 2, 3]] } else { vec![[0, 2, 1], [0, 3, 2]] };
    let uvs = positions.iter().map(|p| Vec2::new((p.x + 1.0) / 2.0, (p.z + 1.0) / 4.0)).collect();
    Mesh {
        name: "quad".into(),
        positions,
        uvs: Some(CornerAttribute { values: uvs, triangles: triangles.clone() }),
        triangles,
        ..Mesh::default()
    }
}

/// A floor (y = 1, the lab's y points down) under a ceiling light (y = −1) whose left half
/// (x < 0) shines: either through an emission texture, white on its left half and black on its
/// right, or as two quads of which only the left one emits.
fn room(textured: bool) -> Scene {
    let mut geometry = Geometry::new();
    let floor = Material::diffuse("floor", Vec3::splat(0.5));
    let emission = Vec3::new(4.0, 3.0, 2.0);
    let mut materials = vec![floor];
    geometry.add_mesh(&quad(-1.0, 1.0, 1.0, -1.0), &Affine3A::IDENTITY, |_| 0);
    if textured {
        // 64 texels across: white, then black; clamped. Bilinear filtering ramps over the middle
        // texel's width, symmetric about u = ½, so the power is the sharp step's.
        let texels =
            (0..64).map(|x| if x < 32 { [1.0; 4] } else { [0.0, 0.0, 0.0, 1.0] }).collect();
        let image = Arc::new(TextureImage::from_rgba_f32("half", 64, 1, texels));
        let texture = ImageTexture { wrap: [Wrap::Clamp; 2], ..ImageTexture::new(image) };
        materials.push(Material {
            emission,
            textures: MaterialTextures {
                emission: Some(Texture::Image(texture)),
                ..MaterialTextures::default()
            },
            ..Material::diffuse("light", Vec3::ZERO)
        });
        geometry.add_mesh(&quad(-1.0, 1.0, -1.0, 1.0), &Affine3A::IDENTITY, |_| 1);
    } else {
        materials.push(Material { emission, ..Material::diffuse("light", Vec3::ZERO) });
        materials.push(Material::diffuse("dark", Vec3::ZERO));
        geometry.add_mesh(&quad(-1.0, 0.0, -1.0, 1.0), &Affine3A::IDENTITY, |_| 1);
        geometry.add_mesh(&quad(0.0, 1.0, -1.0, 1.0), &Affine3A::IDENTITY, |_| 2);
    }
    Scene { name: "room".into(), geometry, materials, ..Scene::default() }
}

fn render(scene: &Scene, size: u32, spp: u32) -> Film {
    let bvh = SceneBvh::build(&scene.geometry).unwrap();
    // Direct light only: the floor is lit by the light, nothing bounces back.
    let settings = PathSettings { max_depth: Some(2), ..PathSettings::default() };
    let path = PathScalar::new(scene, &bvh, settings);
    render_samples(&Camera::lab(size, size), &path, spp, &|_| {}).unwrap()
}

/// The mean of the pixels in columns `x0..x1`, rows `y0..y1`.
fn mean(film: &Film, (x0, x1): (u32, u32), (y0, y1): (u32, u32)) -> Vec3 {
    let mut sum = Vec3::ZERO;
    for y in y0..y1 {
        for x in x0..x1 {
            sum += film.pixel(x, y);
        }
    }
    sum / ((x1 - x0) * (y1 - y0)) as f32
}

#[test]
fn a_textured_emitter_lights_as_its_pattern_cut_into_geometry() {
    let n = 48;
    let (textured, split) = (render(&room(true), n, 64), render(&room(false), n, 64));
    // The ceiling seen directly (the top rows, where it spans the whole width): its left half
    // shines, its right half is dark, in both.
    let (left, right) = ((4, n / 2 - 3), (n / 2 + 3, n - 4));
    let top = (1, 4);
    for film in [&textured, &split] {
        let shining = mean(film, left, top);
        assert!(shining.abs_diff_eq(Vec3::new(4.0, 3.0, 2.0), 1e-3), "{shining}");
        assert_eq!(mean(film, right, top), Vec3::ZERO);
    }
    // The floor (the bottom rows), lit by light sampling and by rays that hit the light: the
    // same light on each side, brighter under the shining half.
    let bottom = (n - 4, n - 1);
    for side in [left, right] {
        let (a, b) = (mean(&textured, side, bottom), mean(&split, side, bottom));
        assert!(b.x > 0.01, "the floor is lit: {b}");
        let relative = ((a - b).abs() / b).max_element();
        assert!(relative < 0.04, "side {side:?}: textured {a}, split {b}");
    }
    let ratio = mean(&textured, left, bottom).x / mean(&textured, right, bottom).x;
    assert!(ratio > 1.3, "the floor under the light is brighter: {ratio}");
}

/// A constant emission texture `c` is the same light as an emission `c` times as bright: the
/// same pixels, sample for sample (light sampling picks and weighs it the same).
#[test]
fn a_constant_emission_texture_scales_the_emission() {
    let mut scene = room(true);
    let c = Vec4::new(0.25, 0.5, 0.75, 1.0);
    let image = Arc::new(TextureImage::from_rgba_f32("c", 1, 1, vec![c.to_array()]));
    scene.materials[1].textures.emission = Some(Texture::Image(ImageTexture::new(image)));
    let mut plain = scene.clone();
    plain.materials[1].textures.emission = None;
    plain.materials[1].emission *= c.truncate();
    let (a, b) = (render(&scene, 24, 4), render(&plain, 24, 4));
    for (p, q) in a.pixels().iter().zip(b.pixels()) {
        assert!(p.abs_diff_eq(*q, 1e-5 * q.max_element().max(1.0)), "{p} {q}");
    }
}
