//! The window's pixels: an [`Accumulator`]'s mean as `0x00RRGGBB` words, the format of
//! `raylab view`'s frame buffer.

use glam::Vec3;
use rayon::prelude::*;

use super::Accumulator;
use crate::film::{Display, to_8bit_clamped, to_8bit_clamped_lane};

/// Rows per parallel task when writing a window's pixels.
const ROWS_PER_TASK: usize = 16;

impl Accumulator {
    /// Writes the mean into a `width×height` window buffer of `0x00RRGGBB` words, scaled to fill
    /// it by nearest neighbour (a picture rendered at a fraction of the window's resolution fills
    /// the window). Channels as in [`Film::to_rgb8_clamped`](crate::film::Film::to_rgb8_clamped). Runs on the current rayon pool.
    ///
    /// # Panics
    /// If `out` does not hold `width×height` words.
    pub fn write_0rgb(&self, out: &mut [u32], width: u32, height: u32) {
        self.write_0rgb_shown(out, width, height, &Display::LAB);
    }

    /// [`write_0rgb`](Self::write_0rgb) through a display transform (the lab's is the clamp
    /// without gamma).
    ///
    /// # Panics
    /// If `out` does not hold `width×height` words.
    pub fn write_0rgb_shown(&self, out: &mut [u32], width: u32, height: u32, display: &Display) {
        let factor = self.mean_factor();
        // One loop per conversion, so that the lab's clamp is inlined on its own.
        let same_size = (self.width(), self.height()) == (width, height);
        if *display == Display::LAB && same_size {
            assert_eq!(out.len(), width as usize * height as usize, "a word per window pixel");
            #[cfg(target_arch = "x86_64")]
            let avx2 = crate::cpu::Isa::detect().at_least(crate::cpu::Isa::Avx2);
            let run = ROWS_PER_TASK * width as usize;
            out.par_chunks_mut(run).zip(self.sum.pixels().par_chunks(run)).for_each(
                |(out, sums)| {
                    #[cfg(target_arch = "x86_64")]
                    if avx2 {
                        // SAFETY: AVX2 was detected above.
                        return unsafe { write_run_lab_avx2(out, sums, factor) };
                    }
                    write_run_lab(out, sums, factor)
                },
            );
        } else if *display == Display::LAB {
            self.write_words(out, width, height, |sum| {
                (*sum * factor).to_array().map(to_8bit_clamped)
            });
        } else {
            self.write_words(out, width, height, |sum| {
                (*sum * factor).to_array().map(|v| display.level(v))
            });
        }
    }

