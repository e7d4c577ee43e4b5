//! Ray/box tests of one ray against the eight children of a [`WideNode`].
//!
//! Each kernel computes, for every child, the same values as [`RayBoxTest::enter_with_margin`]
//! (the scalar twin) in the same order of operations: per axis `tn = (near plane − o)·(1/d)`
//! folded into `near = max(tn, near)` and `tf = (far plane − o)·(1/d)` into `far = min(tf, far)`,
//! then `near − margin <= far + margin`, with the ray's one margin for every box. x86's
//! `maxps`/`minps` return their second operand when the first is NaN, which is how the scalar
//! `f32::max`/`min` treat a NaN `tn`/`tf` (a ray inside a box's face plane): the tests in
//! `bvh/tests.rs` check that all kernels agree bit for bit.

use super::bounds::{Bounds, Frustum, RayBoxTest};
use super::leaf::{Record, RecordHits, record_hits_scalar};
use super::packet::packet_leaf_scalar;
use super::packet_rays::PacketRays;
use super::wide::{WIDTH, WideBvh, WideNode};
use crate::triangle::WatertightRay;

/// Which children a ray enters, and where.
pub(crate) trait NodeKernel: Sized {
    /// The ray, prepared for this kernel once per ray.
    type Ray: Copy;

    /// Prepares a ray for the boxes inside a root box whose [`RayBoxTest::margin`] is `margin`.
    ///
    /// # Safety
    /// As for [`enter`](Self::enter).
    unsafe fn prepare(ray: &RayBoxTest, margin: f32) -> Self::Ray;

    /// The mask of children entered within `[t_min, t_limit]` (bit `k` for child `k`), and each
    /// child's entry distance (meaningful only where the bit is set), as
    /// [`RayBoxTest::enter_with_margin`] decides them.
    ///
    /// # Safety
    /// The CPU must support the kernel's instruction set (checked once when a BVH picks it).
    unsafe fn enter(node: &WideNode, ray: &Self::Ray, t_limit: f32) -> (u32, [f32; WIDTH]);

    /// Tests the rays of a packet in `open` that enter `bounds` against the triangles of the
    /// leaf inside it: for the closest hit (`occlusion` false: each ray's best hit is offered
    /// every hit), or for occlusion (rays hit are taken out of `open`). Decides exactly as the
    /// single-ray tests do; the scalar twin is [`packet_leaf_scalar`].
    ///
    /// # Safety
    /// As for [`enter`](Self::enter).
    #[inline(always)]
    unsafe fn packet_leaf(
        rays: &mut PacketRays,
        open: &mut u64,
        occlusion: bool,
        bvh: &WideBvh,
        bounds: &Bounds,
        offset: u32,
    ) {
        // SAFETY: the caller's guarantee.
        unsafe { packet_leaf_scalar::<Self>(rays, open, occlusion, bvh, bounds, offset) }
    }

    /// A packet's bound, prepared for this kernel once per packet.
    type Frustum: Copy;

    /// Prepares a packet's bound.
    ///
    /// # Safety
    /// As for [`enter`](Self::enter).
    unsafe fn prepare_frustum(frustum: &Frustum) -> Self::Frustum;

    /// The mask of children that some ray of the packet may enter within `[t_min, t_limit]`,
    /// and the packet's entry distance into each, as [`Frustum::enter`] (the scalar twin)
    /// computes them.
    ///
    /// # Safety
    /// As for [`enter`](Self::enter).
    unsafe fn enter_frustum(
        node: &WideNode,
        frustum: &Self::Frustum,
        t_limit: f32,
    ) -> (u32, [f32; WIDTH]);

    /// What a ray's triangle tests need, in this kernel's registers, prepared once per ray.
    type RecordRay: Copy;

    /// Prepares a ray for [`record_hits`](Self::record_hits).
    ///
    /// # Safety
    /// As for [`enter`](Self::enter).
    unsafe fn prepare_record_ray(ray: &WatertightRay) -> Self::RecordRay;

    /// The hits of a ray on the triangles of a leaf record below `t_max`, as
    /// [`WatertightRay::intersect`] decides them. The records must hold no zero-area triangles
    /// (the BVH leaves them out). The scalar twin is [`record_hits_scalar`].
    ///
    /// # Safety
    /// As for [`enter`](Self::enter).
    unsafe fn record_hits(
        ray: &TriangleRay<Self::RecordRay>,
        record: &Record,
        t_max: f32,
    ) -> RecordHits;
}

