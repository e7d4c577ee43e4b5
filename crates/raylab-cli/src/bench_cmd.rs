//! `raylab bench`: the ray-set benchmark (`docs/benchmarking.md`), side by side with Embree.
//!
//! `--generate DIR` writes the protocol's `primary.rays`, `shadow.rays` and `diffuse.rays` for a
//! mesh. `--rays DIR` builds the BVH, traces the three sets on 1 and N threads the way the Embree
//! reference program does (threads take chunks of 4096 rays from an atomic counter; one untimed
//! warm-up pass, then the median of `--reps` passes), prints a table, and, when DIR holds
//! reference answers (`*.hits`, `shadow.occluded`, as Embree's program writes them), how many of
//! raylab's answers agree with them.

use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::Args;
use raylab::bvh::{BuildSettings, Bvh, Collapse, Isa};
use raylab::ray_sets::{self, Agreement, Frame, HitRecord};
use raylab::{Accelerator, Ray};

use crate::stats::median;
use crate::system;

/// The most threads `--threads` accepts.
const MAX_THREADS: usize = 1024;
/// Rays per work item, as in the Embree reference program.
const CHUNK: usize = 4096;

#[derive(Args, Debug)]
pub struct BenchArgs {
    /// The mesh (.obj, .ply, optionally .gz).
    mesh: PathBuf,

    /// Write the protocol's ray sets for MESH into DIR (created if needed).
    #[arg(long, value_name = "DIR", conflicts_with = "rays", required_unless_present = "rays")]
    generate: Option<PathBuf>,

    /// Trace the ray sets in DIR (`primary.rays`, `shadow.rays`, `diffuse.rays`, or `.gz`).
    #[arg(long, value_name = "DIR")]
    rays: Option<PathBuf>,

    /// Image size of the primary rays: written by --generate; with --rays, how the primary rays
    /// are cut into 8×8 tiles for the packet figure (a square image needs no size).
    #[arg(long, value_name = "WxH", default_value = "512x512", value_parser = crate::args::size)]
    size: crate::args::Size,

    /// Focal length as a multiple of the image width, for --generate (the protocol's f = W).
    #[arg(long, value_name = "F", default_value = "1", value_parser = crate::args::positive_f32)]
    focal: f32,

    /// The second thread count to measure, besides 1 [default: one per core].
    #[arg(long, value_name = "N")]
    threads: Option<usize>,

    /// Timed repetitions per measurement; the median is reported.
    #[arg(long, value_name = "N", default_value = "7")]
    reps: usize,

    /// BVH build preset: fast, medium or high, or auto: what `raylab render` builds (medium,
    /// with leaves of up to 4 triangles below 4096 triangles).
    #[arg(long, value_name = "PRESET", default_value = "auto")]
    build: String,

    /// How the binary tree becomes the 8-wide one: greedy (open the largest child), optimal
    /// (least SAH cost, over binary leaves of up to 4) or optimal:N (over binary leaves of up to
    /// N) [default: the build preset's; high is optimal].
    #[arg(long, value_name = "HOW")]
    collapse: Option<String>,

    /// Scenes of at most this many triangles answer single rays by testing every triangle, without
    /// the tree (0: always the tree) [default: the build preset's, 48].
    #[arg(long, value_name = "N")]
    flat_limit: Option<usize>,

    /// Node-kernel instruction set: scalar, sse2, avx2 or avx512 [default: the best this CPU has].
    #[arg(long, value_name = "ISA")]
    isa: Option<String>,

    /// Print Embree's figures beside raylab's, from the `summary.json` of an Embree reference run
    /// (`embree_bench MESH --rays DIR`, on the same rays); give it twice for the default and the
    /// `--robust` run.
    #[arg(long, value_name = "SUMMARY")]
    embree: Vec<PathBuf>,

    /// Also count, per ray, the tree's nodes, leaves and leaf records visited (the cost of a
    /// ray in the tree's own units; the tree is walked even where a small scene's flat list
    /// answers single rays).
    #[arg(long)]
    counts: bool,

    /// Also write the figures as JSON to FILE.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,

    /// Also write raylab's answers (`primary.hits`, `shadow.hits`, `shadow.occluded`,
    /// `diffuse.hits`) into OUT (created if needed).
    #[arg(long, value_name = "OUT")]
    write_hits: Option<PathBuf>,
}

