//! The path tracer against Mitsuba 3 on Mitsuba's own Cornell box (`scenes/cornell-mitsuba.toml`).
//!
//! The reference `tests/data/mitsuba-cbox-64.pfm` is Mitsuba 3.9.1's `path` integrator (max depth
//! 8, box filter) at 64×64 with 65,536 samples per pixel, made by
//! `tools/mitsuba/cbox_reference.py --variant llvm_ad_rgb --size 64 --spp 4096 --passes 16
//! --seed 2000` (its own noise is about 0.0016 RMS). Mitsuba is not needed to run these tests.
//!
//! The renders are the default `path`, the wavefront ([`Wavefront`]); its pixels are the
//! scalar path's to the bit (`tests/wavefront.rs`, `tests/furnace.rs`).

use std::path::{Path, PathBuf};

use glam::DVec3;
use raylab::film::Display;
use raylab::image_compare::save_failure_images;
use raylab::integrator::Path as Wavefront;
use raylab::scene::{Instancing, LoadOptions};
use raylab::{
    Accumulator, Bvh, Camera, Film, PathSettings, SampleSettings, SamplerKind, Scene, SceneBvh,
    TriangleSampling, image_io,
};

fn repository() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn scene() -> Scene {
    raylab::scene::load_scene_file(&repository().join("scenes/cornell-mitsuba.toml")).unwrap()
}

fn reference() -> Film {
    image_io::load_film(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mitsuba-cbox-64.pfm"),
    )
    .unwrap()
}

/// Renders the scene at 64×64 with its own camera and max depth.
fn render(scene: &Scene, spp: u32, settings: SampleSettings) -> Film {
    render_with(scene, spp, settings, TriangleSampling::Area)
}

fn render_with(
    scene: &Scene,
    spp: u32,
    settings: SampleSettings,
    light_sampling: TriangleSampling,
) -> Film {
    let camera = scene.camera.unwrap().camera(64, 64);
    let bvh = Bvh::new(&scene.vertices());
    let max_depth = scene.settings.max_depth.unwrap().segments();
    let path_settings = PathSettings { max_depth, light_sampling, ..PathSettings::default() };
    let path = Wavefront::new(scene, &bvh, path_settings);
    let mut accumulator = Accumulator::new(64, 64).unwrap();
    // A render of `spp` samples: the count `multijitter` lays out.
    accumulator.settings = SampleSettings { count: spp, ..settings };
    for _ in 0..spp {
        accumulator.add_sample(&camera, &path);
    }
    accumulator.mean().unwrap()
}

fn rmse(a: &Film, b: &Film) -> f64 {
    let sum: f64 = a
        .pixels()
        .iter()
        .zip(b.pixels())
        .map(|(p, q)| (p.as_dvec3() - q.as_dvec3()).length_squared())
        .sum();
    (sum / (3 * a.pixels().len()) as f64).sqrt()
}

fn mean(film: &Film) -> DVec3 {
    film.pixels().iter().map(|p| p.as_dvec3()).sum::<DVec3>() / film.pixels().len() as f64
}

/// Fails with both pictures (sRGB) and their difference saved for a look.
fn fail(name: &str, actual: &Film, expected: &Film, message: String) -> ! {
    let to8 = |film: &Film| film.to_rgb8(&Display::SRGB).unwrap();
    let folder = save_failure_images(name, &to8(actual), &to8(expected)).unwrap();
    panic!("{message}; the images are in {}", folder.display());
}

#[test]
fn the_cornell_box_matches_mitsuba() {
    let scene = scene();
    let reference = reference();
    let film = render(&scene, 256, SampleSettings { seed: 1, ..SampleSettings::default() });
    let (ours, theirs) = (mean(&film), mean(&reference));
    let relative = (ours - theirs) / theirs;
    let error = rmse(&film, &reference);
    eprintln!("mean {ours:?} vs Mitsuba {theirs:?} ({relative:?}); RMSE {error:.5}");
    if relative.abs().max_element() > 0.005 || error > 0.012 {
        fail(
            "mitsuba-cbox",
            &film,
            &reference,
            format!("mean {ours} vs {theirs} (relative {relative}), RMSE {error}"),
        );
    }
}

