//! Rays and hits in rows (structure of arrays), up to a tile of [`ROWS`]: the form in which an
//! integrator that shades a tile in lanes (the lab's) hands rays to an accelerator and takes
//! its answers back, so that neither side turns rows into records and
//! back ([`Accelerator::closest_hits_rows`](super::Accelerator::closest_hits_rows),
//! [`Accelerator::occluded_rows`](super::Accelerator::occluded_rows)). The answers are exactly
//! the one-ray queries'.

use glam::Vec3;

use super::hit::Hit;
use crate::ray::Ray;

/// The most rays in rows: one tile of 8×8.
pub const ROWS: usize = 64;

/// Up to [`ROWS`] rays, coordinate by coordinate: ray `i` is `origin[..][i]`,
/// `direction[..][i]`, `t_min[i]`, `t_max[i]`, for `i < len`. Lanes from `len` on hold values
/// of no meaning.
#[derive(Clone, Debug)]
#[repr(C, align(64))]
pub struct RayRows {
    /// The origins, per world axis.
    pub origin: [[f32; ROWS]; 3],
    /// The directions, per world axis.
    pub direction: [[f32; ROWS]; 3],
    /// Hits at `t < t_min` are ignored.
    pub t_min: [f32; ROWS],
    /// Hits at `t >= t_max` are ignored.
    pub t_max: [f32; ROWS],
    /// The rays in the rows.
    pub len: usize,
}

impl Default for RayRows {
    fn default() -> Self {
        RayRows {
            origin: [[0.0; ROWS]; 3],
            direction: [[0.0; ROWS]; 3],
            t_min: [0.0; ROWS],
            t_max: [0.0; ROWS],
            len: 0,
        }
    }
}

impl RayRows {
    /// Ray `i`.
    ///
    /// # Panics
    /// If `i` is not below [`ROWS`].
    #[inline]
    pub fn ray(&self, i: usize) -> Ray {
        let (o, d) = (&self.origin, &self.direction);
        Ray {
            origin: Vec3::new(o[0][i], o[1][i], o[2][i]),
            direction: Vec3::new(d[0][i], d[1][i], d[2][i]),
            t_min: self.t_min[i],
            t_max: self.t_max[i],
        }
    }

    /// Sets lane `i` to `ray` (the length is the caller's to set).
    ///
    /// # Panics
    /// If `i` is not below [`ROWS`].
    #[inline]
    pub fn set(&mut self, i: usize, ray: &Ray) {
        for axis in 0..3 {
            self.origin[axis][i] = ray.origin[axis];
            self.direction[axis][i] = ray.direction[axis];
        }
        self.t_min[i] = ray.t_min;
        self.t_max[i] = ray.t_max;
    }

    /// Rows of `rays` (at most [`ROWS`]).
    ///
    /// # Panics
    /// If there are more than [`ROWS`] rays.
    pub fn from_rays(rays: &[Ray]) -> Self {
        assert!(rays.len() <= ROWS, "at most {ROWS} rays in rows");
        let mut rows = RayRows { len: rays.len(), ..RayRows::default() };
        for (i, ray) in rays.iter().enumerate() {
            rows.set(i, ray);
        }
        rows
    }
}

/// The closest hits of up to [`ROWS`] rays, field by field: lane `i` is a hit on triangle
/// `triangle[i]` at `t[i]` with barycentrics `b1[i]`, `b2[i]`, or a miss where `triangle[i]` is
/// [`MISS`](Self::MISS) (then `t` is `+∞` and the barycentrics 0).
#[derive(Clone, Debug)]
#[repr(C, align(64))]
pub struct HitRows {
    /// Ray parameters of the hits.
    pub t: [f32; ROWS],
    /// Indices of the triangles hit, [`MISS`](Self::MISS) for none.
    pub triangle: [u32; ROWS],
    /// Barycentric weights of the triangles' `v1`.
    pub b1: [f32; ROWS],
    /// Barycentric weights of the triangles' `v2`.
    pub b2: [f32; ROWS],
}

impl Default for HitRows {
    fn default() -> Self {
        HitRows {
            t: [f32::INFINITY; ROWS],
            triangle: [HitRows::MISS; ROWS],
            b1: [0.0; ROWS],
            b2: [0.0; ROWS],
        }
    }
}

impl HitRows {
    /// The triangle of a lane that hits nothing.
    pub const MISS: u32 = u32::MAX;

    /// Lane `i`'s answer.
    #[inline]
    pub fn hit(&self, i: usize) -> Option<Hit> {
        (self.triangle[i] != Self::MISS).then(|| Hit {
            t: self.t[i],
            triangle: self.triangle[i],
            b1: self.b1[i],
            b2: self.b2[i],
        })
    }

    /// Whether lane `i` hits something.
    #[inline]
    pub fn is_hit(&self, i: usize) -> bool {
        self.triangle[i] != Self::MISS
    }

    /// Sets lane `i` to `hit`.
    #[inline]
    pub fn set(&mut self, i: usize, hit: Option<Hit>) {
        let h = hit.unwrap_or(Hit { t: f32::INFINITY, triangle: Self::MISS, b1: 0.0, b2: 0.0 });
        (self.t[i], self.triangle[i], self.b1[i], self.b2[i]) = (h.t, h.triangle, h.b1, h.b2);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rays_and_hits_go_into_rows_and_back() {
        let rays: Vec<Ray> = (0..5)
            .map(|i| {
                let f = i as f32;
                Ray::segment(Vec3::new(f, -f, 0.5), Vec3::new(1.0, f, -0.0), 2.0 + f)
            })
            .collect();
        let rows = RayRows::from_rays(&rays);
        assert_eq!(rows.len, 5);
        for (i, ray) in rays.iter().enumerate() {
            let back = rows.ray(i);
            let bits = |r: &Ray| {
                let v = |v: Vec3| v.to_array().map(f32::to_bits);
                (v(r.origin), v(r.direction), r.t_min.to_bits(), r.t_max.to_bits())
            };
            assert_eq!(bits(&back), bits(ray));
        }
        let mut hits = HitRows::default();
        assert_eq!(hits.hit(3), None);
        let hit = Hit { t: 0.25, triangle: 7, b1: 0.5, b2: -0.0 };
        hits.set(3, Some(hit));
        assert_eq!(hits.hit(3), Some(hit));
        assert!(hits.is_hit(3) && !hits.is_hit(2));
        hits.set(3, None);
        assert_eq!((hits.hit(3), hits.t[3], hits.b1[3]), (None, f32::INFINITY, 0.0));
    }
}