pub fn run(args: &BenchArgs) -> Result<()> {
    // `None` for auto, chosen by the mesh's size.
    let preset = match args.build.as_str() {
        "auto" => None,
        name => Some(
            BuildSettings::PRESETS
                .iter()
                .find(|(preset, _)| *preset == name)
                .map(|(_, s)| *s)
                .with_context(|| {
                    format!("unknown build preset '{name}': use auto, fast, medium or high")
                })?,
        ),
    };
    let threads = args.threads.unwrap_or_else(system::cores);
    if threads == 0 || threads > MAX_THREADS {
        bail!("--threads must be between 1 and {MAX_THREADS}, not {threads}");
    }
    if args.reps == 0 || args.reps > 1000 {
        bail!("--reps must be between 1 and 1000, not {}", args.reps);
    }
    let loaded = raylab::scene::load_mesh(&args.mesh)?;
    for warning in &loaded.warnings {
        eprintln!("raylab: warning: {warning}");
    }
    // Every instance placed: the ray sets and Embree's columns are over the flattened model.
    let mesh = loaded.flattened();
    let triangles: Vec<_> = mesh.triangle_vertices().collect();
    let embree: Vec<_> = args
        .embree
        .iter()
        .map(|path| crate::embree_columns::load(path, triangles.len()))
        .collect::<Result<_>>()?;
    let mut settings = match preset {
        Some(settings) => settings,
        None => BuildSettings::for_triangles(triangles.len()),
    };
    if let Some(limit) = args.flat_limit {
        settings.flat_limit = limit;
    }
    if let Some(collapse) = &args.collapse {
        // Binary leaves no larger than the wide tree's.
        let largest = settings.max_leaf_size;
        let optimal = |binary_leaf_size: usize| Collapse::Optimal {
            binary_leaf_size: binary_leaf_size.min(largest),
        };
        let size = |n: &str| n.parse::<usize>().ok().filter(|n| (1..=largest).contains(n));
        settings.collapse = match collapse.split_once(':') {
            None if collapse == "greedy" => Collapse::Greedy,
            None if collapse == "optimal" => optimal(4),
            Some(("optimal", n)) if size(n).is_some() => optimal(size(n).expect("checked")),
            _ => bail!(
                "unknown --collapse '{collapse}': use greedy, optimal or optimal:N, N from 1 to \
                 {largest} (the preset's largest leaf)"
            ),
        };
    }

    if let Some(dir) = &args.generate {
        return generate(args, &mesh, &triangles, dir, &settings);
    }
    let dir = args.rays.as_ref().expect("clap requires --generate or --rays");
    let sets = [("primary", false), ("shadow", true), ("diffuse", false)].map(
        |(name, occlusion)| -> Result<(&str, bool, Vec<Ray>)> {
            Ok((name, occlusion, ray_sets::read_rays(&find_file(dir, &format!("{name}.rays"))?)?))
        },
    );
    let sets: Vec<(&str, bool, Vec<Ray>)> = sets.into_iter().collect::<Result<_>>()?;

    // Build: the median over `reps` builds on 1 thread and on N threads.
    let build_ms = |threads: usize| -> Result<(f64, Bvh)> {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
        let mut times = Vec::new();
        let mut bvh = None;
        for _ in 0..args.reps.max(3) {
            let start = Instant::now();
            let built = pool
                .install(|| Bvh::try_build(&triangles, &settings))
                .with_context(|| args.mesh.display().to_string())?;
            times.push(start.elapsed().as_secs_f64() * 1e3);
            bvh = Some(built);
        }
        Ok((median(&mut times), bvh.expect("at least one build")))
    };
    let (build_1, _) = build_ms(1)?;
    let (build_n, bvh) = build_ms(threads)?;
    let bvh = match &args.isa {
        None => bvh,
        Some(name) => {
            let isa = Isa::supported_by_name(name).with_context(|| format!("--isa {name}"))?;
            bvh.with_isa(isa).expect("a set this CPU supports")
        }
    };
    let stats = bvh.stats();

    println!(
        "{}: {} triangles ({} in the BVH), BVH {} preset ({} bins, leaves of up to {}, {} \
         collapse), {} kernels",
        args.mesh.display(),
        stats.triangles,
        stats.indexed_triangles,
        args.build,
        settings.bins,
        settings.max_leaf_size,
        match settings.collapse {
            Collapse::Greedy => "greedy".to_string(),
            Collapse::Optimal { binary_leaf_size } =>
                format!("optimal over binary leaves of up to {binary_leaf_size}"),
        },
        bvh.isa().name()
    );
    println!(
        "BVH build: {build_1:.1} ms on 1 thread, {build_n:.1} ms on {threads}; {} bytes ({:.1} per triangle)",
        stats.bytes(),
        stats.bytes() as f64 / stats.triangles.max(1) as f64
    );
    // The thread counts measured: 1, and N if it differs.
    let thread_counts: Vec<usize> = if threads == 1 { vec![1] } else { vec![1, threads] };
    let mut header = format!("{:<9} {:<9} {:>9}", "set", "query", "rays");
    for &n in &thread_counts {
        header += &format!(
            " {:>13}",
            if n == 1 { "1 thread".to_string() } else { format!("{n} threads") }
        );
    }
    println!("{header}");
    let mut results = Vec::new();
    for (name, occlusion, rays) in &sets {
        let query = if *occlusion { "occluded" } else { "closest" };
        let mut per_threads = Vec::new();
        for &n in &thread_counts {
            let seconds = if *occlusion {
                time_median(args.reps, || trace_occluded(&bvh, rays, n))
            } else {
                time_median(args.reps, || trace_closest(&bvh, rays, n))
            };
            per_threads.push((n, rays.len() as f64 / seconds / 1e6));
        }
        let mut line = format!("{:<9} {:<9} {:>9}", name, query, rays.len());
        for (_, mrays) in &per_threads {
            line += &format!(" {mrays:>8.2} Mr/s");
        }
        println!("{line}");
        results.push(SetResult { set: name.to_string(), query, mrays_per_s: per_threads });
    }

    // The coherent path: primary rays in 8×8 tiles, traced as packets.
    let primary = &sets[0].2;
    let width = if args.size.width as usize * args.size.height as usize == primary.len() {
        args.size.width as usize
    } else {
        primary.len().isqrt()
    };
    let tiles = tile_order(primary.len(), width);
    let tiled: Vec<Ray> = tiles.iter().map(|&i| primary[i]).collect();
    let mut per_threads = Vec::new();
    for &n in &thread_counts {
        let seconds = time_median(args.reps, || trace_packets(&bvh, &tiled, n));
        per_threads.push((n, tiled.len() as f64 / seconds / 1e6));
    }
    let mut line = format!("{:<9} {:<9} {:>9}", "primary", "packet", tiled.len());
    for (_, mrays) in &per_threads {
        line += &format!(" {mrays:>8.2} Mr/s");
    }
    println!("{line}");
    results.push(SetResult {
        set: "primary".to_string(),
        query: "packet",
        mrays_per_s: per_threads,
    });

    // The library's batch engine (`raylab::bvh::Batch`): each set as one batch, on a pool of
    // each thread count, in the tree's order where the engine's rule says it pays.
    let mut batch_answers = Vec::new();
    for (name, occlusion, rays) in &sets {
        let mut per_threads = Vec::new();
        for &n in &thread_counts {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(n).build()?;
            let seconds =
                time_median(args.reps, || pool.install(|| batch_trace(&bvh, rays, *occlusion)));
            per_threads.push((n, rays.len() as f64 / seconds / 1e6));
        }
        let query = if *occlusion { "batch-occ" } else { "batch" };
        let mut line = format!("{:<9} {:<9} {:>9}", name, query, rays.len());
        for (_, mrays) in &per_threads {
            line += &format!(" {mrays:>8.2} Mr/s");
        }
        println!("{line}");
        results.push(SetResult { set: name.to_string(), query, mrays_per_s: per_threads });
        batch_answers.push(batch_trace(&bvh, rays, *occlusion));
    }

    if args.counts {
        print_counts(&bvh, &sets, threads);
    }

    if !embree.is_empty() {
        let rays = [sets[0].2.len(), sets[1].2.len(), sets[2].2.len(), tiled.len()];
        let measured: Vec<_> = results
            .iter()
            .zip(rays)
            .map(|(r, rays)| crate::embree_columns::Measured {
                set: &r.set,
                query: r.query,
                rays,
                mrays_per_s: &r.mrays_per_s,
            })
            .collect();
        print!("{}", crate::embree_columns::table(&embree, &measured));
    }

    // Answers: compare with reference files in DIR where present, and write them if asked.
    let primary_hits: Vec<HitRecord> = trace_closest(&bvh, &sets[0].2, threads);
    let mut packet_hits = vec![HitRecord::default(); primary.len()];
    for (&i, hit) in tiles.iter().zip(trace_packets(&bvh, &tiled, threads)) {
        packet_hits[i] = hit;
    }
    let differ = packet_hits.iter().zip(&primary_hits).filter(|(a, b)| a != b).count();
    println!(
        "primary packets: {} of {} answers identical to single rays",
        primary.len() - differ,
        primary.len()
    );
    let shadow_occluded = trace_occluded(&bvh, &sets[1].2, threads);
    let shadow_hits = trace_closest(&bvh, &sets[1].2, threads);
    let diffuse_hits = trace_closest(&bvh, &sets[2].2, threads);
    let single = [
        BatchAnswers::Closest(primary_hits.clone()),
        BatchAnswers::Occluded(shadow_occluded.clone()),
        BatchAnswers::Closest(diffuse_hits.clone()),
    ];
    let batch_rays: usize = sets.iter().map(|s| s.2.len()).sum();
    let batch_same: usize = batch_answers.iter().zip(&single).map(|(a, b)| a.same_as(b)).sum();
    println!("batches: {batch_same} of {batch_rays} answers identical to single rays");
    for (file, ours) in [
        ("primary.hits", &primary_hits),
        ("shadow.hits", &shadow_hits),
        ("diffuse.hits", &diffuse_hits),
    ] {
        if let Ok(path) = find_file(dir, file) {
            let reference = ray_sets::read_hits(&path)?;
            if reference.len() != ours.len() {
                println!(
                    "{file}: {} records for {} rays, not comparable",
                    reference.len(),
                    ours.len()
                );
            } else {
                println!("{file}: {}", Agreement::of(&reference, ours));
            }
        }
    }
    if let Ok(path) = find_file(dir, "shadow.occluded") {
        let reference = ray_sets::read_occluded(&path)?;
        let same = reference.iter().zip(&shadow_occluded).filter(|(a, b)| a == b).count();
        println!(
            "shadow.occluded: {same} of {} agree ({} differ)",
            reference.len(),
            reference.len().max(shadow_occluded.len()) - same
        );
    }
    if let Some(out) = &args.write_hits {
        std::fs::create_dir_all(out)
            .with_context(|| format!("cannot create '{}'", out.display()))?;
        ray_sets::write_hits(&out.join("primary.hits"), &primary_hits)?;
        ray_sets::write_hits(&out.join("shadow.hits"), &shadow_hits)?;
        ray_sets::write_occluded(&out.join("shadow.occluded"), &shadow_occluded)?;
        ray_sets::write_hits(&out.join("diffuse.hits"), &diffuse_hits)?;
        println!("answers written to {}", out.display());
    }

    if let Some(path) = &args.json {
        let json = to_json(stats.triangles, build_1, build_n, threads, stats.bytes(), &results);
        std::fs::write(path, json).with_context(|| format!("cannot write '{}'", path.display()))?;
    }
    Ok(())
}

