//! A small scene's flat list against incoherent rays: one ray at a time (sixteen triangles per
//! instruction) against many rays at once (rays in lanes, one triangle per step), on Mitsuba's
//! 36-triangle Cornell box. The rays are a path tracer's kind: from points inside the box in
//! uniformly random directions for closest hits, segments between two such points for
//! occlusion, 64 to a batch (the wavefront hands over up to 256, fewer at later bounces).
//!
//! `cargo bench -p raylab --bench flat_rays`

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;

use raylab::scene::LoadOptions;
use raylab::{Accelerator, Hit, Ray, Scene, SceneBvh};

/// Rays per measured batch set, and rays per batch.
const RAYS: usize = 4096;
const BATCH: usize = 64;

/// A xorshift generator: the same rays on every run.
struct Random(u64);

impl Random {
    fn next(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }

    fn inside(&mut self, (lo, hi): (Vec3, Vec3)) -> Vec3 {
        lo + (hi - lo) * Vec3::new(self.next(), self.next(), self.next())
    }

    fn direction(&mut self) -> Vec3 {
        loop {
            let d = Vec3::new(self.next(), self.next(), self.next()) * 2.0 - 1.0;
            if d.length_squared() <= 1.0 && d.length_squared() > 1e-4 {
                return d.normalize();
            }
        }
    }
}

/// The box's BVH, random rays inside it, and random segments inside it.
fn rays() -> (SceneBvh, Vec<Ray>, Vec<Ray>) {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
    let file = root.join("cornell-mitsuba.toml").display().to_string();
    let scene = Scene::open(&file, &LoadOptions::default()).expect("the scene file").scene;
    let accel = SceneBvh::build(&scene.geometry).expect("a BVH");
    let (lo, hi) = scene.geometry.bounds().expect("bounds");
    let inner = (lo + (hi - lo) * 0.02, hi - (hi - lo) * 0.02);
    let mut random = Random(0x9e37_79b9_7f4a_7c15);
    let bounces = (0..RAYS).map(|_| Ray::new(random.inside(inner), random.direction())).collect();
    let shadows = (0..RAYS)
        .map(|_| {
            let (from, to) = (random.inside(inner), random.inside(inner));
            Ray::segment(from, to - from, 1.0)
        })
        .collect();
    (accel, bounces, shadows)
}

fn flat_rays(c: &mut Criterion) {
    let (accel, bounces, shadows) = rays();
    let mut hits = vec![None::<Hit>; RAYS];
    let mut group = c.benchmark_group("cornell_flat_4096_rays");
    group.throughput(Throughput::Elements(RAYS as u64));
    group.bench_function("closest_one_by_one", |b| {
        b.iter(|| {
            for (ray, hit) in bounces.iter().zip(&mut hits) {
                *hit = accel.closest_hit(ray);
            }
        })
    });
    group.bench_function("closest_in_lanes", |b| {
        b.iter(|| {
            for (rays, hits) in bounces.chunks(BATCH).zip(hits.chunks_mut(BATCH)) {
                accel.closest_hits_incoherent(rays, hits);
            }
        })
    });
    // Shadow rays: segments between two points inside the box.
    let mut blocked = vec![false; RAYS];
    group.bench_function("occluded_one_by_one", |b| {
        b.iter(|| {
            for (ray, blocked) in shadows.iter().zip(&mut blocked) {
                *blocked = accel.occluded(ray);
            }
        })
    });
    group.bench_function("occluded_in_lanes", |b| {
        b.iter(|| {
            for (rays, blocked) in shadows.chunks(BATCH).zip(blocked.chunks_mut(BATCH)) {
                accel.occluded_incoherent(rays, blocked);
            }
        })
    });
    group.finish();
}

criterion_group!(benches, flat_rays);
criterion_main!(benches);
