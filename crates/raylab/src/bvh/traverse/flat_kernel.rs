//! The flat list's tests per instruction set ([`FlatKernel`]): one ray against every triangle
//! ([`flat`](super::flat)) and many rays in lanes (`flat_rays.rs`, on x86-64), with
//! the scalar twins as the defaults.

use super::flat::{Flat, closest_hit_scalar, occluded_scalar};
use crate::accel::Hit;
use crate::bvh::isa::Scalar;
use crate::ray::Ray;

/// The flat list's tests per instruction set; the scalar twins are [`closest_hit_scalar`] and
/// [`occluded_scalar`]; the vector forms are [`flat`](super::flat)'s single-ray lanes and
/// `flat_rays.rs`.
pub(crate) trait FlatKernel {
    /// The closest hit among the list's triangles.
    ///
    /// # Safety
    /// The CPU must support the kernel's instruction set (checked once when a BVH picks it).
    unsafe fn closest_hit(flat: &Flat, ray: &Ray) -> Option<Hit>;
    /// Whether any of the list's triangles is hit.
    ///
    /// # Safety
    /// As for [`closest_hit`](Self::closest_hit).
    unsafe fn occluded(flat: &Flat, ray: &Ray) -> bool;

    /// The closest hit of each ray, `hits[i]` for `rays[i]`: exactly
    /// [`closest_hit`](Self::closest_hit)'s answers, by default ray by ray (the scalar twin of
    /// `flat_rays.rs`).
    ///
    /// # Safety
    /// As for [`closest_hit`](Self::closest_hit).
    #[inline(always)]
    unsafe fn closest_hits(flat: &Flat, rays: &[Ray], hits: &mut [Option<Hit>]) {
        assert_eq!(rays.len(), hits.len(), "one answer per ray");
        for (ray, hit) in rays.iter().zip(hits) {
            // SAFETY: the caller's guarantee.
            *hit = unsafe { Self::closest_hit(flat, ray) };
        }
    }
    /// Whether each ray is occluded, `occluded[i]` for `rays[i]`: exactly
    /// [`occluded`](Self::occluded)'s answers, by default ray by ray (the scalar twin of
    /// `flat_rays.rs`).
    ///
    /// # Safety
    /// As for [`closest_hit`](Self::closest_hit).
    #[inline(always)]
    unsafe fn occluded_each(flat: &Flat, rays: &[Ray], occluded: &mut [bool]) {
        assert_eq!(rays.len(), occluded.len(), "one answer per ray");
        for (ray, o) in rays.iter().zip(occluded) {
            // SAFETY: the caller's guarantee.
            *o = unsafe { Self::occluded(flat, ray) };
        }
    }
}

impl FlatKernel for Scalar {
    #[inline(always)]
    unsafe fn closest_hit(flat: &Flat, ray: &Ray) -> Option<Hit> {
        closest_hit_scalar(flat, ray)
    }
    #[inline(always)]
    unsafe fn occluded(flat: &Flat, ray: &Ray) -> bool {
        occluded_scalar(flat, ray)
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::{__m128, __m256, __m512};

    use super::*;
    use crate::bvh::isa::{Avx2, Avx512, Sse};
    use crate::bvh::traverse::flat::{closest_hit_lanes, occluded_lanes};
    use crate::bvh::traverse::flat_rays;

    /// SSE2's four lanes, AVX2's eight, AVX-512's sixteen.
    macro_rules! flat_kernel {
        ($isa:ty, $register:ty, $lanes:literal) => {
            impl FlatKernel for $isa {
                #[inline(always)]
                unsafe fn closest_hit(flat: &Flat, ray: &Ray) -> Option<Hit> {
                    // SAFETY: the caller's guarantee of the instruction set; the register
                    // holds `$lanes` floats.
                    unsafe { closest_hit_lanes::<$register, $lanes>(flat, ray) }
                }
                #[inline(always)]
                unsafe fn occluded(flat: &Flat, ray: &Ray) -> bool {
                    // SAFETY: as above.
                    unsafe { occluded_lanes::<$register, $lanes>(flat, ray) }
                }
                #[inline(always)]
                unsafe fn closest_hits(flat: &Flat, rays: &[Ray], hits: &mut [Option<Hit>]) {
                    // SAFETY: as above.
                    unsafe { flat_rays::closest_hits::<$register, $lanes>(flat, rays, hits) }
                }
                #[inline(always)]
                unsafe fn occluded_each(flat: &Flat, rays: &[Ray], occluded: &mut [bool]) {
                    // SAFETY: as above.
                    unsafe { flat_rays::occluded::<$register, $lanes>(flat, rays, occluded) }
                }
            }
        };
    }
    flat_kernel!(Sse, __m128, 4);
    flat_kernel!(Avx2, __m256, 8);
    flat_kernel!(Avx512, __m512, 16);
}
