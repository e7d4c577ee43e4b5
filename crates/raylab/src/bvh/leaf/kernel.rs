//! The leaf records' kernels: one ray against the up to eight triangles of a leaf record, in
//! one pass, deciding as [`WatertightRay::intersect`] does (the scalar twin is
//! [`record_hits_scalar`]). The vector forms are in `leaf/lanes.rs`.

use super::{Record, RecordHits, TriangleRay, record_hits_scalar};
use crate::bvh::isa::Scalar;
use crate::triangle::WatertightRay;

/// A leaf record's triangle tests, per instruction set.
pub(crate) trait RecordKernel: Sized {
    /// What a ray's triangle tests need, in this kernel's registers, prepared once per ray.
    type RecordRay: Copy;

    /// Prepares a ray for [`record_hits`](Self::record_hits).
    ///
    /// # Safety
    /// The CPU must support the kernel's instruction set (checked once when a BVH picks it).
    unsafe fn prepare_record_ray(ray: &WatertightRay) -> Self::RecordRay;

    /// The hits of a ray on the triangles of a leaf record below `t_max`, as
    /// [`WatertightRay::intersect`] decides them. The records must hold no zero-area triangles
    /// (the BVH leaves them out). The scalar twin is [`record_hits_scalar`].
    ///
    /// # Safety
    /// The CPU must support the kernel's instruction set (checked once when a BVH picks it).
    unsafe fn record_hits(
        ray: &TriangleRay<Self::RecordRay>,
        record: &Record,
        t_max: f32,
    ) -> RecordHits;
}

/// Prepares `ray` for `K`'s triangle tests.
///
/// # Safety
/// As for [`RecordKernel::record_hits`].
#[inline(always)]
pub(crate) unsafe fn prepare_triangle_ray<K: RecordKernel>(
    ray: &WatertightRay,
) -> TriangleRay<K::RecordRay> {
    // SAFETY: the caller's guarantee.
    TriangleRay { ray: *ray, lanes: unsafe { K::prepare_record_ray(ray) } }
}

impl RecordKernel for Scalar {
    type RecordRay = ();

    #[inline(always)]
    unsafe fn prepare_record_ray(_: &WatertightRay) {}

    #[inline(always)]
    unsafe fn record_hits(ray: &TriangleRay<()>, record: &Record, t_max: f32) -> RecordHits {
        record_hits_scalar(&ray.ray, record, t_max)
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::*;

    use super::*;
    use crate::bvh::isa::{Avx2, Avx512, Sse};
    use crate::bvh::leaf::lanes::{record_hits_avx2, record_hits_sse};
    use crate::bvh::simd::RayBroadcast;

    impl RecordKernel for Sse {
        type RecordRay = RayBroadcast<__m128>;

        #[inline(always)]
        unsafe fn prepare_record_ray(ray: &WatertightRay) -> RayBroadcast<__m128> {
            // SAFETY: SSE2 is part of x86-64.
            unsafe { RayBroadcast::new(ray) }
        }

        #[inline(always)]
        unsafe fn record_hits(
            ray: &TriangleRay<RayBroadcast<__m128>>,
            record: &Record,
            t_max: f32,
        ) -> RecordHits {
            record_hits_sse(ray, record, t_max)
        }
    }

    impl RecordKernel for Avx2 {
        type RecordRay = RayBroadcast<__m256>;

        #[inline(always)]
        unsafe fn prepare_record_ray(ray: &WatertightRay) -> RayBroadcast<__m256> {
            // SAFETY: the caller checked AVX2 support (this function's contract).
            unsafe { RayBroadcast::new(ray) }
        }

        #[inline(always)]
        unsafe fn record_hits(
            ray: &TriangleRay<RayBroadcast<__m256>>,
            record: &Record,
            t_max: f32,
        ) -> RecordHits {
            // SAFETY: the caller checked AVX2 support (this function's contract).
            unsafe { record_hits_avx2::<false>(ray, record, t_max) }
        }
    }

    /// Leaf records with AVX-512 VL's two-table permute.
    impl RecordKernel for Avx512 {
        type RecordRay = RayBroadcast<__m256>;

        #[inline(always)]
        unsafe fn prepare_record_ray(ray: &WatertightRay) -> RayBroadcast<__m256> {
            // SAFETY: the caller checked AVX-512 F and VL support (this function's contract).
            unsafe { RayBroadcast::new(ray) }
        }

        #[inline(always)]
        unsafe fn record_hits(
            ray: &TriangleRay<RayBroadcast<__m256>>,
            record: &Record,
            t_max: f32,
        ) -> RecordHits {
            // SAFETY: the caller checked AVX-512 F and VL support (this function's contract).
            unsafe { record_hits_avx2::<true>(ray, record, t_max) }
        }
    }
}
