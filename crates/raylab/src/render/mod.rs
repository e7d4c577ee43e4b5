//! Rendering a frame: camera rays through every pixel, in parallel, one or more samples each.
//!
//! The image is cut into bands of rows that rayon's threads take in any order, and each band
//! into tiles whose camera rays are traced together. Every sample of a pixel draws its numbers
//! from a [`Sampler`] made from (seed, pixel, sample index) alone, so the picture is the same for
//! any thread count or tiling.
//!
//! The first two numbers place the sample in the pixel (with the [`Filter`]), the next two on
//! the lens when the camera has an aperture, and the integrator takes the rest. With the lab's
//! sampler, sample 0 of a pixel goes through its centre, which is the lab's one ray per pixel.
//! An [`Accumulator`] adds samples one pass at a time, which is how `raylab view` refines a still
//! picture; a render of `N` samples at once ([`render_samples`]) is the same passes in the same
//! order, so it gives the same pixels bit for bit.

use glam::{Vec2, Vec3};
use image::RgbImage;
use rayon::prelude::*;

use crate::camera::{Camera, RayGenerator};
use crate::film::{Film, FilmError};
pub use crate::filter::Filter;
use crate::integrator::Integrator;
use crate::ray::Ray;
use crate::region::Region;
use crate::sampling::{Sampler, SamplerKind};

mod window;

/// Rows per unit of parallel work by default: small enough to balance two cores; a band is
/// traced in tiles of `tile`×`band` pixels, whose rays are coherent (the accelerator traces them
/// as packets).
const BAND_ROWS: u32 = 8;
/// Tile width by default.
const TILE: u32 = 8;
/// The most pixels in a tile: what the tile's arrays on the stack hold.
const MAX_TILE_PIXELS: usize = 64;

/// How samples are drawn: the seed, the sampler (`None`: the integrator's choice), the filter and
/// the tiling (which never changes the pixels, only the order of the work).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleSettings {
    /// The seed every sampler derives from.
    pub seed: u64,
    /// The sampler, or `None` for [`Integrator::sampler_kind`].
    pub sampler: Option<SamplerKind>,
    /// The pixel filter.
    pub filter: Filter,
    /// Tile width and height in pixels (their product at most 64).
    pub tile: (u32, u32),
}

impl Default for SampleSettings {
    fn default() -> Self {
        SampleSettings { seed: 0, sampler: None, filter: Filter::Box, tile: (TILE, BAND_ROWS) }
    }
}

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
    for _ in 0..samples.max(1) {
        accumulator.add_sample_with_progress(camera, integrator, progress);
    }
    accumulator.mean()
}

/// Adds sample `sample` of every pixel of `region` (of the camera's image) to `pixels`, the
/// region's pixels row by row.
fn add_pass(
    camera: &Camera,
    integrator: &(impl Integrator + ?Sized),
    settings: &SampleSettings,
    sample: u32,
    region: Region,
    pixels: &mut [Vec3],
    progress: &(dyn Fn(u32) + Sync),
) -> u64 {
    let width = region.width() as usize;
    debug_assert_eq!(pixels.len() as u64, region.pixels());
    let rays = camera.rays();
    let kind = settings.sampler.unwrap_or_else(|| integrator.sampler_kind());
    let (_, band_rows) = tile_shape(settings.tile);
    #[cfg(target_arch = "x86_64")]
    let avx2 = std::arch::is_x86_feature_detected!("avx2");
    let discarded = std::sync::atomic::AtomicU64::new(0);
    let count = |n: u64| {
        if n > 0 {
            discarded.fetch_add(n, std::sync::atomic::Ordering::Relaxed);
        }
    };
    pixels.par_chunks_mut(width * band_rows).enumerate().for_each(|(band, pixels)| {
        let band = Band {
            camera: &rays,
            has_lens: camera.has_lens(),
            kind,
            settings,
            sample,
            width,
            first_row: region.y0 as usize + band * band_rows,
            first_column: region.x0 as usize,
        };
        #[cfg(target_arch = "x86_64")]
        if avx2 {
            // SAFETY: AVX2 was detected above.
            count(unsafe { band.add_avx2(integrator, pixels) });
            progress((pixels.len() / width) as u32);
            return;
        }
        count(band.add(integrator, pixels));
        progress((pixels.len() / width) as u32);
    });
    discarded.into_inner()
}

