//! Small statistics shared by the detectors, the spectrum and the workflow.

/// The median (NaN for an empty slice); reorders `v`.
pub(crate) fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    let n = v.len();
    let (lower, &mut mid, _) = v.select_nth_unstable_by(n / 2, f64::total_cmp);
    if n % 2 == 1 {
        mid
    } else {
        let below = lower.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        0.5 * (below + mid)
    }
}

/// The arithmetic mean (0 for an empty slice).
pub(crate) fn mean(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len().max(1) as f64
}

/// Ordinary least-squares slope of x_k against t_k = k dt: sum (t - t_mean)(x - x_mean) / sum (t - t_mean)^2.
pub(crate) fn slope(x: &[f64], dt_s: f64) -> f64 {
    let n = x.len() as f64;
    let t_mean = (n - 1.0) / 2.0 * dt_s;
    let x_mean = mean(x);
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (k, &v) in x.iter().enumerate() {
        let dt = k as f64 * dt_s - t_mean;
        sxy += dt * (v - x_mean);
        sxx += dt * dt;
    }
    if sxx > 0.0 {
        sxy / sxx
    } else {
        0.0
    }
}