#[test]
fn solid_angle_light_sampling_converges_to_the_same_image() {
    let scene = scene();
    let reference = reference();
    let settings = SampleSettings { seed: 6, ..SampleSettings::default() };
    let area = render_with(&scene, 128, settings, TriangleSampling::Area);
    let solid = render_with(&scene, 128, settings, TriangleSampling::SolidAngle);
    let relative = (mean(&solid) - mean(&reference)) / mean(&reference);
    let relative_area = (mean(&area) - mean(&reference)) / mean(&reference);
    let (e_area, e_solid) = (rmse(&area, &reference), rmse(&solid, &reference));
    eprintln!(
        "128 spp: area sampling RMSE {e_area:.5}, solid angle {e_solid:.5}, mean {relative:?} (area {relative_area:?})"
    );
    assert!(relative.abs().max_element() < 0.005, "{relative}");
    // Not noisier than area sampling (the light is small here, so not much better either).
    assert!(e_solid < 1.1 * e_area, "solid angle {e_solid} vs area {e_area}");
}

#[test]
fn error_falls_as_one_over_the_square_root_of_the_samples() {
    let scene = scene();
    let reference = reference();
    for kind in [SamplerKind::Independent, SamplerKind::Sobol, SamplerKind::MultiJitter] {
        let samples = [4u32, 16, 64, 256];
        let errors: Vec<f64> = samples
            .into_iter()
            .map(|spp| {
                let settings =
                    SampleSettings { seed: 3, sampler: Some(kind), ..SampleSettings::default() };
                rmse(&render(&scene, spp, settings), &reference)
            })
            .collect();
        // The least-squares slope of log error against log samples: −½ for 1/√spp. The
        // reference's own noise (0.0016) is taken out of each error first.
        let points: Vec<(f64, f64)> = samples
            .iter()
            .zip(&errors)
            .map(|(&n, &e)| ((n as f64).ln(), (e * e - 0.0016f64.powi(2)).max(1e-12).sqrt().ln()))
            .collect();
        let mean_x = points.iter().map(|p| p.0).sum::<f64>() / points.len() as f64;
        let mean_y = points.iter().map(|p| p.1).sum::<f64>() / points.len() as f64;
        let slope = points.iter().map(|p| (p.0 - mean_x) * (p.1 - mean_y)).sum::<f64>()
            / points.iter().map(|p| (p.0 - mean_x).powi(2)).sum::<f64>();
        eprintln!("{kind:?}: RMSE at {samples:?} spp: {errors:?}, slope {slope:.3}");
        // Every step lowers the error: independent samples at the rate of 1/√spp, scrambled
        // Sobol' and multi-jittered points at that rate or faster (stratified points reach
        // spp^−¾ on smooth parts).
        assert!(errors.windows(2).all(|pair| pair[1] < pair[0]), "{kind:?}: {errors:?}");
        let expected = if kind == SamplerKind::Independent { -0.6..=-0.42 } else { -1.0..=-0.42 };
        assert!(expected.contains(&slope), "{kind:?}: slope {slope}, errors {errors:?}");
    }
}

#[test]
fn sobol_samples_beat_independent_ones() {
    let scene = scene();
    let reference = reference();
    let error = |kind| {
        let settings = SampleSettings { seed: 9, sampler: Some(kind), ..SampleSettings::default() };
        rmse(&render(&scene, 16, settings), &reference)
    };
    let (sobol, independent) = (error(SamplerKind::Sobol), error(SamplerKind::Independent));
    let jittered = error(SamplerKind::MultiJitter);
    eprintln!(
        "16 spp: Sobol' {sobol:.5}, multi-jittered {jittered:.5}, independent {independent:.5}"
    );
    assert!(sobol < 0.85 * independent, "Sobol' {sobol} vs independent {independent}");
    assert!(jittered < 0.85 * independent, "multijitter {jittered} vs independent {independent}");
}

