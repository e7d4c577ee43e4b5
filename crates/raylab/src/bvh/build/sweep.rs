//! The SAH sweep of the binned build: which split of a node's bins is cheapest.
//!
//! [`sweep`] takes a node's bins (per bin, per axis, the box and count of the primitives whose
//! centroids fall in it) and weighs every split position, as [`build`](super) describes:
//! the SSE2 version weighs the three axes at once, one per lane, and `sweep_scalar` is its twin.

#[cfg(any(test, not(target_arch = "x86_64")))]
use super::bins::records;
use super::bins::{Aabb, Bin, MAX_BINS};

/// Bin counts up to this (the `fast` and `medium` presets' 8 and 16, `high`'s 32) sweep with
/// short arrays.
const SMALL_BINS: usize = 32;

/// The SAH sweep over binned primitives: the split position (axis, first bin of the right side)
/// with the least area term `A_L·records(n_L, unit) + A_R·records(n_R, unit)`, and that term; the first such
/// position in axis-major order among equals. Axes whose flag in `axes` is false (no extent) are
/// skipped, and so are positions with an empty side.
#[inline]
pub(super) fn sweep(
    binned: &[[Bin; 3]],
    axes: [bool; 3],
    unit: u32,
) -> Option<(usize, usize, f32)> {
    #[cfg(target_arch = "x86_64")]
    {
        // The per-position arrays on the stack are as long as the bins need: clearing 256
        // positions for every small node cost more than its sweep.
        if binned.len() <= SMALL_BINS {
            // SAFETY: SSE2 is part of x86-64.
            unsafe { sweep_sse2::<SMALL_BINS>(binned, axes, unit) }
        } else {
            // SAFETY: SSE2 is part of x86-64.
            unsafe { sweep_sse2::<MAX_BINS>(binned, axes, unit) }
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        sweep_scalar(binned, axes, unit)
    }
}

/// [`sweep`] one axis at a time: the scalar twin.
#[cfg(any(test, not(target_arch = "x86_64")))]
fn sweep_scalar(binned: &[[Bin; 3]], axes: [bool; 3], unit: u32) -> Option<(usize, usize, f32)> {
    let bins = binned.len();
    let mut best: Option<(usize, usize, f32)> = None;
    // The right side's area term for each split position; zero where the right side is empty
    // (such positions are skipped).
    let mut right_cost = [0.0f32; MAX_BINS];
    let mut right_count = [0u32; MAX_BINS];
    for axis in (0..3).filter(|&axis| axes[axis]) {
        // Sweep from the right: position k covers bins k..bins.
        let (mut bounds, mut count) = (Aabb::EMPTY, 0u32);
        for k in (1..bins).rev() {
            let bin = &binned[k][axis];
            bounds = bounds.union(bin.bounds);
            count += bin.count;
            right_count[k] = count;
            right_cost[k] =
                if count > 0 { bounds.half_area_nonempty() * records(count, unit) } else { 0.0 };
        }
        let (mut left, mut left_count) = (Aabb::EMPTY, 0u32);
        for k in 1..bins {
            let bin = &binned[k - 1][axis];
            left = left.union(bin.bounds);
            left_count += bin.count;
            if left_count == 0 || right_count[k] == 0 {
                continue;
            }
            let cost = left.half_area_nonempty() * records(left_count, unit) + right_cost[k];
            if best.is_none_or(|(_, _, c)| cost < c) {
                best = Some((axis, k, cost));
            }
        }
    }
    best
}

/// [`sweep`] for the three axes at once, one per SSE lane, with the scalar twin's arithmetic in
/// the same order (so the same winner, bit for bit). A bin's three boxes (one per axis) are
/// grown as they are; their extents are transposed so that the three areas come out of one set
/// of multiplications.
///
/// # Safety
/// The CPU must support SSE2 (every x86-64 does).
#[cfg(target_arch = "x86_64")]
#[inline]
unsafe fn sweep_sse2<const N: usize>(
    binned: &[[Bin; 3]],
    axes: [bool; 3],
    unit: u32,
) -> Option<(usize, usize, f32)> {
    use std::arch::x86_64::*;
    let bins = binned.len();
    // SAFETY: (the whole body) SSE2, the caller's guarantee; every load and store is of a
    // 16-byte local or array element.
    unsafe {
        let counts = |k: usize| {
            let b = &binned[k];
            _mm_setr_epi32(b[0].count as i32, b[1].count as i32, b[2].count as i32, 0)
        };
        // The half areas of three boxes, one per lane: `d.x·d.y + d.y·d.z + d.z·d.x`.
        let areas = |boxes: &[Aabb; 3]| {
            let d = boxes.map(|b| __m128::from(b.max - b.min));
            let zero = _mm_setzero_ps();
            // Transpose: lane `a` of `dx` is box `a`'s x extent, and so on.
            let t0 = _mm_unpacklo_ps(d[0], d[1]); // x0 x1 y0 y1
            let t1 = _mm_unpacklo_ps(d[2], zero); // x2 0 y2 0
            let t2 = _mm_unpackhi_ps(d[0], d[1]); // z0 z1 . .
            let t3 = _mm_unpackhi_ps(d[2], zero); // z2 0 . .
            let dx = _mm_movelh_ps(t0, t1);
            let dy = _mm_movehl_ps(t1, t0);
            let dz = _mm_movelh_ps(t2, t3);
            _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dy), _mm_mul_ps(dy, dz)), _mm_mul_ps(dz, dx))
        };
        // `⌈n / 2^unit⌉` as a float, exactly `records(n, unit)`.
        let (round_up, shift) = (_mm_set1_epi32((1 << unit) - 1), _mm_cvtsi32_si128(unit as i32));
        let records_lanes =
            |n: __m128i| _mm_cvtepi32_ps(_mm_srl_epi32(_mm_add_epi32(n, round_up), shift));
        let grow = |boxes: &mut [Aabb; 3], k: usize| {
            for (b, bin) in boxes.iter_mut().zip(&binned[k]) {
                *b = b.union(bin.bounds);
            }
        };
        let zero_i = _mm_setzero_si128();

        debug_assert!(bins <= N);
        let mut right_cost = [_mm_setzero_ps(); N];
        let mut right_count = [zero_i; N];
        let (mut right, mut count) = ([Aabb::EMPTY; 3], zero_i);
        for k in (1..bins).rev() {
            grow(&mut right, k);
            count = _mm_add_epi32(count, counts(k));
            right_count[k] = count;
            let cost = _mm_mul_ps(areas(&right), records_lanes(count));
            // Zero where the side is empty (its box is, and its area not finite).
            right_cost[k] = _mm_and_ps(cost, _mm_castsi128_ps(_mm_cmpgt_epi32(count, zero_i)));
        }
        let axis_mask = _mm_castsi128_ps(_mm_setr_epi32(
            -(axes[0] as i32),
            -(axes[1] as i32),
            -(axes[2] as i32),
            0,
        ));
        let mut best_cost = _mm_set1_ps(f32::INFINITY);
        let mut best_bin = zero_i;
        let (mut left, mut left_count) = ([Aabb::EMPTY; 3], zero_i);
        for k in 1..bins {
            grow(&mut left, k - 1);
            left_count = _mm_add_epi32(left_count, counts(k - 1));
            let cost =
                _mm_add_ps(_mm_mul_ps(areas(&left), records_lanes(left_count)), right_cost[k]);
            let both_sides = _mm_and_si128(
                _mm_cmpgt_epi32(left_count, zero_i),
                _mm_cmpgt_epi32(right_count[k], zero_i),
            );
            let valid = _mm_and_ps(_mm_castsi128_ps(both_sides), axis_mask);
            // Strictly better only: the first position wins among equals, as in the twin.
            let better = _mm_and_ps(valid, _mm_cmplt_ps(cost, best_cost));
            best_cost = _mm_or_ps(_mm_and_ps(better, cost), _mm_andnot_ps(better, best_cost));
            let better_i = _mm_castps_si128(better);
            best_bin = _mm_or_si128(
                _mm_and_si128(better_i, _mm_set1_epi32(k as i32)),
                _mm_andnot_si128(better_i, best_bin),
            );
        }
        let (mut costs, mut ks) = ([0.0f32; 4], [0i32; 4]);
        _mm_storeu_ps(costs.as_mut_ptr(), best_cost);
        _mm_storeu_si128(ks.as_mut_ptr().cast(), best_bin);
        // The lowest axis among equal costs, as the twin's axis-major order.
        let mut best: Option<(usize, usize, f32)> = None;
        for axis in 0..3 {
            if ks[axis] != 0 && best.is_none_or(|(_, _, c)| costs[axis] < c) {
                best = Some((axis, ks[axis] as usize, costs[axis]));
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3A;

    use super::*;

    /// The SSE2 sweep picks the scalar twin's split, with the same cost bit for bit: random bins
    /// (many empty, counts up to 9 so that the cost units' rounding matters), bin counts from 2
    /// to 32, both cost units, axes without extent, and copies of one bin on every
    /// axis (equal costs, where the first position and the lowest axis must win).
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn the_sse2_sweep_agrees_with_its_scalar_twin() {
        let mut state = 99u64;
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((state >> 40) as f32) / (1u64 << 24) as f32
        };
        let mut found = 0;
        for case in 0..20_000 {
            let bins = [2, 3, 8, 16, 32][case % 5];
            let mut binned = vec![[Bin::default(); 3]; bins];
            for bin in binned.iter_mut().flatten() {
                if next() < 0.4 {
                    continue;
                }
                let p = Vec3A::new(next(), next(), next()) * 10.0;
                let q =
                    p + Vec3A::new(next(), next(), next()) * if case % 7 == 0 { 0.0 } else { 2.0 };
                *bin = Bin { bounds: Aabb { min: p, max: q }, count: 1 + (next() * 9.0) as u32 };
            }
            if case % 3 == 0 {
                // The same bins on every axis: equal costs across axes.
                for bins in binned.iter_mut() {
                    *bins = [bins[0]; 3];
                }
            }
            let axes = [next() < 0.9, next() < 0.9, next() < 0.9];
            // Both cost units: leaves of up to eight and of up to four.
            let unit = [3, 2][case % 2];
            let scalar = sweep_scalar(&binned, axes, unit);
            // SAFETY: SSE2 is part of x86-64.
            let sse2 = unsafe { sweep_sse2::<MAX_BINS>(&binned, axes, unit) };
            let bits = |s: Option<(usize, usize, f32)>| s.map(|(a, k, c)| (a, k, c.to_bits()));
            // SAFETY: as above.
            let short = unsafe { sweep_sse2::<SMALL_BINS>(&binned, axes, unit) };
            assert_eq!(bits(short), bits(sse2), "case {case}: short arrays");
            assert_eq!(bits(sse2), bits(scalar), "case {case}: {binned:?} {axes:?}");
            found += scalar.is_some() as usize;
        }
        assert!(found > 15_000, "{found}");
    }
}