/// A band of whole rows of one pass ([`add_pass`]).
struct Band<'a> {
    camera: &'a RayGenerator,
    has_lens: bool,
    kind: SamplerKind,
    settings: &'a SampleSettings,
    sample: u32,
    /// Pixels per row.
    width: usize,
    /// The band's first row and column in the camera's image.
    first_row: usize,
    first_column: usize,
}

impl Band<'_> {
    /// [`add`](Self::add) compiled with AVX2 (camera rays, shading and accumulation in wider
    /// registers; the same operations, so the same bits: Rust never fuses a multiply and an
    /// add).
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn add_avx2(&self, integrator: &(impl Integrator + ?Sized), pixels: &mut [Vec3]) -> u64 {
        self.add(integrator, pixels)
    }

    /// Adds this pass's sample of every pixel of the band (`pixels`, its rows) tile by tile.
    #[inline(always)]
    /// Returns how many samples were not finite (NaN or infinite in a channel): they count as
    /// black, so that one bad sample cannot spoil its pixel for good.
    fn add(&self, integrator: &(impl Integrator + ?Sized), pixels: &mut [Vec3]) -> u64 {
        let mut discarded = 0;
        let (rays, kind, settings, sample) = (self.camera, self.kind, self.settings, self.sample);
        let (width, first_row, has_lens) = (self.width, self.first_row, self.has_lens);
        let first_column = self.first_column;
        let rows = pixels.len() / width;
        let (tile_width, _) = tile_shape(settings.tile);
        // A tile's rays, samplers and colours, on the stack.
        let mut tile_rays = [Ray::new(Vec3::ZERO, Vec3::Z); MAX_TILE_PIXELS];
        let mut samplers: [Sampler; MAX_TILE_PIXELS] =
            std::array::from_fn(|_| Sampler::new(kind, 0, (0, 0), 0));
        let mut colours = [Vec3::ZERO; MAX_TILE_PIXELS];
        for tile_x in (0..width).step_by(tile_width) {
            let columns = tile_x..(tile_x + tile_width).min(width);
            let n = columns.len() * rows;
            let mut slot = tile_rays.iter_mut().zip(samplers.iter_mut());
            for y in first_row..first_row + rows {
                for x in columns.clone() {
                    let (ray, sampler) = slot.next().expect("a tile's rays fit");
                    let x = first_column + x;
                    *sampler = Sampler::new(kind, settings.seed, (x as u32, y as u32), sample);
                    let offset = settings.filter.offset(sampler.pixel_2d());
                    let film = Vec2::new(x as f32 + offset.x, y as f32 + offset.y);
                    *ray = if has_lens {
                        rays.lens_ray(film, sampler.next_2d())
                    } else {
                        rays.ray(film.x, film.y)
                    };
                }
            }
            integrator.radiance_each(&tile_rays[..n], &mut samplers[..n], &mut colours[..n]);
            let mut colour = colours.iter();
            for y in 0..rows {
                for x in columns.clone() {
                    let colour = *colour.next().expect("one colour per ray");
                    if colour.is_finite() {
                        pixels[y * width + x] += colour;
                    } else {
                        discarded += 1;
                    }
                }
            }
        }
        discarded
    }
}

/// A tile shape that fits the tile arrays: both sides at least 1, at most 64 pixels.
fn tile_shape((width, height): (u32, u32)) -> (usize, usize) {
    let height = (height as usize).clamp(1, MAX_TILE_PIXELS);
    let width = (width as usize).clamp(1, MAX_TILE_PIXELS / height);
    (width, height)
}

/// Samples added up pass by pass: a picture that refines while the camera stands still.
#[derive(Clone, Debug)]
pub struct Accumulator {
    /// The sums of the region's pixels.
    sum: Film,
    samples: u32,
    /// The camera's image size.
    image: (u32, u32),
    /// The part of the image rendered.
    region: Region,
    /// Samples that were not finite and counted as black.
    discarded: u64,
    /// How samples are drawn; change it only before the first sample.
    pub settings: SampleSettings,
}

