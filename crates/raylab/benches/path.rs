//! The path tracer, scalar (`PathScalar`, one path at a time) against the wavefront
//! (`Path`, a tile's paths stage by stage with batched queries): one pass at a quarter
//! of the scene's size, one thread, the scenes' own depth limits, on `scenes/`'s Mitsuba box and
//! showcase and on the three Mitsuba comparison scenes of `tests/data` (the materials, the
//! instanced glTF boxes and the environment-lit spheres, at a quarter of the 256×256 they are
//! compared at).
//!
//! `cargo bench -p raylab --bench path`; it first prints the wavefront's time per sample by
//! stage (`Path::with_stage_times`, 16 passes in one group, one thread), then times
//! the sampler's draws for a tile's paths one by one and in batches.

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use std::time::{Duration, Instant};

use raylab::integrator::{Integrator, Path, PathScalar};
use raylab::sampling::Sampler;
use raylab::scene::{Instancing, LoadOptions};
use raylab::session::{CameraOptions, RenderOptions, ResolvedSettings};
use raylab::{Accumulator, Camera, SamplerKind, Scene, SceneBvh};

/// A scene file of `scenes/` (or `materials`, `gltf-boxes`, `envmap` of `tests/data`; `gltf-boxes-kept`
/// the boxes kept instanced, under a two-level BVH, where by default they are copied) with its
/// BVH, settings and its camera at a quarter of its size (128×128 for the Cornell box, 160×120
/// for the showcase, 64×64 for the comparison scenes): the same view as a full render.
fn load(name: &str) -> (Scene, SceneBvh, ResolvedSettings, Camera) {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let file = match name {
        "materials" => root.join("tests/data/mitsuba-materials/materials.toml"),
        "gltf-boxes" | "gltf-boxes-kept" => root.join("tests/data/mitsuba-gltf/boxes.toml"),
        "envmap" => root.join("tests/data/mitsuba-envmap/envmap.toml"),
        _ => root.join(format!("../../scenes/{name}.toml")),
    };
    let instancing = if name == "gltf-boxes-kept" { Instancing::Keep } else { Instancing::Auto };
    let opened = Scene::open(&file.display().to_string(), &LoadOptions { instancing })
        .expect("the scene file");
    let scene = opened.scene;
    let accel = SceneBvh::build(&scene.geometry).expect("a BVH");
    let settings = ResolvedSettings::resolve(&scene, &RenderOptions::default());
    // The Mitsuba comparison scenes are timed at 256×256 (BENCHMARKS.md).
    let (width, height) = match name {
        "materials" | "gltf-boxes" | "gltf-boxes-kept" | "envmap" => (256, 256),
        _ => scene.settings.size.expect("the scene file's size"),
    };
    let cameras = CameraOptions { size: Some((width / 4, height / 4)), ..CameraOptions::default() };
    let camera = cameras.camera(scene.camera, &scene, false, &accel).expect("a camera");
    (scene, accel, settings, camera)
}

/// The scenes timed.
const SCENES: [&str; 6] =
    ["cornell-mitsuba", "showcase", "materials", "gltf-boxes", "gltf-boxes-kept", "envmap"];

/// One pass of `integrator` over the camera's pixels, on the current thread pool.
fn pass(camera: &Camera, settings: &ResolvedSettings, integrator: &dyn Integrator) -> Accumulator {
    passes(camera, settings, integrator, 1)
}

/// `count` passes as one group (each pixel's samples side by side, as `raylab render` traces
/// them), on the current thread pool.
fn passes(
    camera: &Camera,
    settings: &ResolvedSettings,
    integrator: &dyn Integrator,
    count: u32,
) -> Accumulator {
    let mut accumulator = Accumulator::new(camera.width, camera.height).expect("an accumulator");
    accumulator.settings = settings.samples;
    accumulator.add_samples_with_progress(camera, integrator, count, &|_| {});
    accumulator
}

