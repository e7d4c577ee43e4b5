//! Rendering a frame: camera rays through every pixel, in parallel, one or more samples each.
//!
//! The image is cut into bands of rows that rayon's threads take in any order, and each band
//! into tiles whose camera rays are traced together. Every sample of a pixel draws its numbers
//! from a [`Sampler`](crate::sampling::Sampler) made from (seed, pixel, sample index) alone, so
//! the picture is the same for any thread count or tiling.
//!
//! The first two numbers place the sample in the pixel (with the [`Filter`](crate::filter::Filter)), the next two on
//! the lens when the camera has an aperture, and the integrator takes the rest. With the lab's
//! sampler, sample 0 of a pixel goes through its centre, which is the lab's one ray per pixel.
//! An [`Accumulator`] adds samples a pass at a time, which is how `raylab view` refines a still
//! picture, or a group of passes at a time, each pixel's samples traced side by side
//! ([`Accumulator::add_samples_with_progress`], as `raylab render` and [`render_samples`] do):
//! each pixel's samples are added in the order of their indices either way, so the pixels are
//! the same bit for bit.

use crate::camera::Camera;
use crate::film::{Film, FilmError};
use crate::integrator::Integrator;

mod accumulator;
mod band;
mod passes;
mod settings;
mod sums;
mod window;

pub use accumulator::Accumulator;
pub use settings::{PASS_GROUP, SampleSettings};

/// Renders the camera's whole image with one sample per pixel (with the lab's integrator, one
/// ray through each pixel's centre).
///
/// `progress` is called with the number of rows just finished, from the worker threads; use it
/// for a progress bar or pass `&|_| {}`. Runs on the current rayon thread pool: use
/// [`rayon::ThreadPool::install`] to choose the thread count.
pub fn render(
    camera: &Camera,
    integrator: &(impl Integrator + ?Sized),
    progress: &(dyn Fn(u32) + Sync),
) -> Result<Film, FilmError> {
    render_samples(camera, integrator, 1, progress)
}

