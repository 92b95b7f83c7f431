//! The round, rotating Earth's linearised navigation-error model and its covariance: the growth
//! law a Monte Carlo on [`crate::RoundEarth`] is set beside, as the flat closed forms are on
//! Woodman's Earth.
//!
//! The psi-angle error model of a stationary navigator (Titterton & Weston, *Strapdown Inertial
//! Navigation Technology*, 2nd ed., §12.2-12.3; Groves, *Principles of GNSS, Inertial, and
//! Multisensor Integrated Navigation Systems*, 2nd ed., §14.2), north-east-down, v = 0 (so the
//! transport rate is zero), f = (0, 0, -g):
//! - d(dr)/dt = dv;
//! - d(dv)/dt = -psi x f - 2 omega_ie x dv + dg + C accel_error, with the gravity error of a
//!   position error dg = (-g dr_N / (R_N + h), -g dr_E / (R_E + h), +2 g dr_D / R) (the gravity
//!   direction turning with a horizontal displacement: the Schuler loop, each channel with its own
//!   radius of curvature; the magnitude falling with height: the unstable vertical channel, R the
//!   Gaussian mean radius; held: dr_D = dv_D = 0);
//! - d(psi)/dt = -omega_ie x psi - C gyro_error.
//!
//! Each error source drives it through augmented states (its value per body axis; a ramp also its
//! rate) or as white noise: white noise of PSD N^2 (ARW, VRW), a random constant bias, a known
//! constant bias, a known ramp, a random walk of PSD K^2, and a first-order Gauss-Markov process
//! (the flicker bank of the noise crate is a sum of them), and a random initial attitude error.
//! The known sources give the error's mean, the random ones its covariance. The system is linear
//! with constant coefficients, so both are exact over an interval h: m <- Phi m,
//! P <- Phi P Phi^T + Q_d, Phi = exp(F h), Q_d from Van Loan's block exponential (C. F. Van Loan,
//! "Computing integrals involving the matrix exponential", IEEE TAC 23(3), 1978).
//! The discrete white noise of a simulation at interval dt has this law to O(dt) of the
//! dynamics' rates (Schuler 1.2e-3 rad/s): far below any Monte Carlo's resolution.

use crate::round_earth::{RoundEarth, Vertical};
use crate::Attitude;
use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

/// Error states: position (3), velocity (3), psi (3), the source's augmented states (its value
/// per axis, and for a ramp its rate per axis).
const N: usize = 15;
/// First augmented state (the source's value), and the ramp's rate.
const VALUE: usize = 9;
const RATE: usize = 12;
type Mat = SMatrix<f64, N, N>;
type Vec15 = SVector<f64, N>;

/// Which sensor an error source acts on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sensor {
    Gyro,
    Accel,
}

/// One error source, per body axis (x, y, z), in SI units: rad/s for gyros, m/s^2 for
/// accelerometers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Source {
    /// White noise of PSD `n2` per axis (rad^2/s for gyros, (m/s^2)^2 s for accelerometers: N^2).
    White { sensor: Sensor, n2: [f64; 3] },
    /// A constant bias drawn once with variance `var` per axis.
    RandomBias { sensor: Sensor, var: [f64; 3] },
    /// A known constant bias `value` per axis.
    Bias { sensor: Sensor, value: [f64; 3] },
    /// A known ramp: the error grows as `rate` t per axis (rad/s^2; m/s^3).
    Ramp { sensor: Sensor, rate: [f64; 3] },
    /// A random walk from zero, of white-noise PSD `k2` per axis.
    RandomWalk { sensor: Sensor, k2: [f64; 3] },
    /// A stationary first-order Gauss-Markov process of variance `var` and correlation time
    /// `tau_s` per axis.
    GaussMarkov {
        sensor: Sensor,
        var: [f64; 3],
        tau_s: [f64; 3],
    },
    /// An initial attitude error of variance `var` about north, east, down (rad^2).
    Attitude { var: [f64; 3] },
}

/// The mean and covariance of the nine navigation errors (dr_N, dr_E, dr_D, dv_N, dv_E, dv_D,
/// psi_N, psi_E, psi_D) at one time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorMoments {
    pub mean: SVector<f64, 9>,
    pub cov: SMatrix<f64, 9, 9>,
}

