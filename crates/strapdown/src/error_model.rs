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
    /// The same process b seen after a bias calibration: the error is b(t) - m, with m a
    /// constant estimate jointly Gaussian with b(0): Cov(m, b(0)) = `rho` var and Var m = `vm`
    /// var per axis (m = b(0), a perfect turn-on calibration: rho = vm = 1; m the mean of b over
    /// a window W before the start: rho = (T/W)(1 - e^{-W/T}), vm = 2 (T/W)^2 (W/T - 1 +
    /// e^{-W/T}), from the autocovariance var e^{-|u|/T}, [`window_reference`]). b after t = 0
    /// depends on the past only through b(0) (Markov), so (b(0), m) is all the initial state.
    GaussMarkovReferenced {
        sensor: Sensor,
        var: [f64; 3],
        tau_s: [f64; 3],
        rho: [f64; 3],
        vm: [f64; 3],
    },
    /// A warm-up transient a e^{-t/tau} per axis: `amplitude` known, or drawn per run from
    /// N(0, amplitude^2) when `per_run`.
    Transient {
        sensor: Sensor,
        amplitude: [f64; 3],
        tau_s: [f64; 3],
        per_run: bool,
    },
    /// A sinusoid a sin(2 pi f t + phase) per axis, point-sampled every `dt_s` and held over each
    /// sample (what the simulation feeds the mechanisation): over every sample interval it has
    /// the integral of the continuous sinusoid a' sin(2 pi f t + phase') with
    /// a' = a (w dt / 2) / sin(w dt / 2) and phase' = phase - w dt / 2 (integrate
    /// a' sin(w t + phase') over [k dt, (k + 1) dt]), which the model integrates. `phase`
    /// None: uniform per run (mean zero, the covariance a'^2/2 of each quadrature; the second
    /// moments are exact, the distribution is not Gaussian).
    Sinusoid {
        sensor: Sensor,
        amplitude: [f64; 3],
        freq_hz: [f64; 3],
        phase: Option<f64>,
        dt_s: f64,
    },
    /// A stationary resonance per axis: white noise through x'' + 2 zeta w0 x' + w0^2 x = w,
    /// std `sigma`, natural frequency `freq_hz` = w0 / 2 pi, half-power bandwidth
    /// `bandwidth_hz` = 2 zeta f0 (the noise crate's resonance, `closed_form::resonance_exponent`;
    /// Maybeck vol. 1 §4.11): stationary Var x = sigma^2, Var x' = w0^2 sigma^2, uncorrelated,
    /// so the driving PSD is 4 zeta w0^3 sigma^2.
    Resonance {
        sensor: Sensor,
        sigma: [f64; 3],
        freq_hz: [f64; 3],
        bandwidth_hz: [f64; 3],
    },
    /// An initial attitude error: a rotation vector about north, east, down (rad, the sense of
    /// [`crate::nav_error`]'s `attitude_nav_rad`: estimate = exp([psi x]) truth) of known `mean`
    /// and covariance `cov`.
    Attitude { mean: [f64; 3], cov: [[f64; 3]; 3] },
}

/// Cov(m, b(0)) / var and Var(m) / var for m the mean of a stationary first-order Gauss-Markov
/// process of correlation time `tau_s` over a window of `window_s` before t = 0 (from its
/// autocovariance var e^{-|u|/T}: (1/W) int_0^W e^{-v/T} dv and (2/W^2) int_0^W (W - v)
/// e^{-v/T} dv), series below W/T = 1e-3 so nothing cancels.
pub fn window_reference(tau_s: f64, window_s: f64) -> (f64, f64) {
    let x = window_s / tau_s;
    if x < 1e-3 {
        // 1 - x/2 + x^2/6 and 1 - x/3 + x^2/12: remainders below 1e-12.
        (1.0 - x / 2.0 + x * x / 6.0, 1.0 - x / 3.0 + x * x / 12.0)
    } else {
        let e = (-x).exp();
        ((1.0 - e) / x, 2.0 * (x - 1.0 + e) / (x * x))
    }
}

/// The mean and covariance of the nine navigation errors (dr_N, dr_E, dr_D, dv_N, dv_E, dv_D,
/// psi_N, psi_E, psi_D) at one time. psi is in the sense of [`crate::nav_error`]
/// (estimate = exp([psi x]) truth).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorMoments {
    pub mean: SVector<f64, 9>,
    pub cov: SMatrix<f64, 9, 9>,
}

impl ErrorMoments {
    /// No error at all.
    pub fn zero() -> ErrorMoments {
        ErrorMoments {
            mean: SVector::zeros(),
            cov: SMatrix::zeros(),
        }
    }
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
    /// The moments of independent errors added (means add, covariances add).
    pub fn add(&mut self, other: &ErrorMoments) {
        self.mean += other.mean;
        self.cov += other.cov;
    }
}

