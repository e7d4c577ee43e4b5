//! The rays a path tracer really traces, and what each costs: renders a few passes of a scene
//! with the wavefront path tracer, records every batch of rays it asks the BVH for (the camera
//! rays, the later bounces' closest hits, the shadow rays), then traces them again, one by one
//! and as the batches they came in, and prints per kind the rays per sample, the share that hits,
//! the nanoseconds per ray (the best of five replays, one thread) and, for a one-level BVH, what
//! a ray visits (`Bvh::closest_hit_counted`).
//!
//! ```sh
//! cargo bench -p raylab --bench path_rays   # the repository's Cornell box, 64×64, 2 passes
//! cargo bench -p raylab --bench path_rays -- crates/raylab/tests/data/mitsuba-gltf/boxes.toml
//! cargo bench -p raylab --bench path_rays -- scenes/cornell-mitsuba.toml 128 4  # size, passes
//! ```
//!
//! `--split` (after the other arguments) also times a one-level BVH's bounces by outcome: the
//! rays that hit, the rays that miss, and as many rays that miss the root box (each bounce's
//! origin moved 100 units up, pointing up): the per-ray setup and one node.
//!
//! `--group` (after the other arguments) renders the passes as one group, each pixel's samples
//! side by side, as `raylab render` traces them (`Accumulator::add_samples_with_progress`),
//! instead of one pass at a time.
//!
//! `--isas` (after the other arguments) also times the bounces and shadow rays one by one and
//! as batches (in lanes through the tree, `bvh/traverse/tree_rays.rs`) with every instruction
//! set this CPU has.
//!
//! `--write DIR` (after the other arguments) also writes the scene's world triangles as
//! `DIR/scene.obj` and the rays as the ray-set protocol's files (`primary.rays` the camera's,
//! `diffuse.rays` the bounces, `shadow.rays` the shadow rays), so that Embree traces the very
//! same rays: `../shared/bench/embree/embree_bench DIR/scene.obj --rays DIR --out DIR/embree`.
//!
//! Replayed rays find the tree in the cache where the render's rays may not: the figures are
//! the queries' own cost, a lower bound on their share of a render.

use std::sync::Mutex;
use std::time::Instant;

use raylab::bvh::TraversalStats;
use raylab::integrator::Path;
use raylab::scene::LoadOptions;
use raylab::session::{CameraOptions, RenderOptions, ResolvedSettings};
use raylab::{Accelerator, Accumulator, Hit, Ray, Scene, SceneBvh};

/// The rays a render asks for, batch by batch, kind by kind; the answers come from the BVH.
struct Recorder<'a> {
    bvh: &'a SceneBvh,
    camera: Mutex<Vec<Vec<Ray>>>,
    bounces: Mutex<Vec<Vec<Ray>>>,
    shadows: Mutex<Vec<Vec<Ray>>>,
}

impl Accelerator for Recorder<'_> {
    fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        self.bvh.closest_hit(ray)
    }
    fn occluded(&self, ray: &Ray) -> bool {
        self.bvh.occluded(ray)
    }
    fn closest_hits(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        self.camera.lock().unwrap().push(rays.to_vec());
        self.bvh.closest_hits(rays, hits)
    }
    fn closest_hits_incoherent(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        self.bounces.lock().unwrap().push(rays.to_vec());
        self.bvh.closest_hits_incoherent(rays, hits)
    }
    fn occluded_incoherent(&self, rays: &[Ray], occluded: &mut [bool]) {
        self.shadows.lock().unwrap().push(rays.to_vec());
        self.bvh.occluded_incoherent(rays, occluded)
    }
}