impl ErrorMoments {
    /// Mean square of the horizontal position error (mean squared plus variance), m^2.
    pub fn horizontal_position_ms(&self) -> f64 {
        self.second_moment(0) + self.second_moment(1)
    }
    /// Mean square of the horizontal velocity error, (m/s)^2.
    pub fn horizontal_velocity_ms(&self) -> f64 {
        self.second_moment(3) + self.second_moment(4)
    }
    /// E[x_i^2] of state `i` (0-8 in the order above).
    pub fn second_moment(&self, i: usize) -> f64 {
        self.mean[i] * self.mean[i] + self.cov[(i, i)]
    }
}

/// The continuous system of a stationary navigator at `earth.place` with body attitude
/// `attitude` (body to NED) and one `source`: F, the white-noise covariance G Q G^T, P(0), m(0).
fn system(earth: &RoundEarth, attitude: &Attitude, source: &Source) -> (Mat, Mat, Mat, Vec15) {
    let place = earth.place;
    let g = place.gravity_mps2();
    let r = place.schuler_radius_m();
    let (s, c) = place.lat_rad.sin_cos();
    let w = earth.rate_rad_s();
    let omega = Vector3::new(w * c, 0.0, -w * s);
    let cross = |v: &Vector3<f64>| Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0);
    let f = Vector3::new(0.0, 0.0, -g);
    let held = earth.vertical == Vertical::Held;
    let mut a = Mat::zeros();
    // d(dr)/dt = dv
    for i in 0..3 {
        a[(i, 3 + i)] = 1.0;
    }
    // d(dv)/dt = dg - 2 omega x dv - psi x f  (-psi x f = f x psi)
    let (rn, re) = crate::earth::radii_m(place.lat_rad);
    a[(3, 0)] = -g / (rn + place.height_m);
    a[(4, 1)] = -g / (re + place.height_m);
    a[(5, 2)] = 2.0 * g / r;
    a.fixed_view_mut::<3, 3>(3, 3)
        .copy_from(&(-2.0 * cross(&omega)));
    a.fixed_view_mut::<3, 3>(3, 6).copy_from(&cross(&f));
    // d(psi)/dt = -omega x psi - C gyro_error
    a.fixed_view_mut::<3, 3>(6, 6).copy_from(&(-cross(&omega)));
    let cm = *attitude.matrix();
    let (sensor, row) = match source {
        Source::White { sensor, .. }
        | Source::RandomBias { sensor, .. }
        | Source::Bias { sensor, .. }
        | Source::Ramp { sensor, .. }
        | Source::RandomWalk { sensor, .. }
        | Source::GaussMarkov { sensor, .. } => (
            Some(*sensor),
            match sensor {
                Sensor::Gyro => 6,
                Sensor::Accel => 3,
            },
        ),
        Source::Attitude { .. } => (None, 6),
    };
    let sign = if sensor == Some(Sensor::Gyro) {
        -1.0
    } else {
        1.0
    };
    let mut q = Mat::zeros();
    let mut p0 = Mat::zeros();
    let mut m0 = Vec15::zeros();
    let diag = |v: &[f64; 3]| Matrix3::from_diagonal(&Vector3::from(*v));
    match source {
        Source::White { n2, .. } => {
            // G = sign C into the driven rows; G Q G^T = C diag(N^2) C^T.
            q.fixed_view_mut::<3, 3>(row, row)
                .copy_from(&(cm * diag(n2) * cm.transpose()));
        }
        Source::RandomBias { var, .. } => {
            a.fixed_view_mut::<3, 3>(row, VALUE).copy_from(&(sign * cm));
            p0.fixed_view_mut::<3, 3>(VALUE, VALUE)
                .copy_from(&diag(var));
        }
        Source::Bias { value, .. } => {
            a.fixed_view_mut::<3, 3>(row, VALUE).copy_from(&(sign * cm));
            m0.fixed_rows_mut::<3>(VALUE)
                .copy_from(&Vector3::from(*value));
        }
        Source::Ramp { rate, .. } => {
            a.fixed_view_mut::<3, 3>(row, VALUE).copy_from(&(sign * cm));
            for i in 0..3 {
                a[(VALUE + i, RATE + i)] = 1.0;
            }
            m0.fixed_rows_mut::<3>(RATE)
                .copy_from(&Vector3::from(*rate));
        }
        Source::RandomWalk { k2, .. } => {
            a.fixed_view_mut::<3, 3>(row, VALUE).copy_from(&(sign * cm));
            q.fixed_view_mut::<3, 3>(VALUE, VALUE).copy_from(&diag(k2));
        }
        Source::GaussMarkov { var, tau_s, .. } => {
            a.fixed_view_mut::<3, 3>(row, VALUE).copy_from(&(sign * cm));
            for i in 0..3 {
                a[(VALUE + i, VALUE + i)] = -1.0 / tau_s[i];
                q[(VALUE + i, VALUE + i)] = 2.0 * var[i] / tau_s[i];
                p0[(VALUE + i, VALUE + i)] = var[i];
            }
        }
        Source::Attitude { var } => {
            p0.fixed_view_mut::<3, 3>(6, 6).copy_from(&diag(var));
        }
    }
    if held {
        for j in 0..N {
            a[(2, j)] = 0.0;
            a[(5, j)] = 0.0;
            a[(j, 2)] = 0.0;
            a[(j, 5)] = 0.0;
        }
        for j in 0..N {
            q[(2, j)] = 0.0;
            q[(5, j)] = 0.0;
            q[(j, 2)] = 0.0;
            q[(j, 5)] = 0.0;
        }
    }
    (a, q, p0, m0)
}

