//! The lab frame: the Cornell box at 500×500 with shadows and ambient light, as `raylab render`
//! draws it by default, on 1 and 2 threads.
//!
//! `cargo bench -p raylab --bench lab_frame`

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use raylab::{Accelerator, BruteForce, Bvh, Camera, Lab, Scene, Stage, render};

fn lab_frame(c: &mut Criterion) {
    let scene = Scene::built_in("cornell").expect("built in");
    let brute_force = BruteForce::new(&scene.vertices());
    let bvh = Bvh::new(&scene.vertices());
    let accelerators: [(&str, &dyn Accelerator); 2] =
        [("brute_force", &brute_force), ("bvh", &bvh)];
    let camera = Camera::lab(500, 500);
    let mut group = c.benchmark_group("lab_frame_500x500");
    group.sample_size(30);
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("threads");
        for ((name, accel), stage) in
            accelerators.iter().flat_map(|a| [(*a, Stage::Flat), (*a, Stage::Ambient)])
        {
            let integrator = Lab::new(&scene, accel, stage);
            group.bench_with_input(
                BenchmarkId::new(format!("{name}_{stage}"), format!("{threads}_threads")),
                &threads,
                |b, _| {
                    b.iter(|| {
                        pool.install(|| render(&camera, &integrator, &|_| {}).expect("render"))
                    })
                },
            );
        }
    }
    group.finish();
}

criterion_group!(benches, lab_frame);
criterion_main!(benches);
