//! Piecewise-constant densities on `[0, 1)` and `[0, 1)²`: sampling a tabulated function in
//! proportion to its values, as an environment map is sampled in proportion to its luminance.
//!
//! A 1D table of `n` non-negative values `f₀ … fₙ₋₁` defines the density
//! `p(x) = fᵢ / (Σⱼ fⱼ / n)` for `x ∈ [i/n, (i+1)/n)`. Sampling inverts its cumulative
//! distribution: the bin `i` whose CDF interval holds `u`, then `x = (i + (u − cᵢ)/(cᵢ₊₁ − cᵢ))/n`,
//! linear within the bin (PBR 4th ed., §A.4.1 "Piecewise-constant 1D functions"). A 2D table
//! (rows of `width` values, `height` rows, row 0 at `v ∈ [0, 1/height)`) is a marginal density
//! over rows, the sums of each row, and a conditional density over each row (§A.4.2,
//! "Piecewise-constant 2D distributions"; Mitsuba 3's `DiscreteDistribution2D` samples the
//! same density). `p(u, v) = p(v) · p(u | v)`.
//!
//! Each row is a [`DiscreteDistribution`] (the bins' cumulative distribution, in `f32`,
//! summed in `f64`, and nothing else); a density is read from the CDF's steps, so that the
//! density reported is exactly the one sampled, and a 2D table of `w × h` values takes
//! `(w + 1)·h + h + 1` floats and a small record per row (an 8k × 4k environment map: 128 MiB;
//! environment maps are at least as wide as tall, so the rows' records stay small). Negative and NaN values count as zero; a table of zeros is uniform.
//!
//! Tests: `sampling::tests::piecewise_*` (chi-square goodness of fit in 1D and 2D, against a
//! table with empty rows and columns and a bright spot; densities integrating to one;
//! uniform fallbacks).

use glam::Vec2;
use rayon::prelude::*;

use super::{DiscreteDistribution, ONE_MINUS_EPSILON, rescaled};

/// A piecewise-constant density on `[0, 1)` from `n` bins: a [`DiscreteDistribution`] over
/// the bins (the bin that `u` picks, and `u` rescaled within it), spread evenly across each.
#[derive(Clone, Debug, PartialEq)]
pub struct PiecewiseConstant1D {
    bins: DiscreteDistribution,
    /// The mean of the values (`Σ fᵢ / n`), `0` for a table of zeros.
    integral: f64,
}

impl PiecewiseConstant1D {
    /// The density of `values` (at least one); negative and NaN values count as zero, and a
    /// table of zeros (or one whose sum is not finite) is uniform.
    ///
    /// # Panics
    /// With no values.
    pub fn new(values: &[f32]) -> PiecewiseConstant1D {
        assert!(!values.is_empty(), "a piecewise-constant density needs a value");
        match DiscreteDistribution::new(values) {
            Some(bins) => {
                let total: f64 = values.iter().map(|&f| if f > 0.0 { f as f64 } else { 0.0 }).sum();
                PiecewiseConstant1D { bins, integral: total / values.len() as f64 }
            }
            None => PiecewiseConstant1D {
                bins: DiscreteDistribution::new(&vec![1.0; values.len()]).expect("ones"),
                integral: 0.0,
            },
        }
    }

    /// The number of bins.
    pub fn len(&self) -> usize {
        self.bins.len()
    }

    /// Always false: a density has at least one bin.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The mean of the values (the integral of the tabulated function over `[0, 1)`); `0`
    /// for a table of zeros.
    pub fn integral(&self) -> f64 {
        self.integral
    }

    /// The probability of bin `i`.
    #[inline]
    pub fn probability(&self, i: usize) -> f32 {
        self.bins.pmf(i)
    }

    /// The density at `x ∈ [0, 1)` (outside: the nearest bin's).
    #[inline]
    pub fn pdf(&self, x: f32) -> f32 {
        let n = self.len();
        let i = ((x * n as f32) as usize).min(n - 1);
        self.probability(i) * n as f32
    }

    /// The bin that `u ∈ [0, 1)` picks, its probability, and `u` rescaled to `[0, 1)` within
    /// the bin's share (to place the point within the bin some other way).
    #[inline]
    pub fn sample_bin(&self, u: f32) -> (usize, f32, f32) {
        self.bins.sample(u)
    }

    /// The point that `u ∈ [0, 1)` picks, its density, and its bin.
    #[inline]
    pub fn sample(&self, u: f32) -> (f32, f32, usize) {
        let n = self.len();
        // Never a bin of probability zero: `pick` skips them.
        let (i, p, start) = self.bins.pick(u);
        let x = ((i as f32 + rescaled(u, start, p)) / n as f32).min(ONE_MINUS_EPSILON);
        (x, p * n as f32, i)
    }
}

/// A piecewise-constant density on `[0, 1)²` from a table of `width × height` values, row by
/// row (`u` along a row, `v` across rows).
#[derive(Clone, Debug, PartialEq)]
pub struct PiecewiseConstant2D {
    /// Each row's density over `u`.
    rows: Vec<PiecewiseConstant1D>,
    /// The density over rows (`v`), from the rows' sums.
    marginal: PiecewiseConstant1D,
}

