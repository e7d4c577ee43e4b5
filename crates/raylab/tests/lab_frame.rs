//! Known answers of the lab frame: the lab's light model at points where it has a closed form,
//! the stages, freedom from shadow acne at any scale, determinism, and a golden image.

use std::f32::consts::PI;
use std::path::Path;

use glam::Vec3;
use image::RgbImage;
use raylab::image_compare::{compare_rgb8, save_failure_images};
use raylab::{
    BruteForce, Camera, Film, Integrator, Lab, Ray, Sampler, SamplerKind, Scene, Stage, image_io,
    render, render_samples,
};

fn cornell() -> Scene {
    Scene::built_in("cornell").unwrap()
}

/// The (unclamped) colour the lab camera sees at `point`, by a ray from the camera to it.
fn radiance_at(scene: &Scene, stage: Stage, point: Vec3, camera_position: Vec3) -> Vec3 {
    let accel = BruteForce::new(&scene.vertices());
    let ray = Ray::new(camera_position, point - camera_position);
    let hit = raylab::Accelerator::closest_hit(&accel, &ray).expect("the point is visible");
    assert!((hit.t - 1.0).abs() < 1e-4, "the ray meets something before the point: t = {}", hit.t);
    Lab::new(scene, &accel, stage).radiance(&ray, &mut sampler())
}

fn render_scene(scene: &Scene, camera: &Camera, stage: Stage) -> Film {
    let accel = BruteForce::new(&scene.vertices());
    render(camera, &Lab::new(scene, &accel, stage), &|_| {}).unwrap()
}

/// Fails, leaving the actual, expected and diff images in a temporary folder, if more than
/// `max_pixels` pixels differ by more than one level in some channel.
fn assert_images_close(name: &str, actual: &RgbImage, expected: &RgbImage, max_pixels: usize) {
    let diff = compare_rgb8(actual, expected, 1).expect("images of the same size");
    if diff.pixels_over_tolerance > max_pixels {
        let folder = save_failure_images(name, actual, expected).unwrap();
        panic!("{name}: {diff:?}; actual, expected and diff images are in {}", folder.display());
    }
}

/// A sampler for calls of `radiance` (the lab integrator draws no random numbers).
fn sampler() -> Sampler {
    Sampler::new(SamplerKind::Lab, 0, (0, 0), 0)
}

const CAMERA: Vec3 = Vec3::new(0.0, 0.0, -3.0);

#[test]
fn the_floor_below_the_light_has_the_closed_form_colour() {
    // (0, 1, −0.7) is 1.5 below the light at (0, −0.5, −0.7), head on: D = 14 / (4π·1.5²).
    let d = 14.0 / (4.0 * PI * 2.25);
    let expected = Vec3::new(0.15, 0.75, 0.15) * (d + 0.5);
    assert!((expected.y - 0.7464).abs() < 1e-4);
    let colour = radiance_at(&cornell(), Stage::Ambient, Vec3::new(0.0, 1.0, -0.7), CAMERA);
    assert!((colour - expected).abs().max_element() < 1e-5, "{colour} vs {expected}");
    // The stages on the way there.
    let direct = radiance_at(&cornell(), Stage::Direct, Vec3::new(0.0, 1.0, -0.7), CAMERA);
    assert!((direct - Vec3::splat(d)).abs().max_element() < 1e-5, "{direct}");
    for stage in [Stage::Reflected, Stage::Shadows] {
        let colour = radiance_at(&cornell(), stage, Vec3::new(0.0, 1.0, -0.7), CAMERA);
        assert!((colour - Vec3::new(0.15, 0.75, 0.15) * d).abs().max_element() < 1e-5, "{stage}");
    }
}