/// The best of five timings of `run`, in seconds.
fn best_of_five(mut run: impl FnMut()) -> f64 {
    (0..5)
        .map(|_| {
            let start = Instant::now();
            run();
            start.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // `cargo bench` passes `--bench` to every bench target: not one of this tool's arguments.
    let mut args = std::env::args().skip(1).filter(|a| a != "--bench").peekable();
    // Without arguments: the repository's Mitsuba Cornell box, small and quick.
    let (file, size, passes) = match args.next_if(|a| !a.starts_with("--")) {
        Some(file) => {
            let size: u32 =
                args.next_if(|a| !a.starts_with("--")).map_or(Ok(256), |s| s.parse())?;
            let passes: u32 =
                args.next_if(|a| !a.starts_with("--")).map_or(Ok(4), |s| s.parse())?;
            (file, size, passes)
        }
        None => {
            let file = concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes/cornell-mitsuba.toml");
            println!(
                "(no scene given: {file} at 64×64, 2 passes; usage: path_rays [SCENE.toml [SIZE [PASSES]]] [--write DIR] [--split] [--isas] [--group])"
            );
            (file.to_string(), 64, 2)
        }
    };
    let (mut write, mut split, mut isas, mut group) = (None, false, false, false);
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--write" => write = Some(std::path::PathBuf::from(args.next().ok_or("--write DIR")?)),
            "--split" => split = true,
            "--isas" => isas = true,
            "--group" => group = true,
            other => return Err(format!("unknown argument {other}").into()),
        }
    }
    let scene = Scene::open(&file, &LoadOptions::default())?.scene;
    let bvh = SceneBvh::build(&scene.geometry)?;
    let settings = ResolvedSettings::resolve(&scene, &RenderOptions::default());
    let cameras = CameraOptions { size: Some((size, size)), ..CameraOptions::default() };
    let camera = cameras.camera(scene.camera, &scene, false, &bvh)?;
    let recorder = Recorder {
        bvh: &bvh,
        camera: Mutex::default(),
        bounces: Mutex::default(),
        shadows: Mutex::default(),
    };
    let wavefront = Path::new(&scene, &recorder, settings.path_settings());
    let mut accumulator = Accumulator::new(camera.width, camera.height)?;
    accumulator.settings = settings.samples;
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    pool.install(|| match group {
        true => accumulator.add_samples_with_progress(&camera, &wavefront, passes, &|_| {}),
        false => (0..passes).for_each(|_| accumulator.add_sample(&camera, &wavefront)),
    });
    let samples = f64::from(passes) * f64::from(camera.width * camera.height);
    println!("{file}: {}×{}, {passes} passes, one thread", camera.width, camera.height);
    println!(
        "{:8} {:>11} {:>6} {:>11} {:>11} {:>7} {:>7}",
        "rays", "per sample", "hit", "single ns", "batched ns", "nodes", "leaves"
    );
    let kinds = [
        ("camera", recorder.camera.into_inner()?, false),
        ("bounces", recorder.bounces.into_inner()?, false),
        ("shadows", recorder.shadows.into_inner()?, true),
    ];
    if let Some(dir) = &write {
        std::fs::create_dir_all(dir)?;
        let mut obj = String::new();
        for [a, b, c] in scene.geometry.vertices() {
            for v in [a, b, c] {
                obj += &format!("v {:e} {:e} {:e}\n", v.x, v.y, v.z);
            }
        }
        for i in 0..scene.geometry.len() {
            obj += &format!("f {} {} {}\n", 3 * i + 1, 3 * i + 2, 3 * i + 3);
        }
        std::fs::write(dir.join("scene.obj"), obj)?;
        for ((_, batches, _), file) in kinds.iter().zip(["primary", "diffuse", "shadow"]) {
            let rays: Vec<Ray> = batches.iter().flatten().copied().collect();
            raylab::ray_sets::write_rays(&dir.join(format!("{file}.rays")), &rays)?;
        }
    }
    for (name, batches, shadow) in &kinds {
        let count: usize = batches.iter().map(Vec::len).sum();
        if count == 0 {
            continue;
        }
        let query = |ray: &Ray| {
            if *shadow { bvh.occluded(ray) } else { bvh.closest_hit(ray).is_some() }
        };
        let hits = batches.iter().flatten().filter(|ray| query(ray)).count();
        let single = best_of_five(|| {
            for ray in batches.iter().flatten() {
                std::hint::black_box(query(std::hint::black_box(ray)));
            }
        });
        // As the render asked: packets for the camera's tiles, the batch entry points after.
        let batched = best_of_five(|| {
            for batch in batches {
                if *shadow {
                    let mut occluded = vec![false; batch.len()];
                    bvh.occluded_incoherent(batch, &mut occluded);
                    std::hint::black_box(&occluded);
                } else {
                    let mut hits = vec![None; batch.len()];
                    match *name {
                        "camera" => bvh.closest_hits(batch, &mut hits),
                        _ => bvh.closest_hits_incoherent(batch, &mut hits),
                    }
                    std::hint::black_box(&hits);
                }
            }
        });
        let (nodes, leaves) = match &bvh {
            SceneBvh::Flat(tree) => {
                let mut stats = TraversalStats::default();
                for ray in batches.iter().flatten() {
                    match shadow {
                        true => tree.occluded_counted(ray, &mut stats),
                        false => tree.closest_hit_counted(ray, &mut stats).is_some(),
                    };
                }
                let [nodes, leaves, _] = stats.per_ray();
                (format!("{nodes:.2}"), format!("{leaves:.2}"))
            }
            SceneBvh::Instanced(_) => ("-".into(), "-".into()),
        };
        println!(
            "{name:8} {:>11.3} {:>5.1}% {:>11.1} {:>11.1} {nodes:>7} {leaves:>7}",
            count as f64 / samples,
            100.0 * hits as f64 / count as f64,
            single * 1e9 / count as f64,
            batched * 1e9 / count as f64,
        );
    }
    if isas {
        incoherent_by_isa(&scene.geometry.vertices(), &kinds[1].1, &kinds[2].1);
    }
    if split && let SceneBvh::Flat(tree) = &bvh {
        bounces_by_outcome(tree, &kinds[1].1);
    }
    camera_orders(&bvh, &camera);
    Ok(())
}

