//! Vector lanes for the SIMD kernels, and the watertight triangle test lane by lane.
//!
//! [`Lanes`] is the handful of vector operations the kernels need, for SSE's four lanes, AVX's
//! eight and AVX-512's sixteen, so that one generic function serves every width: the packet
//! leaves (rays across lanes), the 4-triangle leaf blocks and the flat list of small scenes
//! (triangles across lanes). [`watertight_lanes_with`] is [`WatertightRay::intersect`] lane by lane,
//! the same operations in the same order, so every lane decides as the scalar test does.

use std::arch::x86_64::*;

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
            let half = _mm_min_ps(_mm256_castps256_ps128(self), _mm256_extractf128_ps::<1>(self));
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
            _mm512_castsi512_ps(_mm512_xor_si512(_mm512_castps_si512(self), _mm512_castps_si512(o)))
        }
    }
    #[inline(always)]
    unsafe fn or_bits(self, o: Self) -> Self {
        // SAFETY: the trait's contract: the caller guarantees the instruction set.
        unsafe {
            _mm512_castsi512_ps(_mm512_or_si512(_mm512_castps_si512(self), _mm512_castps_si512(o)))
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