impl Accumulator {
    /// An empty accumulator for a `width×height` image.
    pub fn new(width: u32, height: u32) -> Result<Accumulator, FilmError> {
        Accumulator::for_region(width, height, Region::full(width, height))
    }

    /// An empty accumulator for the pixels of `region` of a `width×height` image (see
    /// [`Region`]): exactly the pixels the whole image's accumulator has there, bit for bit.
    ///
    /// # Panics
    /// If the region is empty or reaches outside the image ([`Region::new`] checks both).
    pub fn for_region(width: u32, height: u32, region: Region) -> Result<Accumulator, FilmError> {
        assert!(
            region.x0 < region.x1 && region.y0 < region.y1,
            "the region {region} must not be empty"
        );
        assert!(
            region.x1 <= width && region.y1 <= height,
            "the region {region} must lie in the {width}×{height} image"
        );
        Ok(Accumulator {
            sum: Film::new(region.width(), region.height())?,
            samples: 0,
            image: (width, height),
            region,
            discarded: 0,
            settings: SampleSettings::default(),
        })
    }

    /// An accumulator that goes on from `samples` samples whose sums are `sums` (a checkpoint's,
    /// see [`sums`](Self::sums)): the next sample added is sample `samples`, so the picture is
    /// the one an accumulator that never stopped would have.
    ///
    /// # Panics
    /// As [`for_region`](Self::for_region), and if `sums` is not the region's size.
    pub fn resume(
        (width, height): (u32, u32),
        region: Region,
        sums: Film,
        samples: u32,
        settings: SampleSettings,
    ) -> Result<Accumulator, FilmError> {
        let mut accumulator = Accumulator::for_region(width, height, region)?;
        assert_eq!(
            (sums.width(), sums.height()),
            (region.width(), region.height()),
            "the sums must be the region's size"
        );
        accumulator.sum = sums;
        accumulator.samples = samples;
        accumulator.settings = settings;
        Ok(accumulator)
    }

    /// Width in pixels of what it holds (the region's).
    pub fn width(&self) -> u32 {
        self.sum.width()
    }

    /// Height in pixels of what it holds (the region's).
    pub fn height(&self) -> u32 {
        self.sum.height()
    }

    /// The size of the camera's whole image.
    pub fn image_size(&self) -> (u32, u32) {
        self.image
    }

    /// The part of the image it holds.
    pub fn region(&self) -> Region {
        self.region
    }

    /// The sum of every sample of each pixel so far (the region's pixels, row by row): with
    /// [`samples`](Self::samples), all a checkpoint needs.
    pub fn sums(&self) -> &Film {
        &self.sum
    }

    /// Samples per pixel so far.
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// How many samples so far were NaN or infinite in some channel: they are counted as black
    /// instead of reaching the picture (`raylab render` reports them).
    pub fn discarded_samples(&self) -> u64 {
        self.discarded
    }

    /// Forgets every sample (the camera moved).
    pub fn clear(&mut self) {
        self.sum.pixels_mut().fill(Vec3::ZERO);
        self.discarded = 0;
        self.samples = 0;
    }

    /// Renders the next sample of every pixel and adds it in.
    ///
    /// # Panics
    /// If the camera's image size is not the accumulator's.
    pub fn add_sample(&mut self, camera: &Camera, integrator: &(impl Integrator + ?Sized)) {
        self.add_sample_with_progress(camera, integrator, &|_| {});
    }

    /// [`add_sample`](Self::add_sample), calling `progress` with the rows finished.
    pub fn add_sample_with_progress(
        &mut self,
        camera: &Camera,
        integrator: &(impl Integrator + ?Sized),
        progress: &(dyn Fn(u32) + Sync),
    ) {
        assert_eq!(
            (camera.width, camera.height),
            self.image,
            "the camera's image size must be the accumulator's"
        );
        let (settings, sample, region) = (&self.settings, self.samples, self.region);
        self.discarded +=
            add_pass(camera, integrator, settings, sample, region, self.sum.pixels_mut(), progress);
        self.samples += 1;
    }