/// Renders `samples` samples per pixel (at least 1) with the default [`SampleSettings`] and
/// returns their mean. `progress` gets rows finished, `height` per sample. Exactly the pixels of
/// an [`Accumulator`] given the same samples.
pub fn render_samples(
    camera: &Camera,
    integrator: &(impl Integrator + ?Sized),
    samples: u32,
    progress: &(dyn Fn(u32) + Sync),
) -> Result<Film, FilmError> {
    let mut accumulator = Accumulator::new(camera.width, camera.height)?;
    // In groups of up to sixteen passes, each pixel's samples side by side: the same pixels.
    accumulator.add_samples_with_progress(camera, integrator, samples.max(1), progress);
    accumulator.mean()
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::ray::Ray;
    use crate::region::Region;
    use crate::sampling::Sampler;
    use crate::sampling::SamplerKind;

    /// An accumulator of a region holds exactly the pixels of the whole image's there, for the
    /// lab's integrator and the path tracer, regions at odd places and of odd sizes.
    #[test]
    fn regions_are_the_whole_images_pixels() {
        use crate::bvh::Bvh;
        use crate::integrator::{Lab, PathScalar, PathSettings, Stage};
        use crate::scene::Scene;
        let scene = Scene::built_in("cornell").expect("the lab scene");
        let bvh = Bvh::new(&scene.vertices());
        let lab = Lab::new(&scene, &bvh, Stage::Ambient);
        let path = PathScalar::new(&scene, &bvh, PathSettings::default());
        let (width, height) = (37, 29);
        let camera = crate::Camera::lab(width, height);
        let integrators: [&dyn Integrator; 2] = [&lab, &path];
        for integrator in integrators {
            let mut whole = Accumulator::new(width, height).unwrap();
            for _ in 0..2 {
                whole.add_sample(&camera, integrator);
            }
            for corners in [[0, 0, 37, 29], [3, 5, 20, 6], [36, 0, 37, 29], [9, 11, 31, 28]] {
                let region = Region::new(corners, width, height).unwrap();
                let mut part = Accumulator::for_region(width, height, region).unwrap();
                for _ in 0..2 {
                    part.add_sample(&camera, integrator);
                }
                let mean = part.mean().unwrap();
                let all = whole.mean().unwrap();
                for y in region.y0..region.y1 {
                    for x in region.x0..region.x1 {
                        let (a, b) = (mean.pixel(x - region.x0, y - region.y0), all.pixel(x, y));
                        assert_eq!(a.to_array().map(f32::to_bits), b.to_array().map(f32::to_bits));
                    }
                }
                assert!(mean.pixels().iter().any(|p| *p != Vec3::ZERO), "{region}");
            }
        }
    }

    /// Passes in groups give the pixels, layers and discarded counts of the same passes one by
    /// one, to the bit: the lab's integrator, the wavefront path tracer with an albedo and a
    /// depth layer, and an integrator that returns NaN and infinities; every sampler kind; a
    /// pinhole and a thin-lens camera; tiles of odd shapes, and bands so tall (200 rows) that a
    /// group of more than five passes is split; a region at an odd place; groups of every size
    /// from 1 to 16 (the last group short).
    #[test]
    fn groups_of_passes_give_the_passes_pixels() {
        use crate::bvh::Bvh;
        use crate::integrator::{Lab, Path, PathSettings, Stage, WithAovs};
        use crate::scene::Scene;
        use crate::settings::AovKind;
        /// Radiance from the ray's direction, NaN or infinite where it points up and left.
        struct Spoiled;
        impl Integrator for Spoiled {
            fn radiance(&self, ray: &Ray, _: &mut Sampler) -> Vec3 {
                let d = ray.direction;
                match (d.x < 0.0, d.y) {
                    (true, y) if y < -0.2 => Vec3::NAN,
                    (true, y) if y < -0.1 => Vec3::new(1.0, f32::INFINITY, 1.0),
                    _ => d.abs(),
                }
            }
        }
        let scene = Scene::built_in("cornell").expect("the lab scene");
        let bvh = Bvh::new(&scene.vertices());
        let lab = Lab::new(&scene, &bvh, Stage::Ambient);
        let path = Path::new(&scene, &bvh, PathSettings::default());
        let aovs = [AovKind::Albedo, AovKind::Depth];
        let with_layers = WithAovs::new(&path, &scene, &bvh, &aovs);
        let (width, height) = (23, 13);
        let pinhole = crate::Camera::lab(width, height);
        let lens = crate::Camera { aperture_radius: 0.05, focus_distance: 3.0, ..pinhole };
        let region = Region::new([2, 1, 21, 12], width, height).unwrap();
        const SPP: u32 = 21;
        let cases: [(&dyn Integrator, usize, SamplerKind, &crate::Camera); 5] = [
            (&lab, 0, SamplerKind::Lab, &pinhole),
            (&with_layers, 2, SamplerKind::Sobol, &pinhole),
            (&with_layers, 2, SamplerKind::MultiJitter, &lens),
            (&path, 0, SamplerKind::Independent, &lens),
            (&Spoiled, 0, SamplerKind::Sobol, &pinhole),
        ];
        for (integrator, layers, kind, camera) in cases {
            for tile in [(0, 8), (5, 3), (64, 1), (0, 200)] {
                let accumulator = || {
                    let mut a = Accumulator::for_region(width, height, region).unwrap();
                    a.settings.sampler = Some(kind);
                    a.settings.count = SPP;
                    a.settings.tile = tile;
                    a.settings.seed = 3;
                    a.with_layers(layers, None).unwrap()
                };
                let mut single = accumulator();
                for _ in 0..SPP {
                    single.add_sample(camera, integrator);
                }
                let bits = |a: &Accumulator| {
                    let films = std::iter::once(a.sums()).chain(a.layer_sums());
                    let pixels = films.flat_map(|f| f.pixels().iter().flat_map(|p| p.to_array()));
                    pixels.map(f32::to_bits).collect::<Vec<_>>()
                };
                // A picture started again in used memory is a fresh picture's first sample.
                let (mut once, mut restarted) = (accumulator(), accumulator());
                once.add_sample(camera, integrator);
                for _ in 0..3 {
                    restarted.add_sample(camera, integrator);
                }
                restarted.restart_with_sample(camera, integrator);
                let case = format!("{kind:?} {tile:?} restarted");
                assert_eq!(restarted.samples(), 1, "{case}");
                assert_eq!(restarted.discarded_samples(), once.discarded_samples(), "{case}");
                assert!(bits(&restarted) == bits(&once), "{case}");
                for group in 1..=PASS_GROUP + 1 {
                    let mut grouped = accumulator();
                    while grouped.samples() < SPP {
                        let count = group.min(SPP - grouped.samples());
                        grouped.add_samples_with_progress(camera, integrator, count, &|_| {});
                    }
                    let case = format!("{kind:?} {tile:?} groups of {group}");
                    assert_eq!(grouped.samples(), SPP, "{case}");
                    assert_eq!(grouped.discarded_samples(), single.discarded_samples(), "{case}");
                    assert!(bits(&grouped) == bits(&single), "{case}");
                }
            }
        }
        // The spoiled integrator's samples were discarded, in groups as one by one.
        let mut spoiled = Accumulator::new(width, height).unwrap();
        spoiled.add_samples_with_progress(&pinhole, &Spoiled, SPP, &|_| {});
        assert!(spoiled.discarded_samples() >= u64::from(SPP), "{}", spoiled.discarded_samples());
    }

    /// Samples that are NaN or infinite never reach the picture: they are counted and count as
    /// black, and the finite samples still do.
    #[test]
    fn samples_that_are_not_finite_are_counted_not_added() {
        use std::sync::atomic::{AtomicU64, Ordering};
        /// Radiance 1, except NaN, +∞ or −∞ (in one channel or all) for rays up and left; it
        /// counts what it spoils.
        struct Spoiled(AtomicU64);
        impl Integrator for Spoiled {
            fn radiance(&self, ray: &Ray, _: &mut Sampler) -> Vec3 {
                let d = ray.direction;
                let spoiled = match (d.x < 0.0, d.y) {
                    (true, y) if y < -0.3 => Vec3::NAN,
                    (true, y) if y < -0.2 => Vec3::new(1.0, f32::INFINITY, 1.0),
                    (true, y) if y < -0.1 => Vec3::new(1.0, 1.0, f32::NEG_INFINITY),
                    _ => return Vec3::ONE,
                };
                self.0.fetch_add(1, Ordering::Relaxed);
                spoiled
            }
        }
        let spoiled = Spoiled(AtomicU64::new(0));
        let camera = crate::Camera::lab(8, 8);
        let mut accumulator = Accumulator::new(8, 8).unwrap();
        accumulator.add_sample(&camera, &spoiled);
        accumulator.add_sample(&camera, &spoiled);
        let returned = spoiled.0.load(Ordering::Relaxed);
        assert!(returned >= 8, "{returned} samples spoiled");
        assert_eq!(accumulator.discarded_samples(), returned);
        let mean = accumulator.mean().unwrap();
        assert!(mean.pixels().iter().all(|p| p.is_finite()));
        // Every pixel's mean is its finite samples' share: 0, 1/2 or 1.
        assert!(mean.pixels().iter().all(|p| [0.0, 0.5, 1.0].contains(&p.x) && p.x == p.z));
        assert!(
            mean.pixels().iter().any(|p| p.x == 0.0) && mean.pixels().iter().any(|p| p.x == 1.0)
        );
        accumulator.clear();
        assert_eq!(accumulator.discarded_samples(), 0);
    }
}