/// A ray prepared for the triangle tests of a kernel whose per-ray form is `R`: the scalar test's
/// setup (for the triangles a kernel leaves undecided) and the kernel's.
#[derive(Clone, Copy)]
pub(crate) struct TriangleRay<R> {
    pub ray: WatertightRay,
    pub lanes: R,
}

/// Prepares `ray` for `K`'s triangle tests.
///
/// # Safety
/// As for [`NodeKernel::enter`].
#[inline(always)]
pub(crate) unsafe fn prepare_triangle_ray<K: NodeKernel>(
    ray: &WatertightRay,
) -> TriangleRay<K::RecordRay> {
    // SAFETY: the caller's guarantee.
    TriangleRay { ray: *ray, lanes: unsafe { K::prepare_record_ray(ray) } }
}

/// Plane rows of the near and far planes per axis: the box's min for a positive direction.
#[inline(always)]
pub(super) fn plane_rows(negative: [bool; 3]) -> ([usize; 3], [usize; 3]) {
    // Written out rather than `[0, 1, 2].map(..)`, whose closure is not inlined into the
    // instruction sets' entry points (it lacks their target features).
    let near = |axis: usize| if negative[axis] { 3 + axis } else { axis };
    let far = |axis: usize| if negative[axis] { axis } else { 3 + axis };
    ([near(0), near(1), near(2)], [far(0), far(1), far(2)])
}

/// The scalar twin: [`RayBoxTest::enter_with_margin`] per child.
pub(crate) struct Scalar;

impl NodeKernel for Scalar {
    type Ray = (RayBoxTest, f32);
    type RecordRay = ();

    #[inline(always)]
    unsafe fn prepare_record_ray(_: &WatertightRay) {}

    #[inline(always)]
    unsafe fn record_hits(ray: &TriangleRay<()>, record: &Record, t_max: f32) -> RecordHits {
        record_hits_scalar(&ray.ray, record, t_max)
    }

    #[inline(always)]
    unsafe fn prepare(ray: &RayBoxTest, margin: f32) -> (RayBoxTest, f32) {
        (*ray, margin)
    }

    #[inline(always)]
    unsafe fn enter(
        node: &WideNode,
        (ray, margin): &(RayBoxTest, f32),
        t_limit: f32,
    ) -> (u32, [f32; WIDTH]) {
        let mut mask = 0;
        let mut near = [0.0; WIDTH];
        for (k, slot) in near.iter_mut().enumerate() {
            if let Some(t) = ray.enter_with_margin(&node.bounds(k), t_limit, *margin) {
                mask |= 1 << k;
                *slot = t;
            }
        }
        (mask, near)
    }

    type Frustum = Frustum;

    #[inline(always)]
    unsafe fn prepare_frustum(frustum: &Frustum) -> Frustum {
        *frustum
    }

    #[inline(always)]
    unsafe fn enter_frustum(
        node: &WideNode,
        frustum: &Frustum,
        t_limit: f32,
    ) -> (u32, [f32; WIDTH]) {
        let mut mask = 0;
        let mut near = [0.0; WIDTH];
        for (k, slot) in near.iter_mut().enumerate() {
            if let Some(t) = frustum.enter(&node.bounds(k), t_limit) {
                mask |= 1 << k;
                *slot = t;
            }
        }
        (mask, near)
    }
}