    /// Writes `0x00RRGGBB` words of the levels `level` gives each pixel's sum, scaled by
    /// nearest neighbour.
    #[inline]
    fn write_words(
        &self,
        out: &mut [u32],
        width: u32,
        height: u32,
        level: impl Fn(&Vec3) -> [u8; 3] + Sync,
    ) {
        assert_eq!(out.len(), width as usize * height as usize, "a word per window pixel");
        let (source_width, source_height) = (self.width() as usize, self.height() as usize);
        let word = |sum: &Vec3| {
            let [r, g, b] = level(sum);
            (r as u32) << 16 | (g as u32) << 8 | b as u32
        };
        if (source_width, source_height) == (width as usize, height as usize) {
            // Same size: pixel for pixel.
            #[cfg(target_arch = "x86_64")]
            let avx2 = crate::cpu::Isa::detect().at_least(crate::cpu::Isa::Avx2);
            out.par_chunks_mut(ROWS_PER_TASK * source_width)
                .zip(self.sum.pixels().par_chunks(ROWS_PER_TASK * source_width))
                .for_each(|(out, sums)| {
                    #[cfg(target_arch = "x86_64")]
                    if avx2 {
                        // SAFETY: AVX2 was detected above.
                        return unsafe { write_run_avx2(out, sums, &word) };
                    }
                    write_run(out, sums, &word)
                });
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

/// Writes the words of a run of pixels.
#[inline(always)]
fn write_run(out: &mut [u32], sums: &[Vec3], word: &impl Fn(&Vec3) -> u32) {
    for (w, s) in out.iter_mut().zip(sums) {
        *w = word(s);
    }
}

/// Pixels per step of [`write_run_lab`].
const LAB_LANES: usize = 8;

/// [`write_run`] of the lab's words (each channel of `sum · factor` through
/// [`to_8bit_clamped`]), eight pixels at a time: their 24 channels in one array, put through
/// [`to_8bit_clamped_lane`] together, which the compiler vectorizes. The same words.
#[inline(always)]
fn write_run_lab(out: &mut [u32], sums: &[Vec3], factor: f32) {
    assert_eq!(out.len(), sums.len(), "a word per pixel");
    let (words, words_rest) = out.as_chunks_mut::<LAB_LANES>();
    let (pixels, pixels_rest) = sums.as_chunks::<LAB_LANES>();
    for (words, pixels) in words.iter_mut().zip(pixels) {
        let mut channels = [0.0f32; 3 * LAB_LANES];
        for (rgb, sum) in channels.chunks_exact_mut(3).zip(pixels) {
            rgb.copy_from_slice(&(*sum * factor).to_array());
        }
        let levels = channels.map(to_8bit_clamped_lane);
        for (word, rgb) in words.iter_mut().zip(levels.chunks_exact(3)) {
            *word = rgb[0] << 16 | rgb[1] << 8 | rgb[2];
        }
    }
    for (word, sum) in words_rest.iter_mut().zip(pixels_rest) {
        let [r, g, b] = (*sum * factor).to_array().map(to_8bit_clamped_lane);
        *word = r << 16 | g << 8 | b;
    }
}

/// [`write_run_lab`] compiled with AVX2 (the same operations, so the same words).
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn write_run_lab_avx2(out: &mut [u32], sums: &[Vec3], factor: f32) {
    write_run_lab(out, sums, factor)
}

/// [`write_run`] compiled with AVX2 (the same operations, so the same words).
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn write_run_avx2(out: &mut [u32], sums: &[Vec3], word: &impl Fn(&Vec3) -> u32) {
    write_run(out, sums, word)
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

    /// Sums below 0, inside [0, 1], above 1, infinite and NaN, and the words of the lab's clamp
    /// of them written one by one (`write_run`).
    fn special_sums() -> (Vec<Vec3>, f32, Vec<u32>) {
        let special = [-1.0, 0.0, 0.5, 1.0, 3.0, f32::INFINITY, f32::NAN, 1e-9, 0.999];
        let sums: Vec<Vec3> = (0..999)
            .map(|i| {
                let v =
                    |k: usize| special[(i * 7 + k * 3) % special.len()] * (1.0 + i as f32 * 1e-3);
                Vec3::new(v(0), v(1), v(2))
            })
            .collect();
        let factor = 0.75;
        let word = |sum: &Vec3| {
            let [r, g, b] = (*sum * factor).to_array().map(to_8bit_clamped);
            (r as u32) << 16 | (g as u32) << 8 | b as u32
        };
        let mut base = vec![0u32; sums.len()];
        write_run(&mut base, &sums, &word);
        assert!(base.iter().any(|&w| w & 0xFF == 0xFF) && base.iter().any(|&w| w & 0xFF == 0));
        (sums, factor, base)
    }

    /// The lab's runs, eight pixels at a time, give the one-by-one words, on runs of every
    /// length modulo 8; and a window of the picture's own size takes them.
    #[test]
    fn lab_runs_are_the_words_one_by_one() {
        let (sums, factor, base) = special_sums();
        for start in 0..8 {
            let mut lanes = vec![2u32; sums.len()];
            write_run_lab(&mut lanes[start..], &sums[start..], factor);
            assert_eq!(base[start..], lanes[start..]);
        }
        // The same-size branch of `write_0rgb`, through the accumulator (factor 1/2).
        let mut accumulator = Accumulator::new(37, 27).unwrap();
        accumulator.sum.pixels_mut().copy_from_slice(&sums);
        accumulator.samples = 2;
        let mut out = vec![0u32; sums.len()];
        accumulator.write_0rgb(&mut out, 37, 27);
        let half: Vec<u32> = sums
            .iter()
            .map(|s| {
                let [r, g, b] = (*s * 0.5).to_array().map(to_8bit_clamped);
                (r as u32) << 16 | (g as u32) << 8 | b as u32
            })
            .collect();
        assert_eq!(out, half);
    }

    /// Window words are the same compiled for AVX2 as for the baseline instruction set.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn window_words_are_the_same_with_avx2() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            eprintln!("skipped: this CPU has no AVX2 (its words are never written so)");
            return;
        }
        let (sums, factor, base) = special_sums();
        let word = |sum: &Vec3| {
            let [r, g, b] = (*sum * factor).to_array().map(to_8bit_clamped);
            (r as u32) << 16 | (g as u32) << 8 | b as u32
        };
        let mut wide = vec![1u32; sums.len()];
        // SAFETY: AVX2 was detected above.
        unsafe { write_run_avx2(&mut wide, &sums, &word) };
        assert_eq!(base, wide);
        for start in 0..8 {
            let mut lanes_avx2 = vec![3u32; sums.len()];
            // SAFETY: AVX2 was detected above.
            unsafe { write_run_lab_avx2(&mut lanes_avx2[start..], &sums[start..], factor) };
            assert_eq!(base[start..], lanes_avx2[start..]);
        }
    }
}
