//! Comparing images with a tolerance, for regression tests against reference pictures.

use std::path::PathBuf;

use image::{Rgb, RgbImage};

use crate::image_io::{ImageIoError, save_rgb8};

/// How two images of the same size differ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageDifference {
    /// The largest difference of any channel of any pixel, in 8-bit levels.
    pub max_channel_diff: u8,
    /// Mean absolute difference over all channels, in 8-bit levels.
    pub mean_abs_diff: f64,
    /// Pixels with a channel differing by more than the tolerance.
    pub pixels_over_tolerance: usize,
    /// All pixels.
    pub pixels: usize,
}

impl ImageDifference {
    /// The fraction of pixels over the tolerance.
    pub fn fraction_over_tolerance(&self) -> f64 {
        self.pixels_over_tolerance as f64 / self.pixels.max(1) as f64
    }
}

/// Compares `actual` with `expected`; a pixel counts as different when any channel differs by
/// more than `tolerance` levels. `None` if the sizes differ.
pub fn compare_rgb8(
    actual: &RgbImage,
    expected: &RgbImage,
    tolerance: u8,
) -> Option<ImageDifference> {
    if actual.dimensions() != expected.dimensions() {
        return None;
    }
    let (mut max, mut sum, mut over) = (0u8, 0u64, 0usize);
    for (a, e) in actual.pixels().zip(expected.pixels()) {
        let pixel_max = (0..3).map(|c| a[c].abs_diff(e[c])).max().unwrap_or(0);
        sum += (0..3).map(|c| a[c].abs_diff(e[c]) as u64).sum::<u64>();
        max = max.max(pixel_max);
        over += (pixel_max > tolerance) as usize;
    }
    let pixels = actual.pixels().len();
    Some(ImageDifference {
        max_channel_diff: max,
        mean_abs_diff: sum as f64 / (3 * pixels.max(1)) as f64,
        pixels_over_tolerance: over,
        pixels,
    })
}

/// A picture of where two images differ: black where equal, brighter where they differ more
/// (each channel's difference ×8), so that one-level differences are still visible.
pub fn diff_image(actual: &RgbImage, expected: &RgbImage) -> RgbImage {
    RgbImage::from_fn(actual.width(), actual.height(), |x, y| {
        let (a, e) =
            (actual.get_pixel(x, y), expected.get_pixel_checked(x, y).unwrap_or(&Rgb([0; 3])));
        Rgb([0, 1, 2].map(|c| a[c].abs_diff(e[c]).saturating_mul(8)))
    })
}

/// Writes `actual.png`, `expected.png` and `diff.png` into a new folder under the system's
/// temporary folder and returns its path: what an image test leaves behind when it fails.
pub fn save_failure_images(
    test_name: &str,
    actual: &RgbImage,
    expected: &RgbImage,
) -> Result<PathBuf, ImageIoError> {
    let folder = std::env::temp_dir().join(format!("raylab-{test_name}-{}", std::process::id()));
    std::fs::create_dir_all(&folder).map_err(|source| ImageIoError::Io {
        action: "write",
        path: folder.clone(),
        source,
    })?;
    save_rgb8(&folder.join("actual.png"), actual)?;
    save_rgb8(&folder.join("expected.png"), expected)?;
    save_rgb8(&folder.join("diff.png"), &diff_image(actual, expected))?;
    Ok(folder)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_pixels_over_the_tolerance() {
        let a = RgbImage::from_pixel(4, 4, Rgb([100, 100, 100]));
        let mut b = a.clone();
        b.put_pixel(0, 0, Rgb([102, 100, 100]));
        b.put_pixel(1, 0, Rgb([100, 90, 100]));
        let d = compare_rgb8(&a, &b, 2).unwrap();
        assert_eq!(d.max_channel_diff, 10);
        assert_eq!(d.pixels_over_tolerance, 1);
        assert_eq!(d.pixels, 16);
        assert!((d.mean_abs_diff - 12.0 / 48.0).abs() < 1e-12);
        assert_eq!(compare_rgb8(&a, &a, 0).unwrap().pixels_over_tolerance, 0);
        assert!(compare_rgb8(&a, &RgbImage::new(4, 5), 0).is_none());
        assert_eq!(diff_image(&a, &b).get_pixel(1, 0).0, [0, 80, 0]);
    }
}
