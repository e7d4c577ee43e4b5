//! Textures in renders: one sample per pixel does not alias (the lab's integrator reads the
//! mip-map level of each pixel's ray cone), measured against a supersampled reference.

mod common;

use std::sync::Arc;

use glam::{Vec2, Vec3};
use raylab::mesh::CornerAttribute;
use raylab::render::render_samples;
use raylab::texture::{ImageTexture, Texture, TextureImage};
use raylab::{Aov, AovKind, BruteForce, Camera, Film, Lab, Material, Mesh, Scene, Stage};

/// A floor (the lab's y = 1, below the camera) 100 wide and 400 deep, tiled with a black and
/// white checkerboard, one tile of 2×2 squares per unit of length: squares of ½.
fn checker_floor() -> Scene {
    // 16×16 texels, squares of 8: sharp edges under bilinear filtering.
    let texels = (0..256u32)
        .map(|i| if (i % 16 / 8 + i / 16 / 8) % 2 == 0 { [0, 0, 0, 255] } else { [255; 4] })
        .collect();
    let image = TextureImage::from_rgba8("checker", 16, 16, texels, false);
    let corners = [(-50.0, 0.0), (50.0, 0.0), (50.0, 400.0), (-50.0, 400.0)];
    let mesh = Mesh {
        name: "floor".into(),
        positions: corners.iter().map(|&(x, z)| Vec3::new(x, 1.0, z)).collect(),
        triangles: vec![[0, 2, 1], [0, 3, 2]],
        uvs: Some(CornerAttribute {
            values: corners.iter().map(|&(x, z)| Vec2::new(x, z)).collect(),
            triangles: vec![[0, 2, 1], [0, 3, 2]],
        }),
        ..Mesh::default()
    };
    let mut material = Material::diffuse("checker", Vec3::ONE);
    material.textures.base_color = Some(Texture::Image(ImageTexture::new(Arc::new(image))));
    let mut geometry = raylab::Geometry::new();
    geometry.add_mesh(&mesh, &glam::Affine3A::IDENTITY, |_| 0);
    Scene::new("floor", geometry, vec![material], raylab::PointLight::lab())
}

/// The mean absolute difference of the red channel over the rows of the floor.
fn error(film: &Film, reference: &Film, rows: std::ops::Range<u32>) -> f64 {
    let width = film.width();
    let mut sum = 0.0;
    for y in rows.clone() {
        for x in 0..width {
            let i = (y * width + x) as usize;
            sum += f64::from((film.pixels()[i].x - reference.pixels()[i].x).abs());
        }
    }
    sum / f64::from(width * rows.len() as u32)
}

#[test]
fn one_sample_per_pixel_does_not_alias_a_receding_checkerboard() {
    let scene = checker_floor();
    let accel = BruteForce::new(&scene.vertices());
    let camera = Camera::lab(96, 64);
    // The reference: the texture at points (footprint 0), averaged over 256 samples spread
    // over each pixel: the pixel's true mean.
    let aov = Aov::new(&scene, &accel, AovKind::Albedo);
    let reference = render_samples(&camera, &aov, 256, &|_| {}).unwrap();
    // The horizon is the middle row; the floor fills the rows below it. Far rows (just below
    // the horizon) hold many squares per pixel.
    let far = 33..44;
    let near = 56..64;
    let flat = Lab::new(&scene, &accel, Stage::Flat);
    let point = render_samples(&camera, &flat, 1, &|_| {}).unwrap();
    let filtered = render_samples(&camera, &flat.for_camera(&camera), 1, &|_| {}).unwrap();
    let (point_far, filtered_far) =
        (error(&point, &reference, far.clone()), error(&filtered, &reference, far));
    eprintln!("far rows: point {point_far:.4}, filtered {filtered_far:.4}");
    // Read at points, far pixels are black or white at random against a grey mean: an error
    // near ½. Filtered, they are close to the grey (measured: 0.40 against 0.06).
    assert!(point_far > 0.3, "point lookups alias: {point_far}");
    assert!(filtered_far < 0.2 * point_far, "filtered {filtered_far} against point {point_far}");
    // Near, where a square spans pixels, the pattern stays: the filter is isotropic, the size
    // of the footprint's long axis, so it blurs a slanted floor across a little (measured: 0.041
    // against 0.031 for point lookups), far from the ½ of a wrong or washed-out texture.
    let (point_near, filtered_near) =
        (error(&point, &reference, near.clone()), error(&filtered, &reference, near));
    eprintln!("near rows: point {point_near:.4}, filtered {filtered_near:.4}");
    assert!(filtered_near < 0.1, "near: {filtered_near} against {point_near}");
}

/// The same bumps as geometry: a 128 × 128 grid displaced, with the exact normals at its
/// vertices.
fn bumpy_wall() -> Scene {
    let n = 128u32;
    let at = |i: u32| -1.0 + 2.0 * i as f32 / n as f32;
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (at(i), at(j));
            positions.push(Vec3::new(
                x,
                y,
                -common::BUMP_A * ((common::BUMP_K * x).sin() + (common::BUMP_K * y).sin()),
            ));
            normals.push(common::bump_normal(x, y));
        }
    }
    let index = |i: u32, j: u32| j * (n + 1) + i;
    let mut triangles = Vec::new();
    for j in 0..n {
        for i in 0..n {
            // Counter-clockwise from the camera's side (−z).
            triangles.push([index(i, j), index(i, j + 1), index(i + 1, j)]);
            triangles.push([index(i + 1, j), index(i, j + 1), index(i + 1, j + 1)]);
        }
    }
    let mesh = Mesh {
        name: "bumps".into(),
        positions,
        normals: Some(CornerAttribute { values: normals, triangles: triangles.clone() }),
        triangles,
        ..Mesh::default()
    };
    let mut geometry = raylab::Geometry::new();
    geometry.add_mesh(&mesh, &glam::Affine3A::IDENTITY, |_| 0);
    common::wall_scene(geometry, Material::diffuse("wall", Vec3::splat(0.8)))
}

