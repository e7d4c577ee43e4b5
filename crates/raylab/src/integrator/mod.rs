//! Integrators: what colour a camera ray sees.
//!
//! One file per integrator. [`Lab`] is the lab's direct-light model with shadows and a constant
//! ambient term, with a [`Stage`] for each step of the lab.

mod lab;

use glam::Vec3;

pub use lab::{Lab, Stage};

use crate::ray::Ray;

/// Computes the colour seen along a camera ray.
pub trait Integrator: Sync {
    /// The colour (linear, unclamped) seen along `ray`.
    fn radiance(&self, ray: &Ray) -> Vec3;

    /// The colour seen along each ray, `out[i]` for `rays[i]`: exactly what
    /// [`radiance`](Self::radiance) gives one ray at a time. Integrators override it to trace
    /// coherent rays (a tile of camera rays) together.
    ///
    /// # Panics
    /// If the slices differ in length.
    fn radiance_each(&self, rays: &[Ray], out: &mut [Vec3]) {
        assert_eq!(rays.len(), out.len(), "one colour per ray");
        for (ray, colour) in rays.iter().zip(out) {
            *colour = self.radiance(ray);
        }
    }
}
