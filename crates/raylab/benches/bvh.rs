//! BVH build and traversal on the bunny (in the repository) and the dragon (871k triangles, from
//! `shared/data` beside the checkout, skipped if absent): the protocol's primary, shadow and
//! diffuse rays at 256×256, one thread.
//!
//! `cargo bench -p raylab --bench bvh`

use std::path::{Path, PathBuf};

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use raylab::bvh::{BuildSettings, Bvh};
use raylab::ray_sets::{self, Frame, HitRecord};
use raylab::{Accelerator, Mesh};

fn meshes() -> Vec<(&'static str, PathBuf)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let candidates = [
        ("bunny", root.join("tests/data/meshes/bunny.obj.gz")),
        ("dragon", root.join("../../../shared/data/dragon.obj.gz")),
    ];
    candidates.into_iter().filter(|(_, p)| p.is_file()).collect()
}

fn bvh(c: &mut Criterion) {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().expect("a thread");
    for (name, path) in meshes() {
        let mesh: Mesh = raylab::scene::load_mesh(&path).expect("loads").flattened();
        let triangles: Vec<_> = mesh.triangle_vertices().collect();

        let mut build = c.benchmark_group(format!("bvh_build_{name}"));
        build.sample_size(10);
        build.throughput(Throughput::Elements(triangles.len() as u64));
        for (preset, settings) in BuildSettings::PRESETS {
            // The tree is freed outside the timing, as Embree's build time (`rtcCommitScene`)
            // leaves out releasing the scene.
            build.bench_with_input(BenchmarkId::new(preset, "1_thread"), &settings, |b, s| {
                b.iter_with_large_drop(|| pool.install(|| Bvh::build(&triangles, s)))
            });
        }
        // Refit to the same triangles moved a little: the cost of an animated frame.
        let mut bvh = Bvh::build(&triangles, &BuildSettings::default());
        let moved: Vec<_> = triangles.iter().map(|t| t.map(|v| v * 1.001)).collect();
        build.bench_function("refit", |b| b.iter(|| bvh.refit(&moved)));
        build.finish();

        let bvh = Bvh::build(&triangles, &BuildSettings::default());
        let frame = Frame::of(&mesh).expect("triangles");
        let primary = ray_sets::primary_rays(&frame, 256, 256, 256.0);
        let hits: Vec<HitRecord> =
            primary.iter().map(|r| HitRecord::from_hit(bvh.closest_hit(r))).collect();
        let shadow = ray_sets::shadow_rays(&frame, &primary, &hits);
        let diffuse = ray_sets::diffuse_rays(&frame, &mesh, &primary, &hits);

        let mut trace = c.benchmark_group(format!("bvh_trace_{name}"));
        trace.sample_size(10);
        for (set, rays, occlusion) in
            [("primary", &primary, false), ("shadow", &shadow, true), ("diffuse", &diffuse, false)]
        {
            trace.throughput(Throughput::Elements(rays.len() as u64));
            trace.bench_function(set, |b| {
                b.iter(|| {
                    if occlusion {
                        rays.iter().filter(|r| bvh.occluded(r)).count()
                    } else {
                        rays.iter().filter(|r| bvh.closest_hit(r).is_some()).count()
                    }
                })
            });
        }
        trace.finish();
    }
}

criterion_group!(benches, bvh);
criterion_main!(benches);
