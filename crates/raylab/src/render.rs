//! Rendering a frame: camera rays through every pixel, in parallel, one or more samples each.
//!
//! The image is cut into bands of rows that rayon's threads take in any order, and each band
//! into 8×8 tiles whose camera rays are traced together. Every pixel depends only on its own
//! coordinates and the sample's number, so the picture is the same for any thread count or
//! tiling.
//!
//! Sample 0 of a pixel goes through its centre, which is the lab's one ray per pixel; samples
//! 1, 2, … are spread over the pixel (anti-aliasing) by [`sample_offset`](crate::sampling::sample_offset). An [`Accumulator`]
//! adds samples one pass at a time, which is how `raylab view` refines a still picture; a render
//! of `N` samples at once ([`render_samples`]) is the same passes in the same order, so it gives
//! the same pixels bit for bit.

use glam::Vec3;
use image::RgbImage;
use rayon::prelude::*;

use crate::camera::Camera;
use crate::film::{Film, FilmError, to_8bit_clamped};
use crate::integrator::Integrator;
use crate::ray::Ray;

/// Rows per unit of parallel work: small enough to balance two cores; a band is traced in
/// tiles of `TILE`×`BAND_ROWS` pixels, whose rays are coherent (the accelerator traces them as
/// packets).
const BAND_ROWS: usize = 8;
/// Tile width.
const TILE: usize = 8;
/// Rows per parallel task when writing a window's pixels.
const ROWS_PER_TASK: usize = 16;

/// Renders the camera's whole image with one ray through each pixel's centre.
///
/// `progress` is called with the number of rows just finished, from the worker threads; use it
/// for a progress bar or pass `&|_| {}`. Runs on the current rayon thread pool: use
/// [`rayon::ThreadPool::install`] to choose the thread count.
pub fn render(
    camera: &Camera,
    integrator: &impl Integrator,
    progress: &(dyn Fn(u32) + Sync),
) -> Result<Film, FilmError> {
    let mut film = Film::new(camera.width, camera.height)?;
    add_pass(camera, integrator, 0, film.pixels_mut(), progress);
    Ok(film)
}

/// Renders `samples` samples per pixel (at least 1) and returns their mean: sample 0 through
/// each pixel's centre, then spread over the pixel. `progress` gets rows finished, `height` per
/// sample. Exactly the pixels of an [`Accumulator`] given the same samples.
pub fn render_samples(
    camera: &Camera,
    integrator: &impl Integrator,
    samples: u32,
    progress: &(dyn Fn(u32) + Sync),
) -> Result<Film, FilmError> {
    let mut accumulator = Accumulator::new(camera.width, camera.height)?;
    for _ in 0..samples.max(1) {
        accumulator.add_sample_with_progress(camera, integrator, progress);
    }
    accumulator.mean()
}

/// Adds sample `sample` of every pixel to `pixels` (the camera's image, row by row).
fn add_pass(
    camera: &Camera,
    integrator: &impl Integrator,
    sample: u32,
    pixels: &mut [Vec3],
    progress: &(dyn Fn(u32) + Sync),
) {
    let width = camera.width as usize;
    debug_assert_eq!(pixels.len(), width * camera.height as usize);
    let rays = camera.rays();
    pixels.par_chunks_mut(width * BAND_ROWS).enumerate().for_each(|(band, pixels)| {
        let first_row = band * BAND_ROWS;
        let rows = pixels.len() / width;
        // A tile's rays and colours, on the stack.
        let mut tile_rays = [Ray::new(Vec3::ZERO, Vec3::Z); TILE * BAND_ROWS];
        let mut colours = [Vec3::ZERO; TILE * BAND_ROWS];
        for tile_x in (0..width).step_by(TILE) {
            let columns = tile_x..(tile_x + TILE).min(width);
            let n = columns.len() * rows;
            let mut ray = tile_rays.iter_mut();
            for y in first_row..first_row + rows {
                for x in columns.clone() {
                    let offset = crate::sampling::sample_offset(x as u32, y as u32, sample);
                    *ray.next().expect("a tile's rays fit") =
                        rays.ray(x as f32 + offset.x, y as f32 + offset.y);
                }
            }
            integrator.radiance_each(&tile_rays[..n], &mut colours[..n]);
            let mut colour = colours.iter();
            for y in 0..rows {
                for x in columns.clone() {
                    pixels[y * width + x] += *colour.next().expect("one colour per ray");
                }
            }
        }
        progress(rows as u32);
    });
}

