//! Statistics of a set of values shared by every crate of the workspace: [`mean`],
//! [`mean_square`], [`rms`], [`sample_variance`] and [`sample_std`] (divisor n - 1),
//! [`weighted_mean`] and [`weighted_mean_square`], [`quantile`] (of an ascending slice) and
//! [`median`]; and [`ln_gamma`], the one special function two crates need (the chi-squared
//! distribution of `allan`, the power-law closed forms of `noise`).
//!
//! One rule on empty input: every function returns NaN (and so do the sample variance and
//! standard deviation of a single value, which have no spread to estimate from). An empty set has
//! no mean, RMS or quantile, and a NaN cannot pass for a measured zero (it shows as `NaN`, or
//! `null` in JSON, and fails every comparison); a caller that means something else for an empty
//! set says so where it calls. A NaN among the values propagates to the result of the means,
//! RMS and variances; `quantile` and `median` order values with `f64::total_cmp` (NaN after
//! +inf).
//!
//! No units: results carry the unit of the values (the square of it for [`mean_square`],
//! [`weighted_mean_square`] and [`sample_variance`]). The operation order of each function is
//! fixed and stated in its documentation (documented outputs are compared byte for byte), so
//! results are the same bits wherever they are computed: every sum runs left to right in slice
//! order, then divides once. A caller that sums in another order (pairwise, lanes, Welford's
//! update, compensated) does not call these functions.
//!
//! ```
//! let v = [2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0];
//! assert_eq!(stats::mean(&v), 5.0);
//! assert_eq!(stats::sample_variance(&v), 32.0 / 7.0);
//! assert_eq!(stats::rms(&[3.0, -4.0]), 12.5f64.sqrt());
//! // Type-7 quantiles of an ascending slice, numpy's default.
//! let sorted = [1.0, 2.0, 3.0, 4.0, 10.0];
//! assert_eq!(stats::quantile(&sorted, 0.5), 3.0);
//! assert!((stats::quantile(&sorted, 0.95) - 8.8).abs() < 1e-12);
//! assert_eq!(stats::median(&mut [4.0, 1.0, 3.0, 2.0]), 2.5);
//! // Nothing to average: NaN, never a silent 0.
//! assert!(stats::mean(&[]).is_nan());
//! ```

/// The arithmetic mean, sum / n in slice order (NaN for an empty slice).
#[inline]
pub fn mean(values: &[f64]) -> f64 {
    values.iter().sum::<f64>() / values.len() as f64
}

/// The mean square sum x^2 / n, each square `x * x` summed in slice order (NaN for an empty
/// slice).
#[inline]
pub fn mean_square(values: &[f64]) -> f64 {
    values.iter().map(|x| x * x).sum::<f64>() / values.len() as f64
}

/// The root mean square sqrt(sum x^2 / n): the square root of [`mean_square`] (NaN for an empty
/// slice).
#[inline]
pub fn rms(values: &[f64]) -> f64 {
    mean_square(values).sqrt()
}

/// The sample variance with divisor n - 1 (Bessel's correction), two passes: m = [`mean`], then
/// sum (x - m) (x - m) in slice order, divided by n - 1 (NaN for fewer than two values).
#[inline]
pub fn sample_variance(values: &[f64]) -> f64 {
    if values.is_empty() {
        // The sum below would be 0 and the divisor -1: -0, not NaN.
        return f64::NAN;
    }
    let m = mean(values);
    values.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (values.len() as f64 - 1.0)
}

/// The sample standard deviation, the square root of [`sample_variance`] (divisor n - 1; NaN
/// for fewer than two values).
#[inline]
pub fn sample_std(values: &[f64]) -> f64 {
    sample_variance(values).sqrt()
}

/// The weighted mean sum w x / sum w: the products `w * x` summed in slice order, divided by the
/// weights summed in slice order (NaN for empty slices or weights summing to zero). `values` and
/// `weights` have the same length.
#[inline]
pub fn weighted_mean(values: &[f64], weights: &[f64]) -> f64 {
    debug_assert_eq!(values.len(), weights.len());
    let w = weights.iter().sum::<f64>();
    values.iter().zip(weights).map(|(x, w)| w * x).sum::<f64>() / w
}