impl PiecewiseConstant2D {
    /// The density of `values` (`width × height` of them, row by row); negative and NaN values
    /// count as zero; a table of zeros is uniform, and so is a row of zeros within its row.
    ///
    /// # Panics
    /// If `values` does not hold `width × height` values, or either is zero.
    pub fn new(values: &[f32], width: usize, height: usize) -> PiecewiseConstant2D {
        assert!(width > 0 && height > 0, "a 2D density needs a value");
        assert_eq!(values.len(), width * height, "{width} × {height} values");
        // Row by row on every core (an 8k × 4k map's 4,096 rows).
        let rows: Vec<PiecewiseConstant1D> =
            values.par_chunks_exact(width).map(PiecewiseConstant1D::new).collect();
        let sums: Vec<f32> = rows.iter().map(|r| r.integral() as f32).collect();
        PiecewiseConstant2D { marginal: PiecewiseConstant1D::new(&sums), rows }
    }

    /// The table's width and height.
    pub fn size(&self) -> (usize, usize) {
        (self.rows[0].len(), self.rows.len())
    }

    /// The mean of the values; `0` for a table of zeros.
    pub fn integral(&self) -> f64 {
        self.marginal.integral()
    }

    /// The point that `u ∈ [0, 1)²` picks (`u.y` the row, then `u.x` within it) and its density.
    #[inline]
    pub fn sample(&self, u: Vec2) -> (Vec2, f32) {
        let (v, pdf_v, row) = self.marginal.sample(u.y);
        let (x, pdf_u, _) = self.rows[row].sample(u.x);
        (Vec2::new(x, v), pdf_v * pdf_u)
    }

    /// The bin `(column, row)` that `u ∈ [0, 1)²` picks (`u.y` the row, then `u.x` within it),
    /// its probability, and `u` rescaled to `[0, 1)²` within the bin's shares.
    #[inline]
    pub fn sample_bin(&self, u: Vec2) -> ((usize, usize), f32, Vec2) {
        let (row, p_row, v) = self.marginal.sample_bin(u.y);
        let (column, p_column, x) = self.rows[row].sample_bin(u.x);
        ((column, row), p_row * p_column, Vec2::new(x, v))
    }

    /// [`sample_bin`](Self::sample_bin) for each of `us` (at most
    /// [`SEARCH_LANES`](super::SEARCH_LANES)): the same bins, probabilities and rescaled
    /// numbers, the lanes' searches taken in step (`DiscreteDistribution::sample_each`).
    ///
    /// # Panics
    /// If the slices differ in length or hold more than `SEARCH_LANES`.
    pub fn sample_bin_each(&self, us: &[Vec2], out: &mut [((usize, usize), f32, Vec2)]) {
        let lanes = us.len();
        assert!(lanes <= super::SEARCH_LANES && out.len() == lanes, "a bin per number");
        // (Arrays, not vectors: this runs for every chunk of lanes.)
        const N: usize = super::SEARCH_LANES;
        let (mut v, mut x) = ([0.0f32; N], [0.0f32; N]);
        for ((v, x), u) in v.iter_mut().zip(&mut x).zip(us) {
            (*v, *x) = (u.y, u.x);
        }
        let mut rows = [(0usize, 0.0f32, 0.0f32); N];
        let marginal = [&self.marginal.bins; N];
        DiscreteDistribution::sample_each(&marginal[..lanes], &v[..lanes], &mut rows[..lanes]);
        let mut conditional = [&self.marginal.bins; N];
        for (table, &(row, ..)) in conditional.iter_mut().zip(&rows[..lanes]) {
            *table = &self.rows[row].bins;
        }
        let mut columns = [(0usize, 0.0f32, 0.0f32); N];
        DiscreteDistribution::sample_each(
            &conditional[..lanes],
            &x[..lanes],
            &mut columns[..lanes],
        );
        for (l, slot) in out.iter_mut().enumerate() {
            let ((row, p_row, v), (column, p_column, x)) = (rows[l], columns[l]);
            *slot = ((column, row), p_row * p_column, Vec2::new(x, v));
        }
    }

    /// The probability of bin `(column, row)`.
    #[inline]
    pub fn probability(&self, column: usize, row: usize) -> f32 {
        self.marginal.probability(row) * self.rows[row].probability(column)
    }

    /// [`probability`](Self::probability) without bounds checks.
    ///
    /// # Safety
    /// `column` must be below the table's width and `row` below its height.
    #[inline(always)]
    pub(crate) unsafe fn probability_unchecked(&self, column: usize, row: usize) -> f32 {
        // SAFETY: the caller's bounds: the marginal has a bin per row, each row a bin per column.
        unsafe {
            self.marginal.bins.pmf_unchecked(row)
                * self.rows.get_unchecked(row).bins.pmf_unchecked(column)
        }
    }

    /// The density at `p ∈ [0, 1)²`.
    #[inline]
    pub fn pdf(&self, p: Vec2) -> f32 {
        let height = self.rows.len();
        let row = ((p.y * height as f32) as usize).min(height - 1);
        self.marginal.probability(row) * height as f32 * self.rows[row].pdf(p.x)
    }
}
