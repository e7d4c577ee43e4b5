//! The film that samples are added into: per-pixel sums, pass by pass.

use glam::Vec3;
#[cfg(feature = "io")]
use image::RgbImage;
use rayon::prelude::*;

use super::passes::{Pass, add_pass};
use super::settings::SampleSettings;
use crate::camera::Camera;
use crate::film::{Film, FilmError};
use crate::integrator::Integrator;
use crate::region::Region;

/// Pixels per task when sums are cleared.
const CLEAR_CHUNK: usize = 16 * 1024;

/// Samples added up pass by pass: a picture that refines while the camera stands still.
#[derive(Clone, Debug)]
pub struct Accumulator {
    /// The sums of the region's pixels.
    pub(super) sum: Film,
    /// The sums of each extra layer's pixels (see [`with_layers`](Self::with_layers)).
    layers: Vec<Film>,
    pub(super) samples: u32,
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
            layers: Vec::new(),
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

    /// The same accumulator with `count` extra layers (AOVs), summed beside the picture from the
    /// same samples: for an integrator whose [`layer_count`](Integrator::layer_count) is
    /// `count`. `sums`, where given, are the layers' sums so far (a checkpoint's); else zero.
    ///
    /// # Panics
    /// If a film of `sums` is not the region's size, or there are sums for another count.
    pub fn with_layers(mut self, count: usize, sums: Option<Vec<Film>>) -> Result<Self, FilmError> {
        self.layers = match sums {
            Some(sums) => {
                assert_eq!(sums.len(), count, "sums for each layer");
                for film in &sums {
                    assert_eq!(
                        (film.width(), film.height()),
                        (self.width(), self.height()),
                        "a layer's sums must be the region's size"
                    );
                }
                sums
            }
            None => (0..count)
                .map(|_| Film::new(self.width(), self.height()))
                .collect::<Result<_, _>>()?,
        };
        Ok(self)
    }

    /// The sums of each extra layer so far (for a checkpoint).
    pub fn layer_sums(&self) -> &[Film] {
        &self.layers
    }

    /// The mean of extra layer `k`'s samples so far.
    ///
    /// # Panics
    /// If there is no layer `k`.
    pub fn layer_mean(&self, k: usize) -> Result<Film, FilmError> {
        mean_of(&self.layers[k], self.mean_factor())
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
        // On the current pool's threads: a window's sums are megabytes, and `raylab view`
        // clears them for every moving frame.
        let clear = |pixels: &mut [Vec3]| {
            pixels.par_chunks_mut(CLEAR_CHUNK).for_each(|chunk| chunk.fill(Vec3::ZERO))
        };
        clear(self.sum.pixels_mut());
        for layer in &mut self.layers {
            clear(layer.pixels_mut());
        }
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

    /// [`clear`](Self::clear) and then [`add_sample`](Self::add_sample), the same sums to the
    /// bit, in one pass: each band of rows is zeroed just before its first sample is added
    /// (`raylab view` starts a new picture every frame while the camera moves).
    ///
    /// # Panics
    /// If the camera's image size is not the accumulator's.
    pub fn restart_with_sample(
        &mut self,
        camera: &Camera,
        integrator: &(impl Integrator + ?Sized),
    ) {
        self.add_pass_of(camera, integrator, 1, true, &|_| {});
    }

    /// [`add_sample`](Self::add_sample), calling `progress` with the rows finished.
    pub fn add_sample_with_progress(
        &mut self,
        camera: &Camera,
        integrator: &(impl Integrator + ?Sized),
        progress: &(dyn Fn(u32) + Sync),
    ) {
        self.add_samples_with_progress(camera, integrator, 1, progress);
    }

    /// Adds `count` samples of every pixel (at least 1), as many calls of
    /// [`add_sample`](Self::add_sample) would, to the bit, but with each pixel's samples traced
    /// side by side: a pixel's camera rays make coherent packets, and its paths start on the
    /// same surface. `progress` gets the rows finished, a row once per sample.
    pub fn add_samples_with_progress(
        &mut self,
        camera: &Camera,
        integrator: &(impl Integrator + ?Sized),
        count: u32,
        progress: &(dyn Fn(u32) + Sync),
    ) {
        self.add_pass_of(camera, integrator, count, false, progress);
    }

    /// [`add_samples_with_progress`](Self::add_samples_with_progress), the sums first zeroed
    /// band by band where `restart` is set.
    fn add_pass_of(
        &mut self,
        camera: &Camera,
        integrator: &(impl Integrator + ?Sized),
        count: u32,
        restart: bool,
        progress: &(dyn Fn(u32) + Sync),
    ) {
        assert_eq!(
            (camera.width, camera.height),
            self.image,
            "the camera's image size must be the accumulator's"
        );
        assert_eq!(
            integrator.layer_count(),
            self.layers.len(),
            "the accumulator must have the integrator's layers"
        );
        if restart {
            // (After the checks: a failed one leaves the picture as it was.)
            self.discarded = 0;
            self.samples = 0;
        }
        // At least one; no more than the sample indices hold.
        let count = count.max(1).min(u32::MAX - self.samples);
        if count == 0 {
            return;
        }
        let (settings, sample, region) = (&self.settings, self.samples, self.region);
        let (sum, layers) = (self.sum.pixels_mut(), &mut self.layers);
        let pass = Pass { settings, sample, count, region, restart };
        self.discarded += add_pass(camera, integrator, pass, sum, layers, progress);
        self.samples += count;
    }

    /// The factor that turns sums into means: `1/samples` (black before the first sample).
    #[inline]
    pub(super) fn mean_factor(&self) -> f32 {
        1.0 / self.samples.max(1) as f32
    }

    /// The mean of the samples so far, as a film.
    pub fn mean(&self) -> Result<Film, FilmError> {
        mean_of(&self.sum, self.mean_factor())
    }

    #[cfg(feature = "io")]
    /// The mean as 8-bit RGB, shown as the lab shows it (see [`Film::to_rgb8_clamped`]).
    pub fn to_rgb8_clamped(&self) -> Result<RgbImage, FilmError> {
        self.mean()?.to_rgb8_clamped()
    }
}

/// Each pixel of `sums` times `factor`, as a film.
fn mean_of(sums: &Film, factor: f32) -> Result<Film, FilmError> {
    let mut film = Film::new(sums.width(), sums.height())?;
    for (pixel, sum) in film.pixels_mut().iter_mut().zip(sums.pixels()) {
        *pixel = *sum * factor;
    }
    Ok(film)
}
