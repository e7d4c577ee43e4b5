//! The batch engine (`raylab::bvh::Batch`) answers every ray as its own single query does, bit
//! for bit, in the tree's order or as the rays come, on one thread or two, for every instruction
//! set; a bad ray stops a batch with the first bad ray's error.

use glam::Vec3;
use raylab::bvh::{Batch, Bvh, Isa, RaySource};
use raylab::{Accelerator, Ray};

/// The bunny (75k triangles) from the tests' data.
fn bunny() -> Vec<[Vec3; 3]> {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes/bunny.obj.gz");
    raylab::load_mesh(&path).expect("the bunny loads").flattened().triangle_vertices().collect()
}

/// Rays from around the bunny's box in every direction, some segments (`t_max`), some starting
/// inside it (`t_min`), some that can hit nothing (a zero direction, an empty range).
fn rays(bvh: &Bvh, n: usize) -> Vec<Ray> {
    let b = bvh.bounds();
    let (centre, size) = ((b.min + b.max) * 0.5, b.max - b.min);
    let mut state = 0x853c_49e6_748f_ea9bu64;
    let mut next = move || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (state >> 40) as f32 / (1u64 << 24) as f32 - 0.5
    };
    (0..n)
        .map(|i| {
            let origin = centre + Vec3::new(next(), next(), next()) * size * 2.0;
            let aim = centre + Vec3::new(next(), next(), next()) * size;
            let mut ray = Ray::new(origin, aim - origin);
            match i % 7 {
                1 => ray.t_max = next() + 0.5,
                2 => ray.t_min = next() + 0.5,
                3 if i % 1000 == 3 => ray.direction = Vec3::ZERO,
                4 if i % 1000 == 4 => (ray.t_min, ray.t_max) = (1.0, 0.5),
                _ => {}
            }
            ray
        })
        .collect()
}

fn same_hits(a: &[Option<raylab::Hit>], b: &[Option<raylab::Hit>]) -> bool {
    let bits = |h: &Option<raylab::Hit>| {
        h.map(|h| (h.t.to_bits(), h.triangle, h.b1.to_bits(), h.b2.to_bits()))
    };
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| bits(x) == bits(y))
}

#[test]
fn batches_answer_as_single_rays_in_any_order_on_any_threads() {
    let triangles = bunny();
    let mut checked = 0;
    for isa in Isa::ALL {
        let Some(bvh) = Bvh::new(&triangles).with_isa(isa) else {
            eprintln!("note: this CPU lacks {}: its batch is not tested here", isa.name());
            continue;
        };
        // More than one chunk and than the ordering threshold.
        let rays = rays(&bvh, Batch::ORDER_MIN_RAYS + 3 * Batch::CHUNK + 17);
        let single: Vec<_> = rays.iter().map(|r| bvh.closest_hit(r)).collect();
        let blocked: Vec<_> = rays.iter().map(|r| bvh.occluded(r)).collect();
        let counts: Vec<_> = rays.iter().map(|r| bvh.count_crossings(r)).collect();
        assert!(single.iter().filter(|h| h.is_some()).count() > rays.len() / 10, "too few hits");
        assert!(counts.iter().any(|&c| c >= 2), "no ray crosses the surface twice");
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            for ordered in [None, Some(false), Some(true)] {
                let batch = match ordered {
                    None => Batch::new(&bvh),
                    Some(o) => Batch::new(&bvh).ordered(o),
                };
                let what = format!("{} {threads} threads, ordered {ordered:?}", isa.name());
                let hits = pool.install(|| batch.closest_hits(&rays[..])).unwrap();
                assert!(same_hits(&hits, &single), "{what}: closest hits differ");
                let occluded = pool.install(|| batch.occluded(&rays[..])).unwrap();
                assert_eq!(occluded, blocked, "{what}: occlusion differs");
                let crossings = pool.install(|| batch.crossing_counts(&rays[..])).unwrap();
                assert_eq!(crossings, counts, "{what}: crossing counts differ");
                checked += 1;
            }
        }
        // A batch of one ray, and an empty one.
        let one = Batch::new(&bvh).closest_hits(&rays[5..6]).unwrap();
        assert!(same_hits(&one, &single[5..6]));
        assert!(Batch::new(&bvh).occluded(&rays[..0]).unwrap().is_empty());
    }
    assert!(checked >= 12, "{checked} combinations");
}

/// A source that refuses rays whose direction has a negative `y` below -0.45 (of its length):
/// the first of them must be named, in the tree's order too, whichever thread meets which.
struct Picky<'a>(&'a [Ray]);

impl RaySource for Picky<'_> {
    type Error = usize;

    fn len(&self) -> usize {
        self.0.len()
    }

    fn ray(&self, i: usize) -> Result<Ray, usize> {
        let ray = self.0[i];
        if ray.direction.normalize_or_zero().y < -0.45 && i > 1000 { Err(i) } else { Ok(ray) }
    }

    fn ray_unchecked(&self, i: usize) -> Ray {
        self.0[i]
    }
}

#[test]
fn a_bad_ray_stops_the_batch_with_the_first_bad_ray() {
    let triangles = bunny();
    let bvh = Bvh::new(&triangles);
    let rays = rays(&bvh, Batch::ORDER_MIN_RAYS + 5 * Batch::CHUNK);
    let picky = Picky(&rays);
    let first = (0..rays.len()).find(|&i| picky.ray(i).is_err()).expect("some ray is refused");
    assert!(first > 1000);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
    for ordered in [false, true] {
        let batch = Batch::new(&bvh).ordered(ordered);
        assert_eq!(pool.install(|| batch.closest_hits(&picky)).unwrap_err(), first);
        assert_eq!(pool.install(|| batch.occluded(&picky)).unwrap_err(), first);
    }
}
