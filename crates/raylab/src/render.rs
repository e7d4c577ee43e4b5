//! Rendering a frame: one camera ray per pixel, in parallel.
//!
//! The image is cut into bands of rows that rayon's threads take in any order, and each band
//! into 8×8 tiles whose camera rays are traced together. Every pixel depends only on its own
//! coordinates, so the picture is the same for any thread count or tiling.

use glam::Vec3;
use rayon::prelude::*;

use crate::camera::Camera;
use crate::film::{Film, FilmError};
use crate::integrator::Integrator;
use crate::ray::Ray;

/// Rows per unit of parallel work: small enough to balance two cores; a band is traced in
/// tiles of `TILE`×`BAND_ROWS` pixels, whose rays are coherent (the accelerator traces them as
/// packets).
const BAND_ROWS: usize = 8;
/// Tile width.
const TILE: usize = 8;

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
    let width = camera.width as usize;
    let rays = camera.rays();
    film.pixels_mut().par_chunks_mut(width * BAND_ROWS).enumerate().for_each(|(band, pixels)| {
        let first_row = band * BAND_ROWS;
        let rows = pixels.len() / width;
        // A tile's rays and colours, on the stack.
        let mut tile_rays = [Ray::new(Vec3::ZERO, Vec3::Z); TILE * BAND_ROWS];
        let mut colours = [Vec3::ZERO; TILE * BAND_ROWS];
        for tile_x in (0..width).step_by(TILE) {
            let columns = tile_x..(tile_x + TILE).min(width);
            let n = columns.len() * rows;
            let mut ray = tile_rays.iter_mut();
            for y in 0..rows {
                for x in columns.clone() {
                    *ray.next().expect("a tile's rays fit") =
                        rays.pixel_ray(x as u32, (first_row + y) as u32);
                }
            }
            integrator.radiance_each(&tile_rays[..n], &mut colours[..n]);
            let mut colour = colours.iter();
            for y in 0..rows {
                for x in columns.clone() {
                    pixels[y * width + x] = *colour.next().expect("one colour per ray");
                }
            }
        }
        progress(rows as u32);
    });
    Ok(film)
}