/// Samples added up pass by pass: a picture that refines while the camera stands still.
#[derive(Clone, Debug)]
pub struct Accumulator {
    sum: Film,
    samples: u32,
}

impl Accumulator {
    /// An empty accumulator for a `width×height` image.
    pub fn new(width: u32, height: u32) -> Result<Accumulator, FilmError> {
        Ok(Accumulator { sum: Film::new(width, height)?, samples: 0 })
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.sum.width()
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.sum.height()
    }

    /// Samples per pixel so far.
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// Forgets every sample (the camera moved).
    pub fn clear(&mut self) {
        self.sum.pixels_mut().fill(Vec3::ZERO);
        self.samples = 0;
    }

    /// Renders the next sample of every pixel and adds it in.
    ///
    /// # Panics
    /// If the camera's image size is not the accumulator's.
    pub fn add_sample(&mut self, camera: &Camera, integrator: &impl Integrator) {
        self.add_sample_with_progress(camera, integrator, &|_| {});
    }

    fn add_sample_with_progress(
        &mut self,
        camera: &Camera,
        integrator: &impl Integrator,
        progress: &(dyn Fn(u32) + Sync),
    ) {
        assert_eq!(
            (camera.width, camera.height),
            (self.width(), self.height()),
            "the camera's image size must be the accumulator's"
        );
        add_pass(camera, integrator, self.samples, self.sum.pixels_mut(), progress);
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

    /// Writes the mean into a `width×height` window buffer of `0x00RRGGBB` words, scaled to fill
    /// it by nearest neighbour (a picture rendered at a fraction of the window's resolution fills
    /// the window). Channels as in [`Film::to_rgb8_clamped`]. Runs on the current rayon pool.
    ///
    /// # Panics
    /// If `out` does not hold `width×height` words.
    pub fn write_0rgb(&self, out: &mut [u32], width: u32, height: u32) {
        assert_eq!(out.len(), width as usize * height as usize, "a word per window pixel");
        let (source_width, source_height) = (self.width() as usize, self.height() as usize);
        let factor = self.mean_factor();
        let word = |sum: &Vec3| {
            let [r, g, b] = (*sum * factor).to_array().map(to_8bit_clamped);
            (r as u32) << 16 | (g as u32) << 8 | b as u32
        };
        if (source_width, source_height) == (width as usize, height as usize) {
            // Same size: pixel for pixel.
            out.par_chunks_mut(ROWS_PER_TASK * source_width)
                .zip(self.sum.pixels().par_chunks(ROWS_PER_TASK * source_width))
                .for_each(|(out, sums)| out.iter_mut().zip(sums).for_each(|(w, s)| *w = word(s)));
            return;
        }
        let columns: Vec<usize> = (0..width as usize)
            .map(|x| (x * source_width / width as usize).min(source_width - 1))
            .collect();
        out.par_chunks_exact_mut(width as usize).enumerate().for_each(|(y, row)| {
            let source_row = (y * source_height / height as usize).min(source_height - 1);
            let sums = &self.sum.pixels()[source_row * source_width..][..source_width];
            for (w, &x) in row.iter_mut().zip(&columns) {
                *w = word(&sums[x]);
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn window_words_are_nearest_neighbour_and_clamped() {
        let mut accumulator = Accumulator::new(2, 1).unwrap();
        accumulator
            .sum
            .pixels_mut()
            .copy_from_slice(&[Vec3::new(2.0, 1.0, 0.5), Vec3::new(-1.0, 0.0, 0.25)]);
        accumulator.samples = 2;
        let mut out = [0u32; 4 * 2];
        accumulator.write_0rgb(&mut out, 4, 2);
        let left = 255 << 16 | 128 << 8 | 64; // (1, 0.5, 0.25)
        let right = 32; // (0, 0, 0.125)
        assert_eq!(out, [left, left, right, right, left, left, right, right]);
        let mut one = [0u32; 1];
        accumulator.write_0rgb(&mut one, 1, 1);
        assert_eq!(one, [left]);
    }
}