/// Prints nanoseconds per sample by stage: the wavefront's stages as it measures them, and the
/// rest of the pass (camera rays, filter, accumulation) as the pass's time less the
/// integrator's; then the share of vertices shaded wholly in lanes (the rest left their light
/// sample or bounce to the scalar steps: a point light, a textured emitter, an overflowing
/// offset), and how full the chunks of lanes ran (vertices per sixteen lanes shaded).
fn stage_table(_: &mut Criterion) {
    const PASSES: u32 = 16;
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().expect("a thread");
    println!(
        "ns per sample by stage, a quarter of the scene's size, {PASSES} passes in a group, one thread"
    );
    println!(
        "{:16} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>7} {:>6} {:>9}",
        "scene",
        "scalar",
        "wavefr.",
        "camera+",
        "hits",
        "surface",
        "draws",
        "shading",
        "occl.",
        "lanes",
        "fill",
        "vertices"
    );
    for name in SCENES {
        let (scene, accel, settings, camera) = load(name);
        let scalar = PathScalar::new(&scene, &accel, settings.path_settings());
        let wavefront = Path::new(&scene, &accel, settings.path_settings()).with_stage_times();
        let time = |integrator: &dyn Integrator| {
            pool.install(|| {
                let start = Instant::now();
                passes(&camera, &settings, integrator, PASSES);
                start.elapsed()
            })
        };
        pool.install(|| {
            // Warm-ups.
            pass(&camera, &settings, &scalar);
            pass(&camera, &settings, &wavefront);
        });
        let scalar_time = time(&scalar);
        let before = wavefront.stage_times().expect("measured");
        let wavefront_time = time(&wavefront);
        let after = wavefront.stage_times().expect("measured");
        let samples = f64::from(PASSES) * f64::from(camera.width * camera.height);
        let ns = |d: Duration| d.as_secs_f64() * 1e9 / samples;
        let stages = [
            after.closest_hits - before.closest_hits,
            after.surfaces - before.surfaces,
            after.draws - before.draws,
            after.shading - before.shading,
            after.occlusion - before.occlusion,
        ];
        let in_stages: Duration = stages.iter().sum();
        let vertices = (after.vertices - before.vertices) as f64;
        let lanes = (after.lanes - before.lanes) as f64 / vertices;
        let fill = vertices / (16.0 * (after.chunks - before.chunks) as f64);
        println!(
            "{:16} {:8.0} {:8.0} {:8.0} {:8.0} {:8.0} {:8.0} {:8.0} {:8.0} {:6.0}% {:5.0}% {:9.2}",
            name,
            ns(scalar_time),
            ns(wavefront_time),
            ns(wavefront_time.saturating_sub(in_stages)),
            ns(stages[0]),
            ns(stages[1]),
            ns(stages[2]),
            ns(stages[3]),
            ns(stages[4]),
            100.0 * lanes,
            100.0 * fill,
            vertices / samples,
        );
    }
}

/// The sampler's draws for 64 paths, one by one and a batch at a time
/// (`Sampler::next_1d_each`, `next_2d_each`): a path vertex's three 1D and two 2D draws.
fn draws(c: &mut Criterion) {
    let samplers: Vec<Sampler> =
        (0..64u32).map(|i| Sampler::new(SamplerKind::Sobol, 7, (i % 8, i / 8), i * 17)).collect();
    let lanes: Vec<usize> = (0..64).collect();
    let mut group = c.benchmark_group("sampler_draws_64_paths");
    group.bench_function("one_by_one", |b| {
        b.iter(|| {
            let mut samplers = samplers.clone();
            let mut sum = 0.0;
            for sampler in &mut samplers {
                sum += sampler.next_1d() + sampler.next_2d().x + sampler.next_1d();
                sum += sampler.next_2d().y + sampler.next_1d();
            }
            sum
        })
    });
    group.bench_function("batched", |b| {
        let mut numbers = vec![0.0f32; 64];
        let mut points = vec![glam::Vec2::ZERO; 64];
        b.iter(|| {
            let mut samplers = samplers.clone();
            let mut sum = 0.0;
            for round in 0..5 {
                if round % 2 == 1 {
                    Sampler::next_2d_each(&mut samplers, &lanes, &mut points);
                    sum += points.iter().map(|p| p.x).sum::<f32>();
                } else {
                    Sampler::next_1d_each(&mut samplers, &lanes, &mut numbers);
                    sum += numbers.iter().sum::<f32>();
                }
            }
            sum
        })
    });
    group.finish();
}

fn path(c: &mut Criterion) {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().expect("a thread");
    let mut group = c.benchmark_group("path_quarter_size_1spp_1_thread");
    group.sample_size(20);
    for name in SCENES {
        let (scene, accel, settings, camera) = load(name);
        let scalar = PathScalar::new(&scene, &accel, settings.path_settings());
        let wavefront = Path::new(&scene, &accel, settings.path_settings());
        let integrators: [(&str, &dyn Integrator); 2] =
            [("scalar", &scalar), ("wavefront", &wavefront)];
        for (kind, integrator) in integrators {
            group.bench_with_input(BenchmarkId::new(kind, name), &name, |b, _| {
                b.iter(|| pool.install(|| pass(&camera, &settings, integrator)))
            });
        }
    }
    group.finish();
}

criterion_group!(benches, stage_table, draws, path);
criterion_main!(benches);