/// `DIR/NAME`, or `DIR/NAME.gz`.
fn find_file(dir: &Path, name: &str) -> Result<PathBuf> {
    let plain = dir.join(name);
    if plain.is_file() {
        return Ok(plain);
    }
    let gz = dir.join(format!("{name}.gz"));
    if gz.is_file() {
        return Ok(gz);
    }
    bail!("'{}': no such file (nor .gz)", plain.display())
}

fn generate(
    args: &BenchArgs,
    mesh: &raylab::Mesh,
    triangles: &[[glam::Vec3; 3]],
    dir: &Path,
    settings: &BuildSettings,
) -> Result<()> {
    let frame = Frame::of(mesh).context("the mesh has no triangles")?;
    // Three sets of 32-byte rays and the primary hits, at most.
    let rays = args.size.width as u64 * args.size.height as u64;
    let needed = rays.saturating_mul(3 * 32 + 8);
    if rays > u32::MAX as u64 || raylab::memory::available_bytes().is_some_and(|a| needed > a) {
        bail!(
            "--size {}x{} makes {rays} rays per set, {} of memory: too many",
            args.size.width,
            args.size.height,
            raylab::film::format_bytes(needed)
        );
    }
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create '{}'", dir.display()))?;
    let bvh =
        Bvh::try_build(triangles, settings).with_context(|| args.mesh.display().to_string())?;
    let focal = args.focal as f64 * args.size.width as f64;
    let primary = ray_sets::primary_rays(&frame, args.size.width, args.size.height, focal);
    let hits = trace_closest(&bvh, &primary, system::cores());
    let shadow = ray_sets::shadow_rays(&frame, &primary, &hits);
    let diffuse = ray_sets::diffuse_rays(&frame, mesh, &primary, &hits);
    for (name, rays) in [("primary", &primary), ("shadow", &shadow), ("diffuse", &diffuse)] {
        ray_sets::write_rays(&dir.join(format!("{name}.rays")), rays)?;
    }
    println!(
        "{}: {} primary, {} shadow and {} diffuse rays written to {}",
        args.mesh.display(),
        primary.len(),
        shadow.len(),
        diffuse.len(),
        dir.display()
    );
    Ok(())
}