/// The weighted mean square sum w x^2 / sum w: the terms `w * x * x` (that is (w x) x) summed in
/// slice order, divided by the weights summed in slice order (NaN for empty slices or weights
/// summing to zero). `values` and `weights` have the same length.
#[inline]
pub fn weighted_mean_square(values: &[f64], weights: &[f64]) -> f64 {
    debug_assert_eq!(values.len(), weights.len());
    let w = weights.iter().sum::<f64>();
    values
        .iter()
        .zip(weights)
        .map(|(x, w)| w * x * x)
        .sum::<f64>()
        / w
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

/// The Lanczos approximation's parts at z = x - 1 (Numerical Recipes 3rd ed. §6.1, g = 7, 9
/// coefficients): t = z + g + 1/2 and the series a = c_0 + sum_i c_i / (z + i), so that
/// Gamma(x) = sqrt(2 pi) t^(z + 1/2) e^-t a (relative error below 1e-15 for x >= 1/2).
fn lanczos(z: f64) -> (f64, f64) {
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    let t = z + G + 0.5;
    let a = C
        .iter()
        .enumerate()
        .skip(1)
        .fold(C[0], |a, (i, &c)| a + c / (z + i as f64));
    (t, a)
}

/// ln Gamma(x), x > 0, by the Lanczos approximation ([`lanczos`]), below 1/2 through the
/// reflection Gamma(x) Gamma(1 - x) = pi / sin(pi x).
pub fn ln_gamma(x: f64) -> f64 {
    if x < 0.5 {
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let z = x - 1.0;
    let (t, a) = lanczos(z);
    0.5 * (2.0 * std::f64::consts::PI).ln() + (z + 0.5) * t.ln() - t + a.ln()
}

/// Gamma(x) for 0 < x < 3 by the Lanczos approximation ([`lanczos`]) directly, without the
/// logarithm or the reflection (the series holds for x > 0; larger x would overflow t^(z + 1/2)
/// sooner than ln Gamma does). NaN for x <= 0.
pub fn gamma(x: f64) -> f64 {
    if x.is_nan() || x <= 0.0 {
        return f64::NAN;
    }
    let z = x - 1.0;
    let (t, a) = lanczos(z);
    (2.0 * std::f64::consts::PI).sqrt() * t.powf(z + 0.5) * (-t).exp() * a
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_input_is_nan_everywhere() {
        assert!(mean(&[]).is_nan());
        assert!(rms(&[]).is_nan());
        assert!(mean_square(&[]).is_nan());
        assert!(sample_variance(&[]).is_nan() && sample_std(&[]).is_nan());
        assert!(sample_variance(&[3.0]).is_nan());
        assert!(weighted_mean(&[], &[]).is_nan() && weighted_mean_square(&[], &[]).is_nan());
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

    #[test]
    fn variance_and_mean_square_against_hand_computed_values() {
        // 2, 4, 4, 4, 5, 5, 7, 9: mean 5, squared deviations 9 1 1 1 0 0 4 16 = 32.
        let v = [2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0];
        assert_eq!(sample_variance(&v), 32.0 / 7.0);
        assert_eq!(sample_std(&v), (32.0f64 / 7.0).sqrt());
        // Mean square 232 / 8 = 29; its root is the RMS.
        assert_eq!(mean_square(&v), 29.0);
        assert_eq!(rms(&v), 29f64.sqrt());
        // Two values a, b: variance (a - b)^2 / 2.
        assert_eq!(sample_variance(&[1.0, 4.0]), 4.5);
        // A constant (whose mean is exact) has no spread.
        assert_eq!(sample_variance(&[0.5; 7]), 0.0);
    }

    #[test]
    fn weighted_means_against_hand_computed_values() {
        // (1*1 + 3*2 + 0*5) / 4 = 7/4; (1*1 + 3*4 + 0*25) / 4 = 13/4.
        let (x, w) = ([1.0, 2.0, 5.0], [1.0, 3.0, 0.0]);
        assert_eq!(weighted_mean(&x, &w), 1.75);
        assert_eq!(weighted_mean_square(&x, &w), 3.25);
        // Equal weights: the plain mean and mean square.
        let y = [0.5, -1.25, 3.0, 2.0];
        assert_eq!(weighted_mean(&y, &[2.0; 4]), mean(&y));
        assert_eq!(weighted_mean_square(&y, &[1.0; 4]), mean_square(&y));
    }

    /// The operation order is the one the callers wrote by hand: the same bits.
    #[test]
    fn operation_order_is_left_to_right_then_divide() {
        let v: Vec<f64> = (1..=101)
            .map(|k| (k as f64 * 0.37).sin() * 1e3 + 0.1)
            .collect();
        let n = v.len() as f64;
        let m = v.iter().sum::<f64>() / n;
        assert_eq!(mean(&v).to_bits(), m.to_bits());
        let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64;
        assert_eq!(sample_variance(&v).to_bits(), var.to_bits());
        let ms = v.iter().map(|x| x * x).sum::<f64>() / n;
        assert_eq!(mean_square(&v).to_bits(), ms.to_bits());
        let w: Vec<f64> = (0..v.len()).map(|k| 1.0 + k as f64 / 7.0).collect();
        let sw: f64 = w.iter().sum();
        let wm = v.iter().zip(&w).map(|(x, w)| w * x).sum::<f64>() / sw;
        assert_eq!(weighted_mean(&v, &w).to_bits(), wm.to_bits());
        let wms = v.iter().zip(&w).map(|(x, w)| w * x * x).sum::<f64>() / sw;
        assert_eq!(weighted_mean_square(&v, &w).to_bits(), wms.to_bits());
    }

    /// Gamma at known values: Gamma(n) = (n - 1)!, Gamma(1/2) = sqrt(pi), Gamma(1/4) (Abramowitz
    /// & Stegun 6.1.10 table value 3.625609908221908), within 1e-14 relative.
    #[test]
    fn ln_gamma_at_known_values() {
        let pi = std::f64::consts::PI;
        let cases = [
            (1.0, 1.0),
            (2.0, 1.0),
            (5.0, 24.0),
            (10.0, 362_880.0),
            (0.5, pi.sqrt()),
            (0.25, 3.625_609_908_221_908),
            (1.5, pi.sqrt() / 2.0),
        ];
        for (x, g) in cases {
            let got = ln_gamma(x).exp();
            assert!(((got - g) / g).abs() < 1e-14, "Gamma({x}) = {got}, not {g}");
            if x < 3.0 {
                let direct = gamma(x);
                assert!(((direct - g) / g).abs() < 1e-14, "gamma({x}) = {direct}");
            }
        }
    }
}