#[test]
fn the_ceiling_above_the_light_saturates_green_and_blue() {
    // (0, −1, −0.7) is 0.5 above the light: D = 14 / (4π·0.25) = 14/π on the cyan ceiling.
    let colour = radiance_at(&cornell(), Stage::Ambient, Vec3::new(0.0, -1.0, -0.7), CAMERA);
    let red = 0.15 * (14.0 / PI + 0.5);
    assert!((red - 0.743).abs() < 1e-3);
    assert!((colour.x - red).abs() < 1e-5, "{colour}");
    assert!(colour.y > 1.0 && colour.z > 1.0, "{colour}");
}

#[test]
fn the_rendered_frame_shows_the_known_answers_at_their_pixels() {
    let camera = Camera::lab(500, 500);
    let image = render_scene(&cornell(), &camera, Stage::Ambient).to_rgb8_clamped().unwrap();
    let pixel_of = |point: Vec3| {
        let film = camera.project(point).unwrap();
        image.get_pixel(film.x as u32, film.y as u32).0
    };
    let floor = pixel_of(Vec3::new(0.0, 1.0, -0.7));
    // The pixel centre is a fraction of a pixel from the point: allow one level.
    let expected = (0.75 * (14.0 / (4.0 * PI * 2.25) + 0.5) * 255.0).round() as i32;
    assert!((floor[1] as i32 - expected).abs() <= 1, "{floor:?} vs green {expected}");
    let ceiling = pixel_of(Vec3::new(0.0, -1.0, -0.7));
    let expected_red = (0.15 * (14.0 / PI + 0.5) * 255.0).round() as i32;
    assert!((ceiling[0] as i32 - expected_red).abs() <= 1, "{ceiling:?}");
    assert_eq!(&ceiling[1..], &[255, 255]);
}

#[test]
fn a_wall_seen_from_behind_is_not_lit_through_itself() {
    // From outside the room, behind the back wall (z = 1), looking at it: the light is on the
    // wall's other side, so only the ambient term remains.
    let scene = cornell();
    let behind = Vec3::new(0.0, 0.0, 3.0);
    let back_wall = Vec3::new(0.1, 0.2, 1.0);
    assert_eq!(radiance_at(&scene, Stage::Shadows, back_wall, behind), Vec3::ZERO);
    assert_eq!(radiance_at(&scene, Stage::Direct, back_wall, behind), Vec3::ZERO);
    let ambient = radiance_at(&scene, Stage::Ambient, back_wall, behind);
    assert!((ambient - Vec3::splat(0.75 * 0.5)).abs().max_element() < 1e-6, "{ambient}");
    // A light moved behind the wall lights that side, and the room's inside stays dark there.
    let mut outside_light = scene.clone();
    outside_light.point_light_mut().position = Vec3::new(0.0, 0.0, 2.0);
    assert!(radiance_at(&outside_light, Stage::Shadows, back_wall, behind).y > 0.1);
    assert_eq!(radiance_at(&outside_light, Stage::Shadows, back_wall, CAMERA), Vec3::ZERO);
}

#[test]
fn closest_hit_not_first_hit() {
    // Straight ahead, the ray meets the back wall (triangles 8–9, early in the list) and, nearer,
    // the tall blue block (triangles 20–29): the pixel must be blue.
    let scene = cornell();
    let ray = Ray::new(CAMERA, Vec3::Z);
    let hits: Vec<(usize, f32)> = scene
        .vertices()
        .iter()
        .enumerate()
        .filter_map(|(i, &[v0, v1, v2])| {
            raylab::triangle::WatertightRay::new(&ray)
                .intersect(v0, v1, v2, f32::INFINITY)
                .map(|h| (i, h.t))
        })
        .collect();
    let first = hits[0];
    let nearest = hits.iter().copied().min_by(|a, b| a.1.total_cmp(&b.1)).unwrap();
    assert!(
        first.0 < 10 && nearest.0 >= 20,
        "the ray should meet the wall first in order: {hits:?}"
    );
    let accel = BruteForce::new(&scene.vertices());
    let hit = raylab::Accelerator::closest_hit(&accel, &ray).unwrap();
    assert_eq!(hit.triangle as usize, nearest.0);
    assert_eq!(hit.t, nearest.1);
    let material = &scene.materials[scene.geometry.material_id(hit.triangle as usize) as usize];
    assert_eq!(material.bsdf.albedo(), Vec3::new(0.15, 0.15, 0.75));
}