/// One set's figures: its name, its query, and Mrays/s per thread count.
struct SetResult {
    set: String,
    query: &'static str,
    mrays_per_s: Vec<(usize, f64)>,
}

/// Runs `f` over `rays` on `threads` threads that take chunks of [`CHUNK`] rays from a shared
/// counter; `f` writes each chunk's answers into its slots.
/// Prints the mean nodes, leaves and leaf records each set's rays visit (`--counts`), counted on
/// `threads` threads.
fn print_counts(bvh: &Bvh, sets: &[(&str, bool, Vec<Ray>)], threads: usize) {
    use raylab::bvh::TraversalStats;
    use rayon::prelude::*;
    println!(
        "per ray, in the tree: wide nodes tested, leaves entered, records in them (up to 8 triangles each)"
    );
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build();
    for (name, occlusion, rays) in sets {
        let count = || {
            rays.par_chunks(4096)
                .map(|chunk| {
                    let mut stats = TraversalStats::default();
                    for ray in chunk {
                        if *occlusion {
                            bvh.occluded_counted(ray, &mut stats);
                        } else {
                            bvh.closest_hit_counted(ray, &mut stats);
                        }
                    }
                    stats
                })
                .reduce(TraversalStats::default, |a, b| a + b)
        };
        let stats = match &pool {
            Ok(pool) => pool.install(count),
            Err(_) => count(),
        };
        let [nodes, leaves, records] = stats.per_ray();
        let query = if *occlusion { "occluded" } else { "closest" };
        println!(
            "{name:<9} {query:<9} {nodes:>7.2} nodes {leaves:>6.2} leaves {records:>6.2} records"
        );
    }
}

