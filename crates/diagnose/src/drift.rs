//! Drift consequence of a static log (DESIGN.md, diagnose step 6): heading and horizontal position
//! drift over segments of a log, computed the same way for the measured log and for logs simulated
//! from the model, so the three are directly comparable.
//!
//! Linearised static, level strapdown error model (body FRD = nav NED at zero heading):
//! - the constant bias is calibrated out by the log's own mean, as a static calibration would
//!   (Woodman §3.2.1 gyro, §4.2 accelerometer; theory.md §1.5, §1.6);
//! - attitude error is the rectangle-rule integral of the gyro error (Woodman eqs 2, 36-37);
//! - a tilt error eps projects g sin(eps) ~ g eps of gravity onto the horizontal (Woodman §6.2.3,
//!   theory.md §1.2): with specific force (0, 0, -g) in NED, the rotation error delta gives
//!   delta x f = (-g delta_y, g delta_x, 0);
//! - velocity and position follow Woodman's rectangle rule, eqs (45)-(46): v += dt a, s += dt v.

use serde::Serialize;

/// Standard gravity, m/s^2 (DESIGN.md / INTERFACES.md convention).
pub const G_MPS2: f64 = 9.80665;

/// Channels of an IMU log in the order gx gy gz ax ay az.
pub const CHANNELS: [&str; 6] = ["gx", "gy", "gz", "ax", "ay", "az"];

/// Heading and horizontal position error at the end of every full segment of one length.
#[derive(Clone, Debug, Default, Serialize)]
pub struct SegmentDrift {
    pub horizon_s: f64,
    pub heading_rad: Vec<f64>,
    pub horizontal_m: Vec<f64>,
}

/// Summary of segment drifts (RMS over segments, and how many segments there were).
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct DriftSummary {
    pub horizon_s: f64,
    pub segments: usize,
    pub heading_rms_rad: f64,
    pub horizontal_rms_m: f64,
}

impl SegmentDrift {
    pub fn summary(&self) -> DriftSummary {
        let rms = |v: &[f64]| {
            if v.is_empty() {
                f64::NAN
            } else {
                (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
            }
        };
        DriftSummary {
            horizon_s: self.horizon_s,
            segments: self.heading_rad.len(),
            heading_rms_rad: rms(&self.heading_rad),
            horizontal_rms_m: rms(&self.horizontal_m),
        }
    }

    /// Append the segments of another drift of the same horizon (seeds are merged in index order).
    pub fn extend(&mut self, other: &SegmentDrift) {
        self.heading_rad.extend_from_slice(&other.heading_rad);
        self.horizontal_m.extend_from_slice(&other.horizontal_m);
    }
}

fn mean(x: &[f64]) -> f64 {
    if x.is_empty() {
        0.0
    } else {
        x.iter().sum::<f64>() / x.len() as f64
    }
}

/// Segment drifts of a static log. `channels` are gx gy gz (rad/s) and ax ay (m/s^2); a missing
/// channel (None) contributes no error. Segments are consecutive, non-overlapping, of
/// `round(horizon_s / dt_s)` samples each; a horizon longer than the log gives no segment.
pub fn segment_drift(channels: &[Option<&[f64]>; 5], dt_s: f64, horizon_s: f64) -> SegmentDrift {
    let n = channels
        .iter()
        .flatten()
        .map(|c| c.len())
        .min()
        .unwrap_or(0);
    let len = (horizon_s / dt_s).round() as usize;
    let mut out = SegmentDrift {
        horizon_s,
        ..Default::default()
    };
    if len == 0 || n < len {
        return out;
    }
    let bias: Vec<f64> = channels
        .iter()
        .map(|c| c.map(|c| mean(&c[..n])).unwrap_or(0.0))
        .collect();
    let value = |ch: usize, k: usize| channels[ch].map(|c| c[k] - bias[ch]).unwrap_or(0.0);
    for seg in 0..n / len {
        let (mut th_x, mut th_y, mut th_z) = (0.0, 0.0, 0.0);
        let (mut v_n, mut v_e, mut p_n, mut p_e) = (0.0, 0.0, 0.0, 0.0);
        for k in seg * len..(seg + 1) * len {
            th_x += value(0, k) * dt_s;
            th_y += value(1, k) * dt_s;
            th_z += value(2, k) * dt_s;
            let a_n = value(3, k) - G_MPS2 * th_y;
            let a_e = value(4, k) + G_MPS2 * th_x;
            v_n += a_n * dt_s;
            v_e += a_e * dt_s;
            p_n += v_n * dt_s;
            p_e += v_e * dt_s;
        }
        out.heading_rad.push(th_z);
        out.horizontal_m.push(p_n.hypot(p_e));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A gyro ramp (bias varying linearly in time, mean removed) gives a known tilt and position:
    /// with omega_k = r (k - (n-1)/2) dt over one segment of the whole log, theta is a sum we can
    /// write in closed form; check against a direct double loop instead of re-deriving it.
    #[test]
    fn constant_gyro_error_gives_cubic_position_law() {
        // Bias calibrated from a different (zero-mean) window is equivalent to a constant error eps
        // after calibration; build that with two halves: the first half has +eps, the second -eps, so the
        // mean is 0 and each 10 s segment sees a constant eps. Woodman / theory.md §1.3: s = g eps t^3 / 6.
        let dt = 0.001;
        let eps = 1e-3;
        let n = 20_000;
        let gy: Vec<f64> = (0..n).map(|k| if k < n / 2 { eps } else { -eps }).collect();
        let d = segment_drift(&[None, Some(&gy), None, None, None], dt, 10.0);
        assert_eq!(d.horizontal_m.len(), 2);
        let t: f64 = 10.0;
        let law = G_MPS2 * eps * t.powi(3) / 6.0;
        // Rectangle rule with updated values: dt^3 sum_j j(j+1)(j+2)/2 / n^3 = (1/6)(1 + 3/n + 2/n^2),
        // relative excess 3 dt / t to first order; allow 4 dt / t.
        let tol = 4.0 * dt / t;
        for &p in &d.horizontal_m {
            assert!((p / law - 1.0).abs() < tol, "{p} vs {law}");
        }
        assert_eq!(d.heading_rad, vec![0.0, 0.0]);
    }

    #[test]
    fn accel_error_gives_quadratic_law_and_short_logs_give_no_segments() {
        // Woodman eq (10): s = eps t^2 / 2.
        let dt = 0.01;
        let eps = 0.02;
        let n = 2000;
        let ax: Vec<f64> = (0..n).map(|k| if k < n / 2 { eps } else { -eps }).collect();
        let d = segment_drift(&[None, None, None, Some(&ax), None], dt, 10.0);
        let law = eps * 100.0 / 2.0;
        for &p in &d.horizontal_m {
            assert!((p / law - 1.0).abs() < 2.0 * dt / 10.0, "{p} vs {law}");
        }
        let none = segment_drift(&[None, None, None, Some(&ax), None], dt, 3600.0);
        assert!(none.horizontal_m.is_empty());
        assert!(none.summary().horizontal_rms_m.is_nan());
    }
}