#[test]
fn the_same_pixels_for_any_thread_count_and_tiling() {
    let scene = scene();
    // The default sampler, and `multijitter` on a power-of-two grid (4 samples: its draws in
    // lanes) and on another (3 samples: one by one).
    for (sampler, spp) in
        [(None, 3), (Some(SamplerKind::MultiJitter), 4), (Some(SamplerKind::MultiJitter), 3)]
    {
        let films: Vec<Film> = [(1, (8, 8)), (2, (8, 8)), (2, (3, 5)), (3, (64, 1))]
            .into_iter()
            .map(|(threads, tile)| {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                let settings =
                    SampleSettings { seed: 4, tile, sampler, ..SampleSettings::default() };
                pool.install(|| render(&scene, spp, settings))
            })
            .collect();
        for film in &films[1..] {
            assert!(
                film.pixels()
                    .iter()
                    .zip(films[0].pixels())
                    .all(|(a, b)| a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits)),
                "{sampler:?}"
            );
        }
    }
    let films = [render(&scene, 3, SampleSettings { seed: 4, ..SampleSettings::default() })];
    // A different seed gives different pixels.
    let other = render(&scene, 3, SampleSettings { seed: 5, ..SampleSettings::default() });
    assert_ne!(other, films[0]);
    assert!(films[0].pixels().iter().all(|p| p.is_finite() && p.min_element() >= 0.0));
}

/// A scene file under `tests/data` rendered by the wavefront path tracer at the size of the
/// Mitsuba reference beside it (`reference.pfm`), `spp` samples with `seed`, through the scene's
/// own accelerator (two levels where it keeps a mesh drawn in several places, as `instancing`
/// says): the accelerator, the camera, the render and the reference.
fn render_beside_its_reference(
    file: &str,
    spp: u32,
    seed: u64,
    instancing: Instancing,
) -> (SceneBvh, Camera, Film, Film) {
    let scene_file = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(file);
    let options = LoadOptions { instancing };
    let scene = raylab::scene::load_scene_file_with(&scene_file, &options).unwrap();
    let reference = image_io::load_film(&scene_file.with_file_name("reference.pfm")).unwrap();
    let (width, height) = (reference.width(), reference.height());
    let camera = scene.camera.unwrap().camera(width, height);
    let accel = SceneBvh::build(&scene.geometry).unwrap();
    let max_depth = scene.settings.max_depth.unwrap().segments();
    let path =
        Wavefront::new(&scene, &accel, PathSettings { max_depth, ..PathSettings::default() });
    let mut accumulator = Accumulator::new(width, height).unwrap();
    accumulator.settings = SampleSettings { seed, ..SampleSettings::default() };
    for _ in 0..spp {
        accumulator.add_sample(&camera, &path);
    }
    let film = accumulator.mean().unwrap();
    drop(path);
    (accel, camera, film, reference)
}