/// The continuous system of a stationary navigator at `earth.place` with body attitude
/// `attitude` (body to NED) and one `source`: F, the white-noise covariance G Q G^T, P(0), m(0).
///
/// The model's attitude state is Titterton & Weston's psi (estimate = (I - [psi x]) truth, the
/// sign of their eq 12.10), the negative of [`crate::nav_error`]'s; [`moments`] reports the
/// latter.
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
    let mut q = Mat::zeros();
    let mut p0 = Mat::zeros();
    let mut m0 = Vec15::zeros();
    let diag = |v: &[f64; 3]| Matrix3::from_diagonal(&Vector3::from(*v));
    // The rows a sensor's error drives, and its sign: -C into psi for a gyro, +C into dv for an
    // accelerometer.
    let drive = |sensor: Sensor| match sensor {
        Sensor::Gyro => (6, -cm),
        Sensor::Accel => (3, cm),
    };
    // An augmented value state per axis driving the sensor's rows.
    let augment = |a: &mut Mat, sensor: Sensor| {
        let (row, gain) = drive(sensor);
        a.fixed_view_mut::<3, 3>(row, VALUE).copy_from(&gain);
    };
    match source {
        Source::White { sensor, n2 } => {
            // G = sign C into the driven rows; G Q G^T = C diag(N^2) C^T.
            let (row, _) = drive(*sensor);
            q.fixed_view_mut::<3, 3>(row, row)
                .copy_from(&(cm * diag(n2) * cm.transpose()));
        }
        Source::RandomBias { sensor, var } => {
            augment(&mut a, *sensor);
            p0.fixed_view_mut::<3, 3>(VALUE, VALUE)
                .copy_from(&diag(var));
        }
        Source::Bias { sensor, value } => {
            augment(&mut a, *sensor);
            m0.fixed_rows_mut::<3>(VALUE)
                .copy_from(&Vector3::from(*value));
        }
        Source::Ramp { sensor, rate } => {
            augment(&mut a, *sensor);
            for i in 0..3 {
                a[(VALUE + i, RATE + i)] = 1.0;
            }
            m0.fixed_rows_mut::<3>(RATE)
                .copy_from(&Vector3::from(*rate));
        }
        Source::RandomWalk { sensor, k2 } => {
            augment(&mut a, *sensor);
            q.fixed_view_mut::<3, 3>(VALUE, VALUE).copy_from(&diag(k2));
        }
        Source::GaussMarkov { sensor, var, tau_s } => {
            augment(&mut a, *sensor);
            for i in 0..3 {
                a[(VALUE + i, VALUE + i)] = -1.0 / tau_s[i];
                q[(VALUE + i, VALUE + i)] = 2.0 * var[i] / tau_s[i];
                p0[(VALUE + i, VALUE + i)] = var[i];
            }
        }
        Source::GaussMarkovReferenced {
            sensor,
            var,
            tau_s,
            rho,
            vm,
        } => {
            // States b (VALUE) and the constant estimate m (RATE); the error b - m drives.
            let (row, gain) = drive(*sensor);
            a.fixed_view_mut::<3, 3>(row, VALUE).copy_from(&gain);
            a.fixed_view_mut::<3, 3>(row, RATE).copy_from(&(-gain));
            for i in 0..3 {
                a[(VALUE + i, VALUE + i)] = -1.0 / tau_s[i];
                q[(VALUE + i, VALUE + i)] = 2.0 * var[i] / tau_s[i];
                p0[(VALUE + i, VALUE + i)] = var[i];
                p0[(VALUE + i, RATE + i)] = rho[i] * var[i];
                p0[(RATE + i, VALUE + i)] = rho[i] * var[i];
                p0[(RATE + i, RATE + i)] = vm[i] * var[i];
            }
        }
        Source::Transient {
            sensor,
            amplitude,
            tau_s,
            per_run,
        } => {
            augment(&mut a, *sensor);
            for i in 0..3 {
                a[(VALUE + i, VALUE + i)] = -1.0 / tau_s[i];
                if *per_run {
                    p0[(VALUE + i, VALUE + i)] = amplitude[i] * amplitude[i];
                } else {
                    m0[VALUE + i] = amplitude[i];
                }
            }
        }
        Source::Sinusoid {
            sensor,
            amplitude,
            freq_hz,
            phase,
            dt_s,
        } => {
            // (s, c) = a' (sin, cos)(w t + phase'): ds/dt = w c, dc/dt = -w s; s drives.
            augment(&mut a, *sensor);
            for i in 0..3 {
                let w = std::f64::consts::TAU * freq_hz[i];
                let half = 0.5 * w * dt_s;
                let gain = if half.abs() < 1e-6 {
                    1.0 + half * half / 6.0
                } else {
                    half / half.sin()
                };
                let amp = amplitude[i] * gain;
                a[(VALUE + i, RATE + i)] = w;
                a[(RATE + i, VALUE + i)] = -w;
                match phase {
                    Some(p) => {
                        let (sp, cp) = (p - half).sin_cos();
                        m0[VALUE + i] = amp * sp;
                        m0[RATE + i] = amp * cp;
                    }
                    None => {
                        p0[(VALUE + i, VALUE + i)] = amp * amp / 2.0;
                        p0[(RATE + i, RATE + i)] = amp * amp / 2.0;
                    }
                }
            }
        }
        Source::Resonance {
            sensor,
            sigma,
            freq_hz,
            bandwidth_hz,
        } => {
            // (x, x'): x'' = -w0^2 x - 2 zeta w0 x' + w; x drives.
            augment(&mut a, *sensor);
            for i in 0..3 {
                let w0 = std::f64::consts::TAU * freq_hz[i];
                let zeta = bandwidth_hz[i] / (2.0 * freq_hz[i]);
                let var = sigma[i] * sigma[i];
                a[(VALUE + i, RATE + i)] = 1.0;
                a[(RATE + i, VALUE + i)] = -w0 * w0;
                a[(RATE + i, RATE + i)] = -2.0 * zeta * w0;
                q[(RATE + i, RATE + i)] = 4.0 * zeta * w0.powi(3) * var;
                p0[(VALUE + i, VALUE + i)] = var;
                p0[(RATE + i, RATE + i)] = w0 * w0 * var;
            }
        }
        Source::Attitude { mean, cov } => {
            // The model's psi is the negative of nav_error's (see above).
            m0.fixed_rows_mut::<3>(6)
                .copy_from(&(-Vector3::from(*mean)));
            p0.fixed_view_mut::<3, 3>(6, 6)
                .copy_from(&Matrix3::from_fn(|i, j| cov[i][j]));
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

/// Phi = exp(F h) and Q_d = int_0^h exp(F s) Q exp(F^T s) ds: Van Loan's block exponential
/// (exp of [[-F, Q], [0, F^T]] h) over a step h / 2^k short enough that ||F|| h / 2^k <= 1 (a
/// fast decay, 1/T of a short correlation time, would overflow exp(-F h) over a long step),
/// then doubled k times: Phi(2h) = Phi(h)^2, Q_d(2h) = Q_d(h) + Phi(h) Q_d(h) Phi(h)^T.
fn discretise(a: &Mat, q: &Mat, h: f64) -> (Mat, Mat) {
    let norm = a.abs().row_sum().max() * h;
    let k = if norm > 1.0 {
        norm.log2().ceil() as i32
    } else {
        0
    };
    let h0 = h / 2f64.powi(k);
    let mut m = SMatrix::<f64, { 2 * N }, { 2 * N }>::zeros();
    m.fixed_view_mut::<N, N>(0, 0).copy_from(&(-a * h0));
    m.fixed_view_mut::<N, N>(0, N).copy_from(&(q * h0));
    m.fixed_view_mut::<N, N>(N, N)
        .copy_from(&(a.transpose() * h0));
    let e = m.exp();
    let mut phi: Mat = e.fixed_view::<N, N>(N, N).transpose();
    let qd = phi * e.fixed_view::<N, N>(0, N);
    let mut qd = 0.5 * (qd + qd.transpose());
    for _ in 0..k {
        qd += phi * qd * phi.transpose();
        phi *= phi;
    }
    (phi, 0.5 * (qd + qd.transpose()))
}

/// The error's mean and covariance at each of `times_s` (ascending, seconds from the start) of
/// a stationary navigator on `earth` with body attitude `attitude` and the error `source` alone.
pub fn moments(
    earth: &RoundEarth,
    attitude: &Attitude,
    source: &Source,
    times_s: &[f64],
) -> Vec<ErrorMoments> {
    // Long steps are exact too (`discretise`); this bound only keeps the doubling short.
    const MAX_STEP_S: f64 = 600.0;
    let (a, q, mut p, mut m) = system(earth, attitude, source);
    // The model's psi is the negative of nav_error's: flip its sign in the report.
    let flip = SVector::<f64, 9>::from_fn(|i, _| if i >= 6 { -1.0 } else { 1.0 });
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
        let cov = p.fixed_view::<9, 9>(0, 0).into_owned();
        out.push(ErrorMoments {
            mean: m.fixed_rows::<9>(0).component_mul(&flip),
            cov: SMatrix::from_fn(|i, j| cov[(i, j)] * flip[i] * flip[j]),
        });
    }
    out
}