/// Phi = exp(F h) and Q_d = int_0^h exp(F s) Q exp(F^T s) ds (Van Loan 1978, eq for the
/// "integrals involving the matrix exponential": the exponential of [[-F, Q], [0, F^T]] h).
fn discretise(a: &Mat, q: &Mat, h: f64) -> (Mat, Mat) {
    let mut m = SMatrix::<f64, { 2 * N }, { 2 * N }>::zeros();
    m.fixed_view_mut::<N, N>(0, 0).copy_from(&(-a * h));
    m.fixed_view_mut::<N, N>(0, N).copy_from(&(q * h));
    m.fixed_view_mut::<N, N>(N, N)
        .copy_from(&(a.transpose() * h));
    let e = m.exp();
    let phi = e.fixed_view::<N, N>(N, N).transpose();
    let qd = phi * e.fixed_view::<N, N>(0, N);
    (phi, 0.5 * (qd + qd.transpose()))
}

/// The error's mean and covariance at each of `times_s` (ascending, seconds from the start) of
/// a stationary navigator on `earth` with body attitude `attitude` and the error `source` alone.
/// Steps of at most `MAX_STEP_S` keep the exponentials' arguments small.
pub fn moments(
    earth: &RoundEarth,
    attitude: &Attitude,
    source: &Source,
    times_s: &[f64],
) -> Vec<ErrorMoments> {
    const MAX_STEP_S: f64 = 10.0;
    let (a, q, mut p, mut m) = system(earth, attitude, source);
    let mut out = Vec::with_capacity(times_s.len());
    let mut t = 0.0;
    let mut cache: Option<(f64, Mat, Mat)> = None;
    for &target in times_s {
        let span = (target - t).max(0.0);
        let steps = (span / MAX_STEP_S).ceil() as usize;
        if steps > 0 {
            let h = span / steps as f64;
            let (phi, qd) = match cache {
                Some((ch, phi, qd)) if ch == h => (phi, qd),
                _ => {
                    let (phi, qd) = discretise(&a, &q, h);
                    cache = Some((h, phi, qd));
                    (phi, qd)
                }
            };
            for _ in 0..steps {
                p = phi * p * phi.transpose() + qd;
                m = phi * m;
            }
        }
        t = target.max(t);
        out.push(ErrorMoments {
            mean: m.fixed_rows::<9>(0).into_owned(),
            cov: p.fixed_view::<9, 9>(0, 0).into_owned(),
        });
    }
    out
}
