//! Passes of samples over an image: the scheduler.
//!
//! A pass adds sample `n` of every pixel of a region; a group of passes adds samples `n` to
//! `n + count − 1`, each pixel's samples traced side by side. The region is cut into bands of
//! whole rows that rayon's threads take in any order, and each band into tiles whose camera
//! rays are traced together (the accelerator traces them as packets: a pixel's samples make
//! the most coherent ones). Every sample draws its numbers from a [`Sampler`] made from (seed,
//! pixel, sample index) alone, so the order of the work never changes a pixel, and each
//! pixel's samples are added to its sum in their order: a group gives the pixels of its passes
//! one by one, to the bit. The pixels go into an [`Accumulator`](super::Accumulator)'s sums.

use glam::Vec3;
use rayon::prelude::*;

use super::band::{Band, MAX_TILE_PIXELS, tile_shape};
use super::settings::SampleSettings;
use crate::camera::Camera;
use crate::film::Film;
use crate::integrator::Integrator;
use crate::region::Region;

/// Which passes: samples `sample` to `sample + count − 1` of the pixels of `region` (of the
/// camera's image), drawn as `settings` say.
pub(super) struct Pass<'a> {
    pub settings: &'a SampleSettings,
    pub sample: u32,
    /// How many passes, from `sample` on (at least 1).
    pub count: u32,
    pub region: Region,
    /// The sums start again from zero: each band zeroes its rows (and its layers' rows) before
    /// adding the pass's first samples, rather than the whole picture being cleared first.
    pub restart: bool,
}

/// Adds `pass`'s samples of every pixel of its region to `pixels` (the region's pixels row by
/// row) and of each layer to `layers` (one film of the region each), each pixel's in the order
/// of their indices. `progress` gets the rows finished, a row once per sample.
pub(super) fn add_pass(
    camera: &Camera,
    integrator: &(impl Integrator + ?Sized),
    Pass { settings, sample, count, region, restart }: Pass,
    pixels: &mut [Vec3],
    layers: &mut [Film],
    progress: &(dyn Fn(u32) + Sync),
) -> u64 {
    let (_, band_rows) = tile_shape(settings.tile);
    // As many of a pixel's samples at once as a tile's arrays hold for a column of a band, and
    // at most `PASS_GROUP` (more fill no packet better).
    let most = ((MAX_TILE_PIXELS / band_rows).max(1) as u32).min(super::settings::PASS_GROUP);
    let mut discarded = 0;
    let end = sample.saturating_add(count.max(1));
    let mut first = sample;
    while first < end {
        let group = most.min(end - first);
        // Only the first group restarts the sums.
        let restart = restart && first == sample;
        let pass = Pass { settings, sample: first, count: group, region, restart };
        discarded += add_group(camera, integrator, pass, pixels, layers, progress);
        first += group;
    }
    discarded
}

