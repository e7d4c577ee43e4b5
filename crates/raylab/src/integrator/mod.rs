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
}