/// Five materials side by side (`tests/data/mitsuba-materials/materials.toml`: rough gold,
/// glass, frosted glass, plastic, brushed aluminium on a diffuse floor, an area light and a
/// sky) against Mitsuba 3's render of the same file, same sphere mesh
/// (`tools/mitsuba/materials_reference.py`, 160×64, 16,384 spp): the mean radiance of a patch on
/// each sphere within 3 % (measured: 0.2–0.7 %) and of the whole image within 0.5 % (0.06 %).
/// The brushed sphere is anisotropic: its look depends on the shading frame, which is Mitsuba's
/// in both (the tangent along `dp/du`: a mesh without UVs, each triangle's first edge).
#[test]
fn every_material_matches_mitsuba() {
    let (_, camera, film, reference) =
        render_beside_its_reference("mitsuba-materials/materials.toml", 128, 11, Instancing::Auto);
    // A 5×5 patch at the middle of each sphere (the file's centres, y-up, in the lab's frame).
    let patch = |film: &Film, centre: glam::Vec3| {
        let p = camera.project(raylab::scene::model_to_lab(centre)).expect("in view");
        let (cx, cy) = (p.x as u32, p.y as u32);
        let mut sum = DVec3::ZERO;
        for y in cy - 2..=cy + 2 {
            for x in cx - 2..=cx + 2 {
                sum += film.pixel(x, y).as_dvec3();
            }
        }
        sum / 25.0
    };
    let mut report = Vec::new();
    let mut worst = 0.0f64;
    for (name, x) in
        [("gold", -4.0), ("glass", -2.0), ("frosted", 0.0), ("plastic", 2.0), ("brushed", 4.0)]
    {
        let centre = glam::Vec3::new(x, 0.0, 0.0);
        let (ours, theirs) = (patch(&film, centre), patch(&reference, centre));
        let relative = ((ours - theirs) / theirs.max(DVec3::splat(1e-3))).abs().max_element();
        worst = worst.max(relative);
        report.push(format!("{name}: {ours:.4} vs {theirs:.4} ({:.1} %)", 100.0 * relative));
    }
    let (ours, theirs) = (mean(&film), mean(&reference));
    let whole = ((ours - theirs) / theirs).abs().max_element();
    report.push(format!("image mean {ours:.4} vs {theirs:.4} ({:.2} %)", 100.0 * whole));
    eprintln!("{}", report.join("\n"));
    if worst > 0.03 || whole > 0.005 {
        fail("mitsuba-materials", &film, &reference, report.join("; "));
    }
}

/// A textured, instanced glTF scene (`tests/data/mitsuba-gltf/boxes.toml`: Khronos' textured
/// box placed eighteen times by the glTF's nodes, two of them under a parent node, on a floor
/// under an area light and a sky) against Mitsuba 3's render of the same file
/// (`tools/mitsuba/materials_reference.py`, which places the glTF's mesh by its nodes as
/// Mitsuba's shapegroup and instances; 64×64, 16,384 spp, `multijitter`): the whole image's mean
/// within 0.5 % and each 8×8 block's within 4 % (measured: 0.02 % and 0.77 %). The boxes' logo
/// is read through the glTF's texture coordinates, as a scene file's image texture reads any
/// mesh's (`v` up from the bottom row, as OBJ's and Mitsuba's): with the coordinates turned
/// upside down the worst block is 38 % off. Both ways of drawing the boxes are compared: kept
/// instanced (a two-level BVH) and copied into world space, as `Instancing::Auto` does with so
/// small a mesh.
#[test]
fn a_textured_instanced_gltf_scene_matches_mitsuba() {
    gltf_scene_matches_mitsuba(Instancing::Keep, "mitsuba-gltf");
    gltf_scene_matches_mitsuba(Instancing::Auto, "mitsuba-gltf-flat");
}

fn gltf_scene_matches_mitsuba(instancing: Instancing, name: &str) {
    let (accel, _, film, reference) =
        render_beside_its_reference("mitsuba-gltf/boxes.toml", 256, 12, instancing);
    let instanced = matches!(accel, SceneBvh::Instanced(_));
    assert_eq!(instanced, instancing == Instancing::Keep, "the boxes are instances if kept");
    let worst = worst_block(&film, &reference, 1e-2);
    let (ours, theirs) = (mean(&film), mean(&reference));
    let whole = ((ours - theirs) / theirs).abs().max_element();
    let report = format!(
        "worst 8×8 block ({}, {}) {:.2} %, image mean {ours:.4} vs {theirs:.4} ({:.2} %)",
        worst.1,
        worst.2,
        100.0 * worst.0,
        100.0 * whole
    );
    eprintln!("{instancing:?}: {report}");
    if worst.0 > 0.04 || whole > 0.005 {
        fail(name, &film, &reference, report);
    }
}