/// The bounces and shadow rays timed one by one and as the batches they came in (the tree's
/// incoherent queries: in lanes where the set has them), with each instruction set this CPU
/// has, on a one-level tree without a flat list.
fn incoherent_by_isa(triangles: &[[glam::Vec3; 3]], bounces: &[Vec<Ray>], shadows: &[Vec<Ray>]) {
    use raylab::bvh::{BuildSettings, Isa};
    let settings = BuildSettings { flat_limit: 0, ..BuildSettings::for_triangles(triangles.len()) };
    for isa in Isa::ALL {
        let Some(tree) = raylab::Bvh::build(triangles, &settings).with_isa(isa) else { continue };
        for (name, batches) in [("bounces", bounces), ("shadow rays", shadows)] {
            let count: usize = batches.iter().map(Vec::len).sum();
            let shadow = name == "shadow rays";
            let single = best_of_five(|| {
                for ray in batches.iter().flatten() {
                    match shadow {
                        true => std::hint::black_box(tree.occluded(ray)),
                        false => std::hint::black_box(tree.closest_hit(ray).is_some()),
                    };
                }
            });
            let batched = best_of_five(|| {
                for batch in batches {
                    if shadow {
                        let mut occluded = vec![false; batch.len()];
                        tree.occluded_incoherent(batch, &mut occluded);
                        std::hint::black_box(&occluded);
                    } else {
                        let mut hits = vec![None; batch.len()];
                        tree.closest_hits_incoherent(batch, &mut hits);
                        std::hint::black_box(&hits);
                    }
                }
            });
            println!(
                "{:8} {name:12} one by one {:6.1} ns, batched {:6.1} ns",
                isa.name(),
                single * 1e9 / count as f64,
                batched * 1e9 / count as f64
            );
        }
    }
}

/// The bounces of `batches` timed apart by outcome (see the module documentation): the best of
/// five replays, one thread, with what each kind of ray visits.
fn bounces_by_outcome(tree: &raylab::Bvh, batches: &[Vec<Ray>]) {
    let all: Vec<Ray> = batches.iter().flatten().copied().collect();
    let (hit, miss): (Vec<Ray>, Vec<Ray>) =
        all.iter().partition(|ray| tree.closest_hit(ray).is_some());
    let up = glam::Vec3::Y;
    let away: Vec<Ray> = all.iter().map(|ray| Ray::new(ray.origin + up * 100.0, up)).collect();
    for (name, rays) in
        [("bounces that hit", &hit), ("bounces that miss", &miss), ("root missed", &away)]
    {
        if rays.is_empty() {
            continue;
        }
        let time = best_of_five(|| {
            for ray in rays.iter() {
                std::hint::black_box(tree.closest_hit(std::hint::black_box(ray)));
            }
        });
        let mut stats = TraversalStats::default();
        for ray in rays.iter() {
            tree.closest_hit_counted(ray, &mut stats);
        }
        let [nodes, leaves, _] = stats.per_ray();
        println!(
            "{name:18} {:>8} rays {:>7.1} ns  nodes {nodes:.2}  leaves {leaves:.2}",
            rays.len(),
            time * 1e9 / rays.len() as f64
        );
    }
}

/// Camera rays traced as packets in two orders: 64 pixels, one sample each (the wavefront's
/// tiles, 8×8 pixels), and 4 pixels with 16 samples each (2×2 pixels; Mitsuba's lanes are the
/// samples of one pixel). The same kind of rays, 16 samples of every pixel either way.
fn camera_orders(bvh: &SceneBvh, camera: &raylab::Camera) {
    let rays = camera.rays();
    let ray = |x: u32, y: u32, s: u32| {
        let mut sampler = raylab::sampling::Sampler::new(raylab::SamplerKind::Sobol, 0, (x, y), s);
        let u = sampler.pixel_2d();
        rays.ray(x as f32 + u.x, y as f32 + u.y)
    };
    let (w, h) = (camera.width - camera.width % 8, camera.height - camera.height % 8);
    let mut pixel_major = Vec::new();
    let mut sample_major = Vec::new();
    for s in 0..16 {
        for (bx, by) in (0..h / 8).flat_map(|by| (0..w / 8).map(move |bx| (bx, by))) {
            pixel_major.push((0..64).map(|k| ray(bx * 8 + k % 8, by * 8 + k / 8, s)).collect());
        }
    }
    for (bx, by) in (0..h / 2).flat_map(|by| (0..w / 2).map(move |bx| (bx, by))) {
        sample_major
            .push((0..64).map(|k| ray(bx * 2 + k / 16 % 2, by * 2 + k / 32, k % 16)).collect());
    }
    for (name, batches) in
        [("8×8 pixels × 1 sample", &pixel_major), ("2×2 pixels × 16 samples", &sample_major)]
    {
        let batches: &Vec<Vec<Ray>> = batches;
        let count: usize = batches.iter().map(Vec::len).sum();
        let time = best_of_five(|| {
            for batch in batches {
                let mut hits = vec![None; batch.len()];
                bvh.closest_hits(batch, &mut hits);
                std::hint::black_box(&hits);
            }
        });
        println!("camera packets of {name}: {:.1} ns per ray", time * 1e9 / count as f64);
    }
}
