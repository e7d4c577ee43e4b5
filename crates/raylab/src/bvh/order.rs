//! Many rays put in an order that shares the tree's nodes: a large batch of incoherent rays
//! traced in this order finds more of the tree in the cache.
//!
//! Two rays visit the same nodes when they run through the same part of the tree's box. A ray's
//! segment inside the box (from where it enters, or starts, to where it leaves, or ends) is
//! given by its two end points, so the order sorts rays by a Morton code of those six
//! coordinates ([`segment_key`]): four bits each (sixteen cells across the box), the bits of
//! the six interleaved into 24. Rays whose segments miss the box get the largest key and come last.
//! [`order_by_key`] sorts the keys with a stable radix sort, so the order depends on the rays
//! alone, never on a thread count.
//!
//! The order changes nothing in the answers, only their speed; each ray's answer is the same
//! in any order. Garanzha and Loop sort rays by a hash of origin and direction ("Fast ray
//! sorting and breadth-first packet traversal for GPU ray tracing", Eurographics 2010); the
//! segment key here orders random rays better than a Morton code of origin and direction
//! (BENCHMARKS.md compares the two on the bunny and the dragon). Small batches, or trees that
//! fit the caches, gain less than the sort costs.
//!
//! ```
//! use raylab::bvh::{Bvh, order};
//! use raylab::{Accelerator, Ray, Scene};
//! use glam::Vec3;
//!
//! let scene = Scene::built_in("cornell")?;
//! let bvh = Bvh::new(&scene.vertices());
//! let rays: Vec<Ray> = (0..100)
//!     .map(|i| Ray::new(Vec3::new(0.0, 0.0, -3.0), Vec3::new(i as f32 * 0.01 - 0.5, 0.1, 1.0)))
//!     .collect();
//! let keys: Vec<u32> = rays.iter().map(|r| order::segment_key(&bvh.bounds(), r)).collect();
//! for i in order::order_by_key(&keys) {
//!     let _hit = bvh.closest_hit(&rays[i as usize]);
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use glam::Vec3A;

use super::Bounds;
use crate::ray::Ray;

/// Bits per coordinate of the segment's end points: sixteen cells per axis of the box. (Five
/// bits trace a little faster but sort much slower.)
const BITS: u32 = 4;

/// The key of a segment that misses the box: the largest key, so such rays come last.
pub const MISS: u32 = (1 << (6 * BITS)) - 1;

/// `SPREAD[g]`: the four bits of `g` at every sixth bit (bit `b` of `g` at bit `6b`).
const SPREAD: [u32; 1 << BITS] = {
    let mut table = [0u32; 1 << BITS];
    let mut g = 0;
    while g < table.len() {
        let mut b = 0;
        while b < BITS {
            table[g] |= ((g as u32 >> b) & 1) << (6 * b);
            b += 1;
        }
        g += 1;
    }
    table
};

/// A key that sorts rays running through the same part of `bounds` (a tree's box,
/// [`Bvh::bounds`](super::Bvh::bounds)) next to each other: the Morton code of the ray's segment
/// inside the box, its entry point (or origin) and its exit point (or end), each coordinate
/// one of sixteen equal cells across the box (four bits; a point on the boundary of two cells
/// goes to either), 24 bits in all. [`MISS`] where the segment `[t_min, t_max]` misses the box,
/// or for an empty box (a segment inside the box's last corner cell has that key too).
///
/// Any ray gets a key, also one with a zero or non-finite direction (the key is then some
/// number, for a caller that has not checked its rays yet): it never panics.
#[inline]
pub fn segment_key(bounds: &Bounds, ray: &Ray) -> u32 {
    let (min, max) = (Vec3A::from(bounds.min), Vec3A::from(bounds.max));
    let (origin, direction) = (Vec3A::from(ray.origin), Vec3A::from(ray.direction));
    let inverse = direction.recip();
    let (t0, t1) = ((min - origin) * inverse, (max - origin) * inverse);
    // A NaN (0·∞: a zero direction with the origin on that slab's plane) does not limit the
    // segment along that axis.
    let unlimited = t0.is_nan_mask() | t1.is_nan_mask();
    let t_enter = Vec3A::select(unlimited, Vec3A::NEG_INFINITY, t0.min(t1));
    let t_leave = Vec3A::select(unlimited, Vec3A::INFINITY, t0.max(t1));
    let near = t_enter.max_element().max(ray.t_min.max(0.0));
    let far = t_leave.min_element().min(ray.t_max);
    // Also false for a NaN limit.
    let crosses = near <= far;
    if !crosses || bounds.is_empty() {
        return MISS;
    }
    // Sixteen cells per axis; a flat axis is all in cell 0.
    let extent = max - min;
    let cells_per_length =
        Vec3A::select(extent.cmpgt(Vec3A::ZERO), (1 << BITS) as f32 / extent, Vec3A::ZERO);
    let top = ((1 << BITS) - 1) as f32;
    let cells = |t: f32| {
        let p = (origin + t * direction - min) * cells_per_length - 0.5;
        let p = p.clamp(Vec3A::ZERO, Vec3A::splat(top));
        // Rounded to the nearest integer by adding 2²³ (so `p − ½` to its cell): the cell is
        // then the low bits (any bits for a NaN, which `clamp` may keep; still a cell in range).
        (p + Vec3A::splat(8_388_608.0)).to_array().map(|x| (x.to_bits() & top as u32) as usize)
    };
    let ([x0, y0, z0], [x1, y1, z1]) = (cells(near), cells(far));
    (SPREAD[x0] << 5)
        | (SPREAD[y0] << 4)
        | (SPREAD[z0] << 3)
        | (SPREAD[x1] << 2)
        | (SPREAD[y1] << 1)
        | SPREAD[z1]
}

