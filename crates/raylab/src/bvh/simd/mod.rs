//! Vector lanes for the SIMD kernels: one trait over SSE's four lanes, AVX's eight and
//! AVX-512's sixteen.
//!
//! [`Lanes`] is the handful of vector operations the kernels need, so that one generic function
//! serves every width: the packet leaves (rays across lanes), the leaf records and the flat list
//! of small scenes (triangles across lanes). Each operation is one intrinsic, or a few; the
//! `intrinsics!` macro writes them out, each with the trait's safety contract, so that the
//! three implementations below are tables of intrinsics rather than a hundred wrapper functions.

use std::arch::x86_64::*;

mod watertight;

pub(crate) use watertight::{
    LaneHits, RayBroadcast, RayLanes, ShearedLanes, shear_point, watertight_lanes_with,
    watertight_sheared, watertight_sheared_scaled,
};

/// The vector operations of the kernels. Every method is `unsafe`: the CPU must support the
/// register's instruction set (for the whole trait), and the pointer methods say what their
/// pointer must be.
pub(crate) trait Lanes: Copy {
    /// A comparison's lanes: all-ones registers for SSE and AVX, a mask register for
    /// AVX-512.
    type Mask: LaneMask;

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
    unsafe fn div(self, o: Self) -> Self;
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

/// Trait methods, each an `unsafe fn` whose body is an intrinsic expression evaluated under the
/// trait's contract: `fn name(args) -> Ret = expression;`.
macro_rules! intrinsics {
    ($(fn $name:ident($($args:tt)*) $(-> $ret:ty)? = $body:expr;)*) => {
        $(
            #[inline(always)]
            unsafe fn $name($($args)*) $(-> $ret)? {
                // SAFETY: the trait's contract: the caller guarantees the instruction set, and
                // for `load`, `loadu` and `store` a pointer to a register's floats (aligned to
                // the register's size for `load`).
                unsafe { $body }
            }
        )*
    };
}

impl Lanes for __m128 {
    type Mask = __m128;

    intrinsics! {
        fn splat(x: f32) -> Self = _mm_set1_ps(x);
        fn load(p: *const f32) -> Self = _mm_load_ps(p);
        fn loadu(p: *const f32) -> Self = _mm_loadu_ps(p);
        fn store(self, p: *mut f32) = _mm_storeu_ps(p, self);
        fn add(self, o: Self) -> Self = _mm_add_ps(self, o);
        fn sub(self, o: Self) -> Self = _mm_sub_ps(self, o);
        fn mul(self, o: Self) -> Self = _mm_mul_ps(self, o);
        fn div(self, o: Self) -> Self = _mm_div_ps(self, o);
        fn min(self, o: Self) -> Self = _mm_min_ps(self, o);
        fn max(self, o: Self) -> Self = _mm_max_ps(self, o);
        fn abs(self) -> Self = _mm_andnot_ps(_mm_set1_ps(-0.0), self);
        fn xor(self, o: Self) -> Self = _mm_xor_ps(self, o);
        fn or_bits(self, o: Self) -> Self = _mm_or_ps(self, o);
        fn sign(self) -> Self = _mm_and_ps(self, _mm_set1_ps(-0.0));
        // As integers, `x > −1` exactly where the sign bit is clear.
        fn sign_clear(self) -> Self::Mask =
            _mm_castsi128_ps(_mm_cmpgt_epi32(_mm_castps_si128(self), _mm_set1_epi32(-1)));
        fn le_mask(self, o: Self) -> u32 = _mm_movemask_ps(_mm_cmple_ps(self, o)) as u32;
        fn select(mask: Self::Mask, if_true: Self, if_false: Self) -> Self =
            _mm_or_ps(_mm_and_ps(mask, if_true), _mm_andnot_ps(mask, if_false));
        fn reduce_min(self) -> f32 = {
            let pairs = _mm_min_ps(self, _mm_movehl_ps(self, self));
            _mm_cvtss_f32(_mm_min_ss(pairs, _mm_shuffle_ps::<1>(pairs, pairs)))
        };
        fn eq(self, o: Self) -> Self::Mask = _mm_cmpeq_ps(self, o);
        fn gt(self, o: Self) -> Self::Mask = _mm_cmpgt_ps(self, o);
        fn lt(self, o: Self) -> Self::Mask = _mm_cmplt_ps(self, o);
        fn nlt(self, o: Self) -> Self::Mask = _mm_cmpnlt_ps(self, o);
        fn nle(self, o: Self) -> Self::Mask = _mm_cmpnle_ps(self, o);
    }
}

impl LaneMask for __m128 {
    intrinsics! {
        fn and(self, o: Self) -> Self = _mm_and_ps(self, o);
        fn or(self, o: Self) -> Self = _mm_or_ps(self, o);
        fn andnot_of(self, o: Self) -> Self = _mm_andnot_ps(o, self);
        fn bits(self) -> u32 = _mm_movemask_ps(self) as u32;
    }
}

impl Lanes for __m256 {
    type Mask = __m256;

