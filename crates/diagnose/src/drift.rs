//! Drift consequence of a static log (docs/diagnose.md, diagnose step 6): heading and horizontal position
//! drift over segments of a log, computed the same way for the measured log and for logs simulated
//! from the model, so the three are directly comparable.
//!
//! Each segment is dead-reckoned from rest by the project's strapdown mechanisation (the default
//! `Accurate` scheme; Woodman eqs 41-46 and better, crate `strapdown`), starting level at the origin,
//! after the static calibration a user would do: each channel's mean over the whole log is taken as its
//! bias and removed, the accelerometers are then referred to the ideal specific force (0, 0, -g) of a
//! level IMU (Woodman §3.2.1 gyro, §4.2 accelerometer; docs/model.md §1.5, §1.6). The errors are the
//! navigation solution minus the static truth (`strapdown::nav_error`).

use serde::Serialize;

/// Standard gravity, m/s^2 (the noise crate's definition, shared by the workspace).
pub use noise::units::STANDARD_GRAVITY_MPS2 as G_MPS2;

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
        DriftSummary {
            horizon_s: self.horizon_s,
            segments: self.heading_rad.len(),
            heading_rms_rad: stats::rms(&self.heading_rad),
            horizontal_rms_m: stats::rms(&self.horizontal_m),
        }
    }

    /// Append the segments of another drift of the same horizon (seeds are merged in index order).
    pub fn extend(&mut self, other: &SegmentDrift) {
        self.heading_rad.extend_from_slice(&other.heading_rad);
        self.horizontal_m.extend_from_slice(&other.horizontal_m);
    }
}

/// Segment drifts of a static log. `channels` are gx gy gz (rad/s) and ax ay az (m/s^2); a missing
/// channel (None) reads its ideal value. Segments are consecutive, non-overlapping, of
/// `round(horizon_s / dt_s)` samples each; a horizon longer than the log gives no segment. This
/// is the default drift protocol (`protocol::Protocol::default()`: the log-mean calibration, a
/// perfect start) on the Earth of `latitude_deg` (`protocol::earth_at`), computed by the same
/// code as `imudrift drift`.
pub fn segment_drift(
    channels: &[Option<&[f64]>; 6],
    dt_s: f64,
    horizon_s: f64,
    latitude_deg: Option<f64>,
) -> SegmentDrift {
    let e = crate::protocol::segment_errors(
        channels,
        dt_s,
        horizon_s,
        &crate::protocol::Protocol {
            latitude_deg,
            ..Default::default()
        },
    );
    SegmentDrift {
        horizon_s,
        heading_rad: e.heading_rad,
        horizontal_m: e.pos_horizontal_m,
    }
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
        // mean is 0 and each 10 s segment sees a constant eps. Woodman / docs/model.md §1.3: s = g eps t^3 / 6.
        let dt = 0.001;
        let eps = 1e-3;
        let n = 20_000;
        let gy: Vec<f64> = (0..n).map(|k| if k < n / 2 { eps } else { -eps }).collect();
        let d = segment_drift(&[None, Some(&gy), None, None, None, None], dt, 10.0, None);
        assert_eq!(d.horizontal_m.len(), 2);
        let t: f64 = 10.0;
        let law = G_MPS2 * eps * t.powi(3) / 6.0;
        // The law is first order in the tilt (here 0.01 rad: sin differs by 2e-5 relative) and
        // continuous-time; the trapezoidal mechanisation's discretisation error is O(dt / t).
        let tol = 4.0 * dt / t;
        for &p in &d.horizontal_m {
            assert!((p / law - 1.0).abs() < tol, "{p} vs {law}");
        }
        assert!(
            d.heading_rad.iter().all(|h| h.abs() < 1e-12),
            "{:?}",
            d.heading_rad
        );
    }

    #[test]
    fn constant_z_gyro_error_gives_linear_heading() {
        // Woodman §3.2.1: theta(t) = eps t. The rotation is exact per step, so only rounding remains.
        let dt = 0.01;
        let eps = 2e-3;
        let n = 4000;
        let gz: Vec<f64> = (0..n).map(|k| if k < n / 2 { eps } else { -eps }).collect();
        let d = segment_drift(&[None, None, Some(&gz), None, None, None], dt, 20.0, None);
        assert!(
            (d.heading_rad[0] - eps * 20.0).abs() < 1e-12,
            "{:?}",
            d.heading_rad
        );
        assert!(
            (d.heading_rad[1] + eps * 20.0).abs() < 1e-12,
            "{:?}",
            d.heading_rad
        );
        assert!(d.horizontal_m.iter().all(|p| p.abs() < 1e-9));
    }

    #[test]
    fn accel_error_gives_quadratic_law_and_short_logs_give_no_segments() {
        // Woodman eq (10): s = eps t^2 / 2.
        let dt = 0.01;
        let eps = 0.02;
        let n = 2000;
        let ax: Vec<f64> = (0..n).map(|k| if k < n / 2 { eps } else { -eps }).collect();
        let d = segment_drift(&[None, None, None, Some(&ax), None, None], dt, 10.0, None);
        let law = eps * 100.0 / 2.0;
        for &p in &d.horizontal_m {
            assert!((p / law - 1.0).abs() < 2.0 * dt / 10.0, "{p} vs {law}");
        }
        let none = segment_drift(&[None, None, None, Some(&ax), None, None], dt, 3600.0, None);
        assert!(none.horizontal_m.is_empty());
        assert!(none.summary().horizontal_rms_m.is_nan());
    }
}