#[test]
fn flat_stage_shows_only_triangle_colours_or_black() {
    let image =
        render_scene(&cornell(), &Camera::lab(200, 200), Stage::Flat).to_rgb8_clamped().unwrap();
    let to8 = |c: Vec3| c.to_array().map(raylab::film::to_8bit_clamped);
    let mut palette: Vec<[u8; 3]> =
        cornell().materials.iter().map(|m| to8(m.bsdf.albedo())).collect();
    palette.push([0, 0, 0]);
    palette.sort();
    palette.dedup();
    assert_eq!(palette.len(), 8, "seven colours and black");
    let mut seen = std::collections::BTreeSet::new();
    for pixel in image.pixels() {
        assert!(palette.contains(&pixel.0), "pixel {:?} is not a triangle colour", pixel.0);
        seen.insert(pixel.0);
    }
    // From the lab's camera the room fills the view: every colour is seen, and no black.
    assert_eq!(seen.len(), 7, "{seen:?}");
    assert!(!seen.contains(&[0, 0, 0]));
}

#[test]
fn no_shadow_acne_at_any_scene_scale() {
    let base = cornell();
    let below_light = Vec3::new(0.0, 1.0, -0.7);
    let reference = radiance_at(&base, Stage::Shadows, below_light, CAMERA);
    let camera = Camera::lab(100, 100);
    let reference_image = render_scene(&base, &camera, Stage::Shadows).to_rgb8_clamped().unwrap();
    for scale in [1e-3f32, 1e3, 1e-6, 1e6] {
        let scene = base.scaled(scale);
        let lit = radiance_at(&scene, Stage::Shadows, below_light * scale, CAMERA * scale);
        assert!(
            (lit - reference).abs().max_element() < 1e-4,
            "scale {scale}: {lit} instead of {reference}: the floor below the light is in shadow"
        );
        // The whole frame: acne would speckle the lit surfaces. Rounding at a different scale
        // may move an edge or a shadow boundary by a pixel, no more.
        let scaled_camera = Camera { position: camera.position * scale, ..camera };
        let image = render_scene(&scene, &scaled_camera, Stage::Shadows).to_rgb8_clamped().unwrap();
        assert_images_close(&format!("acne-scale-{scale}"), &image, &reference_image, 20);
    }
}

#[test]
fn the_picture_is_the_same_for_any_thread_count() {
    let scene = cornell();
    let camera = Camera { yaw: 0.2, ..Camera::lab(97, 61) };
    let films: Vec<Film> = [1, 2, 3, 8]
        .into_iter()
        .map(|threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| render_scene(&scene, &camera, Stage::Ambient))
        })
        .collect();
    for film in &films[1..] {
        assert!(film == &films[0]);
    }
}