    intrinsics! {
        fn splat(x: f32) -> Self = _mm256_set1_ps(x);
        fn load(p: *const f32) -> Self = _mm256_load_ps(p);
        fn loadu(p: *const f32) -> Self = _mm256_loadu_ps(p);
        fn store(self, p: *mut f32) = _mm256_storeu_ps(p, self);
        fn add(self, o: Self) -> Self = _mm256_add_ps(self, o);
        fn sub(self, o: Self) -> Self = _mm256_sub_ps(self, o);
        fn mul(self, o: Self) -> Self = _mm256_mul_ps(self, o);
        fn div(self, o: Self) -> Self = _mm256_div_ps(self, o);
        fn min(self, o: Self) -> Self = _mm256_min_ps(self, o);
        fn max(self, o: Self) -> Self = _mm256_max_ps(self, o);
        fn abs(self) -> Self = _mm256_andnot_ps(_mm256_set1_ps(-0.0), self);
        fn xor(self, o: Self) -> Self = _mm256_xor_ps(self, o);
        fn or_bits(self, o: Self) -> Self = _mm256_or_ps(self, o);
        fn sign(self) -> Self = _mm256_and_ps(self, _mm256_set1_ps(-0.0));
        // As integers, `x > −1` exactly where the sign bit is clear (AVX2).
        fn sign_clear(self) -> Self::Mask = _mm256_castsi256_ps(_mm256_cmpgt_epi32(
            _mm256_castps_si256(self),
            _mm256_set1_epi32(-1),
        ));
        fn le_mask(self, o: Self) -> u32 =
            _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(self, o)) as u32;
        fn select(mask: Self::Mask, if_true: Self, if_false: Self) -> Self =
            _mm256_blendv_ps(if_false, if_true, mask);
        fn reduce_min(self) -> f32 =
            _mm_min_ps(_mm256_castps256_ps128(self), _mm256_extractf128_ps::<1>(self))
                .reduce_min();
        fn eq(self, o: Self) -> Self::Mask = _mm256_cmp_ps::<_CMP_EQ_OQ>(self, o);
        fn gt(self, o: Self) -> Self::Mask = _mm256_cmp_ps::<_CMP_GT_OQ>(self, o);
        fn lt(self, o: Self) -> Self::Mask = _mm256_cmp_ps::<_CMP_LT_OQ>(self, o);
        fn nlt(self, o: Self) -> Self::Mask = _mm256_cmp_ps::<_CMP_NLT_UQ>(self, o);
        fn nle(self, o: Self) -> Self::Mask = _mm256_cmp_ps::<_CMP_NLE_UQ>(self, o);
    }
}

impl LaneMask for __m256 {
    intrinsics! {
        fn and(self, o: Self) -> Self = _mm256_and_ps(self, o);
        fn or(self, o: Self) -> Self = _mm256_or_ps(self, o);
        fn andnot_of(self, o: Self) -> Self = _mm256_andnot_ps(o, self);
        fn bits(self) -> u32 = _mm256_movemask_ps(self) as u32;
    }
}

/// Sixteen lanes, for packets on AVX-512: comparisons give mask registers. The bitwise
/// operations use the integer forms: the float ones need AVX-512 DQ.
impl Lanes for __m512 {
    type Mask = __mmask16;

    intrinsics! {
        fn splat(x: f32) -> Self = _mm512_set1_ps(x);
        fn load(p: *const f32) -> Self = _mm512_load_ps(p);
        fn loadu(p: *const f32) -> Self = _mm512_loadu_ps(p);
        fn store(self, p: *mut f32) = _mm512_storeu_ps(p, self);
        fn add(self, o: Self) -> Self = _mm512_add_ps(self, o);
        fn sub(self, o: Self) -> Self = _mm512_sub_ps(self, o);
        fn mul(self, o: Self) -> Self = _mm512_mul_ps(self, o);
        fn div(self, o: Self) -> Self = _mm512_div_ps(self, o);
        fn min(self, o: Self) -> Self = _mm512_min_ps(self, o);
        fn max(self, o: Self) -> Self = _mm512_max_ps(self, o);
        fn abs(self) -> Self = _mm512_abs_ps(self);
        fn xor(self, o: Self) -> Self = _mm512_castsi512_ps(_mm512_xor_si512(
            _mm512_castps_si512(self),
            _mm512_castps_si512(o),
        ));
        fn or_bits(self, o: Self) -> Self = _mm512_castsi512_ps(_mm512_or_si512(
            _mm512_castps_si512(self),
            _mm512_castps_si512(o),
        ));
        fn sign(self) -> Self = _mm512_castsi512_ps(_mm512_and_si512(
            _mm512_castps_si512(self),
            _mm512_set1_epi32(i32::MIN),
        ));
        fn sign_clear(self) -> Self::Mask =
            _mm512_cmpge_epi32_mask(_mm512_castps_si512(self), _mm512_setzero_si512());
        fn le_mask(self, o: Self) -> u32 = _mm512_cmp_ps_mask::<_CMP_LE_OQ>(self, o) as u32;
        fn select(mask: Self::Mask, if_true: Self, if_false: Self) -> Self =
            _mm512_mask_blend_ps(mask, if_false, if_true);
        fn reduce_min(self) -> f32 = _mm512_reduce_min_ps(self);
        fn eq(self, o: Self) -> Self::Mask = _mm512_cmp_ps_mask::<_CMP_EQ_OQ>(self, o);
        fn gt(self, o: Self) -> Self::Mask = _mm512_cmp_ps_mask::<_CMP_GT_OQ>(self, o);
        fn lt(self, o: Self) -> Self::Mask = _mm512_cmp_ps_mask::<_CMP_LT_OQ>(self, o);
        fn nlt(self, o: Self) -> Self::Mask = _mm512_cmp_ps_mask::<_CMP_NLT_UQ>(self, o);
        fn nle(self, o: Self) -> Self::Mask = _mm512_cmp_ps_mask::<_CMP_NLE_UQ>(self, o);
    }
}

/// AVX-512's mask registers: one bit per lane already, so plain integer operations.
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
