//! Rendering a frame: one camera ray per pixel, in parallel.
//!
//! The image is cut into bands of rows that rayon's threads take in any order. Every pixel
//! depends only on its own coordinates, so the picture is the same for any thread count.

use rayon::prelude::*;

use crate::camera::Camera;
use crate::film::{Film, FilmError};
use crate::integrator::Integrator;

/// Rows per unit of parallel work: small enough to balance two cores, large enough to keep the
/// rays of a band coherent.
const BAND_ROWS: usize = 4;

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
        for (i, pixel) in pixels.iter_mut().enumerate() {
            let (x, y) = (i % width, first_row + i / width);
            *pixel = integrator.radiance(&rays.pixel_ray(x as u32, y as u32));
        }
        progress((pixels.len() / width) as u32);
    });
    Ok(film)
}
