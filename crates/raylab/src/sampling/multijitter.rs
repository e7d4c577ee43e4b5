//! Correlated multi-jittered points (Kensler, "Correlated Multi-Jittered Sampling", Pixar
//! Technical Memo 13-01, 2013): the `multijitter` sampler, Mitsuba 3's best sampler for most
//! scenes.
//!
//! A pixel's `N` samples are laid on an `m × n` grid of cells (`m · n = N`, `m` the largest
//! divisor of `N` not above `√N`: 8 × 8 for 64). Sample `s` takes cell `(s mod m, s div m)`;
//! within its cell it sits in the sub-column `σ(s div m)` and the sub-row `τ(s mod m)` of the
//! cell's `n × m` sub-cells, jittered inside it, where `σ` and `τ` are random permutations shared
//! by every row (and every column): "correlated". So every cell holds one point, every one of the
//! `N` thin columns and rows holds one point (N-rooks), and the pattern is as even as a jittered
//! grid gets (up to rounding: a point within an ulp of its stratum's edge may land on the edge). Each pair of dimensions permutes the sample order and draws its own `σ`, `τ` and
//! jitter from the dimension's seeds, so the pairs are independent of one another; a single
//! dimension is `N` jittered strata in a permuted order.
//!
//! Why a second stratified sampler beside `sobol`: at 64 samples, Owen-scrambled Sobol' points
//! integrate smooth functions with a fifth of this one's error, but functions with an edge (a
//! shadow, a silhouette, a texture's contour: most of what a render's pixels integrate) with
//! more (`cargo bench -p raylab --bench sampler_edges` prints both).
//!
//! Unlike Sobol' points, the pattern depends on `N`: it needs the render's sample count up front
//! (a render with no known end, `raylab view` or a time limit without `--spp`, and a render of one
//! sample fall back to `sobol`), and a render's first `k < N` samples are not stratified by
//! themselves. It is unbiased for any `N`:
//! every cell is used once, and each point is uniform in its cell over the random permutations
//! and jitter.
//!
//! The permutations are our own (a bijection of the next power of two, walked until it falls
//! below the range: "cycle walking", as Kensler does), as is the jitter's hash.

use glam::Vec2;

use super::pcg::{hash32, u32_to_unit};

/// The `m × n` grid of a sample count: `m` the largest divisor of `count` not above its square
/// root, so `m · n = count` exactly (a prime count is a `1 × count` grid: N-rooks alone). Every
/// sampler carries one, so it holds the two sides alone; what the draws derive from them
/// (inverses, masks) a loop of lanes derives once, outside the loop.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Grid {
    /// Columns.
    pub m: u32,
    /// Rows.
    pub n: u32,
}

impl Grid {
    /// The grid of `count` samples (at least one).
    pub fn new(count: u32) -> Grid {
        let count = count.max(1);
        let mut m = count.isqrt();
        while !count.is_multiple_of(m) {
            m -= 1;
        }
        Grid { m, n: count / m }
    }

    /// `1/m`, `1/n` and `1/(m·n)`.
    #[inline(always)]
    fn inverse(self) -> [f32; 3] {
        [self.m, self.n, self.count()].map(|k| 1.0 / k as f32)
    }

    /// The permutations' masks for `m`, `n` and `m·n` (see [`permute`]).
    #[inline(always)]
    fn masks(self) -> [u32; 3] {
        [self.m, self.n, self.count()].map(mask_of)
    }

    /// Whether both sides are powers of two (then `point_2d_pow2` and `point_1d_pow2`
    /// apply).
    pub fn is_power_of_two(self) -> bool {
        self.m.is_power_of_two() && self.n.is_power_of_two()
    }

    /// The sample count, `m · n`.
    pub fn count(self) -> u32 {
        self.m * self.n
    }
}

/// The mask of the least power of two not below `len`, less one.
fn mask_of(len: u32) -> u32 {
    if len <= 1 { 0 } else { u32::MAX >> (len - 1).leading_zeros() }
}

/// Element `i` of a pseudo-random permutation of `0..len` chosen by `seed` (`i < len`; `mask`
/// is [`mask_of`]`(len)`; `seed` a well-mixed hash).
///
/// A bijection of the numbers below `mask + 1` built from steps that are each bijective there
/// (XOR with a constant, multiplication by an odd number, XOR with a right shift, all masked),
/// applied again until the value is below `len`: every cycle of a bijection that leaves
/// `0..len` comes back into it, so the walk ends and the map restricted to `0..len` is a
/// permutation of it (for a power of two, one round).
#[inline(always)]
pub(super) fn permute(i: u32, len: u32, mask: u32, seed: u32) -> u32 {
    let mut x = i;
    loop {
        x = permute_round(x, mask, seed);
        if x < len {
            return x;
        }
    }
}

