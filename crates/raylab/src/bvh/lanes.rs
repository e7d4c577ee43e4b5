//! Vector lanes for the SIMD kernels, and the watertight triangle test lane by lane.
//!
//! [`Lanes`] is the handful of vector operations the kernels need, for SSE's four lanes, AVX's
//! eight and AVX-512's sixteen, so that one generic function serves every width: the packet
//! leaves (rays across lanes), the 4-triangle leaf blocks and the flat list of small scenes
//! (triangles across lanes). [`watertight_lanes`] is [`WatertightRay::intersect`] lane by lane,
//! the same operations in the same order, so every lane decides as the scalar test does.

use std::arch::x86_64::*;

#[cfg(doc)]
use crate::triangle::WatertightRay;

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

/// The watertight test's inputs, one test per lane: the lanes are either triangles against one
/// ray (a leaf block's four, a flat list's sixteen) or rays against one triangle (packets). Every
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
pub(crate) unsafe fn watertight_lanes<V: Lanes>(x: &WatertightLanes<V>, lanes: u32) -> LaneHits<V> {
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
            return LaneHits { hits: 0, hit_mask: none, undecided, t: zero, b1: zero, b2: zero };
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
            let delta_x = V::splat(gamma(5)).mul(max_xt.add(x.abs_shear[0].mul(max_unsheared_z)));
            let delta_y = V::splat(gamma(5)).mul(max_yt.add(x.abs_shear[1].mul(max_unsheared_z)));
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
