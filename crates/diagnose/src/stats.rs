//! Small statistics shared by the detectors, the spectrum and the workflow.

pub(crate) use stats::{mean, median};

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
