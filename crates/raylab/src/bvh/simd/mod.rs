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
    /// The mask of the lanes whose bits are set in `bits` (bit `k` for lane `k`).
    unsafe fn mask_of(bits: u32) -> Self::Mask;
    /// The next float above each lane, as [`next_float_up`](crate::float::next_float_up)
    /// gives it for finite values (`−0` steps as `+0`): `x + 0` (which turns `−0` into `+0`
    /// and leaves every other value), then its bits moved one away from zero if it is not
    /// negative, one toward zero if it is. Infinite and NaN lanes give garbage.
    unsafe fn next_up_finite(self) -> Self;
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
        fn mask_of(bits: u32) -> Self::Mask = {
            let lanes = _mm_setr_epi32(1, 2, 4, 8);
            let picked = _mm_and_si128(_mm_set1_epi32(bits as i32), lanes);
            _mm_castsi128_ps(_mm_cmpeq_epi32(picked, lanes))
        };
        fn next_up_finite(self) -> Self = {
            let v = _mm_castps_si128(_mm_add_ps(self, _mm_setzero_ps()));
            let step = _mm_or_si128(_mm_srai_epi32::<31>(v), _mm_set1_epi32(1));
            _mm_castsi128_ps(_mm_add_epi32(v, step))
        };
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
        fn mask_of(bits: u32) -> Self::Mask = {
            let lanes = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
            let picked = _mm256_and_si256(_mm256_set1_epi32(bits as i32), lanes);
            _mm256_castsi256_ps(_mm256_cmpeq_epi32(picked, lanes))
        };
        fn next_up_finite(self) -> Self = {
            let v = _mm256_castps_si256(_mm256_add_ps(self, _mm256_setzero_ps()));
            let step = _mm256_or_si256(_mm256_srai_epi32::<31>(v), _mm256_set1_epi32(1));
            _mm256_castsi256_ps(_mm256_add_epi32(v, step))
        };
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
        fn next_up_finite(self) -> Self = {
            let v = _mm512_castps_si512(_mm512_add_ps(self, _mm512_setzero_ps()));
            let step = _mm512_or_si512(_mm512_srai_epi32::<31>(v), _mm512_set1_epi32(1));
            _mm512_castsi512_ps(_mm512_add_epi32(v, step))
        };
    }

    #[inline(always)]
    unsafe fn mask_of(bits: u32) -> Self::Mask {
        bits as __mmask16
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

/// The eight floats at each of `rows` (eight pointers, each to eight readable `f32`s, any
/// alignment), transposed ([`transpose8`]): word `k` of the result's register `i` is
/// `rows[k][i]`. What both the packets' copy of rays into rows and the lab's triangle lines
/// load.
///
/// # Safety
/// The CPU must support AVX, and each pointer must be valid for reading eight `f32`s.
#[inline(always)]
pub(crate) unsafe fn transpose8_at(rows: [*const f32; 8]) -> [__m256; 8] {
    // SAFETY: the caller's guarantees (AVX; eight readable floats at each pointer).
    unsafe {
        transpose8([
            _mm256_loadu_ps(rows[0]),
            _mm256_loadu_ps(rows[1]),
            _mm256_loadu_ps(rows[2]),
            _mm256_loadu_ps(rows[3]),
            _mm256_loadu_ps(rows[4]),
            _mm256_loadu_ps(rows[5]),
            _mm256_loadu_ps(rows[6]),
            _mm256_loadu_ps(rows[7]),
        ])
    }
}

/// The 8×8 transposition of eight AVX registers: word `k` of `r[i]` becomes word `i` of the
/// result's register `k` (three rounds of eight shuffles). It moves bits, it computes nothing.
///
/// # Safety
/// The CPU must support AVX.
#[inline(always)]
pub(crate) unsafe fn transpose8(r: [__m256; 8]) -> [__m256; 8] {
    // SAFETY: the caller guarantees AVX; register operations only.
    unsafe {
        let t0 = _mm256_unpacklo_ps(r[0], r[1]);
        let t1 = _mm256_unpackhi_ps(r[0], r[1]);
        let t2 = _mm256_unpacklo_ps(r[2], r[3]);
        let t3 = _mm256_unpackhi_ps(r[2], r[3]);
        let t4 = _mm256_unpacklo_ps(r[4], r[5]);
        let t5 = _mm256_unpackhi_ps(r[4], r[5]);
        let t6 = _mm256_unpacklo_ps(r[6], r[7]);
        let t7 = _mm256_unpackhi_ps(r[6], r[7]);
        // Words (0, 4), (1, 5), (2, 6), (3, 7) of registers 0–3 and of registers 4–7.
        let u0 = _mm256_shuffle_ps::<0x44>(t0, t2);
        let u1 = _mm256_shuffle_ps::<0xEE>(t0, t2);
        let u2 = _mm256_shuffle_ps::<0x44>(t1, t3);
        let u3 = _mm256_shuffle_ps::<0xEE>(t1, t3);
        let u4 = _mm256_shuffle_ps::<0x44>(t4, t6);
        let u5 = _mm256_shuffle_ps::<0xEE>(t4, t6);
        let u6 = _mm256_shuffle_ps::<0x44>(t5, t7);
        let u7 = _mm256_shuffle_ps::<0xEE>(t5, t7);
        [
            _mm256_permute2f128_ps::<0x20>(u0, u4),
            _mm256_permute2f128_ps::<0x20>(u1, u5),
            _mm256_permute2f128_ps::<0x20>(u2, u6),
            _mm256_permute2f128_ps::<0x20>(u3, u7),
            _mm256_permute2f128_ps::<0x31>(u0, u4),
            _mm256_permute2f128_ps::<0x31>(u1, u5),
            _mm256_permute2f128_ps::<0x31>(u2, u6),
            _mm256_permute2f128_ps::<0x31>(u3, u7),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::float::next_float_up;

    /// `mask_of` and `next_up_finite` of every width this CPU has, against their definitions:
    /// every bit pattern of SSE's and AVX's lanes (six of AVX-512's) picks those lanes, and the next float up is
    /// `next_float_up`'s for zeros of both signs, subnormals, the largest and smallest finite
    /// values and ordinary ones of both signs.
    #[test]
    fn masks_from_bits_and_next_floats_up_in_every_width() {
        let values = [
            0.0,
            -0.0,
            f32::from_bits(1),
            -f32::from_bits(1),
            f32::MIN_POSITIVE,
            1.0,
            -1.0,
            3.5e-20,
            -7.25e12,
            f32::MAX,
            f32::MIN,
            0.1,
            -0.3,
            1e30,
            2.0,
            -2.0,
        ];
        let expected = values.map(|v| next_float_up(v).to_bits());

        // SAFETY: SSE2 is part of x86-64.
        unsafe {
            for bits in 0..16u32 {
                let picked =
                    __m128::select(__m128::mask_of(bits), __m128::splat(1.0), __m128::splat(0.0));
                assert_eq!(
                    picked.le_mask(__m128::splat(0.5)) ^ 0xf,
                    bits,
                    "sse2 mask of {bits:#b}"
                );
            }
            for chunk in 0..4 {
                let mut out = [0.0f32; 4];
                __m128::loadu(values[4 * chunk..].as_ptr())
                    .next_up_finite()
                    .store(out.as_mut_ptr());
                assert_eq!(out.map(f32::to_bits), expected[4 * chunk..4 * chunk + 4], "sse2");
            }
        }

        #[target_feature(enable = "avx2")]
        fn avx2(values: &[f32; 16], expected: &[u32; 16]) {
            // SAFETY: compiled with AVX2, called only after detection.
            unsafe {
                for bits in 0..256u32 {
                    let picked = __m256::select(
                        __m256::mask_of(bits),
                        __m256::splat(1.0),
                        __m256::splat(0.0),
                    );
                    assert_eq!(picked.le_mask(__m256::splat(0.5)) ^ 0xff, bits, "avx2 mask");
                }
                for chunk in 0..2 {
                    let mut out = [0.0f32; 8];
                    __m256::loadu(values[8 * chunk..].as_ptr())
                        .next_up_finite()
                        .store(out.as_mut_ptr());
                    assert_eq!(out.map(f32::to_bits), expected[8 * chunk..8 * chunk + 8], "avx2");
                }
            }
        }
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: AVX2 was detected just above.
            unsafe { avx2(&values, &expected) };
        } else {
            eprintln!("note: this CPU lacks AVX2: its lanes are not tested here");
        }

        #[target_feature(enable = "avx512f")]
        fn avx512(values: &[f32; 16], expected: &[u32; 16]) {
            // SAFETY: compiled with AVX-512 F, called only after detection.
            unsafe {
                for bits in [0u32, 1, 0x8000, 0xffff, 0x1234, 0xa5a5] {
                    let picked = __m512::select(
                        __m512::mask_of(bits),
                        __m512::splat(1.0),
                        __m512::splat(0.0),
                    );
                    assert_eq!(picked.le_mask(__m512::splat(0.5)) ^ 0xffff, bits, "avx512 mask");
                }
                let mut out = [0.0f32; 16];
                __m512::loadu(values.as_ptr()).next_up_finite().store(out.as_mut_ptr());
                assert_eq!(out.map(f32::to_bits), *expected, "avx512");
            }
        }
        if std::arch::is_x86_feature_detected!("avx512f") {
            // SAFETY: AVX-512 F was detected just above.
            unsafe { avx512(&values, &expected) };
        } else {
            eprintln!("note: this CPU lacks AVX-512: its lanes are not tested here");
        }
    }

    /// Word `k` of register `i` goes to word `i` of register `k`, every bit kept (NaN
    /// payloads and signed zeros included).
    #[test]
    fn eight_registers_are_transposed() {
        #[target_feature(enable = "avx")]
        fn transposed(words: &[[u32; 8]; 8]) -> [[u32; 8]; 8] {
            // SAFETY: compiled with AVX, called only after detection; loads and stores of
            // eight words each.
            unsafe {
                let r = words.map(|row| _mm256_loadu_ps(row.as_ptr().cast()));
                let mut out = [[0u32; 8]; 8];
                for (row, v) in out.iter_mut().zip(transpose8(r)) {
                    _mm256_storeu_ps(row.as_mut_ptr().cast(), v);
                }
                out
            }
        }
        if !std::arch::is_x86_feature_detected!("avx") {
            eprintln!("note: this CPU lacks AVX: the transposition is not tested here");
            return;
        }
        let mut words: [[u32; 8]; 8] = std::array::from_fn(|i| {
            std::array::from_fn(|k| 0x7FC0_0000 | (i as u32) << 8 | k as u32)
        });
        words[3][5] = 0x8000_0000;
        // SAFETY: AVX was detected just above.
        let out = unsafe { transposed(&words) };
        for (i, row) in words.iter().enumerate() {
            for (k, &w) in row.iter().enumerate() {
                assert_eq!(out[k][i], w, "word {k} of register {i}");
            }
        }
    }
}