/// The indices `0..keys.len()` sorted by their keys, equal keys in index order: a stable LSD
/// radix sort, a byte per pass (a pass whose byte is the same for every key is skipped: three
/// passes for [`segment_key`]'s 24 bits; twelve bits per pass was no faster, its 4096 buckets
/// scattered too widely).
///
/// # Panics
/// With more than `u32::MAX` keys (an index would not fit its `u32`).
pub fn order_by_key(keys: &[u32]) -> Vec<u32> {
    assert!(u32::try_from(keys.len()).is_ok(), "at most u32::MAX keys");
    // Each item the key in the high half, its index in the low half.
    let mut items: Vec<u64> =
        keys.iter().enumerate().map(|(i, &k)| (u64::from(k) << 32) | i as u64).collect();
    const PASSES: [(u32, u32); 4] = [(32, 8), (40, 8), (48, 8), (56, 8)];
    let mut counts = vec![[0u32; 1 << 8]; PASSES.len()];
    for &item in &items {
        for (count, &(shift, bits)) in counts.iter_mut().zip(&PASSES) {
            count[((item >> shift) & ((1 << bits) - 1)) as usize] += 1;
        }
    }
    let mut spare = vec![0u64; items.len()];
    for (count, &(shift, bits)) in counts.iter().zip(&PASSES) {
        if count.iter().any(|&c| c as usize == items.len()) {
            continue;
        }
        let mut next = [0u32; 1 << 8];
        let mut sum = 0;
        for (slot, &c) in next.iter_mut().zip(count) {
            *slot = sum;
            sum += c;
        }
        for &item in &items {
            let digit = ((item >> shift) & ((1 << bits) - 1)) as usize;
            spare[next[digit] as usize] = item;
            next[digit] += 1;
        }
        std::mem::swap(&mut items, &mut spare);
    }
    items.into_iter().map(|item| item as u32).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Pcg32;
    use glam::Vec3;

    fn unit_box() -> Bounds {
        Bounds { min: Vec3::ZERO, max: Vec3::ONE }
    }

    #[test]
    fn the_radix_sort_is_a_stable_sort() {
        let mut rng = Pcg32::new(7, 1);
        for n in [0, 1, 2, 100, 5000] {
            // Few distinct keys (ties), keys in one digit, and keys over all 32 bits.
            for spread in [3u32, 2000, u32::MAX] {
                let keys: Vec<u32> = (0..n).map(|_| rng.next_u32() % spread).collect();
                let mut expected: Vec<u32> = (0..n as u32).collect();
                expected.sort_by_key(|&i| keys[i as usize]);
                assert_eq!(order_by_key(&keys), expected, "{n} keys below {spread}");
            }
        }
    }

    #[test]
    fn a_key_is_the_morton_code_of_the_segment_in_the_box() {
        // Along x through the middle of the box: enters at (0, ½, ½), leaves at (1, ½, ½).
        // Cells: entry (0, 8, 8), exit (15, 8, 8) (½ is the boundary of cells 7 and 8:
        // ½·16 − ½ = 7.5, rounded to even).
        let ray = Ray::new(Vec3::new(-1.0, 0.5, 0.5), Vec3::X);
        let expected = (SPREAD[0] << 5)
            | (SPREAD[8] << 4)
            | (SPREAD[8] << 3)
            | (SPREAD[15] << 2)
            | (SPREAD[8] << 1)
            | SPREAD[8];
        assert_eq!(segment_key(&unit_box(), &ray), expected);
        // The same segment from a ray starting inside and ending at the far side.
        let inside = Ray { origin: Vec3::new(0.0, 0.5, 0.5), t_min: 0.0, t_max: 1.0, ..ray };
        assert_eq!(segment_key(&unit_box(), &inside), expected);
        // The miss key is above every other.
        assert!(expected < MISS && SPREAD[15] * 63 == MISS);
    }

    #[test]
    fn segments_that_miss_the_box_get_the_miss_key() {
        let b = unit_box();
        // Beside the box, pointing away, stopping short, along an axis outside its slab.
        assert_eq!(segment_key(&b, &Ray::new(Vec3::new(-1.0, 2.0, 0.5), Vec3::X)), MISS);
        assert_eq!(segment_key(&b, &Ray::new(Vec3::new(-1.0, 0.5, 0.5), -Vec3::X)), MISS);
        assert_eq!(segment_key(&b, &Ray::segment(Vec3::new(-1.0, 0.5, 0.5), Vec3::X, 0.5)), MISS);
        assert_eq!(segment_key(&Bounds::EMPTY, &Ray::new(Vec3::ZERO, Vec3::X)), MISS);
        // Starting beyond the box's far side: t_min past the exit.
        let late = Ray { t_min: 3.0, ..Ray::new(Vec3::new(-1.0, 0.5, 0.5), Vec3::X) };
        assert_eq!(segment_key(&b, &late), MISS);
    }

    #[test]
    fn a_ray_in_a_face_of_the_box_and_a_flat_box_get_their_cells() {
        // Along x in the box's face z = 0: the z slab does not limit it (0·∞ there).
        let ray = Ray::new(Vec3::new(-1.0, 0.5, 0.0), Vec3::X);
        let key = segment_key(&unit_box(), &ray);
        let expected = (SPREAD[0] << 5)
            | (SPREAD[8] << 4)
            | (SPREAD[0] << 3)
            | (SPREAD[15] << 2)
            | (SPREAD[8] << 1)
            | SPREAD[0];
        assert_eq!(key, expected);
        // A flat box (a square in z = 0): z is cell 0 at both ends.
        let flat = Bounds { min: Vec3::ZERO, max: Vec3::new(1.0, 1.0, 0.0) };
        let down = Ray::new(Vec3::new(0.9, 0.1, 1.0), -Vec3::Z);
        let cells = (SPREAD[14] << 5) | (SPREAD[1] << 4) | (SPREAD[14] << 2) | (SPREAD[1] << 1);
        assert_eq!(segment_key(&flat, &down), cells);
    }

    #[test]
    fn a_bad_ray_gets_some_key_without_a_panic() {
        let b = unit_box();
        for (o, d) in [
            (Vec3::ZERO, Vec3::ZERO),
            (Vec3::NAN, Vec3::X),
            (Vec3::splat(0.5), Vec3::new(f32::INFINITY, 0.0, 0.0)),
            (Vec3::splat(f32::MAX), Vec3::splat(-f32::MAX)),
        ] {
            let _ = segment_key(&b, &Ray::new(o, d));
        }
    }

    #[test]
    fn rays_through_nearby_segments_sort_together() {
        // Rays from both ends of the box's x axis, through a grid of points on its faces,
        // shuffled: sorted, the rays of each half (the left-to-right ones and the
        // right-to-left ones, whose entry cells differ in the highest bit of x) are not mixed.
        let mut rng = Pcg32::new(3, 5);
        let mut rays = Vec::new();
        for k in 0..400 {
            let (y, z) = (rng.next_f32(), rng.next_f32());
            let ray = if k % 2 == 0 {
                Ray::new(Vec3::new(-1.0, y, z), Vec3::X)
            } else {
                Ray::new(Vec3::new(2.0, y, z), -Vec3::X)
            };
            rays.push(ray);
        }
        let keys: Vec<u32> = rays.iter().map(|r| segment_key(&unit_box(), r)).collect();
        let order = order_by_key(&keys);
        let directions: Vec<f32> = order.iter().map(|&i| rays[i as usize].direction.x).collect();
        let changes = directions.windows(2).filter(|w| w[0] != w[1]).count();
        assert_eq!(changes, 1, "the two directions sorted into two runs");
    }
}
