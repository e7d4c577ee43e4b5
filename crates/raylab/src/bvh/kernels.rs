//! Ray/box tests of one ray against the eight children of a [`WideNode`].
//!
//! Each kernel computes, for every child, the same values as [`RayBoxTest::enter`] (the scalar
//! twin) in the same order of operations: per axis `tn = (near plane − o)·(1/d)` folded into
//! `near = max(tn, near)`, and `tf = ((far plane − o)·(1/d))·(1 + 2γ₃)` into `far = min(tf, far)`,
//! then, both moved out by `SLAB_PAD` times the box's reach on the ray's dominant axis,
//! `near <= far`. x86's `maxps`/`minps` return their second operand when the first is NaN,
//! which is how the scalar `f32::max`/`min` treat a NaN `tn`/`tf` (a ray inside a box's face
//! plane): the tests in `bvh/tests.rs` check that all kernels agree bit for bit.

use super::bounds::{Bounds, FAR_SCALE, Frustum, RayBoxTest, SLAB_PAD};
use super::build::BLOCK;
use super::packet::{PACKET, PacketRays, packet_leaf_scalar};
use super::wide::{WIDTH, WideBvh, WideNode};
use crate::triangle::{TriangleBlock, WatertightRay};

/// Which children a ray enters, and where.
pub(crate) trait NodeKernel: Sized {
    /// The ray, prepared for this kernel once per ray.
    type Ray: Copy;

    /// Prepares a ray.
    ///
    /// # Safety
    /// As for [`enter`](Self::enter).
    unsafe fn prepare(ray: &RayBoxTest) -> Self::Ray;

    /// The mask of children entered within `[t_min, t_limit]` (bit `k` for child `k`), and each
    /// child's entry distance (meaningful only where the bit is set).
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
        first_block: u32,
        blocks: u32,
    ) {
        // SAFETY: the caller's guarantee.
        unsafe {
            packet_leaf_scalar::<Self>(rays, open, occlusion, bvh, bounds, first_block, blocks)
        }
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

    /// The hits of a ray on the triangles of `block` below `t_max`, as
    /// [`WatertightRay::intersect`] decides them. The blocks must hold no zero-area triangles
    /// (the BVH leaves them out). The scalar twin is [`block_hits_scalar`].
    ///
    /// # Safety
    /// As for [`enter`](Self::enter).
    #[inline(always)]
    unsafe fn block_hits(
        ray: &WatertightRay,
        block: &TriangleBlock<BLOCK>,
        t_max: f32,
    ) -> BlockHits {
        block_hits_scalar(ray, block, t_max)
    }
}

/// What a block test decides for each of its four lanes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct BlockHits {
    /// Lanes hit, with their `t` and barycentrics below, exactly as `intersect` computes them.
    pub hits: u32,
    /// Lanes that only [`WatertightRay::intersect`] can decide (an edge function rounded to zero
    /// and must be recomputed in double precision).
    pub undecided: u32,
    /// Ray parameter per lane (meaningful where `hits` has the bit).
    pub t: [f32; BLOCK],
    /// Barycentric weight of `v1` per lane.
    pub b1: [f32; BLOCK],
    /// Barycentric weight of `v2` per lane.
    pub b2: [f32; BLOCK],
}

/// The scalar twin of the block kernels: the batched pre-test, then the full scalar test on each
/// candidate. Decides every lane.
#[inline(always)]
pub(crate) fn block_hits_scalar(
    ray: &WatertightRay,
    block: &TriangleBlock<BLOCK>,
    t_max: f32,
) -> BlockHits {
    let mut out = BlockHits::default();
    let mut candidates = ray.block_candidates(block, t_max);
    while candidates != 0 {
        let lane = candidates.trailing_zeros() as usize;
        candidates &= candidates - 1;
        let [v0, v1, v2] = block.triangle(lane);
        if let Some(h) = ray.intersect(v0, v1, v2, t_max) {
            out.hits |= 1 << lane;
            out.t[lane] = h.t;
            out.b1[lane] = h.b1;
            out.b2[lane] = h.b2;
        }
    }
    out
}

/// Plane rows of the near and far planes per axis: the box's min for a positive direction.
#[inline(always)]
fn plane_rows(negative: [bool; 3]) -> ([usize; 3], [usize; 3]) {
    // Written out rather than `[0, 1, 2].map(..)`, whose closure is not inlined into the
    // instruction sets' entry points (it lacks their target features).
    let near = |axis: usize| if negative[axis] { 3 + axis } else { axis };
    let far = |axis: usize| if negative[axis] { axis } else { 3 + axis };
    ([near(0), near(1), near(2)], [far(0), far(1), far(2)])
}

/// The scalar twin: [`RayBoxTest::enter`] per child.
pub(crate) struct Scalar;

impl NodeKernel for Scalar {
    type Ray = RayBoxTest;

    #[inline(always)]
    unsafe fn prepare(ray: &RayBoxTest) -> RayBoxTest {
        *ray
    }