/// One round of [`permute`]'s bijection of the numbers below `mask + 1`.
#[inline(always)]
fn permute_round(mut x: u32, mask: u32, seed: u32) -> u32 {
    let bits = mask.count_ones();
    let (half, third) = (bits / 2 + 1, bits / 3 + 1);
    x = (x ^ seed) & mask;
    x = x.wrapping_mul(seed.rotate_left(16) | 1) & mask;
    x ^= x >> half;
    x = x.wrapping_add(seed >> 11) & mask;
    x = x.wrapping_mul(0x2c1b_3c6d) & mask;
    x ^= x >> third;
    x = (x ^ (seed >> 21)) & mask;
    x = x.wrapping_mul(0x297a_2d39) & mask;
    x ^= x >> half;
    x = x.wrapping_mul(seed.rotate_left(7) | 1) & mask;
    x ^ (x >> 1)
}

/// A number in `[0, 1)` from sample `s` and `seed`: the jitter.
#[inline(always)]
fn jitter(s: u32, seed: u32) -> f32 {
    u32_to_unit(hash32(s ^ seed))
}

/// Point `index` (`< grid.count()`) of a pair of dimensions whose seeds are `seeds` (three
/// independent well-mixed 32-bit hashes): its sample order permuted, then the correlated
/// multi-jittered point of that cell (see the module documentation).
#[inline(always)]
pub(super) fn point_2d(index: u32, grid: &Grid, seeds: [u32; 3]) -> Vec2 {
    if grid.is_power_of_two() {
        return point_2d_pow2(index, grid, seeds);
    }
    let Grid { m, n, .. } = *grid;
    let mask_count = grid.masks()[2];
    let s = permute(index, m * n, mask_count, seeds[0]);
    place::<false>(s, s % m, s / m, grid, seeds)
}

/// [`point_2d`] on a grid whose sides are powers of two: the permutations need one round (their
/// masks cover exactly their ranges) and the cell is a mask and a shift. Straight-line code, so
/// sixteen lanes run it in one loop; the same numbers as the general form's arithmetic.
#[inline(always)]
pub(super) fn point_2d_pow2(index: u32, grid: &Grid, seeds: [u32; 3]) -> Vec2 {
    let s = permute_round(index, grid.masks()[2], seeds[0]);
    place::<true>(s, s & grid.masks()[0], s >> grid.m.trailing_zeros(), grid, seeds)
}

/// The correlated multi-jittered point of sample `s` in cell `(column, row)`.
#[inline(always)]
fn place<const POW2: bool>(
    s: u32,
    column: u32,
    row: u32,
    grid: &Grid,
    [_, columns, rows]: [u32; 3],
) -> Vec2 {
    let Grid { m, n } = *grid;
    let ([inv_m, inv_n, _], [mask_m, mask_n, _]) = (grid.inverse(), grid.masks());
    // The sub-column of this row's point and the sub-row of this column's point, the same
    // permutation for every row (every column).
    let (sub_column, sub_row) = if POW2 {
        (permute_round(row, mask_n, columns), permute_round(column, mask_m, rows))
    } else {
        (permute(row, n, mask_n, columns), permute(column, m, mask_m, rows))
    };
    let (jx, jy) = (jitter(s, columns ^ 0x68e3_1da4), jitter(s, rows ^ 0x5bd1_e995));
    let x = (column as f32 + (sub_column as f32 + jx) * inv_n) * inv_m;
    let y = (row as f32 + (sub_row as f32 + jy) * inv_m) * inv_n;
    // Rounding could reach 1 at the last cell's edge.
    Vec2::new(x.min(ONE_BELOW), y.min(ONE_BELOW))
}

/// Number `index` (`< grid.count()`) of one dimension: the count's jittered strata in a
/// permuted order.
#[inline(always)]
pub(super) fn point_1d(index: u32, grid: &Grid, seeds: [u32; 3]) -> f32 {
    if grid.is_power_of_two() {
        return point_1d_pow2(index, grid, seeds);
    }
    let s = permute(index, grid.count(), grid.masks()[2], seeds[0]);
    stratum(s, grid, seeds[1])
}

/// [`point_1d`] on a grid whose sides are powers of two (see [`point_2d_pow2`]).
#[inline(always)]
pub(super) fn point_1d_pow2(index: u32, grid: &Grid, seeds: [u32; 3]) -> f32 {
    stratum(permute_round(index, grid.masks()[2], seeds[0]), grid, seeds[1])
}

/// Stratum `s` of the count's, jittered.
#[inline(always)]
fn stratum(s: u32, grid: &Grid, jitter_seed: u32) -> f32 {
    ((s as f32 + jitter(s, jitter_seed)) * grid.inverse()[2]).min(ONE_BELOW)
}