/// Anti-aliasing: several samples per pixel are the same for any thread count, one sample is
/// the lab's one ray through the pixel centre, and more samples come closer to the true pixel
/// colours, the mean over each pixel's area, here a 12×12-times-finer render averaged down.
#[test]
fn samples_per_pixel_anti_alias_deterministically() {
    let scene = cornell();
    let accel = BruteForce::new(&scene.vertices());
    let lab = Lab::new(&scene, &accel, Stage::Ambient);
    let camera = Camera { yaw: 0.1, ..Camera::lab(40, 30) };
    let films: Vec<Film> = [1, 2, 5]
        .into_iter()
        .map(|threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| render_samples(&camera, &lab, 7, &|_| {}).unwrap())
        })
        .collect();
    assert!(films.iter().all(|film| film == &films[0]));
    assert!(
        render_samples(&camera, &lab, 1, &|_| {}).unwrap()
            == render(&camera, &lab, &|_| {}).unwrap()
    );

    const FINE: u32 = 12;
    let fine_camera = Camera {
        width: camera.width * FINE,
        height: camera.height * FINE,
        focal_length_px: camera.focal_length_px * FINE as f32,
        ..camera
    };
    let fine = render(&fine_camera, &lab, &|_| {}).unwrap();
    let truth = |x: u32, y: u32| {
        let mut sum = Vec3::ZERO;
        for j in 0..FINE {
            for i in 0..FINE {
                sum += fine.pixel(x * FINE + i, y * FINE + j);
            }
        }
        sum / (FINE * FINE) as f32
    };
    let error = |film: &Film| {
        let mut total = 0.0;
        for y in 0..camera.height {
            for x in 0..camera.width {
                total += (film.pixel(x, y) - truth(x, y)).abs().element_sum();
            }
        }
        total / (camera.width * camera.height) as f32
    };
    let errors: Vec<f32> = [1, 4, 16, 64]
        .into_iter()
        .map(|spp| error(&render_samples(&camera, &lab, spp, &|_| {}).unwrap()))
        .collect();
    // Edges carry the error: it must fall with every step, to well under half of one sample's.
    assert!(errors.windows(2).all(|pair| pair[1] < pair[0]), "{errors:?}");
    assert!(errors[3] < 0.25 * errors[0], "{errors:?}");
}

/// Rendering traces camera rays and their shadow rays in tiles, through the BVH's packets; every
/// pixel is still exactly the colour of its own ray traced alone, at every stage, for a camera
/// turned so that tiles straddle direction axes (and with an odd size, so that tiles are cut).
#[test]
fn tiled_packets_give_each_pixel_its_own_rays_colour() {
    let scene = cornell();
    let bvh = raylab::bvh::Bvh::new(&scene.vertices());
    for camera in [Camera::lab(64, 64), Camera { yaw: 0.3, ..Camera::lab(53, 37) }] {
        for stage in Stage::ALL {
            let lab = Lab::new(&scene, &bvh, stage);
            let film = render(&camera, &lab, &|_| {}).unwrap();
            let rays = camera.rays();
            for y in 0..camera.height {
                for x in 0..camera.width {
                    let alone = lab.radiance(&rays.pixel_ray(x, y), &mut sampler());
                    assert_eq!(film.pixel(x, y), alone, "{stage} pixel ({x}, {y})");
                }
            }
        }
    }
}

/// The lab frame at 100×100, at every stage, against `tests/data/lab_100_<stage>.png`, which an
/// independent float64 implementation of the lab (`tools/reference_lab.py`, Möller–Trumbore in
/// numpy, no code shared) rendered.
///
/// Every pixel must match within one level, except on the image's diagonals: their rays lie in
/// the planes through the room's corner edges, where two walls meet at exactly the same distance
/// and float32 and float64 rounding may pick different walls (either is right). A few of those
/// (at most 8 of 200) may differ.
#[test]
fn golden_lab_frames() {
    const SIZE: u32 = 100;
    let on_a_diagonal = |x: u32, y: u32| x == y || x + y == SIZE - 1;
    for stage in Stage::ALL {
        let golden_path =
            Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("tests/data/lab_100_{stage}.png"));
        let expected = image_io::load_rgb8(&golden_path).unwrap();
        let actual =
            render_scene(&cornell(), &Camera::lab(SIZE, SIZE), stage).to_rgb8_clamped().unwrap();
        let mut ties = 0;
        let mut expected_off_diagonals = expected.clone();
        for (x, y, pixel) in expected_off_diagonals.enumerate_pixels_mut() {
            if on_a_diagonal(x, y) && pixel != actual.get_pixel(x, y) {
                ties += 1;
                *pixel = *actual.get_pixel(x, y);
            }
        }
        assert!(ties <= 8, "stage {stage}: {ties} pixels on the diagonals differ");
        assert_images_close(
            &format!("golden-lab-100-{stage}"),
            &actual,
            &expected_off_diagonals,
            0,
        );
    }
}