fn trace<T: Copy + Default + Send>(
    rays: &[Ray],
    threads: usize,
    f: impl Fn(&[Ray], &mut [T]) + Sync,
) -> Vec<T> {
    let mut out = vec![T::default(); rays.len()];
    let chunks: Vec<Mutex<&mut [T]>> = out.chunks_mut(CHUNK).map(Mutex::new).collect();
    let next = AtomicUsize::new(0);
    let work = || {
        loop {
            let k = next.fetch_add(1, Ordering::Relaxed);
            let Some(chunk) = chunks.get(k) else { break };
            let mut chunk = chunk.lock().expect("no thread panics while holding a chunk");
            let len = chunk.len();
            f(&rays[k * CHUNK..k * CHUNK + len], &mut chunk);
        }
    };
    std::thread::scope(|scope| {
        for _ in 1..threads {
            scope.spawn(work);
        }
        work();
    });
    drop(chunks);
    out
}

fn trace_closest(bvh: &Bvh, rays: &[Ray], threads: usize) -> Vec<HitRecord> {
    trace(rays, threads, |rays, out| {
        for (slot, ray) in out.iter_mut().zip(rays) {
            *slot = HitRecord::from_hit(bvh.closest_hit(ray));
        }
    })
}

/// Closest hits through [`Accelerator::closest_hits`], a chunk at a time.
fn trace_packets(bvh: &Bvh, rays: &[Ray], threads: usize) -> Vec<HitRecord> {
    trace(rays, threads, |rays, out| {
        let mut hits = vec![None; rays.len()];
        bvh.closest_hits(rays, &mut hits);
        for (slot, hit) in out.iter_mut().zip(hits) {
            *slot = HitRecord::from_hit(hit);
        }
    })
}

