//! A band of whole rows of a group of passes: its tiles' camera rays, traced together by the
//! integrator, and their colours added to the band's sums (see [`passes`](super::passes)).

use glam::{Vec2, Vec3};

use super::settings::SampleSettings;
use super::sums::add_finite;
use crate::camera::RayGenerator;
use crate::integrator::Integrator;
use crate::ray::Ray;
use crate::sampling::{Grid, Sampler, SamplerKind, sample_offset};

/// The most pixels in a tile: what a band's tile arrays hold.
pub(super) const MAX_TILE_PIXELS: usize = 1024;

/// A tile shape that fits the tile arrays: both sides at least 1, at most 1,024 pixels.
pub(super) fn tile_shape((width, height): (u32, u32)) -> (usize, usize) {
    let height = (height as usize).clamp(1, MAX_TILE_PIXELS);
    let width = (width as usize).clamp(1, MAX_TILE_PIXELS / height);
    (width, height)
}

/// A band of whole rows of a group of passes (`passes.rs`).
pub(super) struct Band<'a> {
    pub(super) camera: &'a RayGenerator,
    pub(super) has_lens: bool,
    pub(super) kind: SamplerKind,
    pub(super) settings: &'a SampleSettings,
    /// The first sample, and how many of each pixel (side by side in a tile).
    pub(super) sample: u32,
    pub(super) count: usize,
    /// Pixels per row.
    pub(super) width: usize,
    /// The band's first row and column in the camera's image.
    pub(super) first_row: usize,
    pub(super) first_column: usize,
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
    pub(super) unsafe fn add_avx2(
        &self,
        integrator: &(impl Integrator + ?Sized),
        pixels: &mut [Vec3],
        layers: &mut [&mut [Vec3]],
    ) -> u64 {
        self.add(integrator, pixels, layers)
    }

    /// Adds the group's samples of every pixel of the band (`pixels`, its rows) tile by tile,
    /// and of each of the integrator's layers (`layers[k]`, the same rows of layer `k`): a
    /// tile's rays are its pixels' in row order, each pixel's samples side by side, and each
    /// pixel's are added in the order of their indices. Returns how many samples were not
    /// finite (NaN or infinite in a channel): they count as black, so that one bad sample cannot
    /// spoil its pixel for good.
    #[inline(always)]
    pub(super) fn add(
        &self,
        integrator: &(impl Integrator + ?Sized),
        pixels: &mut [Vec3],
        layers: &mut [&mut [Vec3]],
    ) -> u64 {
        let mut discarded = 0;
        let (rays, kind, settings, sample) = (self.camera, self.kind, self.settings, self.sample);
        let (width, first_row, has_lens) = (self.width, self.first_row, self.has_lens);
        let first_column = self.first_column;
        let rows = pixels.len() / width;
        let count = self.count;
        // The lab's pixel positions need no sampler: where the integrator draws no numbers,
        // none is made (it gets the placeholders made below).
        let skip_samplers = kind == SamplerKind::Lab && !has_lens && !integrator.draws_numbers();
        // The tile's columns shrink so that its pixels' samples fit the arrays.
        let (tile_width, _) = tile_shape(tile_or_default(settings.tile, integrator));
        let tile_width = (tile_width / count).max(1);
        // A tile's rays, samplers, colours, film positions and numbers drawn in lanes (the
        // pixel positions', then the lens's): this thread's arrays, kept from band to band.
        let mut arrays = BandArrays::take();
        let BandArrays { tile_rays, samplers, colours, film, drawn, all_lanes } = &mut *arrays;
        // The pattern `multijitter` lays the render's samples out in.
        let grid = Grid::new(settings.count);
        // The layers' values of a tile's rays, ray by ray (empty without layers).
        let layer_count = layers.len();
        let mut layer_values = vec![Vec3::ZERO; MAX_TILE_PIXELS * layer_count];
        for tile_x in (0..width).step_by(tile_width) {
            let columns = tile_x..(tile_x + tile_width).min(width);
            let n = columns.len() * rows * count;
            if skip_samplers {
                // The lab's film positions, from the pixel positions its samplers' `pixel_2d`
                // gives; a pass of the first sample alone puts every pixel's at its centre,
                // found once.
                let centre = (sample == 0 && count == 1)
                    .then(|| settings.filter.offset(sample_offset(0, 0, 0)));
                let mut slot = film.iter_mut();
                for y in first_row..first_row + rows {
                    for x in columns.clone() {
                        let x = first_column + x;
                        for index in sample..sample + count as u32 {
                            let offset = centre.unwrap_or_else(|| {
                                settings.filter.offset(sample_offset(x as u32, y as u32, index))
                            });
                            let film = slot.next().expect("a tile's rays fit");
                            *film = Vec2::new(x as f32, y as f32) + offset;
                        }
                    }
                }
            } else {
                let mut slot = samplers.iter_mut().zip(film.iter_mut());
                for y in first_row..first_row + rows {
                    for x in columns.clone() {
                        let x = first_column + x;
                        let pixel = (x as u32, y as u32);
                        let indices = sample..sample + count as u32;
                        for made in
                            Sampler::counted_range(kind, settings.seed, pixel, indices, grid)
                        {
                            let (sampler, film) = slot.next().expect("a tile's rays fit");
                            *sampler = made;
                            *film = Vec2::new(x as f32, y as f32);
                        }
                    }
                }
            }
            // The pixel positions (and lens numbers): in lanes for the stratified kinds, the
            // same numbers as one by one (`pixel_2d` is their first `next_2d`; the lab's is not).
            let (samplers, lanes) = (&mut samplers[..n], &all_lanes[..n]);
            if !skip_samplers {
                if matches!(kind, SamplerKind::Sobol | SamplerKind::MultiJitter) {
                    Sampler::next_2d_each(samplers, lanes, &mut drawn[..n]);
                } else {
                    for (sampler, u) in samplers.iter_mut().zip(drawn.iter_mut()) {
                        *u = sampler.pixel_2d();
                    }
                }
                for (film, &u) in film[..n].iter_mut().zip(drawn.iter()) {
                    *film += settings.filter.offset(u);
                }
            }
            if has_lens {
                Sampler::next_2d_each(samplers, lanes, &mut drawn[..n]);
                for ((ray, film), &u) in tile_rays.iter_mut().zip(&film[..n]).zip(drawn.iter()) {
                    *ray = rays.lens_ray(*film, u);
                }
            } else {
                rays.rays_through(&film[..n], &mut tile_rays[..n]);
            }
            if layer_count == 0 {
                integrator.radiance_each(&tile_rays[..n], &mut samplers[..n], &mut colours[..n]);
            } else {
                integrator.radiance_and_layers_each(
                    &tile_rays[..n],
                    &mut samplers[..n],
                    &mut colours[..n],
                    &mut layer_values[..n * layer_count],
                );
                let mut values = layer_values.chunks_exact(layer_count);
                for y in 0..rows {
                    for x in columns.clone() {
                        for _ in 0..count {
                            let values = values.next().expect("the layers of each ray");
                            for (layer, &value) in layers.iter_mut().zip(values) {
                                if value.is_finite() {
                                    layer[y * width + x] += value;
                                }
                            }
                        }
                    }
                }
            }
            if count == 1 {
                // One sample per pixel: each row of the tile is a run of pixels and a run of
                // colours, added as runs of floats.
                let colours = colours[..n].chunks_exact(columns.len());
                for (y, colours) in colours.enumerate() {
                    let row = &mut pixels[y * width..][columns.clone()];
                    discarded += add_finite(row, colours);
                }
                continue;
            }
            let mut colour = colours.iter();
            for y in 0..rows {
                for x in columns.clone() {
                    for _ in 0..count {
                        let colour = *colour.next().expect("one colour per ray");
                        if colour.is_finite() {
                            pixels[y * width + x] += colour;
                        } else {
                            discarded += 1;
                        }
                    }
                }
            }
        }
        BandArrays::give_back(arrays);
        discarded
    }
}