#[test]
fn a_normal_mapped_plane_shades_as_the_bumpy_geometry() {
    use raylab::{PathScalar, PathSettings};
    let mut camera = Camera::lab(64, 64);
    camera.focal_length_px = 32.0 * 3.0 / 0.9;
    let settings = PathSettings { max_depth: Some(2), ..PathSettings::default() };
    let images: Vec<(Film, Film)> = [bumpy_wall(), common::normal_mapped_wall()]
        .iter()
        .map(|scene| {
            let accel = raylab::Bvh::new(&scene.vertices());
            let normals = Aov::new(scene, &accel, AovKind::Normals);
            let path = PathScalar::new(scene, &accel, settings);
            (
                render_samples(&camera, &normals, 4, &|_| {}).unwrap(),
                render_samples(&camera, &path, 16, &|_| {}).unwrap(),
            )
        })
        .collect();
    let [(geometry_n, geometry_l), (mapped_n, mapped_l)] = [images[0].clone(), images[1].clone()];
    // The normals agree to a degree on average (the flat wall is not displaced, so each pixel
    // sees the bumps from a slightly different place).
    let mut angle = 0.0f64;
    let mut flat_angle = 0.0f64;
    for (a, b) in geometry_n.pixels().iter().zip(mapped_n.pixels()) {
        let cos = a.normalize().dot(b.normalize()).clamp(-1.0, 1.0);
        angle += f64::from(cos.acos().to_degrees());
        flat_angle +=
            f64::from(a.normalize().dot(Vec3::NEG_Z).clamp(-1.0, 1.0).acos().to_degrees());
    }
    let pixels = geometry_n.pixels().len() as f64;
    let (angle, flat_angle) = (angle / pixels, flat_angle / pixels);
    eprintln!(
        "mean angle to the geometry's normals: mapped {angle:.3}°, unmapped {flat_angle:.3}°"
    );
    assert!(flat_angle > 4.0, "the bumps tilt the normals by {flat_angle}° on average");
    assert!(angle < 0.1 * flat_angle, "mapped normals {angle}° off");
    // The light they shade with agrees within 2 % on average.
    let sum = |film: &Film| film.pixels().iter().map(|p| f64::from(p.x)).sum::<f64>();
    let difference: f64 = geometry_l
        .pixels()
        .iter()
        .zip(mapped_l.pixels())
        .map(|(a, b)| f64::from((a.x - b.x).abs()))
        .sum();
    let relative = difference / sum(&geometry_l);
    eprintln!("mean relative difference of the direct light: {relative:.4}");
    assert!(relative < 0.02, "{relative}");
}

/// A white quad in front of a red wall, cut out by its texture's alpha in a 2 × 2 checker
/// (glTF's `alphaMode: MASK`): camera rays and shadow rays pass the holes and stop at the rest.
#[test]
fn alpha_masked_holes_let_rays_through() {
    use raylab::{Accelerator, Integrator};
    let scene = common::cut_out_scene();
    let accel = raylab::Bvh::new(&scene.vertices());
    let camera = Camera::lab(64, 64);
    let albedo = Aov::new(&scene, &accel, AovKind::Albedo);
    let lab = Lab::new(&scene, &accel, Stage::Shadows);
    let mut sampler =
        raylab::sampling::Sampler::new(raylab::SamplerKind::Independent, 0, (0, 0), 0);
    // Quadrant centres (x, y = ±½ on the quad) at pixels 32 ∓ 64·½/3.
    for (px, py, hole) in [(21, 21, false), (42, 21, true), (21, 42, true), (42, 42, false)] {
        let ray = camera.pixel_ray(px, py);
        let seen = albedo.radiance(&ray, &mut sampler);
        let lit = lab.radiance(&ray, &mut sampler);
        if hole {
            assert_eq!(seen, Vec3::new(0.8, 0.0, 0.0), "({px}, {py}): the wall through the hole");
            assert!(lit.x > 0.0, "({px}, {py}): lit through the hole, not shadowed by it");
        } else {
            assert_eq!(seen, Vec3::ONE, "({px}, {py}): the quad");
        }
        // The plain BVH query sees the quad everywhere: the holes are the integrators' doing.
        assert!(accel.closest_hit(&ray).unwrap().t < 3.5);
    }
    // The tile path (the lab's batches) gives the same colours as ray by ray.
    let rays: Vec<raylab::Ray> = (0..64).map(|x| camera.pixel_ray(x, 21)).collect();
    let mut samplers = vec![sampler.clone(); 64];
    let mut out = vec![Vec3::ZERO; 64];
    lab.radiance_each(&rays, &mut samplers, &mut out);
    for (ray, colour) in rays.iter().zip(&out) {
        assert_eq!(*colour, lab.radiance(ray, &mut sampler));
    }
}