    #[inline(always)]
    unsafe fn enter(node: &WideNode, ray: &RayBoxTest, t_limit: f32) -> (u32, [f32; WIDTH]) {
        let mut mask = 0;
        let mut near = [0.0; WIDTH];
        for (k, slot) in near.iter_mut().enumerate() {
            if let Some(t) = ray.enter(&node.bounds(k), t_limit) {
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

#[cfg(all(test, target_arch = "x86_64"))]
pub(crate) use x86::block_hits_sse;
#[cfg(target_arch = "x86_64")]
pub(crate) use x86::{Avx2, Avx512, Sse};
#[cfg(target_arch = "x86_64")]
pub(crate) use x86::{LaneHits, LaneMask, Lanes, WatertightLanes, watertight_lanes_with};

#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::*;

    use super::*;

    /// Eight children with two 4-wide SSE halves: every x86-64 CPU has SSE2.
    pub(crate) struct Sse;

    /// A ray broadcast into vector registers, its axes in the order dominant axis first (so that
    /// the node kernels take the box's reach from axis 0 without a branch), then the other two.
    #[derive(Clone, Copy)]
    pub(crate) struct Broadcast<V> {
        origin: [V; 3],
        inv: [V; 3],
        t_min: V,
        near_rows: [usize; 3],
        far_rows: [usize; 3],
    }

    impl<V: Lanes> Broadcast<V> {
        /// Broadcasts `ray`.
        ///
        /// # Safety
        /// The CPU must support `V`'s instruction set.
        #[inline(always)]
        unsafe fn new(ray: &RayBoxTest) -> Self {
            let (near_rows, far_rows) = plane_rows(ray.negative);
            let kz = ray.dominant_axis;
            let axes = [kz, (kz + 1) % 3, (kz + 2) % 3];
            // SAFETY: the caller's guarantee.
            unsafe {
                Broadcast {
                    origin: [
                        V::splat(ray.origin[axes[0]]),
                        V::splat(ray.origin[axes[1]]),
                        V::splat(ray.origin[axes[2]]),
                    ],
                    inv: [
                        V::splat(ray.inv_direction[axes[0]]),
                        V::splat(ray.inv_direction[axes[1]]),
                        V::splat(ray.inv_direction[axes[2]]),
                    ],
                    t_min: V::splat(ray.t_min),
                    near_rows: [near_rows[axes[0]], near_rows[axes[1]], near_rows[axes[2]]],
                    far_rows: [far_rows[axes[0]], far_rows[axes[1]], far_rows[axes[2]]],
                }
            }
        }
    }

    /// The few vector operations the frustum kernel needs, for SSE's four lanes and AVX's eight,
    /// so that one generic function serves both.
    pub(crate) trait Lanes: Copy {
        /// # Safety
        /// The CPU must support the register's instruction set (for this whole trait).
        unsafe fn splat(x: f32) -> Self;
        /// # Safety
        /// `p` must point to as many floats as a register holds, aligned to its size.
        unsafe fn load(p: *const f32) -> Self;
        /// # Safety
        /// `p` must point to as many floats as a register holds.
        unsafe fn loadu(p: *const f32) -> Self;
        /// # Safety
        /// `p` must point to as many writable floats as a register holds.
        unsafe fn store(self, p: *mut f32);
        unsafe fn add(self, o: Self) -> Self;
        unsafe fn sub(self, o: Self) -> Self;
        unsafe fn mul(self, o: Self) -> Self;
        /// `minps`: the second operand where either is NaN.
        unsafe fn min(self, o: Self) -> Self;
        /// `maxps`: the second operand where either is NaN.
        unsafe fn max(self, o: Self) -> Self;
        unsafe fn abs(self) -> Self;
        /// Bitwise `self ^ o`.
        unsafe fn xor(self, o: Self) -> Self;
        /// Bitwise `self | o`.
        unsafe fn or_bits(self, o: Self) -> Self;
        /// The sign bit alone (`self & -0.0`).
        unsafe fn sign(self) -> Self;
        /// The lanes whose sign bit is clear (NaNs included, by their sign bit).
        unsafe fn sign_clear(self) -> Self::Mask;
        /// Bit `k` set where lane `k` of `self <= o` (false for NaN).
        unsafe fn le_mask(self, o: Self) -> u32;
        unsafe fn div(self, o: Self) -> Self;
        /// `if_true` in the lanes of `mask`, `if_false` in the others.
        unsafe fn select(mask: Self::Mask, if_true: Self, if_false: Self) -> Self;
        /// The smallest lane (`minps` order: NaN lanes may or may not count; callers keep them
        /// out).
        unsafe fn reduce_min(self) -> f32;
        /// Comparisons give a mask of the lanes where they hold (ordered: false for NaN, except
        /// `nlt` and `nle`, which are true for NaN).
        unsafe fn eq(self, o: Self) -> Self::Mask;
        unsafe fn gt(self, o: Self) -> Self::Mask;
        unsafe fn lt(self, o: Self) -> Self::Mask;
        unsafe fn nlt(self, o: Self) -> Self::Mask;
        unsafe fn nle(self, o: Self) -> Self::Mask;
        /// A comparison's lanes: all-ones registers for SSE and AVX, a mask register for
        /// AVX-512.
        type Mask: LaneMask;
    }

    /// The lanes where a comparison holds.
    pub(crate) trait LaneMask: Copy {
        /// # Safety
        /// The CPU must support the mask's instruction set (for this whole trait).
        unsafe fn and(self, o: Self) -> Self;
        unsafe fn or(self, o: Self) -> Self;
        /// `self & !o`.
        unsafe fn andnot_of(self, o: Self) -> Self;
        /// Bit `k` set where lane `k` holds.
        unsafe fn bits(self) -> u32;
    }

    /// AVX-512's mask registers: one bit per lane already.
    impl LaneMask for __mmask16 {
        #[inline(always)]
        unsafe fn and(self, o: Self) -> Self {
            self & o
        }
        #[inline(always)]
        unsafe fn or(self, o: Self) -> Self {
            self | o
        }
        #[inline(always)]
        unsafe fn andnot_of(self, o: Self) -> Self {
            self & !o
        }
        #[inline(always)]
        unsafe fn bits(self) -> u32 {
            self as u32
        }
    }

    impl Lanes for __m128 {
        type Mask = __m128;

        #[inline(always)]
        unsafe fn splat(x: f32) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm_set1_ps(x) }
        }
        #[inline(always)]
        unsafe fn load(p: *const f32) -> Self {
            // SAFETY: the trait's contract: the ISA, and `p` points to a register's floats.
            unsafe { _mm_load_ps(p) }
        }
        #[inline(always)]
        unsafe fn loadu(p: *const f32) -> Self {
            // SAFETY: the trait's contract: the ISA, and `p` points to a register's floats.
            unsafe { _mm_loadu_ps(p) }
        }
        #[inline(always)]
        unsafe fn store(self, p: *mut f32) {
            // SAFETY: the trait's contract: the ISA, and `p` has room for a register.
            unsafe { _mm_storeu_ps(p, self) }
        }
        #[inline(always)]
        unsafe fn add(self, o: Self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm_add_ps(self, o) }
        }
        #[inline(always)]
        unsafe fn sub(self, o: Self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm_sub_ps(self, o) }
        }
        #[inline(always)]
        unsafe fn mul(self, o: Self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm_mul_ps(self, o) }
        }
        #[inline(always)]
        unsafe fn min(self, o: Self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm_min_ps(self, o) }
        }
        #[inline(always)]
        unsafe fn max(self, o: Self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm_max_ps(self, o) }
        }
        #[inline(always)]
        unsafe fn abs(self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm_andnot_ps(_mm_set1_ps(-0.0), self) }
        }
        #[inline(always)]
        unsafe fn xor(self, o: Self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm_xor_ps(self, o) }
        }
        #[inline(always)]
        unsafe fn or_bits(self, o: Self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm_or_ps(self, o) }
        }
        #[inline(always)]
        unsafe fn sign(self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm_and_ps(self, _mm_set1_ps(-0.0)) }
        }
        #[inline(always)]
        unsafe fn sign_clear(self) -> Self::Mask {
            // As integers, `x > −1` exactly where the sign bit is clear.
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm_castsi128_ps(_mm_cmpgt_epi32(_mm_castps_si128(self), _mm_set1_epi32(-1))) }
        }
        #[inline(always)]
        unsafe fn le_mask(self, o: Self) -> u32 {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm_movemask_ps(_mm_cmple_ps(self, o)) as u32 }
        }
        #[inline(always)]
        unsafe fn select(mask: Self::Mask, if_true: Self, if_false: Self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm_or_ps(_mm_and_ps(mask, if_true), _mm_andnot_ps(mask, if_false)) }
        }
        #[inline(always)]
        unsafe fn reduce_min(self) -> f32 {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe {
                let pairs = _mm_min_ps(self, _mm_movehl_ps(self, self));
                let one = _mm_min_ss(pairs, _mm_shuffle_ps::<1>(pairs, pairs));
                _mm_cvtss_f32(one)
            }
        }
        #[inline(always)]
        unsafe fn div(self, o: Self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm_div_ps(self, o) }
        }
        #[inline(always)]
        unsafe fn eq(self, o: Self) -> Self::Mask {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm_cmpeq_ps(self, o) }
        }
        #[inline(always)]
        unsafe fn gt(self, o: Self) -> Self::Mask {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm_cmpgt_ps(self, o) }
        }
        #[inline(always)]
        unsafe fn lt(self, o: Self) -> Self::Mask {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm_cmplt_ps(self, o) }
        }
        #[inline(always)]
        unsafe fn nlt(self, o: Self) -> Self::Mask {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm_cmpnlt_ps(self, o) }
        }
        #[inline(always)]
        unsafe fn nle(self, o: Self) -> Self::Mask {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm_cmpnle_ps(self, o) }
        }
    }

    impl LaneMask for __m128 {
        #[inline(always)]
        unsafe fn and(self, o: Self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm_and_ps(self, o) }
        }
        #[inline(always)]
        unsafe fn or(self, o: Self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm_or_ps(self, o) }
        }
        #[inline(always)]
        unsafe fn andnot_of(self, o: Self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm_andnot_ps(o, self) }
        }
        #[inline(always)]
        unsafe fn bits(self) -> u32 {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm_movemask_ps(self) as u32 }
        }
    }

    impl Lanes for __m256 {
        type Mask = __m256;

        #[inline(always)]
        unsafe fn splat(x: f32) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm256_set1_ps(x) }
        }
        #[inline(always)]
        unsafe fn load(p: *const f32) -> Self {
            // SAFETY: the trait's contract: the ISA, and `p` points to a register's floats.
            unsafe { _mm256_load_ps(p) }
        }
        #[inline(always)]
        unsafe fn loadu(p: *const f32) -> Self {
            // SAFETY: the trait's contract: the ISA, and `p` points to a register's floats.
            unsafe { _mm256_loadu_ps(p) }
        }
        #[inline(always)]
        unsafe fn store(self, p: *mut f32) {
            // SAFETY: the trait's contract: the ISA, and `p` has room for a register.
            unsafe { _mm256_storeu_ps(p, self) }
        }
        #[inline(always)]
        unsafe fn add(self, o: Self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm256_add_ps(self, o) }
        }
        #[inline(always)]
        unsafe fn sub(self, o: Self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm256_sub_ps(self, o) }
        }
        #[inline(always)]
        unsafe fn mul(self, o: Self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm256_mul_ps(self, o) }
        }
        #[inline(always)]
        unsafe fn min(self, o: Self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm256_min_ps(self, o) }
        }
        #[inline(always)]
        unsafe fn max(self, o: Self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm256_max_ps(self, o) }
        }
        #[inline(always)]
        unsafe fn abs(self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm256_andnot_ps(_mm256_set1_ps(-0.0), self) }
        }
        #[inline(always)]
        unsafe fn xor(self, o: Self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm256_xor_ps(self, o) }
        }
        #[inline(always)]
        unsafe fn or_bits(self, o: Self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm256_or_ps(self, o) }
        }
        #[inline(always)]
        unsafe fn sign(self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm256_and_ps(self, _mm256_set1_ps(-0.0)) }
        }
        #[inline(always)]
        unsafe fn sign_clear(self) -> Self::Mask {
            // As integers, `x > −1` exactly where the sign bit is clear (AVX2).
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe {
                _mm256_castsi256_ps(_mm256_cmpgt_epi32(
                    _mm256_castps_si256(self),
                    _mm256_set1_epi32(-1),
                ))
            }
        }
        #[inline(always)]
        unsafe fn le_mask(self, o: Self) -> u32 {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(self, o)) as u32 }
        }
        #[inline(always)]
        unsafe fn select(mask: Self::Mask, if_true: Self, if_false: Self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm256_blendv_ps(if_false, if_true, mask) }
        }
        #[inline(always)]
        unsafe fn reduce_min(self) -> f32 {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe {
                let half =
                    _mm_min_ps(_mm256_castps256_ps128(self), _mm256_extractf128_ps::<1>(self));
                half.reduce_min()
            }
        }
        #[inline(always)]
        unsafe fn div(self, o: Self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm256_div_ps(self, o) }
        }
        #[inline(always)]
        unsafe fn eq(self, o: Self) -> Self::Mask {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm256_cmp_ps::<_CMP_EQ_OQ>(self, o) }
        }
        #[inline(always)]
        unsafe fn gt(self, o: Self) -> Self::Mask {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm256_cmp_ps::<_CMP_GT_OQ>(self, o) }
        }
        #[inline(always)]
        unsafe fn lt(self, o: Self) -> Self::Mask {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm256_cmp_ps::<_CMP_LT_OQ>(self, o) }
        }
        #[inline(always)]
        unsafe fn nlt(self, o: Self) -> Self::Mask {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm256_cmp_ps::<_CMP_NLT_UQ>(self, o) }
        }
        #[inline(always)]
        unsafe fn nle(self, o: Self) -> Self::Mask {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm256_cmp_ps::<_CMP_NLE_UQ>(self, o) }
        }
    }

    impl LaneMask for __m256 {
        #[inline(always)]
        unsafe fn and(self, o: Self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm256_and_ps(self, o) }
        }
        #[inline(always)]
        unsafe fn or(self, o: Self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm256_or_ps(self, o) }
        }
        #[inline(always)]
        unsafe fn andnot_of(self, o: Self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm256_andnot_ps(o, self) }
        }
        #[inline(always)]
        unsafe fn bits(self) -> u32 {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm256_movemask_ps(self) as u32 }
        }
    }

    /// Sixteen lanes, for packets on AVX-512: comparisons give mask registers.
    impl Lanes for __m512 {
        type Mask = __mmask16;

        #[inline(always)]
        unsafe fn splat(x: f32) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm512_set1_ps(x) }
        }
        #[inline(always)]
        unsafe fn load(p: *const f32) -> Self {
            // SAFETY: the trait's contract: the ISA, and `p` points to a register's floats.
            unsafe { _mm512_load_ps(p) }
        }
        #[inline(always)]
        unsafe fn loadu(p: *const f32) -> Self {
            // SAFETY: the trait's contract: the ISA, and `p` points to a register's floats.
            unsafe { _mm512_loadu_ps(p) }
        }
        #[inline(always)]
        unsafe fn store(self, p: *mut f32) {
            // SAFETY: the trait's contract: the ISA, and `p` has room for a register.
            unsafe { _mm512_storeu_ps(p, self) }
        }
        #[inline(always)]
        unsafe fn add(self, o: Self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm512_add_ps(self, o) }
        }
        #[inline(always)]
        unsafe fn sub(self, o: Self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm512_sub_ps(self, o) }
        }
        #[inline(always)]
        unsafe fn mul(self, o: Self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm512_mul_ps(self, o) }
        }
        #[inline(always)]
        unsafe fn min(self, o: Self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm512_min_ps(self, o) }
        }
        #[inline(always)]
        unsafe fn max(self, o: Self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm512_max_ps(self, o) }
        }
        #[inline(always)]
        unsafe fn abs(self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm512_abs_ps(self) }
        }
        #[inline(always)]
        unsafe fn xor(self, o: Self) -> Self {
            // Integer forms: the float ones need AVX-512 DQ.
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe {
                _mm512_castsi512_ps(_mm512_xor_si512(
                    _mm512_castps_si512(self),
                    _mm512_castps_si512(o),
                ))
            }
        }
        #[inline(always)]
        unsafe fn or_bits(self, o: Self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe {
                _mm512_castsi512_ps(_mm512_or_si512(
                    _mm512_castps_si512(self),
                    _mm512_castps_si512(o),
                ))
            }
        }
        #[inline(always)]
        unsafe fn sign(self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe {
                _mm512_castsi512_ps(_mm512_and_si512(
                    _mm512_castps_si512(self),
                    _mm512_set1_epi32(i32::MIN),
                ))
            }
        }
        #[inline(always)]
        unsafe fn sign_clear(self) -> Self::Mask {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm512_cmpge_epi32_mask(_mm512_castps_si512(self), _mm512_setzero_si512()) }
        }
        #[inline(always)]
        unsafe fn le_mask(self, o: Self) -> u32 {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm512_cmp_ps_mask::<_CMP_LE_OQ>(self, o) as u32 }
        }
        #[inline(always)]
        unsafe fn select(mask: Self::Mask, if_true: Self, if_false: Self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm512_mask_blend_ps(mask, if_false, if_true) }
        }
        #[inline(always)]
        unsafe fn reduce_min(self) -> f32 {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm512_reduce_min_ps(self) }
        }
        #[inline(always)]
        unsafe fn div(self, o: Self) -> Self {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm512_div_ps(self, o) }
        }
        #[inline(always)]
        unsafe fn eq(self, o: Self) -> Self::Mask {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm512_cmp_ps_mask::<_CMP_EQ_OQ>(self, o) }
        }
        #[inline(always)]
        unsafe fn gt(self, o: Self) -> Self::Mask {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm512_cmp_ps_mask::<_CMP_GT_OQ>(self, o) }
        }
        #[inline(always)]
        unsafe fn lt(self, o: Self) -> Self::Mask {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm512_cmp_ps_mask::<_CMP_LT_OQ>(self, o) }
        }
        #[inline(always)]
        unsafe fn nlt(self, o: Self) -> Self::Mask {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm512_cmp_ps_mask::<_CMP_NLT_UQ>(self, o) }
        }
        #[inline(always)]
        unsafe fn nle(self, o: Self) -> Self::Mask {
            // SAFETY: the trait's contract: the caller guarantees the instruction set.
            unsafe { _mm512_cmp_ps_mask::<_CMP_NLE_UQ>(self, o) }
        }
    }

    /// The lanes of a packet row from `base` on.
    ///
    /// # Safety
    /// The CPU must support `V`'s instruction set, and `base` plus the register's lanes must
    /// not pass `PACKET`.
    #[inline(always)]
    unsafe fn lanes<V: Lanes>(row: &[f32; PACKET], base: usize) -> V {
        debug_assert!(base < PACKET);
        // SAFETY: the caller's guarantee.
        unsafe { V::loadu(row.as_ptr().add(base)) }
    }

    /// [`NodeKernel::packet_leaf`] with `L` rays per register `V`: the slab test of the leaf's box
    /// and the watertight test of each of its triangles, for `L` rays at a time, by the same
    /// operations as the single-ray tests ([`RayBoxTest::enter`], [`watertight_lanes`]).
    ///
    /// # Safety
    /// The CPU must support `V`'s instruction set, which holds `L` (4, 8 or 16) floats.
    #[inline(always)]
    unsafe fn packet_leaf_lanes<V: Lanes, const L: usize>(
        rays: &mut PacketRays,
        open: &mut u64,
        occlusion: bool,
        bvh: &WideBvh,
        bounds: &Bounds,
        first_block: u32,
        blocks: u32,
    ) {
        let negative = rays.negative;
        // Per axis, not `[0, 1, 2].map(..)` (see `plane_rows`).
        let (lo, hi) = (bounds.min, bounds.max);
        let near_planes = [
            if negative[0] { hi.x } else { lo.x },
            if negative[1] { hi.y } else { lo.y },
            if negative[2] { hi.z } else { lo.z },
        ];
        let far_planes = [
            if negative[0] { lo.x } else { hi.x },
            if negative[1] { lo.y } else { hi.y },
            if negative[2] { lo.z } else { hi.z },
        ];
        let [kx, ky, kz] = rays.k;
        // SAFETY: the caller's guarantee; every load reads `L` lanes from `base`, and
        // `base + L <= PACKET` because `PACKET` is a multiple of `L`.
        unsafe {
            for base in (0..rays.len).step_by(L) {
                let mut active = (*open >> base) as u32 & ((1 << L) - 1);
                if active == 0 {
                    continue;
                }
                // The slab test, as `RayBoxTest::enter` per lane (no operand is NaN: packet
                // rays have finite origins and `1/d`, and a leaf's box is finite).
                let mut near = lanes::<V>(&rays.box_t_min, base);
                let mut far = lanes::<V>(&rays.box_limit, base);
                let mut reach = V::splat(0.0);
                for axis in 0..3 {
                    let o = lanes::<V>(&rays.origin[axis], base);
                    let inv = lanes::<V>(&rays.inv_direction[axis], base);
                    let t_near = V::splat(near_planes[axis]).sub(o).mul(inv);
                    let t_far = V::splat(far_planes[axis]).sub(o).mul(inv);
                    near = t_near.max(near);
                    far = t_far.mul(V::splat(FAR_SCALE)).min(far);
                    if axis == kz {
                        reach = t_near.abs().max(t_far.abs());
                    }
                }
                let pad = reach.mul(V::splat(SLAB_PAD));
                active &= near.sub(pad).le_mask(far.add(pad));
                if active == 0 {
                    continue;
                }

                let shear = [
                    lanes::<V>(&rays.shear[0], base),
                    lanes::<V>(&rays.shear[1], base),
                    lanes::<V>(&rays.shear[2], base),
                ];
                let origin = [
                    lanes::<V>(&rays.origin[kx], base),
                    lanes::<V>(&rays.origin[ky], base),
                    lanes::<V>(&rays.origin[kz], base),
                ];
                let t_min = lanes::<V>(&rays.triangle_t_min, base);
                'blocks: for b in first_block as usize..(first_block + blocks) as usize {
                    let block = &bvh.blocks[b];
                    for (lane, &id) in bvh.ids[b].iter().enumerate() {
                        if id == u32::MAX {
                            continue;
                        }
                        let [p0, p1, p2] = &block.vertices;
                        let test = WatertightLanes {
                            origin,
                            shear,
                            abs_shear: [shear[0].abs(), shear[1].abs()],
                            t_min,
                            t_max: lanes::<V>(&rays.triangle_limit, base),
                            vertices: [
                                [
                                    V::splat(p0[kx][lane]),
                                    V::splat(p0[ky][lane]),
                                    V::splat(p0[kz][lane]),
                                ],
                                [
                                    V::splat(p1[kx][lane]),
                                    V::splat(p1[ky][lane]),
                                    V::splat(p1[kz][lane]),
                                ],
                                [
                                    V::splat(p2[kx][lane]),
                                    V::splat(p2[ky][lane]),
                                    V::splat(p2[kz][lane]),
                                ],
                            ],
                        };
                        let decided = watertight_lanes(&test, active);
                        let mut hits = decided.hits;
                        let (mut t, mut b1, mut b2) = ([0.0f32; L], [0.0f32; L], [0.0f32; L]);
                        if hits != 0 {
                            decided.t.store(t.as_mut_ptr());
                            decided.b1.store(b1.as_mut_ptr());
                            decided.b2.store(b2.as_mut_ptr());
                        }
                        let mut undecided = decided.undecided;
                        if undecided != 0 {
                            let [v0, v1, v2] = block.triangle(lane);
                            while undecided != 0 {
                                let j = undecided.trailing_zeros() as usize;
                                undecided &= undecided - 1;
                                let i = base + j;
                                let limit = rays.triangle_limit[i];
                                if let Some(h) = rays.triangle_ray(i).intersect(v0, v1, v2, limit) {
                                    hits |= 1 << j;
                                    (t[j], b1[j], b2[j]) = (h.t, h.b1, h.b2);
                                }
                            }
                        }
                        if hits == 0 {
                            continue;
                        }
                        if occlusion {
                            *open &= !((hits as u64) << base);
                            active &= !hits;
                            if active == 0 {
                                break 'blocks;
                            }
                        } else {
                            while hits != 0 {
                                let j = hits.trailing_zeros() as usize;
                                hits &= hits - 1;
                                rays.offer(base + j, t[j], id, b1[j], b2[j]);
                            }
                        }
                    }
                }
            }
        }
    }

    /// A vector in three registers of equal lanes.
    ///
    /// # Safety
    /// The CPU must support `V`'s instruction set.
    #[inline(always)]
    unsafe fn splat3<V: Lanes>(v: glam::Vec3) -> [V; 3] {
        // SAFETY: the caller's guarantee.
        unsafe { [V::splat(v.x), V::splat(v.y), V::splat(v.z)] }
    }

    /// The least and greatest products of two intervals, as `bounds::interval_product`.
    ///
    /// # Safety
    /// The CPU must support `V`'s instruction set.
    #[inline(always)]
    unsafe fn interval_product<V: Lanes>(a_lo: V, a_hi: V, i_lo: V, i_hi: V) -> (V, V) {
        // SAFETY: the caller's guarantee.
        unsafe {
            let (p0, p1) = (a_lo.mul(i_lo), a_lo.mul(i_hi));
            let (p2, p3) = (a_hi.mul(i_lo), a_hi.mul(i_hi));
            (p0.min(p1).min(p2.min(p3)), p0.max(p1).max(p2.max(p3)))
        }
    }

    /// A packet's bound broadcast into vector registers.
    #[derive(Clone, Copy)]
    pub(crate) struct FrustumBroadcast<V> {
        origin_lo: [V; 3],
        origin_hi: [V; 3],
        inv_lo: [V; 3],
        inv_hi: [V; 3],
        t_min: V,
        near_rows: [usize; 3],
        far_rows: [usize; 3],
        pad_axes: [bool; 3],
    }

    impl<V: Lanes> FrustumBroadcast<V> {
        /// # Safety
        /// The CPU must support `V`'s instruction set.
        #[inline(always)]
        unsafe fn new(f: &Frustum) -> Self {
            let (near_rows, far_rows) = plane_rows(f.negative);
            // SAFETY: the caller's guarantee.
            unsafe {
                FrustumBroadcast {
                    origin_lo: splat3(f.origin_lo),
                    origin_hi: splat3(f.origin_hi),
                    inv_lo: splat3(f.inv_lo),
                    inv_hi: splat3(f.inv_hi),
                    t_min: V::splat(f.t_min),
                    near_rows,
                    far_rows,
                    pad_axes: f.pad_axes,
                }
            }
        }

        /// [`Frustum::enter`] for the children from `first` on that `V` holds: their mask (bit 0 for child
        /// `first`), and their entries written to `out[first..]`.
        ///
        /// # Safety
        /// The CPU must support `V`'s instruction set; `first` is 0, or 4 for a 4-lane `V`.
        #[inline(always)]
        unsafe fn enter(
            &self,
            node: &WideNode,
            t_limit: f32,
            first: usize,
            out: &mut [f32],
        ) -> u32 {
            // SAFETY: the caller's guarantee; loads read one register of a 32-byte aligned row
            // of 8 from `first`, which is aligned to the register size.
            unsafe {
                let scale = V::splat(FAR_SCALE);
                let mut near = self.t_min;
                let mut far = V::splat(t_limit);
                let mut reach = V::splat(0.0);
                for axis in 0..3 {
                    let np = V::load(node.planes[self.near_rows[axis]][first..].as_ptr());
                    let fp = V::load(node.planes[self.far_rows[axis]][first..].as_ptr());
                    let (o_lo, o_hi) = (self.origin_lo[axis], self.origin_hi[axis]);
                    let (i_lo, i_hi) = (self.inv_lo[axis], self.inv_hi[axis]);
                    let (tn_lo, tn_hi) = interval_product(np.sub(o_hi), np.sub(o_lo), i_lo, i_hi);
                    let (tf_lo, tf_hi) = interval_product(fp.sub(o_hi), fp.sub(o_lo), i_lo, i_hi);
                    near = tn_lo.max(near);
                    far = tf_hi.mul(scale).min(far);
                    if self.pad_axes[axis] {
                        let axis_reach =
                            tn_lo.abs().max(tn_hi.abs()).max(tf_lo.abs().max(tf_hi.abs()));
                        reach = reach.max(axis_reach);
                    }
                }
                let pad = reach.mul(V::splat(SLAB_PAD));
                let near = near.sub(pad);
                let far = far.add(pad);
                near.store(out[first..].as_mut_ptr());
                near.le_mask(far) << first
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
            first_block: u32,
            blocks: u32,
        ) {
            // SAFETY: the caller's guarantee.
            unsafe {
                packet_leaf_lanes::<__m128, 4>(
                    rays,
                    open,
                    occlusion,
                    bvh,
                    bounds,
                    first_block,
                    blocks,
                )
            }
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

        #[inline(always)]
        unsafe fn block_hits(
            ray: &WatertightRay,
            block: &TriangleBlock<BLOCK>,
            t_max: f32,
        ) -> BlockHits {
            block_hits_sse(ray, block, t_max)
        }

        #[inline(always)]
        unsafe fn prepare(ray: &RayBoxTest) -> Self::Ray {
            // SAFETY: SSE2 is part of x86-64.
            unsafe { Broadcast::new(ray) }
        }

        #[inline(always)]
        unsafe fn enter(node: &WideNode, ray: &Self::Ray, t_limit: f32) -> (u32, [f32; WIDTH]) {
            // SAFETY: SSE2 is part of x86-64; every load reads 4 floats inside a row of 8 of
            // `node`, which is 32-byte aligned, so offsets 0 and 4 are 16-byte aligned.
            unsafe {
                let scale = _mm_set1_ps(FAR_SCALE);
                let limit = _mm_set1_ps(t_limit);
                let mut out = [0.0f32; WIDTH];
                let mut mask = 0u32;
                let pad_scale = _mm_set1_ps(SLAB_PAD);
                let abs = |v: __m128| _mm_andnot_ps(_mm_set1_ps(-0.0), v);
                for half in 0..2 {
                    let mut near = ray.t_min;
                    let mut far = limit;
                    let mut reach = _mm_setzero_ps();
                    for axis in 0..3 {
                        let np = _mm_load_ps(node.planes[ray.near_rows[axis]][4 * half..].as_ptr());
                        let fp = _mm_load_ps(node.planes[ray.far_rows[axis]][4 * half..].as_ptr());
                        let tn = _mm_mul_ps(_mm_sub_ps(np, ray.origin[axis]), ray.inv[axis]);
                        let tf = _mm_mul_ps(_mm_sub_ps(fp, ray.origin[axis]), ray.inv[axis]);
                        near = _mm_max_ps(tn, near);
                        far = _mm_min_ps(_mm_mul_ps(tf, scale), far);
                        // Axis 0 is the dominant axis (see `Broadcast`).
                        if axis == 0 {
                            reach = _mm_max_ps(abs(tn), abs(tf));
                        }
                    }
                    let pad = _mm_mul_ps(reach, pad_scale);
                    let near = _mm_sub_ps(near, pad);
                    let far = _mm_add_ps(far, pad);
                    let hit = _mm_cmple_ps(near, far);
                    mask |= (_mm_movemask_ps(hit) as u32) << (4 * half);
                    _mm_storeu_ps(out[4 * half..].as_mut_ptr(), near);
                }
                (mask, out)
            }
        }
    }

    /// The watertight test's inputs, one test per lane: the lanes are either four triangles
    /// against one ray ([`block_hits_sse`]) or eight rays against one triangle (packets). Every
    /// coordinate is already permuted to the ray's `(kx, ky, kz)`.
    pub(crate) struct WatertightLanes<V> {
        /// The ray origin's `kx`, `ky`, `kz` coordinates.
        pub origin: [V; 3],
        /// `shear_x`, `shear_y`, `shear_z`.
        pub shear: [V; 3],
        /// `|shear_x|`, `|shear_y|`.
        pub abs_shear: [V; 2],
        /// The ray's `t_min` (see [`WatertightRay::intersect`]).
        pub t_min: V,
        /// Hits are accepted below this.
        pub t_max: V,
        /// `vertices[j]`: vertex `j`'s `kx`, `ky`, `kz` coordinates.
        pub vertices: [[V; 3]; 3],
    }

    /// What [`watertight_lanes`] decides per lane.
    pub(crate) struct LaneHits<V: Lanes> {
        /// Lanes hit, with `t` and barycentrics below.
        pub hits: u32,
        /// `hits` as a comparison mask (lanes outside `lanes` included where their
        /// triangles are hit: padding lanes hold NaN vertices, which never are).
        pub hit_mask: V::Mask,
        /// Lanes that only [`WatertightRay::intersect`] can decide (an edge function is zero).
        pub undecided: u32,
        pub t: V,
        pub b1: V,
        pub b2: V,
    }

    /// [`WatertightRay::intersect`] lane by lane, for triangles of non-zero area (or NaN
    /// vertices, which never hit). Every value is computed by the same operations in the same
    /// order (no fused multiply-add), so every decision, `t` and barycentric is the same bit for
    /// bit; lanes whose edge functions round to exactly zero are left `undecided` for the scalar
    /// test's double-precision path. `lanes` masks the lanes that count.
    ///
    /// # Safety
    /// The CPU must support `V`'s instruction set.
    #[inline(always)]
    pub(crate) unsafe fn watertight_lanes<V: Lanes>(
        x: &WatertightLanes<V>,
        lanes: u32,
    ) -> LaneHits<V> {
        // SAFETY: the caller's guarantee.
        unsafe { watertight_lanes_with::<V, true>(x, lanes) }
    }

    /// [`watertight_lanes`], with `EARLY_OUT` returning as soon as no lane can be hit (a branch:
    /// worth it where misses are common and alike, as in a packet's leaves; not where hits and
    /// misses alternate unpredictably, as for one incoherent ray against a whole small scene).
    ///
    /// # Safety
    /// As for [`watertight_lanes`].
    #[inline(always)]
    pub(crate) unsafe fn watertight_lanes_with<V: Lanes, const EARLY_OUT: bool>(
        x: &WatertightLanes<V>,
        lanes: u32,
    ) -> LaneHits<V> {
        use crate::float::gamma;
        // SAFETY: the caller's guarantee.
        unsafe {
            let [ox, oy, oz] = x.origin;
            let [sx, sy, sz] = x.shear;
            let [p0, p1, p2] = &x.vertices;
            let (a_kx, a_ky, a_kz) = (p0[0].sub(ox), p0[1].sub(oy), p0[2].sub(oz));
            let (b_kx, b_ky, b_kz) = (p1[0].sub(ox), p1[1].sub(oy), p1[2].sub(oz));
            let (c_kx, c_ky, c_kz) = (p2[0].sub(ox), p2[1].sub(oy), p2[2].sub(oz));
            let ax = a_kx.sub(sx.mul(a_kz));
            let ay = a_ky.sub(sy.mul(a_kz));
            let bx = b_kx.sub(sx.mul(b_kz));
            let by = b_ky.sub(sy.mul(b_kz));
            let cx = c_kx.sub(sx.mul(c_kz));
            let cy = c_ky.sub(sy.mul(c_kz));
            let e0 = bx.mul(cy).sub(by.mul(cx));
            let e1 = cx.mul(ay).sub(cy.mul(ax));
            let e2 = ax.mul(by).sub(ay.mul(bx));
            let zero = V::splat(0.0);
            let any_zero = e0.eq(zero).or(e1.eq(zero)).or(e2.eq(zero));
            // The scalar test's `all >= 0 or all <= 0`, by sign bits: for edge functions none of
            // which is zero (the lanes that have one are decided apart) it holds exactly where
            // the three signs agree; NaN lanes are rejected below by the range test.
            let inside = e0.xor(e1).or_bits(e0.xor(e2)).sign_clear();
            let det = e0.add(e1).add(e2);
            let az = sz.mul(a_kz);
            let bz = sz.mul(b_kz);
            let cz = sz.mul(c_kz);
            let t_scaled = e0.mul(az).add(e1.mul(bz)).add(e2.mul(cz));
            let t_limit = x.t_max.mul(det).mul(V::splat(crate::triangle::T_LIMIT_SLACK));
            // `det > 0 and 0 < t_scaled < t_limit`, or the same mirrored for `det < 0`: both as
            // one test on `t_scaled` and `t_limit` with `det`'s sign taken off (`det` = ±0
            // gives `t_limit` = ±0 or NaN, which admit nothing, as the scalar test's `det == 0`
            // rejection; a NaN `det` gives a NaN `t_limit`).
            let det_sign = det.sign();
            let t_scaled_unsigned = t_scaled.xor(det_sign);
            let t_limit_unsigned = t_limit.xor(det_sign);
            let in_range = t_scaled_unsigned.gt(zero).and(t_scaled_unsigned.lt(t_limit_unsigned));
            let candidate = any_zero.or(inside.and(in_range));
            let candidates = candidate.bits() & lanes;
            let undecided = candidates & any_zero.bits();
            let decidable = candidates & !undecided;
            if EARLY_OUT && decidable == 0 {
                let none = zero.lt(zero);
                return LaneHits {
                    hits: 0,
                    hit_mask: none,
                    undecided,
                    t: zero,
                    b1: zero,
                    b2: zero,
                };
            }

            // The rest of `intersect`, for the lanes without a zero edge function.
            let inv_det = V::splat(1.0).div(det);
            let t = t_scaled.mul(inv_det);
            // `t.is_nan() || t >= t_max` rejects: accept `t < t_max` (false for NaN).
            let below_max = t.lt(x.t_max);
            // With `t_min > 0`, `t < t_min` rejects; otherwise `t <= delta_t`.
            let explicit = x.t_min.gt(zero);
            let explicit_bits = explicit.bits() & decidable;
            let mut accept = below_max.and(explicit).and(t.nlt(x.t_min));
            if explicit_bits != decidable {
                // The same expression as `conservative_delta_t`.
                let max3 = |a: V, b: V, c: V| a.abs().max(b.abs()).max(c.abs());
                let max_zt = max3(az, bz, cz);
                let delta_z = V::splat(gamma(3)).mul(max_zt);
                let max_xt = max3(ax, bx, cx);
                let max_yt = max3(ay, by, cy);
                let max_unsheared_z = max3(a_kz, b_kz, c_kz);
                let delta_x =
                    V::splat(gamma(5)).mul(max_xt.add(x.abs_shear[0].mul(max_unsheared_z)));
                let delta_y =
                    V::splat(gamma(5)).mul(max_yt.add(x.abs_shear[1].mul(max_unsheared_z)));
                let delta_e = V::splat(2.0).mul(
                    V::splat(gamma(2))
                        .mul(max_xt)
                        .mul(max_yt)
                        .add(delta_y.mul(max_xt))
                        .add(delta_x.mul(max_yt)),
                );
                let max_e = max3(e0, e1, e2);
                let sum = V::splat(gamma(3))
                    .mul(max_e)
                    .mul(max_zt)
                    .add(delta_e.mul(max_zt))
                    .add(delta_z.mul(max_e));
                let delta_t = V::splat(3.0).mul(sum).mul(inv_det.abs());
                accept = accept.or(below_max.and(t.nle(delta_t)).andnot_of(explicit));
            }
            let hit_mask = accept.and(candidate).andnot_of(any_zero);
            let hits = decidable & accept.bits();
            debug_assert_eq!(hits, hit_mask.bits() & lanes, "the mask is the bits");
            LaneHits { hits, hit_mask, undecided, t, b1: e1.mul(inv_det), b2: e2.mul(inv_det) }
        }
    }

    /// One row of a block.
    ///
    /// # Safety
    /// As for [`Lanes::load`]: SSE2 is part of x86-64 and a block's rows are 16-byte aligned.
    #[inline(always)]
    unsafe fn row(r: &[f32; BLOCK]) -> __m128 {
        // SAFETY: as above.
        unsafe { __m128::load(r.as_ptr()) }
    }

    /// [`block_hits_scalar`] for four triangles with SSE2, by [`watertight_lanes`].
    #[inline(always)]
    pub(crate) fn block_hits_sse(
        ray: &WatertightRay,
        block: &TriangleBlock<BLOCK>,
        t_max: f32,
    ) -> BlockHits {
        let (kx, ky, kz) = (ray.kx, ray.ky, ray.kz);
        // SAFETY: SSE2 is part of x86-64; each load reads one row of 4 floats of the block,
        // which is 16-byte aligned (`repr(align(16))`); stores go to arrays of 4 floats.
        unsafe {
            let [p0, p1, p2] = &block.vertices;
            let lanes = WatertightLanes {
                origin: [
                    __m128::splat(ray.origin[kx]),
                    __m128::splat(ray.origin[ky]),
                    __m128::splat(ray.origin[kz]),
                ],
                shear: [
                    __m128::splat(ray.shear_x),
                    __m128::splat(ray.shear_y),
                    __m128::splat(ray.shear_z),
                ],
                abs_shear: [__m128::splat(ray.shear_x.abs()), __m128::splat(ray.shear_y.abs())],
                t_min: __m128::splat(ray.t_min),
                t_max: __m128::splat(t_max),
                vertices: [
                    [row(&p0[kx]), row(&p0[ky]), row(&p0[kz])],
                    [row(&p1[kx]), row(&p1[ky]), row(&p1[kz])],
                    [row(&p2[kx]), row(&p2[ky]), row(&p2[kz])],
                ],
            };
            let decided = watertight_lanes(&lanes, 0xF);
            let mut out = BlockHits {
                hits: decided.hits,
                undecided: decided.undecided,
                ..BlockHits::default()
            };
            if decided.hits != 0 {
                decided.t.store(out.t.as_mut_ptr());
                decided.b1.store(out.b1.as_mut_ptr());
                decided.b2.store(out.b2.as_mut_ptr());
            }
            out
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
            first_block: u32,
            blocks: u32,
        ) {
            // SAFETY: the caller's guarantee.
            unsafe {
                packet_leaf_lanes::<__m256, 8>(
                    rays,
                    open,
                    occlusion,
                    bvh,
                    bounds,
                    first_block,
                    blocks,
                )
            }
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

        #[inline(always)]
        unsafe fn block_hits(
            ray: &WatertightRay,
            block: &TriangleBlock<BLOCK>,
            t_max: f32,
        ) -> BlockHits {
            block_hits_sse(ray, block, t_max)
        }

        #[inline(always)]
        unsafe fn prepare(ray: &RayBoxTest) -> Self::Ray {
            // SAFETY: the caller checked AVX2 support (this function's contract).
            unsafe { Broadcast::new(ray) }
        }

        #[inline(always)]
        unsafe fn enter(node: &WideNode, ray: &Self::Ray, t_limit: f32) -> (u32, [f32; WIDTH]) {
            // SAFETY: the caller checked AVX2 support; every load reads one 32-byte aligned row
            // of 8 floats of `node`.
            unsafe {
                let scale = _mm256_set1_ps(FAR_SCALE);
                let mut near = ray.t_min;
                let mut far = _mm256_set1_ps(t_limit);
                let mut reach = _mm256_setzero_ps();
                let abs = |v: __m256| _mm256_andnot_ps(_mm256_set1_ps(-0.0), v);
                for axis in 0..3 {
                    let np = _mm256_load_ps(node.planes[ray.near_rows[axis]].as_ptr());
                    let fp = _mm256_load_ps(node.planes[ray.far_rows[axis]].as_ptr());
                    let tn = _mm256_mul_ps(_mm256_sub_ps(np, ray.origin[axis]), ray.inv[axis]);
                    let tf = _mm256_mul_ps(_mm256_sub_ps(fp, ray.origin[axis]), ray.inv[axis]);
                    near = _mm256_max_ps(tn, near);
                    far = _mm256_min_ps(_mm256_mul_ps(tf, scale), far);
                    // Axis 0 is the dominant axis (see `Broadcast`).
                    if axis == 0 {
                        reach = _mm256_max_ps(abs(tn), abs(tf));
                    }
                }
                let pad = _mm256_mul_ps(reach, _mm256_set1_ps(SLAB_PAD));
                let near = _mm256_sub_ps(near, pad);
                let far = _mm256_add_ps(far, pad);
                let hit = _mm256_cmp_ps::<_CMP_LE_OQ>(near, far);
                let mut out = [0.0f32; WIDTH];
                _mm256_storeu_ps(out.as_mut_ptr(), near);
                (_mm256_movemask_ps(hit) as u32, out)
            }
        }
    }

    /// AVX2's node and block kernels, and packet leaves 16 rays per instruction with AVX-512.
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
            first_block: u32,
            blocks: u32,
        ) {
            // SAFETY: the caller checked AVX-512 F support (this function's contract).
            unsafe {
                packet_leaf_lanes::<__m512, 16>(
                    rays,
                    open,
                    occlusion,
                    bvh,
                    bounds,
                    first_block,
                    blocks,
                )
            }
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

        #[inline(always)]
        unsafe fn block_hits(
            ray: &WatertightRay,
            block: &TriangleBlock<BLOCK>,
            t_max: f32,
        ) -> BlockHits {
            // SAFETY: as above.
            unsafe { Avx2::block_hits(ray, block, t_max) }
        }

        #[inline(always)]
        unsafe fn prepare(ray: &RayBoxTest) -> Self::Ray {
            // SAFETY: as above.
            unsafe { Avx2::prepare(ray) }
        }

        #[inline(always)]
        unsafe fn enter(node: &WideNode, ray: &Self::Ray, t_limit: f32) -> (u32, [f32; WIDTH]) {
            // SAFETY: as above.
            unsafe { Avx2::enter(node, ray, t_limit) }
        }
    }
}