/// The order that visits the pixels of an image `width` wide (row-major, `count` of them) in 8×8
/// tiles, tile rows first; the file's order if `count` is not a multiple of `width`.
fn tile_order(count: usize, width: usize) -> Vec<usize> {
    if width == 0 || !count.is_multiple_of(width) {
        return (0..count).collect();
    }
    let height = count / width;
    let mut order = Vec::with_capacity(count);
    for tile_y in (0..height).step_by(8) {
        for tile_x in (0..width).step_by(8) {
            for y in tile_y..(tile_y + 8).min(height) {
                for x in tile_x..(tile_x + 8).min(width) {
                    order.push(y * width + x);
                }
            }
        }
    }
    order
}

fn trace_occluded(bvh: &Bvh, rays: &[Ray], threads: usize) -> Vec<bool> {
    trace(rays, threads, |rays, out| {
        for (slot, ray) in out.iter_mut().zip(rays) {
            *slot = bvh.occluded(ray);
        }
    })
}

/// A set's answers from the batch engine, or from single rays.
#[derive(Clone)]
enum BatchAnswers {
    Closest(Vec<HitRecord>),
    Occluded(Vec<bool>),
}

impl BatchAnswers {
    /// How many answers equal `other`'s (none where the kinds differ).
    fn same_as(&self, other: &BatchAnswers) -> usize {
        match (self, other) {
            (BatchAnswers::Closest(a), BatchAnswers::Closest(b)) => {
                a.iter().zip(b).filter(|(x, y)| x == y).count()
            }
            (BatchAnswers::Occluded(a), BatchAnswers::Occluded(b)) => {
                a.iter().zip(b).filter(|(x, y)| x == y).count()
            }
            _ => 0,
        }
    }
}

/// A set traced as one batch by the library's engine, on the current pool, answers written as
/// [`trace_closest`] and [`trace_occluded`] write theirs.
fn batch_trace(bvh: &Bvh, rays: &[Ray], occlusion: bool) -> BatchAnswers {
    let batch = raylab::bvh::Batch::new(bvh);
    let traced = if occlusion {
        let mut out = vec![false; rays.len()];
        batch
            .answers_into(rays, &mut out, |ray| bvh.occluded(ray))
            .map(|()| BatchAnswers::Occluded(out))
    } else {
        let mut out = vec![HitRecord::default(); rays.len()];
        let answer = |ray: &Ray| HitRecord::from_hit(bvh.closest_hit(ray));
        batch.answers_into(rays, &mut out, answer).map(|()| BatchAnswers::Closest(out))
    };
    let Ok(answers) = traced;
    answers
}

/// One untimed warm-up, then the median wall time of `reps` runs, in seconds.
fn time_median<T>(reps: usize, mut f: impl FnMut() -> T) -> f64 {
    std::hint::black_box(f());
    let mut times: Vec<f64> = (0..reps)
        .map(|_| {
            let start = Instant::now();
            std::hint::black_box(f());
            start.elapsed().as_secs_f64()
        })
        .collect();
    median(&mut times)
}

fn to_json(
    triangles: usize,
    build_1: f64,
    build_n: f64,
    threads: usize,
    bvh_bytes: usize,
    results: &[SetResult],
) -> String {
    let build_threads = if threads == 1 {
        format!("\"1\": {build_1:.3}")
    } else {
        format!("\"1\": {build_1:.3}, \"{threads}\": {build_n:.3}")
    };
    // One object per set, its queries in the order measured.
    let mut names: Vec<&str> = Vec::new();
    for r in results {
        if !names.contains(&r.set.as_str()) {
            names.push(&r.set);
        }
    }
    let sets: Vec<String> = names
        .iter()
        .map(|&set| {
            let queries: Vec<String> = results
                .iter()
                .filter(|r| r.set == set)
                .map(|r| {
                    let figures: Vec<String> =
                        r.mrays_per_s.iter().map(|(n, m)| format!("\"{n}\": {m:.4}")).collect();
                    format!("\"{}\": {{{}}}", r.query, figures.join(", "))
                })
                .collect();
            format!("    \"{set}\": {{{}}}", queries.join(", "))
        })
        .collect();
    format!(
        "{{\n  \"triangles\": {triangles},\n  \"build_ms\": {build_1:.3},\n  \"build_ms_threads\": {{{build_threads}}},\n  \"bvh_bytes\": {bvh_bytes},\n  \"sets\": {{\n{}\n  }}\n}}\n",
        sets.join(",\n")
    )
}
