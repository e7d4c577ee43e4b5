//! Integrators: what colour a camera ray sees.
//!
//! [`Lab`] is the lab's direct-light model with shadows and a constant ambient term, with a
//! [`Stage`] for each step of the lab. [`Path`] is the path tracer, which sees the light the lab
//! leaves out (indirect light, soft shadows from area lights): it runs a tile's paths stage by
//! stage, their vertices in SIMD lanes (`wavefront/`). [`PathScalar`] is the same estimator one
//! path at a time (`path.rs`), its twin: the same samples, to the bit. [`Aov`] shows what the
//! camera sees first. [`Chosen`] builds whichever a [`Choice`] names: the one place that
//! chooses, for rendering and viewing alike.
//!
//! An integrator draws every random number it needs from the [`Sampler`] it is given, which the
//! renderer makes from (seed, pixel, sample index) alone: the same sample gives the same colour
//! on any thread.

mod aov;
mod choice;
mod lab;
mod light_sampler;
mod path;
mod wavefront;

use glam::Vec3;

pub use aov::{Aov, AovKind, WithAovs};
pub use choice::{Choice, Chosen};
pub use lab::{Lab, Stage};
pub use light_sampler::{EnvironmentSampling, LightSample, LightSet, TriangleSampling};
pub use path::{PathScalar, PathSettings};
pub use wavefront::{Path, StageTimes};

use crate::accel::{Accelerator, Hit};
use crate::ray::Ray;
use crate::sampling::{Sampler, SamplerKind};
use crate::scene::Scene;

/// The most cut-out holes a ray passes through; behind more, it is taken as blocked.
const MAX_HOLES: u32 = 256;

/// The first hit along `ray` on a surface that is there: the holes of alpha-masked materials
/// (glTF's `alphaMode: MASK`) are passed through, by tracing the same ray again from just past
/// each (its `t_min`), so hits keep their `t` along `ray`.
#[inline]
pub fn closest_opaque_hit<A: Accelerator + ?Sized>(
    scene: &Scene,
    accel: &A,
    ray: &Ray,
) -> Option<Hit> {
    let mut hit = accel.closest_hit(ray)?;
    let mut ray = *ray;
    for _ in 0..MAX_HOLES {
        if !scene.is_cut_out(&ray, &hit) {
            return Some(hit);
        }
        ray.t_min = hit.t.next_up();
        hit = accel.closest_hit(&ray)?;
    }
    Some(hit)
}

/// Whether something that is there (not a cut-out hole) blocks the segment `ray`.
#[inline]
pub fn occluded_opaque<A: Accelerator + ?Sized>(scene: &Scene, accel: &A, ray: &Ray) -> bool {
    // Holes only take blockers away: a segment nothing blocks is clear, and only a blocked
    // one in a scene with holes needs its blockers looked at one by one.
    accel.occluded(ray)
        && (!scene.has_cut_outs() || closest_opaque_hit(scene, accel, ray).is_some())
}

/// Computes the colour seen along a camera ray.
pub trait Integrator: Sync {
    /// The colour (linear, unclamped) seen along `ray`, with random numbers from `sampler`.
    fn radiance(&self, ray: &Ray, sampler: &mut Sampler) -> Vec3;

    /// The colour seen along each ray, `out[i]` for `rays[i]` with `samplers[i]`: exactly what
    /// [`radiance`](Self::radiance) gives one ray at a time. Integrators override it to trace
    /// coherent rays (a tile of camera rays) together.
    ///
    /// # Panics
    /// If the slices differ in length.
    fn radiance_each(&self, rays: &[Ray], samplers: &mut [Sampler], out: &mut [Vec3]) {
        assert_eq!(rays.len(), out.len(), "one colour per ray");
        assert_eq!(rays.len(), samplers.len(), "one sampler per ray");
        for ((ray, sampler), colour) in rays.iter().zip(samplers).zip(out) {
            *colour = self.radiance(ray, sampler);
        }
    }

    /// How many rays wide the tiles are whose camera rays it is handed at once
    /// ([`radiance_each`](Self::radiance_each)), by default: eight, for 8×8 tiles of coherent
    /// camera rays (a pixel's each in a single pass; in a group of `n` passes each pixel's `n`
    /// samples side by side, `8 / n` pixels, at least one). The tiling never changes the pixels.
    fn tile_width(&self) -> u32 {
        8
    }

    /// The sampler this integrator's pictures use unless told otherwise.
    fn sampler_kind(&self) -> SamplerKind {
        SamplerKind::Sobol
    }

    /// Whether [`radiance_each`](Self::radiance_each) and
    /// [`radiance_and_layers_each`](Self::radiance_and_layers_each) draw numbers from their
    /// samplers. An integrator that never does (the lab's) says `false`, and the scheduler may
    /// then skip making them: it is handed samplers of no meaning (another band's, or
    /// placeholders), not its pixels', so it must not draw from them. Its pixel
    /// positions are still drawn as its samplers would draw them.
    fn draws_numbers(&self) -> bool {
        true
    }

    /// How many samples so far it counted as black for not being a finite, non-negative colour
    /// (the path tracers: a NaN from a degenerate triangle, an overflow); `raylab render`
    /// warns when there are any.
    fn discarded_samples(&self) -> u64 {
        0
    }

    /// How many extra layers (AOVs) it computes beside the colour: none, unless it wraps
    /// another integrator to add them ([`WithAovs`]).
    fn layer_count(&self) -> usize {
        0
    }

    /// The colour along each ray, as [`radiance_each`](Self::radiance_each) gives it, and
    /// [`layer_count`](Self::layer_count) layer values for each ray: `layers[i * count + k]` is
    /// layer `k` of ray `i`, from the same ray and the same sample.
    ///
    /// # Panics
    /// If the slices differ in length, or `layers` does not hold `count` values per ray.
    fn radiance_and_layers_each(
        &self,
        rays: &[Ray],
        samplers: &mut [Sampler],
        out: &mut [Vec3],
        layers: &mut [Vec3],
    ) {
        assert_eq!(layers.len(), rays.len() * self.layer_count(), "the layers of each ray");
        self.radiance_each(rays, samplers, out);
    }
}