/// The 8×8 block of `film` whose mean is furthest from `reference`'s, relatively (channel by
/// channel, against at least `floor`): how far, and the block's column and row.
fn worst_block(film: &Film, reference: &Film, floor: f64) -> (f64, u32, u32) {
    let block = |film: &Film, bx: u32, by: u32| {
        let mut sum = DVec3::ZERO;
        for y in by * 8..by * 8 + 8 {
            for x in bx * 8..bx * 8 + 8 {
                sum += film.pixel(x, y).as_dvec3();
            }
        }
        sum / 64.0
    };
    let mut worst = (0.0f64, 0, 0);
    for by in 0..reference.height() / 8 {
        for bx in 0..reference.width() / 8 {
            let (ours, theirs) = (block(film, bx, by), block(reference, bx, by));
            let relative = ((ours - theirs) / theirs.max(DVec3::splat(floor))).abs().max_element();
            if relative > worst.0 {
                worst = (relative, bx, by);
            }
        }
    }
    worst
}

/// Spheres (diffuse, rough gold, smooth plastic) on a floor under an HDR sky with a small
/// bright sun, turned 30° by `to_world`, and a spot light (`tests/data/mitsuba-envmap/
/// envmap.toml`, the sky made by `tools/envmap/sky.py`) against Mitsuba 3's render of the same
/// file (`tools/mitsuba/materials_reference.py`, 128×128, 32,768 spp, `multijitter`), at 256
/// spp: the whole image's mean within 0.5 % (measured 0.02 %) and each 8×8 block's within 6 %
/// (measured 4.2 %, the noise of 256 spp: at 4,096 spp every block is within 0.95 %), but for
/// the sun's sharp reflections in the plastic and the gold (the pixels above 3 in the
/// reference), whose sum is compared on its own, within 15 % (measured 0.8 %): a fraction of a
/// pixel 800 times as bright as the sky, one such pixel's estimate is noisy (at 4,096 spp, 1–8 %
/// off by the seed and sampler). A mirrored or misplaced map, a spot of another profile or a
/// sun sampled wrongly moves blocks by far more.
#[test]
fn an_environment_lit_scene_with_a_sun_and_a_spot_matches_mitsuba() {
    let (_, _, film, reference) =
        render_beside_its_reference("mitsuba-envmap/envmap.toml", 256, 13, Instancing::Auto);
    let highlight: Vec<usize> = (0..reference.pixels().len())
        .filter(|&i| reference.pixels()[i].max_element() > 3.0)
        .collect();
    let masked = |film: &Film| {
        let mut pixels = film.pixels().to_vec();
        for &i in &highlight {
            pixels[i] = glam::Vec3::ZERO;
        }
        Film::from_pixels(film.width(), film.height(), pixels)
    };
    let worst = worst_block(&masked(&film), &masked(&reference), 1e-2);
    let sum = |film: &Film| highlight.iter().map(|&i| film.pixels()[i].as_dvec3()).sum::<DVec3>();
    let (ours, theirs) = (sum(&film), sum(&reference));
    let sharp = ((ours - theirs) / theirs).abs().max_element();
    let (ours, theirs) = (mean(&film), mean(&reference));
    let whole = ((ours - theirs) / theirs).abs().max_element();
    let error = rmse(&film, &reference);
    let report = format!(
        "worst 8×8 block ({}, {}) {:.2} %, the sun's reflection ({} pixels) {:.1} %, image \
         mean {ours:.4} vs {theirs:.4} ({:.2} %), RMSE {error:.4}",
        worst.1,
        worst.2,
        100.0 * worst.0,
        highlight.len(),
        100.0 * sharp,
        100.0 * whole
    );
    eprintln!("{report}");
    if worst.0 > 0.06 || whole > 0.005 || sharp > 0.15 || highlight.is_empty() {
        fail("mitsuba-envmap", &film, &reference, report);
    }
}
