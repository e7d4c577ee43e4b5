//! The wavefront path tracer ([`Path`]) gives the scalar path tracer's samples, bit for
//! bit: every scene in `scenes/`, the lab's box, models (OBJ with textures, glTF), the materials
//! scene of the Mitsuba comparison, a terrain (noise textures read at the point), the glTF boxes
//! kept instanced (placed triangles), a normal-mapped wall and a scene with alpha-masked holes,
//! at several depth limits. Accumulated sums are compared, so every pixel's every sample must
//! agree; the wavefront traces tiles of 128×8 camera rays together (`radiance_each`), the scalar
//! path one ray at a time.

mod common;

use raylab::integrator::{Integrator, Path, PathScalar as PathTracer, PathSettings};
use raylab::scene::{Instancing, LoadOptions};
use raylab::session::CameraOptions;
use raylab::{
    Accumulator, Camera, Film, SampleSettings, SamplerKind, Scene, SceneBvh, TriangleSampling,
};

const SIZE: (u32, u32) = (32, 24);

/// The scenes: every `scenes/*.toml`, the built-in box, three model files, and the Mitsuba
/// comparisons' materials scene (smooth spheres of every BSDF kind, one anisotropic) and
/// environment-lit scene (an HDR sky with a sun, turned, and a spot light).
fn scene_names() -> Vec<String> {
    common::scene_names(&[
        "bunny_lowres.obj",
        "spider/spider.obj",
        "BoxTextured/BoxTextured.gltf",
        "../mitsuba-materials/materials.toml",
        "../mitsuba-envmap/envmap.toml",
    ])
}

fn bits(film: &Film) -> Vec<[u32; 3]> {
    film.pixels().iter().map(|p| p.to_array().map(f32::to_bits)).collect()
}

/// The sums of `passes` passes of `integrator`, with `sampler` (`None`: the integrator's) in a
/// render of 16 samples (the count `multijitter` lays out).
fn sums(
    camera: &Camera,
    integrator: &dyn Integrator,
    passes: u32,
    sampler: Option<SamplerKind>,
) -> Film {
    let mut accumulator = Accumulator::new(camera.width, camera.height).unwrap();
    accumulator.settings = SampleSettings { sampler, count: 16, ..SampleSettings::default() };
    for _ in 0..passes {
        accumulator.add_sample(camera, integrator);
    }
    accumulator.sums().clone()
}

/// Checks the wavefront against the scalar path on `scene` seen by `camera`.
fn check(name: &str, scene: &Scene, camera: &Camera) {
    let accel = SceneBvh::build(&scene.geometry).unwrap();
    // The default sampler at every depth, `multijitter` (its draws in lanes) at two; triangle
    // lights sampled by solid angle (which the lanes leave to the scalar steps) once.
    let (area, solid_angle) = (TriangleSampling::Area, TriangleSampling::SolidAngle);
    let runs =
        [Some(1), Some(2), Some(4), None].map(|depth| (depth, None, area)).into_iter().chain([
            (Some(2), Some(SamplerKind::MultiJitter), area),
            (None, Some(SamplerKind::MultiJitter), area),
            (None, None, solid_angle),
        ]);
    for (max_depth, sampler, light_sampling) in runs {
        let settings = PathSettings { max_depth, light_sampling, ..PathSettings::default() };
        let scalar = PathTracer::new(scene, &accel, settings);
        let wavefront = Path::new(scene, &accel, settings);
        let (expected, got) =
            (sums(camera, &scalar, 2, sampler), sums(camera, &wavefront, 2, sampler));
        assert!(
            expected.pixels().iter().any(|p| p.max_element() > 0.0) || max_depth == Some(1),
            "{name}: a black picture proves nothing"
        );
        let differing = bits(&expected).iter().zip(bits(&got)).filter(|(a, b)| *a != b).count();
        assert_eq!(
            differing, 0,
            "{name}, max depth {max_depth:?}, {sampler:?}, {light_sampling:?}: pixels that differ"
        );
    }
}

#[test]
fn the_wavefront_gives_the_scalar_paths_samples_on_every_scene() {
    let kept = LoadOptions { instancing: Instancing::Keep };
    let gltf_boxes = common::repository().join("crates/raylab/tests/data/mitsuba-gltf/boxes.toml");
    let scenes = scene_names()
        .into_iter()
        .map(|name| (name, LoadOptions::default()))
        .chain([("terrain:32".to_string(), LoadOptions::default())])
        .chain([(gltf_boxes.display().to_string(), kept)]);
    for (name, options) in scenes {
        let opened = Scene::open(&name, &options).unwrap_or_else(|e| panic!("{name}: {e}"));
        if options.instancing == Instancing::Keep {
            assert!(opened.scene.geometry.is_instanced(), "{name}: placed triangles");
        }
        let scene = opened.scene;
        let accel = SceneBvh::build(&scene.geometry).unwrap();
        let cameras = CameraOptions { size: Some(SIZE), ..CameraOptions::default() };
        let camera = cameras.camera(scene.camera, &scene, opened.is_model, &accel).unwrap();
        check(&name, &scene, &camera);
    }
}

/// Normal maps take the general steps (the shading normal needs the interaction's tangent).
#[test]
fn the_wavefront_shades_a_normal_map_as_the_scalar_path_does() {
    let scene = common::normal_mapped_wall();
    assert!(scene.materials[0].textures.normal.is_some());
    check("normal-mapped wall", &scene, &Camera::lab(SIZE.0, SIZE.1));
}

#[test]
fn the_wavefront_passes_alpha_masked_holes_as_the_scalar_path_does() {
    let scene = common::cut_out_scene();
    assert!(scene.has_cut_outs());
    check("cut-out", &scene, &Camera::lab(SIZE.0, SIZE.1));
}