/// The largest `f32` below 1.
const ONE_BELOW: f32 = 1.0 - f32::EPSILON / 2.0;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grids_factor_their_counts_exactly() {
        let cases = [(1, (1, 1)), (2, (1, 2)), (16, (4, 4)), (32, (4, 8)), (49, (7, 7))];
        for (count, (m, n)) in cases {
            assert_eq!(Grid::new(count), Grid { m, n }, "{count}");
        }
        let grid = |count| Grid::new(count);
        assert_eq!((grid(64).m, grid(64).n), (8, 8));
        assert_eq!((grid(97).m, grid(97).n), (1, 97), "a prime");
        assert_eq!((grid(0).m, grid(0).n), (1, 1));
        for count in 1..2000 {
            let grid = Grid::new(count);
            assert_eq!(grid.count(), count);
            assert!(grid.m <= grid.n);
        }
    }

    /// A permutation of `0..len` for every length up to 300 (powers of two and not) and several
    /// seeds: every element taken once.
    #[test]
    fn permute_is_a_permutation() {
        for len in 1..300u32 {
            for seed in [0u32, 1, 0xdead_beef, 12345] {
                let mut seen = vec![false; len as usize];
                for i in 0..len {
                    let p = permute(i, len, mask_of(len), hash32(seed)) as usize;
                    assert!(!seen[p], "len {len} seed {seed}: {p} twice");
                    seen[p] = true;
                }
            }
        }
        // Different seeds, different orders.
        let order = |seed| (0..64).map(|i| permute(i, 64, 63, hash32(seed))).collect::<Vec<_>>();
        assert_ne!(order(1), order(2));
    }

    /// The stratification the module documentation promises, for 64 (8 × 8), 32 (4 × 8) and 49
    /// (7 × 7) samples and many seeds: one point per cell, per thin column and per thin row; a
    /// dimension alone is one number per stratum.
    #[test]
    fn points_are_stratified_as_promised() {
        for count in [64u32, 32, 49] {
            let grid = Grid::new(count);
            for seed in 0..200u32 {
                let seeds = [seed * 3 + 1, seed * 7 + 2, seed * 11 + 3].map(hash32);
                let points: Vec<Vec2> = (0..count).map(|i| point_2d(i, &grid, seeds)).collect();
                let mut cells = vec![0; count as usize];
                let (mut columns, mut rows) = (vec![0; count as usize], vec![0; count as usize]);
                for p in &points {
                    assert!((0.0..1.0).contains(&p.x) && (0.0..1.0).contains(&p.y), "{p}");
                    let cell = (p.x * grid.m as f32) as u32 + grid.m * (p.y * grid.n as f32) as u32;
                    cells[cell as usize] += 1;
                    columns[(p.x * count as f32) as usize] += 1;
                    rows[(p.y * count as f32) as usize] += 1;
                }
                assert!(cells.iter().all(|&c| c == 1), "{count} {seed}: cells {cells:?}");
                assert!(columns.iter().all(|&c| c == 1), "{count} {seed}: columns");
                assert!(rows.iter().all(|&c| c == 1), "{count} {seed}: rows");
                let mut strata = vec![0; count as usize];
                for i in 0..count {
                    strata[(point_1d(i, &grid, seeds) * count as f32) as usize] += 1;
                }
                assert!(strata.iter().all(|&c| c == 1), "{count} {seed}: 1D strata");
            }
        }
    }

    /// Over many seeds, a sample's point is uniform on the square: a chi-square test of the
    /// points of one sample on a 16 × 16 histogram (each bin expects 125 of 32,000), and the
    /// same for a 1D number on 64 bins, for 64 samples (one permutation round) and for 49 and 256
    /// samples (49: the permutations walk; 256: the seeds' bits overlap in the rounds). The
    /// cells alone would not show it: the test sees every seed's single point.
    #[test]
    fn each_sample_is_uniform_over_the_seeds() {
        for (count, sample) in [(64, 5), (49, 17), (256, 200)] {
            let grid = Grid::new(count);
            let trials = 32_000u32;
            let mut bins = vec![0f64; 256];
            let mut bins_1d = vec![0f64; 64];
            for t in 0..trials {
                let seeds =
                    [hash32(t), hash32(t ^ 0x1234_5678), hash32(t.wrapping_mul(0x9e37_79b9))];
                let p = point_2d(sample, &grid, seeds);
                bins[(p.x * 16.0) as usize + 16 * (p.y * 16.0) as usize] += 1.0;
                bins_1d[(point_1d(sample, &grid, seeds) * 64.0) as usize] += 1.0;
            }
            for (bins, name) in [(&bins, "2D"), (&bins_1d, "1D")] {
                let expected = f64::from(trials) / bins.len() as f64;
                let chi2: f64 = bins.iter().map(|&o| (o - expected).powi(2) / expected).sum();
                // The 99.9 % quantile of chi-square with 255 degrees of freedom is about 330;
                // with 63, 104.
                let limit = if bins.len() == 256 { 330.0 } else { 104.0 };
                assert!(chi2 < limit, "{count} samples, {name}: chi-square {chi2:.1}");
            }
        }
    }
}
