//! Summaries of repeated measurements: medians and percentiles, as the benchmarks quote them.

/// The median of `values` (the mean of the middle two for an even count), sorting them; NaN for
/// none.
pub fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    let n = values.len();
    match n {
        0 => f64::NAN,
        _ if n % 2 == 1 => values[n / 2],
        _ => 0.5 * (values[n / 2 - 1] + values[n / 2]),
    }
}

/// The `q`-quantile (0 to 1) of `values` sorted ascending, by nearest rank; NaN for none.
pub fn nearest_rank(sorted: &[f64], q: f64) -> f64 {
    let n = sorted.len();
    if n == 0 {
        return f64::NAN;
    }
    sorted[((q * n as f64).ceil() as usize).clamp(1, n) - 1]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn medians_and_ranks() {
        assert_eq!(median(&mut [5.0, 1.0, 3.0, 100.0]), 4.0);
        assert_eq!(median(&mut [2.0, 9.0, 4.0]), 4.0);
        assert!(median(&mut []).is_nan());
        let sorted = [1.0, 3.0, 5.0, 100.0];
        assert_eq!((nearest_rank(&sorted, 0.1), nearest_rank(&sorted, 0.9)), (1.0, 100.0));
        assert_eq!(nearest_rank(&sorted, 0.5), 3.0);
        assert!(nearest_rank(&[], 0.5).is_nan());
    }
}
