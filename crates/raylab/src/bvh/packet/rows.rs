//! Copying a packet's rays into rows (origins, directions, `t_min`, `t_max`, lane `i` for ray
//! `i`), the first step of filling its lanes ([`fill`](super::setup::fill)): one ray at a time
//! ([`rows_portable`]), or eight at a time by an AVX transposition ([`rows_avx`]).

use super::rays::PACKET;
use crate::ray::Ray;

/// A packet's rays' directions (three rows), `t_min` and `t_max`, lane `i` for ray `i`: what
/// [`fill`](super::setup::fill) reads besides the origins, which it copies straight into the
/// packet's lanes.
pub(super) type RestRows = [[f32; PACKET]; 5];

/// Copies `rays` (at most [`PACKET`]) into rows: their origins into `origin`, their directions,
/// `t_min` and `t_max` into `rest` (the scalar twin of [`rows_avx`]).
#[inline(always)]
pub(super) fn rows_portable(rays: &[Ray], origin: &mut [[f32; PACKET]; 3], rest: &mut RestRows) {
    rows_from(0, rays, origin, rest);
}

/// [`rows_portable`] into lanes `first..`: ray `i` into lane `first + i`.
#[inline(always)]
fn rows_from(first: usize, rays: &[Ray], origin: &mut [[f32; PACKET]; 3], rest: &mut RestRows) {
    for (i, ray) in rays.iter().enumerate() {
        let (o, d) = (ray.origin.to_array(), ray.direction.to_array());
        for axis in 0..3 {
            origin[axis][first + i] = o[axis];
            rest[axis][first + i] = d[axis];
        }
        rest[3][first + i] = ray.t_min;
        rest[4][first + i] = ray.t_max;
    }
}

/// [`rows_portable`] eight rays at a time: a ray is eight floats (`Ray` is `repr(C)`: origin,
/// direction, `t_min`, `t_max`), so eight rays are an 8×8 matrix, loaded as eight AVX
/// registers and transposed by unpacks, shuffles and lane permutes into eight rows (the
/// transposition writes each float where the portable copy does; no arithmetic).
///
/// # Safety
/// The CPU must support AVX.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub(super) unsafe fn rows_avx(rays: &[Ray], origin: &mut [[f32; PACKET]; 3], rest: &mut RestRows) {
    use std::arch::x86_64::*;
    const _: () = assert!(std::mem::size_of::<Ray>() == 32);
    assert!(rays.len() <= PACKET, "a packet holds at most {PACKET} rays");
    let (blocks, tail) = rays.as_chunks::<8>();
    for (b, block) in blocks.iter().enumerate() {
        let base = 8 * b;
        // SAFETY: the caller guarantees AVX; each load reads one `Ray`, 32 bytes of `f32`s
        // (`repr(C)`, asserted above); each store writes 8 floats of a row from `base`, and
        // `base + 8 ≤ rays.len() ≤ PACKET`.
        unsafe {
            // (The closure only computes pointers: no intrinsic is compiled without the
            // caller's AVX.)
            let p = block.as_ptr().cast::<f32>();
            let w = crate::bvh::simd::transpose8_at(std::array::from_fn(|k| p.wrapping_add(8 * k)));
            // Each row's pointer made at its own store (one borrow at a time).
            _mm256_storeu_ps(origin[0].as_mut_ptr().add(base), w[0]);
            _mm256_storeu_ps(origin[1].as_mut_ptr().add(base), w[1]);
            _mm256_storeu_ps(origin[2].as_mut_ptr().add(base), w[2]);
            _mm256_storeu_ps(rest[0].as_mut_ptr().add(base), w[3]);
            _mm256_storeu_ps(rest[1].as_mut_ptr().add(base), w[4]);
            _mm256_storeu_ps(rest[2].as_mut_ptr().add(base), w[5]);
            _mm256_storeu_ps(rest[3].as_mut_ptr().add(base), w[6]);
            _mm256_storeu_ps(rest[4].as_mut_ptr().add(base), w[7]);
        }
    }
    rows_from(8 * blocks.len(), tail, origin, rest);
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    /// The AVX transposition puts every float of every ray where the portable copy puts it,
    /// for every packet length (whole blocks of eight and a tail).
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn rays_are_transposed_into_rows_as_copied() {
        if !crate::cpu::Isa::Avx2.is_supported() {
            eprintln!("skipped: this CPU has no AVX2 (the transposition never runs on it)");
            return;
        }
        let rays: Vec<Ray> = (0..PACKET)
            .map(|i| {
                let f = |k: usize| (i * 8 + k) as f32;
                let mut ray = Ray::new(Vec3::new(f(0), f(1), f(2)), Vec3::new(f(3), f(4), f(5)));
                (ray.t_min, ray.t_max) = (f(6), f(7));
                ray
            })
            .collect();
        for n in 0..=PACKET {
            let (mut origin, mut rest) = ([[-1.0; PACKET]; 3], [[-1.0; PACKET]; 5]);
            let (mut origin_avx, mut rest_avx) = ([[-2.0; PACKET]; 3], [[-2.0; PACKET]; 5]);
            rows_portable(&rays[..n], &mut origin, &mut rest);
            // SAFETY: AVX2 (so AVX) was checked above.
            unsafe { rows_avx(&rays[..n], &mut origin_avx, &mut rest_avx) };
            for i in 0..n {
                let words = [origin[0][i], origin[1][i], origin[2][i]]
                    .into_iter()
                    .chain(rest.iter().map(|row| row[i]));
                for (k, word) in words.enumerate() {
                    assert_eq!(word, (i * 8 + k) as f32, "ray {i} word {k} of {n}");
                }
                assert_eq!(origin.map(|r| r[i]), origin_avx.map(|r| r[i]), "ray {i} of {n}");
                assert_eq!(rest.map(|r| r[i]), rest_avx.map(|r| r[i]), "ray {i} of {n}");
            }
            // Nothing past the rays is written.
            assert!(
                origin_avx.iter().chain(&rest_avx).all(|row| row[n..].iter().all(|&v| v == -2.0))
            );
        }
    }
}