/// [`add_pass`] for a group whose samples of a column of a band fit a tile.
fn add_group(
    camera: &Camera,
    integrator: &(impl Integrator + ?Sized),
    Pass { settings, sample, count, region, restart }: Pass,
    pixels: &mut [Vec3],
    layers: &mut [Film],
    progress: &(dyn Fn(u32) + Sync),
) -> u64 {
    let width = region.width() as usize;
    debug_assert_eq!(pixels.len() as u64, region.pixels());
    let rays = camera.rays();
    let kind = settings.sampler.unwrap_or_else(|| integrator.sampler_kind());
    let (_, band_rows) = tile_shape(settings.tile);
    debug_assert!(count >= 1 && band_rows * count as usize <= MAX_TILE_PIXELS);
    #[cfg(target_arch = "x86_64")]
    let avx2 = crate::cpu::Isa::detect().at_least(crate::cpu::Isa::Avx2);
    let discarded = std::sync::atomic::AtomicU64::new(0);
    let tally = |n: u64| {
        if n > 0 {
            discarded.fetch_add(n, std::sync::atomic::Ordering::Relaxed);
        }
    };
    assert_eq!(layers.len(), integrator.layer_count(), "a film for each layer");
    // Each layer's rows, cut into the same bands as the picture's.
    let band_pixels = width * band_rows;
    let mut band_layers: Vec<Vec<&mut [Vec3]>> =
        (0..pixels.len().div_ceil(band_pixels)).map(|_| Vec::new()).collect();
    for layer in layers.iter_mut() {
        debug_assert_eq!(layer.pixels().len(), pixels.len());
        for (band, rows) in band_layers.iter_mut().zip(layer.pixels_mut().chunks_mut(band_pixels)) {
            band.push(rows);
        }
    }
    let bands = pixels.par_chunks_mut(band_pixels).zip(band_layers.into_par_iter()).enumerate();
    bands.for_each(|(band, (pixels, mut layers))| {
        if restart {
            // While the band's rows are about to be used: in the cache, on this thread.
            pixels.fill(Vec3::ZERO);
            for rows in layers.iter_mut() {
                rows.fill(Vec3::ZERO);
            }
        }
        let band = Band {
            camera: &rays,
            has_lens: camera.has_lens(),
            kind,
            settings,
            sample,
            count: count as usize,
            width,
            first_row: region.y0 as usize + band * band_rows,
            first_column: region.x0 as usize,
        };
        let rows = (pixels.len() / width) as u32 * band.count as u32;
        #[cfg(target_arch = "x86_64")]
        if avx2 {
            // SAFETY: AVX2 was detected above.
            tally(unsafe { band.add_avx2(integrator, pixels, &mut layers) });
            progress(rows);
            return;
        }
        tally(band.add(integrator, pixels, &mut layers));
        progress(rows);
    });
    discarded.into_inner()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::RayGenerator;
    use crate::ray::Ray;
    use crate::sampling::{Grid, Sampler, SamplerKind};
    use glam::Vec2;

    /// Band `b` of pass `sample` (whole rows of an image `width` wide, from its left edge).
    fn band<'a>(
        rays: &'a RayGenerator,
        has_lens: bool,
        kind: SamplerKind,
        settings: &'a SampleSettings,
        sample: u32,
        width: u32,
        b: usize,
    ) -> Band<'a> {
        let (_, band_rows) = tile_shape(settings.tile);
        let (width, first_row) = (width as usize, b * band_rows);
        let (count, first_column) = (1, 0);
        Band {
            camera: rays,
            has_lens,
            kind,
            settings,
            sample,
            count,
            width,
            first_row,
            first_column,
        }
    }

    /// A band makes each pixel's sampler and camera ray as they are made one at a time
    /// (`Sampler::new`, `pixel_2d`, the filter's offset, then the lens's `next_2d`): the Sobol'
    /// kind's numbers are drawn for a whole tile in lanes, the others one by one. An integrator
    /// that returns its ray and its sampler's next number shows both, for every sampler kind,
    /// with and without a lens, over tiles cut short by the image's edge.
    #[test]
    fn a_band_makes_the_rays_and_samplers_made_one_by_one() {
        struct Echo(SamplerKind);
        impl Integrator for Echo {
            fn radiance(&self, ray: &Ray, sampler: &mut Sampler) -> Vec3 {
                let d = ray.direction.normalize();
                Vec3::new(ray.origin.x + d.x, ray.origin.y + d.y, d.z + sampler.next_1d())
            }
            fn sampler_kind(&self) -> SamplerKind {
                self.0
            }
        }
        /// The ray alone (the lab's integrator reads no sampler either).
        struct Numberless(SamplerKind);
        impl Integrator for Numberless {
            fn radiance(&self, ray: &Ray, _: &mut Sampler) -> Vec3 {
                ray.origin + ray.direction * 3.0
            }
            fn sampler_kind(&self) -> SamplerKind {
                self.0
            }
            fn draws_numbers(&self) -> bool {
                false
            }
        }
        let (width, height) = (45, 19);
        for lens in [false, true] {
            let mut camera = crate::Camera::lab(width, height);
            if lens {
                camera.aperture_radius = 0.05;
                camera.focus_distance = 3.0;
            }
            let rays = camera.rays();
            for (_, kind) in SamplerKind::ALL {
                // A render of 16 samples: `multijitter` lays out its pattern.
                let settings = SampleSettings { seed: 7, count: 16, ..SampleSettings::default() };
                let (_, band_rows) = tile_shape(settings.tile);
                for sample in [0, 5] {
                    let mut pixels = vec![Vec3::ZERO; width as usize * height as usize];
                    for (b, rows) in pixels.chunks_mut(width as usize * band_rows).enumerate() {
                        let band =
                            band(&rays, camera.has_lens(), kind, &settings, sample, width, b);
                        assert_eq!(band.add(&Echo(kind), rows, &mut []), 0);
                    }
                    // An integrator that draws no numbers is handed no samplers of its own,
                    // but the same rays.
                    let mut numberless = vec![Vec3::ZERO; width as usize * height as usize];
                    for (b, rows) in numberless.chunks_mut(width as usize * band_rows).enumerate() {
                        let band =
                            band(&rays, camera.has_lens(), kind, &settings, sample, width, b);
                        assert_eq!(band.add(&Numberless(kind), rows, &mut []), 0);
                    }
                    for (i, &pixel) in pixels.iter().enumerate() {
                        let (x, y) = ((i % width as usize) as u32, (i / width as usize) as u32);
                        let grid = Grid::new(settings.count);
                        let mut sampler =
                            Sampler::counted(kind, settings.seed, (x, y), sample, grid);
                        let offset = settings.filter.offset(sampler.pixel_2d());
                        let film = Vec2::new(x as f32 + offset.x, y as f32 + offset.y);
                        let ray = if lens {
                            rays.lens_ray(film, sampler.next_2d())
                        } else {
                            rays.ray(film.x, film.y)
                        };
                        let expected = Echo(kind).radiance(&ray, &mut sampler);
                        assert_eq!(
                            pixel.to_array().map(f32::to_bits),
                            expected.to_array().map(f32::to_bits),
                            "{kind:?}, lens {lens}, sample {sample}, pixel ({x}, {y})"
                        );
                        let expected = Numberless(kind).radiance(&ray, &mut sampler);
                        assert_eq!(
                            numberless[i].to_array().map(f32::to_bits),
                            expected.to_array().map(f32::to_bits),
                            "numberless, {kind:?}, lens {lens}, sample {sample}, ({x}, {y})"
                        );
                    }
                }
            }
        }
    }

    /// An integrator that draws no numbers gets, with no samplers made, the rays that one that
    /// draws them gets: several samples of each pixel side by side, of a band that starts off
    /// the image's left edge, from the first sample and from a later one.
    #[test]
    fn bands_without_samplers_give_the_same_rays() {
        struct Rays(bool);
        impl Integrator for Rays {
            fn radiance(&self, ray: &Ray, _: &mut Sampler) -> Vec3 {
                ray.origin + ray.direction * 2.0
            }
            fn sampler_kind(&self) -> SamplerKind {
                SamplerKind::Lab
            }
            fn draws_numbers(&self) -> bool {
                self.0
            }
        }
        let camera = crate::Camera::lab(45, 19);
        let rays = camera.rays();
        let settings = SampleSettings { seed: 7, count: 16, ..SampleSettings::default() };
        let (_, band_rows) = tile_shape(settings.tile);
        let width = 40;
        for count in [1, 2, 3] {
            for sample in [0, 5] {
                for b in 0..3 {
                    let band = Band {
                        camera: &rays,
                        has_lens: false,
                        kind: SamplerKind::Lab,
                        settings: &settings,
                        sample,
                        count,
                        width,
                        first_row: b * band_rows,
                        first_column: 5,
                    };
                    let mut with = vec![Vec3::ZERO; width * band_rows];
                    let mut without = with.clone();
                    assert_eq!(band.add(&Rays(true), &mut with, &mut []), 0);
                    assert_eq!(band.add(&Rays(false), &mut without, &mut []), 0);
                    let bits = |p: &[Vec3]| -> Vec<[u32; 3]> {
                        p.iter().map(|v| v.to_array().map(f32::to_bits)).collect()
                    };
                    assert!(with.iter().all(|p| *p != Vec3::ZERO));
                    assert_eq!(bits(&with), bits(&without), "count {count}, sample {sample}");
                }
            }
        }
    }

    /// A band renders the same bits compiled for AVX2 as for the baseline instruction set, for
    /// the lab's integrator and the path tracer (a pinhole and a lens), two samples each.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn bands_are_the_same_bits_with_avx2() {
        use crate::bvh::Bvh;
        use crate::integrator::{Lab, PathScalar, PathSettings, Stage};
        use crate::scene::Scene;
        if !std::arch::is_x86_feature_detected!("avx2") {
            eprintln!("skipped: this CPU has no AVX2 (its band is never used)");
            return;
        }
        let scene = Scene::built_in("cornell").expect("the lab scene");
        let bvh = Bvh::new(&scene.vertices());
        let lab = Lab::new(&scene, &bvh, Stage::Ambient);
        let path = PathScalar::new(&scene, &bvh, PathSettings::default());
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
                        let band =
                            band(&rays, camera.has_lens(), kind, &settings, sample, width, b);
                        assert_eq!(band.add(integrator, base, &mut []), 0);
                        // SAFETY: AVX2 was detected above.
                        assert_eq!(unsafe { band.add_avx2(integrator, wide, &mut []) }, 0);
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
}