/// `tile`, its width 0 replaced by the integrator's ([`Integrator::tile_width`]).
fn tile_or_default(
    (width, height): (u32, u32),
    integrator: &(impl Integrator + ?Sized),
) -> (u32, u32) {
    (if width == 0 { integrator.tile_width() } else { width }, height)
}

/// A thread's arrays for a band's tiles (some 130 KiB), kept from band to band: made once per
/// thread rather than written afresh for each band (a lab frame has 63 bands of 1,024 slots).
/// Every slot a tile reads was written for that tile first: rays, film positions, numbers
/// and colours for its `n` rays, and its samplers unless the integrator draws no numbers, when
/// they are placeholders it never reads.
struct BandArrays {
    tile_rays: [Ray; MAX_TILE_PIXELS],
    samplers: [Sampler; MAX_TILE_PIXELS],
    colours: [Vec3; MAX_TILE_PIXELS],
    film: [Vec2; MAX_TILE_PIXELS],
    drawn: [Vec2; MAX_TILE_PIXELS],
    /// `all_lanes[k] = k`: a tile's lanes' indices for the draws in lanes.
    all_lanes: [usize; MAX_TILE_PIXELS],
}

thread_local! {
    /// Each thread's spare [`BandArrays`].
    static SPARE_BAND: std::cell::Cell<Option<Box<BandArrays>>> =
        const { std::cell::Cell::new(None) };
}

impl BandArrays {
    /// This thread's arrays, or new ones.
    fn take() -> Box<BandArrays> {
        SPARE_BAND.take().unwrap_or_else(|| {
            Box::new(BandArrays {
                tile_rays: [Ray::new(Vec3::ZERO, Vec3::Z); MAX_TILE_PIXELS],
                samplers: std::array::from_fn(|_| Sampler::new(SamplerKind::Lab, 0, (0, 0), 0)),
                colours: [Vec3::ZERO; MAX_TILE_PIXELS],
                film: [Vec2::ZERO; MAX_TILE_PIXELS],
                drawn: [Vec2::ZERO; MAX_TILE_PIXELS],
                all_lanes: std::array::from_fn(|k| k),
            })
        })
    }

    /// Keeps `arrays` for this thread's next band.
    fn give_back(arrays: Box<BandArrays>) {
        SPARE_BAND.set(Some(arrays));
    }
}