    /// The factor that turns sums into means: `1/samples` (black before the first sample).
    #[inline]
    fn mean_factor(&self) -> f32 {
        1.0 / self.samples.max(1) as f32
    }

    /// The mean of the samples so far, as a film.
    pub fn mean(&self) -> Result<Film, FilmError> {
        let mut film = Film::new(self.width(), self.height())?;
        let factor = self.mean_factor();
        for (pixel, sum) in film.pixels_mut().iter_mut().zip(self.sum.pixels()) {
            *pixel = *sum * factor;
        }
        Ok(film)
    }

    /// The mean as 8-bit RGB, shown as the lab shows it (see [`Film::to_rgb8_clamped`]).
    pub fn to_rgb8_clamped(&self) -> Result<RgbImage, FilmError> {
        self.mean()?.to_rgb8_clamped()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A band renders the same bits compiled for AVX2 as for the baseline instruction set, for
    /// the lab's integrator and the path tracer (a pinhole and a lens), two samples each.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn bands_are_the_same_bits_with_avx2() {
        use crate::bvh::Bvh;
        use crate::integrator::{Lab, Path, PathSettings, Stage};
        use crate::scene::Scene;
        if !std::arch::is_x86_feature_detected!("avx2") {
            eprintln!("skipped: this CPU has no AVX2 (its band is never used)");
            return;
        }
        let scene = Scene::built_in("cornell").expect("the lab scene");
        let bvh = Bvh::new(&scene.vertices());
        let lab = Lab::new(&scene, &bvh, Stage::Ambient);
        let path = Path::new(&scene, &bvh, PathSettings::default());
        let (width, height) = (48, 24);
        for lens in [false, true] {
            let mut camera = crate::Camera::lab(width, height);
            if lens {
                camera.aperture_radius = 0.05;
                camera.focus_distance = 3.0;
            }
            let integrators: [&dyn Integrator; 2] = [&lab, &path];
            for integrator in integrators {
                let rays = camera.rays();
                let settings = SampleSettings::default();
                let kind = integrator.sampler_kind();
                let mut pixels = [vec![Vec3::ZERO; width as usize * height as usize], vec![]];
                pixels[1] = pixels[0].clone();
                let (_, band_rows) = tile_shape(settings.tile);
                let chunk = width as usize * band_rows;
                for sample in 0..2 {
                    let [base, wide] = &mut pixels;
                    for (b, (base, wide)) in
                        base.chunks_mut(chunk).zip(wide.chunks_mut(chunk)).enumerate()
                    {
                        let band = Band {
                            camera: &rays,
                            has_lens: camera.has_lens(),
                            kind,
                            settings: &settings,
                            sample,
                            width: width as usize,
                            first_row: b * band_rows,
                            first_column: 0,
                        };
                        assert_eq!(band.add(integrator, base), 0);
                        // SAFETY: AVX2 was detected above.
                        assert_eq!(unsafe { band.add_avx2(integrator, wide) }, 0);
                    }
                }
                let bits = |p: &[Vec3]| -> Vec<[u32; 3]> {
                    p.iter().map(|v| v.to_array().map(f32::to_bits)).collect()
                };
                assert!(pixels[0].iter().any(|p| *p != Vec3::ZERO));
                assert_eq!(bits(&pixels[0]), bits(&pixels[1]), "lens {lens}");
            }
        }
    }

    /// An accumulator of a region holds exactly the pixels of the whole image's there, for the
    /// lab's integrator and the path tracer, regions at odd places and of odd sizes.
    #[test]
    fn regions_are_the_whole_images_pixels() {
        use crate::bvh::Bvh;
        use crate::integrator::{Lab, Path, PathSettings, Stage};
        use crate::scene::Scene;
        let scene = Scene::built_in("cornell").expect("the lab scene");
        let bvh = Bvh::new(&scene.vertices());
        let lab = Lab::new(&scene, &bvh, Stage::Ambient);
        let path = Path::new(&scene, &bvh, PathSettings::default());
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
