//! Adding a tile's colours to the picture's sums.

use glam::Vec3;

/// Adds each of `colours` that is finite in every channel to its pixel of `pixels` (as many),
/// eight pixels at a time where all eight are finite (their 24 channels as floats: the same
/// additions, which the compiler vectorizes), one at a time otherwise; returns how many were
/// not finite.
#[inline(always)]
pub(super) fn add_finite(pixels: &mut [Vec3], colours: &[Vec3]) -> u64 {
    assert_eq!(pixels.len(), colours.len(), "a colour per pixel");
    let mut discarded = 0;
    let (pixel_runs, pixel_rest) = pixels.as_chunks_mut::<8>();
    let (colour_runs, colour_rest) = colours.as_chunks::<8>();
    let one_by_one = |pixels: &mut [Vec3], colours: &[Vec3], discarded: &mut u64| {
        for (pixel, colour) in pixels.iter_mut().zip(colours) {
            if colour.is_finite() {
                *pixel += *colour;
            } else {
                *discarded += 1;
            }
        }
    };
    for (pixels, colours) in pixel_runs.iter_mut().zip(colour_runs) {
        let sums = floats_mut(pixels);
        let values = floats(colours);
        if values.iter().fold(true, |finite, v| finite & v.is_finite()) {
            for (sum, value) in sums.iter_mut().zip(values) {
                *sum += *value;
            }
        } else {
            one_by_one(pixels, colours, &mut discarded);
        }
    }
    one_by_one(pixel_rest, colour_rest, &mut discarded);
    discarded
}

/// Eight pixels' channels as 24 floats.
#[inline(always)]
fn floats(pixels: &[Vec3; 8]) -> &[f32; 24] {
    const _: () = assert!(std::mem::size_of::<[Vec3; 8]>() == 24 * 4);
    // SAFETY: `Vec3` is three `f32`s (`repr(C)`, no padding: the size is asserted above) of
    // `f32`'s alignment, so eight of them are 24 floats; the borrow is the same.
    unsafe { &*(pixels as *const [Vec3; 8]).cast::<[f32; 24]>() }
}

/// [`floats`], mutable.
#[inline(always)]
fn floats_mut(pixels: &mut [Vec3; 8]) -> &mut [f32; 24] {
    // SAFETY: as in `floats`; the borrow is the same, exclusive.
    unsafe { &mut *(pixels as *mut [Vec3; 8]).cast::<[f32; 24]>() }
}
