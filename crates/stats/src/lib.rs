//! Statistics of a set of values shared by every crate of the workspace: [`mean`], [`rms`],
//! [`quantile`] (of an ascending slice) and [`median`].
//!
//! One rule on empty input: every function returns NaN. An empty set has no mean, RMS or
//! quantile, and a NaN cannot pass for a measured zero (it shows as `NaN`, or `null` in JSON, and
//! fails every comparison); a caller that means something else for an empty set says so where it
//! calls. A NaN among the values propagates to the result of `mean` and `rms`; `quantile` and
//! `median` order values with `f64::total_cmp` (NaN after +inf).
//!
//! No units: results carry the unit of the values. The operation order of each function is
//! fixed (documented outputs are compared byte for byte), so results are the same bits
//! wherever they are computed.

/// The arithmetic mean, sum / n in slice order (NaN for an empty slice).
pub fn mean(values: &[f64]) -> f64 {
    values.iter().sum::<f64>() / values.len() as f64
}

/// The root mean square sqrt(sum x^2 / n), summed in slice order (NaN for an empty slice).
pub fn rms(values: &[f64]) -> f64 {
    (values.iter().map(|x| x * x).sum::<f64>() / values.len() as f64).sqrt()
}

/// The quantile at probability `p` (clamped to [0, 1]) of an ascending slice by linear
/// interpolation between order statistics: Hyndman & Fan 1996 type 7, numpy's default
/// (NaN for an empty slice).
pub fn quantile(sorted: &[f64], p: f64) -> f64 {
    match sorted.len() {
        0 => f64::NAN,
        1 => sorted[0],
        n => {
            let h = (n - 1) as f64 * p.clamp(0.0, 1.0);
            let lo = h.floor() as usize;
            let hi = (lo + 1).min(n - 1);
            sorted[lo] + (h - lo as f64) * (sorted[hi] - sorted[lo])
        }
    }
}

/// The median: the middle value, or 0.5 (a + b) of the two middle values of an even count
/// (NaN for an empty slice). Found by selection in linear time; reorders `values`.
pub fn median(values: &mut [f64]) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    let n = values.len();
    let (lower, &mut mid, _) = values.select_nth_unstable_by(n / 2, f64::total_cmp);
    if n % 2 == 1 {
        mid
    } else {
        let below = lower.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        0.5 * (below + mid)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_input_is_nan_everywhere() {
        assert!(mean(&[]).is_nan());
        assert!(rms(&[]).is_nan());
        assert!(quantile(&[], 0.5).is_nan());
        assert!(median(&mut []).is_nan());
    }

    #[test]
    fn quantiles_match_numpy_type7() {
        // numpy.percentile([1, 2, 3, 4, 10], [0, 5, 50, 95, 100]) = [1, 1.2, 3, 8.8, 10]
        let s = [1.0, 2.0, 3.0, 4.0, 10.0];
        assert!((quantile(&s, 0.05) - 1.2).abs() < 1e-12);
        assert_eq!(quantile(&s, 0.5), 3.0);
        assert!((quantile(&s, 0.95) - 8.8).abs() < 1e-12);
        assert_eq!((quantile(&s, 0.0), quantile(&s, 1.0)), (1.0, 10.0));
        // Outside [0, 1] p is clamped; one value is every quantile.
        assert_eq!((quantile(&s, -1.0), quantile(&s, 2.0)), (1.0, 10.0));
        assert_eq!(quantile(&[4.0], 0.3), 4.0);
    }

    #[test]
    fn median_of_odd_and_even_counts_and_mean_and_rms() {
        assert_eq!(median(&mut [5.0, 1.0, 3.0]), 3.0);
        assert_eq!(median(&mut [4.0, 1.0, 3.0, 2.0]), 2.5);
        // The median is the type-7 quantile at 1/2 (to rounding: 0.5 (a + b) against
        // a + 0.5 (b - a), an ulp or two of the values).
        let mut v = [0.3, -1.5, 2.25, 7.0, 0.0, 1.0];
        let m = median(&mut v);
        v.sort_by(f64::total_cmp);
        assert!((m - quantile(&v, 0.5)).abs() <= 4.0 * f64::EPSILON);
        assert_eq!(mean(&[1.0, 2.0, 6.0]), 3.0);
        assert_eq!(rms(&[3.0, -4.0]), (12.5f64).sqrt());
        assert!(mean(&[1.0, f64::NAN]).is_nan() && rms(&[f64::NAN]).is_nan());
    }
}
