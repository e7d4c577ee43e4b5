//! Ray queries over a whole scene: the one seam between geometry and integrators.
//!
//! Integrators only ever ask two questions, both through [`Accelerator`]:
//! [`closest_hit`](Accelerator::closest_hit) (what does this ray see?) and
//! [`occluded`](Accelerator::occluded) (is anything in the way?). [`BruteForce`] answers them by
//! testing every triangle, which is exact and fast enough for the lab's 30 triangles; a BVH
//! answers them the same way, only faster.

mod brute_force;
mod hit;
mod rows;

pub use brute_force::BruteForce;
pub use hit::Hit;
pub use rows::{HitRows, ROWS, RayRows};

/// Answers ray queries against a fixed set of triangles.
pub trait Accelerator: Sync {
    /// The nearest hit with `0 < t < ray.t_max`, if any.
    fn closest_hit(&self, ray: &crate::Ray) -> Option<Hit>;

    /// Whether anything is hit with `0 < t < ray.t_max` (any hit; stops at the first).
    fn occluded(&self, ray: &crate::Ray) -> bool;

    /// The closest hit of each ray, `hits[i]` for `rays[i]`: exactly what
    /// [`closest_hit`](Self::closest_hit) answers one ray at a time. Accelerators that trace
    /// coherent rays together (a tile of camera rays) answer faster this way.
    ///
    /// # Panics
    /// If the slices differ in length.
    fn closest_hits(&self, rays: &[crate::Ray], hits: &mut [Option<Hit>]) {
        assert_eq!(rays.len(), hits.len(), "one answer per ray");
        for (ray, hit) in rays.iter().zip(hits) {
            *hit = self.closest_hit(ray);
        }
    }

    /// Whether each ray is occluded, `occluded[i]` for `rays[i]`: exactly what
    /// [`occluded`](Self::occluded) answers one ray at a time, faster for coherent rays on
    /// accelerators that trace them together.
    ///
    /// # Panics
    /// If the slices differ in length.
    fn occluded_each(&self, rays: &[crate::Ray], occluded: &mut [bool]) {
        assert_eq!(rays.len(), occluded.len(), "one answer per ray");
        for (ray, o) in rays.iter().zip(occluded) {
            *o = self.occluded(ray);
        }
    }

    /// The closest hit of each of up to [`ROWS`] rays (a tile of camera rays), in rows:
    /// `hits.hit(i)` for `rays[i]` is exactly what [`closest_hit`](Self::closest_hit) answers;
    /// lanes from `rays.len()` on are left as they were. The form for integrators that shade
    /// a tile in lanes; accelerators that trace packets write their rows directly.
    ///
    /// # Panics
    /// If there are more than [`ROWS`] rays.
    fn closest_hits_rows(&self, rays: &[crate::Ray], hits: &mut HitRows) {
        assert!(rays.len() <= ROWS, "at most {ROWS} rays in rows");
        for (i, ray) in rays.iter().enumerate() {
            hits.set(i, self.closest_hit(ray));
        }
    }

    /// Which of the rays in `rays` (coherent ones: shadow rays toward one light) are occluded,
    /// as a mask: bit `i` for ray `i`, exactly what [`occluded`](Self::occluded) answers (no bit
    /// at or above `rays.len`).
    ///
    /// # Panics
    /// If `rays.len` is above [`ROWS`].
    fn occluded_rows(&self, rays: &RayRows) -> u64 {
        assert!(rays.len <= ROWS, "at most {ROWS} rays in rows");
        (0..rays.len).filter(|&i| self.occluded(&rays.ray(i))).fold(0, |m, i| m | 1 << i)
    }

    /// Whether each of many incoherent rays (a path tracer's shadow rays) is occluded,
    /// `occluded[i]` for `rays[i]`: exactly what [`occluded`](Self::occluded) answers one ray at
    /// a time, faster on accelerators that trace such rays together.
    ///
    /// # Panics
    /// If the slices differ in length.
    fn occluded_incoherent(&self, rays: &[crate::Ray], occluded: &mut [bool]) {
        assert_eq!(rays.len(), occluded.len(), "one answer per ray");
        for (ray, o) in rays.iter().zip(occluded) {
            *o = self.occluded(ray);
        }
    }

    /// The closest hit of each of many incoherent rays (a path tracer's bounces), `hits[i]` for
    /// `rays[i]`: exactly what [`closest_hit`](Self::closest_hit) answers one ray at a time,
    /// faster on accelerators that trace such rays together.
    ///
    /// # Panics
    /// If the slices differ in length.
    fn closest_hits_incoherent(&self, rays: &[crate::Ray], hits: &mut [Option<Hit>]) {
        assert_eq!(rays.len(), hits.len(), "one answer per ray");
        for (ray, hit) in rays.iter().zip(hits) {
            *hit = self.closest_hit(ray);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Hit;

    #[test]
    fn hits_order_by_t_then_by_lower_index() {
        let hit = |t, triangle| Hit { t, triangle, b1: 0.0, b2: 0.0 };
        assert!(hit(1.0, 9).precedes(&hit(2.0, 0)));
        assert!(hit(1.0, 3).precedes(&hit(1.0, 4)));
        assert!(!hit(1.0, 4).precedes(&hit(1.0, 4)) && !hit(1.0, 4).precedes(&hit(1.0, 3)));
        let mut best = None;
        for h in [hit(3.0, 1), hit(2.0, 7), hit(2.0, 5), hit(2.0, 6), hit(2.5, 0)] {
            h.keep_first(&mut best);
        }
        assert_eq!(best, Some(hit(2.0, 5)));
    }
}