#[cfg(target_arch = "x86_64")]
pub(crate) use x86::{Avx2, Avx512, Sse};
#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::*;

    use super::*;
    use crate::bvh::lanes::Lanes;
    use crate::bvh::leaf_kernels::{record_hits_avx2, record_hits_sse};
    use crate::bvh::packet_kernels::{FrustumBroadcast, packet_leaf_lanes};
    use crate::bvh::watertight_lanes::RayBroadcast;

    /// Eight children with two 4-wide SSE halves: every x86-64 CPU has SSE2.
    pub(crate) struct Sse;

    /// A ray broadcast into vector registers, with its box margin.
    #[derive(Clone, Copy)]
    pub(crate) struct Broadcast<V> {
        origin: [V; 3],
        inv: [V; 3],
        t_min: V,
        margin: V,
        near_rows: [usize; 3],
        far_rows: [usize; 3],
    }

    impl<V: Lanes> Broadcast<V> {
        /// Broadcasts `ray`.
        ///
        /// # Safety
        /// The CPU must support `V`'s instruction set.
        #[inline(always)]
        unsafe fn new(ray: &RayBoxTest, margin: f32) -> Self {
            let (near_rows, far_rows) = plane_rows(ray.negative);
            // SAFETY: the caller's guarantee.
            unsafe {
                Broadcast {
                    origin: [
                        V::splat(ray.origin[0]),
                        V::splat(ray.origin[1]),
                        V::splat(ray.origin[2]),
                    ],
                    inv: [
                        V::splat(ray.inv_direction[0]),
                        V::splat(ray.inv_direction[1]),
                        V::splat(ray.inv_direction[2]),
                    ],
                    t_min: V::splat(ray.t_min),
                    margin: V::splat(margin),
                    near_rows,
                    far_rows,
                }
            }
        }
    }

    impl NodeKernel for Sse {
        type Ray = Broadcast<__m128>;
        type Frustum = FrustumBroadcast<__m128>;

        #[inline(always)]
        unsafe fn packet_leaf(
            rays: &mut PacketRays,
            open: &mut u64,
            occlusion: bool,
            bvh: &WideBvh,
            bounds: &Bounds,
            offset: u32,
        ) {
            // SAFETY: the caller's guarantee.
            unsafe { packet_leaf_lanes::<__m128, 4>(rays, open, occlusion, bvh, bounds, offset) }
        }

        #[inline(always)]
        unsafe fn prepare_frustum(frustum: &Frustum) -> Self::Frustum {
            // SAFETY: SSE2 is part of x86-64.
            unsafe { FrustumBroadcast::new(frustum) }
        }

        #[inline(always)]
        unsafe fn enter_frustum(
            node: &WideNode,
            frustum: &Self::Frustum,
            t_limit: f32,
        ) -> (u32, [f32; WIDTH]) {
            let mut out = [0.0; WIDTH];
            // SAFETY: SSE2 is part of x86-64; 0 and 4 are the halves of a node.
            unsafe {
                let mask = frustum.enter(node, t_limit, 0, &mut out)
                    | frustum.enter(node, t_limit, 4, &mut out);
                (mask, out)
            }
        }

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

        #[inline(always)]
        unsafe fn prepare(ray: &RayBoxTest, margin: f32) -> Self::Ray {
            // SAFETY: SSE2 is part of x86-64.
            unsafe { Broadcast::new(ray, margin) }
        }

        #[inline(always)]
        unsafe fn enter(node: &WideNode, ray: &Self::Ray, t_limit: f32) -> (u32, [f32; WIDTH]) {
            // SAFETY: SSE2 is part of x86-64; every load reads 4 floats inside a row of 8 of
            // `node`, which is 32-byte aligned, so offsets 0 and 4 are 16-byte aligned.
            unsafe {
                let limit = _mm_set1_ps(t_limit);
                let mut out = [0.0f32; WIDTH];
                let mut mask = 0u32;
                for half in 0..2 {
                    let mut near = ray.t_min;
                    let mut far = limit;
                    for axis in 0..3 {
                        let np = _mm_load_ps(node.planes[ray.near_rows[axis]][4 * half..].as_ptr());
                        let fp = _mm_load_ps(node.planes[ray.far_rows[axis]][4 * half..].as_ptr());
                        let tn = _mm_mul_ps(_mm_sub_ps(np, ray.origin[axis]), ray.inv[axis]);
                        let tf = _mm_mul_ps(_mm_sub_ps(fp, ray.origin[axis]), ray.inv[axis]);
                        near = _mm_max_ps(tn, near);
                        far = _mm_min_ps(tf, far);
                    }
                    let near = _mm_sub_ps(near, ray.margin);
                    let far = _mm_add_ps(far, ray.margin);
                    let hit = _mm_cmple_ps(near, far);
                    mask |= (_mm_movemask_ps(hit) as u32) << (4 * half);
                    _mm_storeu_ps(out[4 * half..].as_mut_ptr(), near);
                }
                (mask, out)
            }
        }
    }

    /// All eight children in one AVX2 register.
    pub(crate) struct Avx2;

    impl NodeKernel for Avx2 {
        type Ray = Broadcast<__m256>;
        type Frustum = FrustumBroadcast<__m256>;

        #[inline(always)]
        unsafe fn packet_leaf(
            rays: &mut PacketRays,
            open: &mut u64,
            occlusion: bool,
            bvh: &WideBvh,
            bounds: &Bounds,
            offset: u32,
        ) {
            // SAFETY: the caller's guarantee.
            unsafe { packet_leaf_lanes::<__m256, 8>(rays, open, occlusion, bvh, bounds, offset) }
        }

        #[inline(always)]
        unsafe fn prepare_frustum(frustum: &Frustum) -> Self::Frustum {
            // SAFETY: the caller checked AVX2 support (this function's contract).
            unsafe { FrustumBroadcast::new(frustum) }
        }

        #[inline(always)]
        unsafe fn enter_frustum(
            node: &WideNode,
            frustum: &Self::Frustum,
            t_limit: f32,
        ) -> (u32, [f32; WIDTH]) {
            let mut out = [0.0; WIDTH];
            // SAFETY: the caller checked AVX2 support; 0 is the start of a node's rows.
            unsafe {
                let mask = frustum.enter(node, t_limit, 0, &mut out);
                (mask, out)
            }
        }

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

        #[inline(always)]
        unsafe fn prepare(ray: &RayBoxTest, margin: f32) -> Self::Ray {
            // SAFETY: the caller checked AVX2 support (this function's contract).
            unsafe { Broadcast::new(ray, margin) }
        }

        #[inline(always)]
        unsafe fn enter(node: &WideNode, ray: &Self::Ray, t_limit: f32) -> (u32, [f32; WIDTH]) {
            // SAFETY: the caller checked AVX2 support; every load reads one 32-byte aligned row
            // of 8 floats of `node`.
            unsafe {
                let mut near = ray.t_min;
                let mut far = _mm256_set1_ps(t_limit);
                for axis in 0..3 {
                    let np = _mm256_load_ps(node.planes[ray.near_rows[axis]].as_ptr());
                    let fp = _mm256_load_ps(node.planes[ray.far_rows[axis]].as_ptr());
                    let tn = _mm256_mul_ps(_mm256_sub_ps(np, ray.origin[axis]), ray.inv[axis]);
                    let tf = _mm256_mul_ps(_mm256_sub_ps(fp, ray.origin[axis]), ray.inv[axis]);
                    near = _mm256_max_ps(tn, near);
                    far = _mm256_min_ps(tf, far);
                }
                let near = _mm256_sub_ps(near, ray.margin);
                let far = _mm256_add_ps(far, ray.margin);
                let hit = _mm256_cmp_ps::<_CMP_LE_OQ>(near, far);
                let mut out = [0.0f32; WIDTH];
                _mm256_storeu_ps(out.as_mut_ptr(), near);
                (_mm256_movemask_ps(hit) as u32, out)
            }
        }
    }

    /// AVX2's node kernel, leaf records with AVX-512 VL's two-table permute, and packet leaves
    /// 16 rays per instruction with AVX-512.
    pub(crate) struct Avx512;

    impl NodeKernel for Avx512 {
        type Ray = <Avx2 as NodeKernel>::Ray;
        type Frustum = <Avx2 as NodeKernel>::Frustum;

        #[inline(always)]
        unsafe fn packet_leaf(
            rays: &mut PacketRays,
            open: &mut u64,
            occlusion: bool,
            bvh: &WideBvh,
            bounds: &Bounds,
            offset: u32,
        ) {
            // SAFETY: the caller checked AVX-512 F support (this function's contract).
            unsafe { packet_leaf_lanes::<__m512, 16>(rays, open, occlusion, bvh, bounds, offset) }
        }

        #[inline(always)]
        unsafe fn prepare_frustum(frustum: &Frustum) -> Self::Frustum {
            // SAFETY: AVX-512 implies AVX2 (this function's contract).
            unsafe { Avx2::prepare_frustum(frustum) }
        }

        #[inline(always)]
        unsafe fn enter_frustum(
            node: &WideNode,
            frustum: &Self::Frustum,
            t_limit: f32,
        ) -> (u32, [f32; WIDTH]) {
            // SAFETY: as above.
            unsafe { Avx2::enter_frustum(node, frustum, t_limit) }
        }

        type RecordRay = RayBroadcast<__m256>;

        #[inline(always)]
        unsafe fn prepare_record_ray(ray: &WatertightRay) -> RayBroadcast<__m256> {
            // SAFETY: the caller checked AVX-512 F support (this function's contract).
            unsafe { RayBroadcast::new(ray) }
        }

        #[inline(always)]
        unsafe fn record_hits(
            ray: &TriangleRay<RayBroadcast<__m256>>,
            record: &Record,
            t_max: f32,
        ) -> RecordHits {
            // SAFETY: the caller checked AVX-512 F support (this function's contract).
            unsafe { record_hits_avx2::<true>(ray, record, t_max) }
        }

        #[inline(always)]
        unsafe fn prepare(ray: &RayBoxTest, margin: f32) -> Self::Ray {
            // SAFETY: as above.
            unsafe { Avx2::prepare(ray, margin) }
        }

        #[inline(always)]
        unsafe fn enter(node: &WideNode, ray: &Self::Ray, t_limit: f32) -> (u32, [f32; WIDTH]) {
            // SAFETY: as above.
            unsafe { Avx2::enter(node, ray, t_limit) }
        }
    }
}
