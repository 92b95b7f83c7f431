//! Closed forms: the Allan variance of each error term (docs/model.md §2, IEEE Std 952-1997 Annex C via
//! Hou 2004) and its growth law when integrated once, twice and through tilt (docs/model.md §4).
//!
//! All arguments and results are SI: rad/s (gyro) or m/s^2 (accel) for the signal, s for times.
//! `*_avar` functions take the averaging time `tau_s` of a continuous record; `*_avar_sampled`
//! give the exact Allan variance of the discrete generator (sample interval `dt_s`, `tau_s = m·dt_s`)
//! where sampling changes it, so tests can compare at any sample rate.

use crate::units::STANDARD_GRAVITY_MPS2;
use num_complex::Complex64;
use std::f64::consts::{LN_2, PI};

/// sqrt(2 ln2 / pi) = 0.6643: the Allan-deviation plateau of flicker noise per unit IEEE B (Hou 4.38-4.50).
pub const FLICKER_PLATEAU_PER_B: f64 = 0.664_282_470_267_960_1;

/// Power-law noise S(f) = h f^alpha (one-sided PSD, -2 < alpha < 0): its Allan variance
/// sigma^2(tau) = 2 int_0^inf S(f) sin^4(pi f tau) / (pi f tau)^2 df (NIST SP 1065, the conversion
/// from the spectral density; IEEE Std 952-1997 Annex C with the two-sided PSD) is h K(alpha) tau^(-alpha-1), and this is K(alpha).
///
/// With x = pi f tau, K = 2 pi^(-1-alpha) M(alpha - 1), M(s) = int_0^inf x^(s-1) sin^4 x dx; from
/// sin^4 = (3 - 4 cos 2x + cos 4x)/8 and int_0^inf x^(s-1) cos(a x) dx = Gamma(s) cos(pi s/2) a^(-s)
/// (Gradshteyn & Ryzhik 3.761.9, continued to -4 < s < 0, where the constant's part vanishes),
/// M(s) = Gamma(s) cos(pi s/2) (4^(-s) - 4 2^(-s)) / 8. Written in e = alpha + 1 (the pole of
/// Gamma at s = -2 cancels): K = 4 cos(pi e/2) Gamma(1+e) (2 pi)^(-e) g(e) / ((2-e)(1-e)) with
/// g(e) = (1 - 2^(-e))/e (ln 2 at e = 0). Its limits are SP 1065's power-law table: white FM
/// (alpha = 0) h/(2 tau), flicker FM 2 ln2 h, random-walk FM (2 pi^2/3) h tau; checked against
/// numerical quadrature in the tests (`power_law_constant_matches_quadrature`).
pub fn power_law_avar_constant(alpha: f64) -> f64 {
    let e = alpha + 1.0;
    // (1 - 2^-e)/e = -expm1(-e ln2)/e, -> ln 2 as e -> 0.
    let g = if e.abs() < 1e-12 {
        LN_2
    } else {
        -(-e * LN_2).exp_m1() / e
    };
    4.0 * (PI * e / 2.0).cos() * gamma_near_one(1.0 + e) * (2.0 * PI).powf(-e) * g
        / ((2.0 - e) * (1.0 - e))
}

/// The one-sided PSD coefficient h of S(f) = h f^alpha whose Allan deviation is `level` at
/// `tau_ref_s` (`power_law_avar_constant`): h = level^2 / (K(alpha) tau_ref^(-alpha-1)).
pub fn power_law_h(alpha: f64, level: f64, tau_ref_s: f64) -> f64 {
    level * level / (power_law_avar_constant(alpha) * tau_ref_s.powf(-alpha - 1.0))
}

/// The weight c of a continuum of first-order Gauss-Markov processes, variance c T^beta d(ln T)
/// (beta = -alpha - 1), whose PSD is h f^alpha: each has the Lorentzian S(f) = 4 s^2 T / (1 + (2 pi
/// f T)^2) (one-sided), and int_0^inf c T^beta 4 T / (1 + (2 pi f T)^2) d(ln T) = 4 c (2 pi f)^alpha
/// int_0^inf u^beta / (1 + u^2) du with the integral pi / (2 cos(pi beta / 2)) for -1 < beta < 1
/// (Gradshteyn & Ryzhik 3.241.2), so c = h cos(pi beta / 2) / (2 pi (2 pi)^alpha). At alpha = -1
/// this is IEEE flicker's sigma_0^2 = B^2 ln(rho) / pi per component (h = B^2 / pi, c = h).
pub fn power_law_component_weight(alpha: f64, h: f64) -> f64 {
    let beta = -alpha - 1.0;
    h * (PI * beta / 2.0).cos() / (2.0 * PI * (2.0 * PI).powf(alpha))
}

/// Gamma(x) for 0 < x < 3 (`stats::gamma`, the Lanczos approximation of Numerical Recipes
/// 3rd ed. §6.1; relative error below 1e-15 there).
fn gamma_near_one(x: f64) -> f64 {
    stats::gamma(x)
}

/// Quantisation noise Q: sigma^2 = 3 Q^2 / tau^2 (Hou 4.29). Exact for the sampled generator too,
/// since a white phase error e_k gives E[(e_{n+2m} - 2e_{n+m} + e_n)^2]/(2 tau^2) = 3 var(e)/tau^2 (NIST SP 1065 eq 11).
pub fn quantization_avar(q: f64, tau_s: f64) -> f64 {
    3.0 * q * q / (tau_s * tau_s)
}

/// White noise (ARW / VRW) of density N: sigma^2 = N^2 / tau (Hou 4.36). Exact for samples N/sqrt(dt)·w_k
/// averaged m at a time (variance N^2/(m dt)).
pub fn white_noise_avar(n: f64, tau_s: f64) -> f64 {
    n * n / tau_s
}

/// Flicker (bias instability) plateau for IEEE coefficient B: (2 ln2 / pi) B^2 (Hou 4.38-4.50, T >> 1/f0).
pub fn flicker_plateau_avar(b: f64) -> f64 {
    2.0 * LN_2 / PI * b * b
}

/// Rate random walk K: sigma^2 = K^2 tau / 3 (Hou 4.53).
pub fn rate_random_walk_avar(k: f64, tau_s: f64) -> f64 {
    k * k * tau_s / 3.0
}

/// Exact Allan variance of the sampled random walk b_{j+1} = b_j + K sqrt(dt) w_j, averaged m = tau/dt
/// samples at a time: K^2 dt (2m^2 + 1)/(6m) = K^2 tau/3 + K^2 dt^2/(6 tau).
/// (Derived: the difference of adjacent m-averages weighs the increments triangularly 1..m..1, and
/// sum of the squared weights is m(2m^2+1)/3.)
pub fn rate_random_walk_avar_sampled(k: f64, tau_s: f64, dt_s: f64) -> f64 {
    rate_random_walk_avar(k, tau_s) + k * k * dt_s * dt_s / (6.0 * tau_s)
}

/// Random walk K: the continuous form (Hou 4.53, `dt_s` None) or the sampled one.
pub fn rate_random_walk_avar_at(k: f64, tau_s: f64, dt_s: Option<f64>) -> f64 {
    match dt_s {
        None => rate_random_walk_avar(k, tau_s),
        Some(dt) => rate_random_walk_avar_sampled(k, tau_s, dt),
    }
}

/// Rate ramp R (Omega = R t): sigma^2 = R^2 tau^2 / 2 (Hou 4.56). Exact for samples too.
pub fn rate_ramp_avar(r: f64, tau_s: f64) -> f64 {
    r * r * tau_s * tau_s / 2.0
}

/// First-order Gauss-Markov of stationary std sigma and correlation time T (Hou 4.60 written with
/// sigma_b^2 = q_c^2 T / 2, docs/model.md §2):
/// sigma^2 = (2 sigma^2 T / tau) [1 - (T / 2 tau)(3 - 4 e^{-tau/T} + e^{-2 tau/T})].
pub fn gauss_markov_avar(sigma: f64, tc_s: f64, tau_s: f64) -> f64 {
    let x = tau_s / tc_s;
    // The bracket cancels badly for x -> 0; there use its series
    // x^2/3 - x^3/4 + 7x^4/60 - x^5/24 + 31x^6/2520 (sympy, docs/model.md §6 style check).
    let bracket = if x < 1e-2 {
        x * x * (1.0 / 3.0 + x * (-0.25 + x * (7.0 / 60.0 + x * (-1.0 / 24.0 + x * 31.0 / 2520.0))))
    } else {
        1.0 - (3.0 - 4.0 * (-x).exp() + (-2.0 * x).exp()) / (2.0 * x)
    };
    2.0 * sigma * sigma * tc_s / tau_s * bracket
}

/// Exact Allan variance of the sampled Gauss-Markov sequence x_{j+1} = phi x_j + sigma sqrt(1-phi^2) w_j
/// (phi = e^{-dt/T}, stationary), averaged m = tau/dt samples at a time:
/// (Var(S_m) - Cov(S_m, S'_m)) / m^2 with Var(S_m) = sigma^2 [m + 2 phi (m(1-phi) - (1-phi^m))/(1-phi)^2]
/// and Cov = sigma^2 phi (1-phi^m)^2/(1-phi)^2 for adjacent sums S, S' of m samples.
/// (Derived from the AR(1) autocovariance sigma^2 phi^|j|; tends to `gauss_markov_avar` as dt goes to 0.)
/// For T >> tau the sum cancels; there the process is the random walk of density K^2 = 2 sigma^2 / T
/// (docs/model.md §2, "T << T_c: q_c^2 T/3") with relative error O(tau/T) < 1e-4.
pub fn gauss_markov_avar_sampled(sigma: f64, tc_s: f64, tau_s: f64, dt_s: f64) -> f64 {
    let m = (tau_s / dt_s).round().max(1.0);
    let a = dt_s / tc_s;
    if m * a < 1e-4 {
        // Random walk whose per-step variance is the GM innovation variance sigma^2 (1 - phi^2):
        // var_step (2m^2+1)/(6m) (see rate_random_walk_avar_sampled).
        let var_step = -sigma * sigma * (-2.0 * a).exp_m1();
        return var_step * (2.0 * m * m + 1.0) / (6.0 * m);
    }
    let phi = (-a).exp();
    let one_minus_phi = -(-a).exp_m1();
    let one_minus_phim = -(-a * m).exp_m1();
    let var_sum =
        m + 2.0 * phi * (m * one_minus_phi - one_minus_phim) / (one_minus_phi * one_minus_phi);
    let cov = phi * one_minus_phim * one_minus_phim / (one_minus_phi * one_minus_phi);
    sigma * sigma * (var_sum - cov) / (m * m)
}

/// Gauss-Markov: the continuous form (Hou 4.60, `dt_s` None) or the sampled one.
pub fn gauss_markov_avar_at(sigma: f64, tc_s: f64, tau_s: f64, dt_s: Option<f64>) -> f64 {
    match dt_s {
        None => gauss_markov_avar(sigma, tc_s, tau_s),
        Some(dt) => gauss_markov_avar_sampled(sigma, tc_s, tau_s, dt),
    }
}

/// Sinusoid of amplitude A and frequency f0, phase averaged: sigma^2 = A^2 (sin^2(pi f0 tau)/(pi f0 tau))^2 (Hou 4.64).
pub fn sinusoid_avar(amplitude: f64, f0_hz: f64, tau_s: f64) -> f64 {
    let x = PI * f0_hz * tau_s;
    if x == 0.0 {
        return 0.0;
    }
    let s = x.sin();
    amplitude * amplitude * (s * s / x).powi(2)
}

/// The sampled sinusoid, phase averaged: the m-sample average of sin is sin(.)·D with
/// D = sin(pi f0 m dt)/(m sin(pi f0 dt)) instead of sin(x)/x, so sigma^2 = A^2 sin^2(pi f0 tau) D^2.
/// (Derived; tends to `sinusoid_avar` as dt goes to 0.)
pub fn sinusoid_avar_sampled(amplitude: f64, f0_hz: f64, tau_s: f64, dt_s: f64) -> f64 {
    let m = (tau_s / dt_s).round().max(1.0);
    let x = PI * f0_hz * m * dt_s;
    let den = m * (PI * f0_hz * dt_s).sin();
    if den == 0.0 {
        return 0.0;
    }
    let d = x.sin() / den;
    amplitude * amplitude * x.sin().powi(2) * d * d
}

/// Woodman's bias random walk from a bias stability BS over a period T: K = BS / sqrt(T)
/// (Woodman eq 9, BRW = BS/sqrt(t); AirSim `ImuSimple.hpp` `bias_stability/sqrt(tau)`).
pub fn woodman_bias_random_walk(stability: f64, period_s: f64) -> f64 {
    stability / period_s.sqrt()
}

/// ADEV maximum of a Gauss-Markov process: 0.6174 sigma at tau = 1.8927 T (docs/model.md §2, numerical maximisation).
pub const GAUSS_MARKOV_ADEV_PEAK_PER_SIGMA: f64 = 0.6174;
/// Where that maximum lies, in correlation times.
pub const GAUSS_MARKOV_ADEV_PEAK_TAU_PER_TC: f64 = 1.8927;

/// How an error reaches the navigation solution (docs/model.md §4, static level IMU, small angles).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Integration {
    /// Integrated once: angle from a gyro error, velocity from an accelerometer error.
    Once,
    /// Integrated twice: position from an accelerometer error.
    Twice,
    /// Through tilt: horizontal position from a gyro error, g·theta integrated twice (× g, three integrals).
    Tilt,
}

impl Integration {
    /// Number of time integrals.
    pub fn folds(self) -> i32 {
        match self {
            Integration::Once => 1,
            Integration::Twice => 2,
            Integration::Tilt => 3,
        }
    }
    fn gain(self) -> f64 {
        if self == Integration::Tilt {
            STANDARD_GRAVITY_MPS2
        } else {
            1.0
        }
    }
}

fn factorial(k: i32) -> f64 {
    (1..=k).map(f64::from).product()
}

/// Variance of the k-fold integral of white noise of density N: N^2 t^{2k-1} / ((k-1)!^2 (2k-1))
/// (docs/model.md §4 key identity: t, t^3/3, t^5/20, t^7/252).
pub fn white_kfold_variance(n: f64, t_s: f64, k: i32) -> f64 {
    n * n * t_s.powi(2 * k - 1) / (factorial(k - 1).powi(2) * f64::from(2 * k - 1))
}

/// Constant bias b: b t, b t^2/2 (Woodman eq 10), g b t^3/6 (docs/model.md §4). Deterministic, signed.
pub fn constant_bias_growth(b: f64, t_s: f64, how: Integration) -> f64 {
    let k = how.folds();
    how.gain() * b * t_s.powi(k) / factorial(k)
}

/// Warm-up transient A e^{-t/tau}: the k-fold integral A tau^k (sum_{j<k} (-1)^{k-1-j} x^j/j! +
/// (-1)^k e^{-x}), x = t/tau (Cauchy's formula for repeated integrals applied to the exponential;
/// derived, as `TemperatureProfile::excursion_integral`, which computes it). Deterministic, signed.
pub fn transient_growth(amplitude: f64, tau_s: f64, t_s: f64, how: Integration) -> f64 {
    let profile = crate::temperature::TemperatureProfile::Warmup {
        start_c: 1.0,
        end_c: 0.0,
        time_constant_s: tau_s,
    };
    how.gain()
        * amplitude
        * profile
            .excursion_integral(0.0, t_s, how.folds())
            .unwrap_or(f64::NAN)
}

/// Rate ramp R t: the k-fold integral is R t^{k+1}/(k+1)! (the constant-bias row of docs/model.md §4
/// integrated once more). Deterministic, signed.
pub fn rate_ramp_growth(r: f64, t_s: f64, how: Integration) -> f64 {
    let k = how.folds() + 1;
    how.gain() * r * t_s.powi(k) / factorial(k)
}

/// Standard deviation from white noise N: N sqrt(t) (Woodman eq 5), N sqrt(t^3/3) (eq 18),
/// g N sqrt(t^5/20) (docs/model.md §1.3, §4).
pub fn white_noise_growth_std(n: f64, t_s: f64, how: Integration) -> f64 {
    how.gain() * white_kfold_variance(n, t_s, how.folds()).sqrt()
}

/// Standard deviation from a random walk K (RRW or Woodman's bias random walk, zero initial bias):
/// K sqrt(t^3/3), K sqrt(t^5/20), g K sqrt(t^7/252) (docs/model.md §4).
pub fn random_walk_growth_std(k: f64, t_s: f64, how: Integration) -> f64 {
    how.gain() * white_kfold_variance(k, t_s, how.folds() + 1).sqrt()
}

/// Standard deviation from a stationary Gauss-Markov bias (sigma, T). Once: exact,
/// 2 sigma^2 T [t - T(1 - e^{-t/T})]. Twice and through tilt: the t >> T asymptotes 2 sigma^2 T t^3/3 and
/// g^2 2 sigma^2 T t^5/20 (docs/model.md §4); `None` while t < 10 T, where they do not hold.
pub fn gauss_markov_growth_std(sigma: f64, tc_s: f64, t_s: f64, how: Integration) -> Option<f64> {
    let var = match how {
        Integration::Once => {
            let x = t_s / tc_s;
            // t - T(1 - e^{-x}) = T (x - 1 + e^{-x}); for small x use x^2/2 - x^3/6 + x^4/24.
            let inner = if x < 1e-3 {
                x * x * (0.5 - x / 6.0 + x * x / 24.0)
            } else {
                x + (-x).exp_m1()
            };
            2.0 * sigma * sigma * tc_s * tc_s * inner
        }
        _ if t_s < 10.0 * tc_s => return None,
        _ => white_kfold_variance((2.0 * sigma * sigma * tc_s).sqrt(), t_s, how.folds()),
    };
    Some(how.gain() * var.sqrt())
}

/// Sinusoid A sin(2 pi f t + phi) with its phase uniform (drawn per run): the variance over the phase of
/// its integral, w = 2 pi f: once (A/w)^2 (1 - cos wt); twice (A/w)^2 [t^2/2 - t sin(wt)/w + (1 - cos wt)/w^2];
/// thrice (A/w)^2 [t^4/8 + t^2 cos(wt)/(2 w^2) - t sin(wt)/w^3 + (1 - cos wt)/w^4]. The mean is zero.
/// (Derived with sympy by integrating the sinusoid and averaging the square over the phase; not in docs/model.md.)
pub fn sinusoid_growth_std(amplitude: f64, f0_hz: f64, t_s: f64, how: Integration) -> f64 {
    let w = std::f64::consts::TAU * f0_hz;
    let (c, sn) = ((w * t_s).cos(), (w * t_s).sin());
    // 1 - cos(wt) without cancellation for small wt.
    let one_minus_cos = 2.0 * (0.5 * w * t_s).sin().powi(2);
    let bracket = match how {
        Integration::Once => one_minus_cos,
        Integration::Twice => t_s * t_s / 2.0 - t_s * sn / w + one_minus_cos / (w * w),
        Integration::Tilt => {
            t_s.powi(4) / 8.0 + t_s * t_s * c / (2.0 * w * w) - t_s * sn / w.powi(3)
                + one_minus_cos / w.powi(4)
        }
    };
    how.gain() * amplitude / w * bracket.max(0.0).sqrt()
}

/// u - sin u, with its Taylor series below |u| = 0.5 (where the difference cancels):
/// u^3/3! - u^5/5! + u^7/7! - ... (terms to u^17 leave < 1e-22 relative there).
fn u_minus_sin(u: f64) -> f64 {
    if u.abs() >= 0.5 {
        return u - u.sin();
    }
    let (mut term, mut sum) = (u * u * u / 6.0, 0.0);
    for n in (3..19).step_by(2) {
        sum += term;
        term *= -u * u / (((n + 1) * (n + 2)) as f64);
    }
    sum
}

/// u^2/2 - (1 - cos u), with its Taylor series below |u| = 0.5: u^4/4! - u^6/6! + u^8/8! - ...
fn half_u2_minus_one_minus_cos(u: f64) -> f64 {
    if u.abs() >= 0.5 {
        return u * u / 2.0 - 2.0 * (0.5 * u).sin().powi(2);
    }
    let (mut term, mut sum) = (u.powi(4) / 24.0, 0.0);
    for n in (4..20).step_by(2) {
        sum += term;
        term *= -u * u / (((n + 1) * (n + 2)) as f64);
    }
    sum
}

/// Coefficients (a_k, b_k) of the k-fold integral from 0 of sin(w s + phi), w = 2 pi f0, written
/// I_k(t) = a_k cos(phi) + b_k sin(phi), for k = 1, 2, 3 (`None` otherwise):
///   I1(t) = cos phi (1 - cos wt)/w + sin phi (sin wt)/w
///   I2(t) = cos phi (t/w - sin wt/w^2) + sin phi (1 - cos wt)/w^2
///   I3(t) = cos phi (t^2/(2w) + (cos wt - 1)/w^3) + sin phi (t/w^2 - sin wt/w^3)
/// Checked by differentiation (and I_k(0) = 0 for each):
///   d/dt I1 = cos phi sin wt + sin phi cos wt = sin(wt + phi);
///   d/dt I2 = cos phi (1 - cos wt)/w + sin phi sin wt/w = I1;
///   d/dt I3 = cos phi (t/w - sin wt/w^2) + sin phi (1 - cos wt)/w^2 = I2.
/// (\[derived\] k-fold integral of a sinusoid; docs/model.md §2 gives its Allan form, Hou 4.64.)
/// The cancelling differences use series for small wt (`u_minus_sin`, `half_u2_minus_one_minus_cos`).
pub fn sinusoid_kfold_coefficients(f0_hz: f64, t_s: f64, k: i32) -> Option<(f64, f64)> {
    let w = std::f64::consts::TAU * f0_hz;
    let u = w * t_s;
    let one_minus_cos = 2.0 * (0.5 * u).sin().powi(2);
    match k {
        1 => Some((one_minus_cos / w, u.sin() / w)),
        2 => Some((u_minus_sin(u) / (w * w), one_minus_cos / (w * w))),
        3 => Some((
            half_u2_minus_one_minus_cos(u) / w.powi(3),
            u_minus_sin(u) / w.powi(3),
        )),
        _ => None,
    }
}

/// Mean and variance of the integrated sinusoid `amplitude · sin(2 pi f0 t + phase)` (integrated
/// once, twice, or through tilt, times g) at time t, with (a_k, b_k) from
/// `sinusoid_kfold_coefficients`. Fixed phase: mean A (a_k cos phi + b_k sin phi), variance 0.
/// Phase uniform on [0, 2 pi) (drawn per run, `phase_rad = None`): mean 0, variance
/// A^2 (a_k^2 + b_k^2)/2 (E cos^2 = E sin^2 = 1/2, E cos sin = 0).
/// (\[derived\] k-fold integral of a sinusoid; docs/model.md §2 gives its Allan form, Hou 4.64.)
pub fn sinusoid_growth(
    amplitude: f64,
    f0_hz: f64,
    phase_rad: Option<f64>,
    t_s: f64,
    how: Integration,
) -> (f64, f64) {
    let (a, b) = sinusoid_kfold_coefficients(f0_hz, t_s, how.folds()).expect("folds are 1..=3");
    let gain = how.gain() * amplitude;
    match phase_rad {
        Some(phi) => (gain * (a * phi.cos() + b * phi.sin()), 0.0),
        None => (0.0, gain * gain * (a * a + b * b) / 2.0),
    }
}

/// `sinusoid_growth` for the generator's samples: the noise crate point-samples the sinusoid at
/// t_k = k dt and the mechanisation holds each sample over its interval (rectangle rule). For the
/// once-integrated error at t = n dt that is exactly the continuous integral delayed by dt/2 with
/// a gain: dt sum_{j<n} sin(w j dt + phi) = (x / sin x) I1(t; phi - x), x = pi f0 dt, by the
/// geometric series dt / (e^{i w dt} - 1) = e^{-i x} (x / sin x) / (i w). The same delay and gain
/// are applied to every fold (nested sums add O(dt/t) relative, the mechanisation's own
/// discretisation). A random phase is unchanged by the delay; its variance takes the gain squared.
/// `dt_s = 0` gives the continuous law.
/// (\[derived\] k-fold integral of a sampled sinusoid; docs/model.md §2 gives its Allan form, Hou 4.64.)
pub fn sinusoid_growth_sampled(
    amplitude: f64,
    f0_hz: f64,
    phase_rad: Option<f64>,
    t_s: f64,
    dt_s: f64,
    how: Integration,
) -> (f64, f64) {
    let x = PI * f0_hz * dt_s;
    let gain = if x == 0.0 { 1.0 } else { x / x.sin() };
    sinusoid_growth(amplitude * gain, f0_hz, phase_rad.map(|p| p - x), t_s, how)
}

/// Quantisation of the integrated output (LSB = Q sqrt(12)), integrated by the rectangle rule over
/// n = t/dt samples, assuming the rounding residuals are independent and uniform (dithered by noise of an
/// LSB or more per sample, as in the Allan closed form): the once-integrated error is r_0 - r_n, variance
/// 2 Q^2; twice dt (n r_0 - sum r_j), variance Q^2 t (t + dt); thrice
/// dt^2 (r_0 n(n+1)/2 - sum (n - j + 1) r_j), variance dt^4 Q^2 [n^2 (n+1)^2 / 4 + n(n+1)(2n+1)/6].
/// (Derived for the generator's quantiser, which carries the residual r from sample to sample.)
pub fn quantization_growth_std(q: f64, t_s: f64, dt_s: f64, how: Integration) -> f64 {
    let n = (t_s / dt_s).round();
    let var = match how {
        Integration::Once => 2.0 * q * q,
        Integration::Twice => q * q * t_s * (t_s + dt_s),
        Integration::Tilt => {
            let tri = n * (n + 1.0) / 2.0;
            dt_s.powi(4) * q * q * (tri * tri + n * (n + 1.0) * (2.0 * n + 1.0) / 6.0)
        }
    };
    how.gain() * var.sqrt()
}

/// Temperature bias: coefficient c (per degC) times the integral of the temperature excursion from
/// the reference (`TemperatureProfile::excursion_integral`); deterministic, signed. Woodman §3.2.4:
/// a residual temperature bias integrates into orientation error.
pub fn temperature_bias_growth(
    coefficient: f64,
    profile: &crate::temperature::TemperatureProfile,
    reference_c: f64,
    t_s: f64,
    how: Integration,
) -> f64 {
    let integral = profile
        .excursion_integral(reference_c, t_s, how.folds())
        .expect("folds are 1..=3");
    how.gain() * coefficient * integral
}

/// Exact variance of the k-fold integral (k = 1, 2, 3) of a stationary Gauss-Markov process of std
/// sigma and correlation time T at time t, with x = t/T: sigma^2 T^{2k} V_k(x),
/// V_1 = 2(x - 1 + e^{-x}) (docs/model.md §4),
/// V_2 = 2x^3/3 - x^2 + 2 - 2(1 + x) e^{-x},
/// V_3 = x^5/10 - x^4/4 + x^3/3 - 2 + (2 + 2x + x^2) e^{-x}.
/// (Derived with sympy from Var I_k = int int w(u) w(v) sigma^2 e^{-|u-v|/T} du dv, w(u) = (t-u)^{k-1}/(k-1)!.
/// For t >> T they tend to docs/model.md §4's asymptotes 2 sigma^2 T t^{2k-1}/((k-1)!^2 (2k-1)), for t << T to a
/// random constant's (sigma t^k/k!)^2.) Below x = 0.5 the series V_k = 2 sum_{n>=2k} (-1)^n C(n-1, k-1) x^n/n!
/// avoids the cancellation. `None` for k outside 1..=3.
pub fn gauss_markov_kfold_variance(sigma: f64, tc_s: f64, t_s: f64, k: i32) -> Option<f64> {
    if !(1..=3).contains(&k) {
        return None;
    }
    let x = t_s / tc_s;
    let v = if x < 0.5 {
        // Terms shrink by x/n per step: 25 terms leave < 1e-30 relative.
        let binom = |n: i32, j: i32| factorial(n) / (factorial(j) * factorial(n - j));
        (2 * k..2 * k + 25)
            .map(|n| {
                let sign = if n % 2 == 0 { 1.0 } else { -1.0 };
                2.0 * sign * binom(n - 1, k - 1) * x.powi(n) / factorial(n)
            })
            .sum()
    } else {
        let e = (-x).exp();
        match k {
            1 => 2.0 * (x - 1.0 + e),
            2 => 2.0 * x.powi(3) / 3.0 - x * x + 2.0 - 2.0 * (1.0 + x) * e,
            _ => {
                x.powi(5) / 10.0 - x.powi(4) / 4.0 + x.powi(3) / 3.0 - 2.0
                    + (2.0 + 2.0 * x + x * x) * e
            }
        }
    };
    Some(sigma * sigma * tc_s.powi(2 * k) * v)
}

/// Moments of the mean m = (1/W) int_{-W}^0 b(s) ds of a stationary Gauss-Markov process b (std
/// sigma, correlation time `tc_s`) over a calibration window of length `window_s` before t = 0,
/// normalised by sigma^2: (rho, Var(m)/sigma^2, Var(m | b(0))/sigma^2), rho = Cov(m, b(0))/sigma^2.
///
/// ```text
/// [derived] from Cov(b(s), b(u)) = sigma^2 e^{-|s-u|/T} (docs/model.md §3), with u = W/T:
///   rho            = (1 - e^{-u}) / u
///   Var(m)/sigma^2 = (2/u) (1 - rho)
///   Var(m|b0)/sigma^2 = Var(m)/sigma^2 - rho^2 = (2u - 3 + 4 e^{-u} - e^{-2u}) / u^2
///                  = sum_{n>=3} (-1)^n (4 - 2^n) u^(n-2) / n!   (series used below u = 0.5,
///                    where the closed form cancels; leading term 2u/3)
/// ```
/// E[m | b(0)] = rho b(0). The W -> 0 limit is m = b(0): (1, 1, 0).
pub fn gauss_markov_window_mean_moments(tc_s: f64, window_s: f64) -> (f64, f64, f64) {
    let u = window_s / tc_s;
    if u < 0.5 {
        // Terms shrink by ~u/n per step: 25 terms leave < 1e-30 relative.
        let mut fact = 1.0;
        let (mut rho, mut vm, mut cond) = (0.0, 0.0, 0.0);
        for n in 1..=27 {
            fact *= f64::from(n);
            let sign = if n % 2 == 0 { 1.0 } else { -1.0 };
            // rho = sum_{n>=1} (-u)^(n-1)/n!, Var(m)/sigma^2 = 2 sum_{n>=2} (-1)^n u^(n-2)/n!.
            rho += (-u).powi(n - 1) / fact;
            if n >= 2 {
                vm += 2.0 * sign * u.powi(n - 2) / fact;
            }
            if n >= 3 {
                cond += sign * (4.0 - 2f64.powi(n)) * u.powi(n - 2) / fact;
            }
        }
        (rho, vm, cond)
    } else {
        let rho = -(-u).exp_m1() / u;
        let vm = 2.0 / u * (1.0 - rho);
        let cond = (2.0 * u - 3.0 + 4.0 * (-u).exp() - (-2.0 * u).exp()) / (u * u);
        (rho, vm, cond)
    }
}

/// Variance of the k-fold integral (k = 1, 2, 3) at time `t_s` of a
/// stationary Gauss-Markov process b (std `sigma`, correlation time `tc_s`) referenced to its value
/// at t = 0, x(t) = b(t) - b(0) (the bias perfectly calibrated at turn-on).
///
/// \[derived\] (formulas below in plain text):
///
/// ```text
/// x has covariance sigma^2 (e^{-|t-s|/T} - e^{-t/T} - e^{-s/T} + 1). With
/// I_k[x](t) = I_k[b](t) - b(0) t^k/k!:
///   Var I_k[x] = Var I_k[b] - 2 (t^k/k!) Cov(I_k[b](t), b(0)) + sigma^2 (t^k/k!)^2,
/// where Var I_k[b] is the exact stationary form ([`gauss_markov_kfold_variance`])
/// and Cov(I_k[b](t), b(0)) = sigma^2 J_k(t), J_k the k-fold integral of e^{-s/T} from 0:
///   J_k = T^k (-1)^k (e^{-x} - sum_{j<k} (-x)^j/j!),  x = t/T,
/// i.e. J_1 = T (1 - e^{-x}), J_2 = T^2 (x - 1 + e^{-x}), J_3 = T^3 (x^2/2 - x + 1 - e^{-x}).
/// Writing a = x^k/k!, Var I_k[x] = sigma^2 T^{2k} (v_k - 2 a j_k + a^2) with v_k, j_k the
/// normalised forms. Below x = 0.5 the three terms cancel (each ~a^2, the sum ~x^{2k+1}), so the
/// series is used: from v_k = sum_{n>=2k} 2 (-1)^n C(n-1, k-1) x^n/n! and
/// a j_k = sum_{m>=2k} (-1)^m x^m / ((m-k)! k!), whose x^{2k} terms cancel a^2,
///   v_k - 2 a j_k + a^2 = sum_{m>=2k+1} (-1)^m [2 C(m-1, k-1)/m! - 2/((m-k)! k!)] x^m.
/// ```
/// Its leading term (k = 1: 2x^3/3) is the random walk of density K^2 = 2 sigma^2/T
/// (K^2 t^3/3), as b(t) - b(0) ~ b'(0) t for t << T. Checked against 2-D quadrature of the
/// covariance and against that random-walk limit in the tests.
pub fn gauss_markov_kfold_from_start_variance(sigma: f64, tc_s: f64, t_s: f64, k: i32) -> f64 {
    sigma * sigma * tc_s.powi(2 * k) * from_start_normalised(t_s / tc_s, k)
}

/// v_k - 2 a j_k + a^2 of `gauss_markov_kfold_from_start_variance` at x = t/T (sigma = T = 1, no gain).
fn from_start_normalised(x: f64, k: i32) -> f64 {
    let fact = factorial;
    if x < 0.5 {
        let binom = |n: i32, j: i32| fact(n) / (fact(j) * fact(n - j));
        // Terms shrink by ~x/m per step: 25 terms leave < 1e-30 relative.
        (2 * k + 1..2 * k + 26)
            .map(|m| {
                let sign = if m % 2 == 0 { 1.0 } else { -1.0 };
                let c = 2.0 * binom(m - 1, k - 1) / fact(m) - 2.0 / (fact(m - k) * fact(k));
                sign * c * x.powi(m)
            })
            .sum::<f64>()
    } else {
        let Some(vk) = gauss_markov_kfold_variance(1.0, 1.0, x, k) else {
            return f64::NAN;
        };
        let a = x.powi(k) / fact(k);
        vk - 2.0 * a * kfold_exp_integral(x, k) + a * a
    }
}

/// j_k(x), the k-fold integral from 0 of e^{-s} at x (k = 1, 2, 3; J_k = T^k j_k(t/T)):
/// j_1 = 1 - e^{-x}, j_2 = x - 1 + e^{-x}, j_3 = x^2/2 - x + 1 - e^{-x}.
fn kfold_exp_integral(x: f64, k: i32) -> f64 {
    let e = (-x).exp();
    match k {
        1 => 1.0 - e,
        2 => x - 1.0 + e,
        _ => x * x / 2.0 - x + 1.0 - e,
    }
}

/// Variance of the k-fold integral (k = 1, 2, 3) at time `t_s` of a
/// stationary Gauss-Markov process b (std `sigma`, correlation time `tc_s`) referenced to its mean
/// over a calibration window before t = 0, x(t) = b(t) - m, m = (1/W) int_{-W}^0 b(s) ds
/// (`window_s` = W; `ImuErrors::with_calibration_window`).
///
/// ```text
/// [derived] For s >= 0, Cov(b(s), m) = sigma^2 e^{-s/T} rho, rho = (T/W)(1 - e^{-W/T}), so
/// Cov(I_k[b](t), m) = rho sigma^2 J_k(t) and, with a = t^k/k! and Var(m) = sigma^2 vm
/// ([`gauss_markov_window_mean_moments`]),
///   Var I_k[x] = Var I_k[b] - 2 a rho sigma^2 J_k + a^2 sigma^2 vm
///              = sigma^2 T^{2k} (v_k - 2 a rho j_k + a^2 vm)                          (direct)
///              = sigma^2 T^{2k} (S + a^2 (1 - 2 rho + vm) + 2 a (1 - rho)(j_k - a))    (split)
/// with S = v_k - 2 a j_k + a^2 the from-start form ([`gauss_markov_kfold_from_start_variance`]): the split
/// is b - m = (b - b(0)) + (b(0) - m), Var(b(0) - m) = sigma^2 (1 - 2 rho + vm) and
/// Cov(I_k[b - b(0)], b(0) - m) = sigma^2 T^k (1 - rho)(j_k - a). W -> 0 gives rho, vm -> 1:
/// the from-start law.
/// ```
/// Numerics: the direct form cancels when W << T (it is the from-start sum plus small terms);
/// the split cancels when W >> T and t >> T (its last term is ~ -2 a^2). So the split is used
/// for x = t/T < 0.5 (there j_k - a = sum_{m>k} (-1)^{m-k} x^m/m!, a series, and the terms are
/// ~a^2 (1 - 2 rho + vm) > 0 with a relative correction O(x)) and for W/T < 1 (there
/// vm > 0.73 bounds the result below by ~a^2 vm / 2), the direct form otherwise (there
/// 1 - 2 rho + vm > 0.47 and rho < 0.64, nothing cancels). Checked against 2-D quadrature.
pub fn gauss_markov_kfold_from_window_variance(
    sigma: f64,
    tc_s: f64,
    window_s: f64,
    t_s: f64,
    k: i32,
) -> f64 {
    let x = t_s / tc_s;
    let (rho, vm, cond) = gauss_markov_window_mean_moments(tc_s, window_s);
    let a = x.powi(k) / factorial(k);
    let v = if x < 0.5 || window_s < tc_s {
        let j_minus_a = if x < 0.5 {
            // Terms shrink by ~x/m per step: 25 terms leave < 1e-30 relative.
            (k + 1..k + 26)
                .map(|m| {
                    let sign = if (m - k) % 2 == 0 { 1.0 } else { -1.0 };
                    sign * x.powi(m) / factorial(m)
                })
                .sum::<f64>()
        } else {
            kfold_exp_integral(x, k) - a
        };
        // 1 - 2 rho + vm = (1 - rho)^2 + Var(m | b0)/sigma^2, both terms >= 0 and the second
        // from its series for W << T, so nothing cancels.
        let g = (1.0 - rho) * (1.0 - rho) + cond;
        from_start_normalised(x, k) + a * a * g + 2.0 * a * (1.0 - rho) * j_minus_a
    } else {
        let Some(vk) = gauss_markov_kfold_variance(1.0, 1.0, x, k) else {
            return f64::NAN;
        };
        vk - 2.0 * a * rho * kfold_exp_integral(x, k) + a * a * vm
    };
    sigma * sigma * tc_s.powi(2 * k) * v
}

/// A resonance (second-order Gauss-Markov process: white noise through a damped oscillator,
/// x'' + 2 zeta w0 x' + w0^2 x = w(t)) of stationary std sigma, natural frequency f0 and half-power
/// bandwidth B = 2 zeta f0 (so zeta = B / (2 f0) < 1), in the complex form its closed forms use:
/// R(u) = sigma^2 e^{-zeta w0 |u|} (cos(wd u) + zeta/sqrt(1 - zeta^2) sin(wd |u|)), wd = w0 sqrt(1 - zeta^2)
/// (Maybeck, Stochastic Models, Estimation and Control vol. 1 (1979), the second-order Gauss-Markov
/// shaping filter; docs/real-effects.md), which is R(u) = sigma^2 Re[C e^{-s |u|}] with
/// s = zeta w0 - i wd and C = 1 - i zeta/sqrt(1 - zeta^2). Every closed form of the first-order
/// Gauss-Markov process (autocovariance sigma^2 e^{-|u|/T}) is analytic in 1/T, so the resonance's is
/// Re[C x (that form at 1/T = s)]. Returns (C, s).
pub fn resonance_exponent(f0_hz: f64, bandwidth_hz: f64) -> (Complex64, Complex64) {
    let zeta = bandwidth_hz / (2.0 * f0_hz);
    let w0 = 2.0 * PI * f0_hz;
    let root = (1.0 - zeta * zeta).max(0.0).sqrt();
    (
        Complex64::new(1.0, -zeta / root),
        Complex64::new(zeta * w0, -w0 * root),
    )
}

/// Autocovariance of the resonance at lag `lag_s` (see [`resonance_exponent`]).
pub fn resonance_autocovariance(sigma: f64, f0_hz: f64, bandwidth_hz: f64, lag_s: f64) -> f64 {
    let (c, s) = resonance_exponent(f0_hz, bandwidth_hz);
    sigma * sigma * (c * (-s * lag_s.abs()).exp()).re
}

/// Allan variance of the continuous resonance: Re[C sigma^2 g(tau s)] with g the first-order
/// Gauss-Markov form of [`gauss_markov_avar`] per unit sigma, g(x) = (2/x) [1 - (3 - 4 e^{-x} + e^{-2x})/(2x)]
/// (Hou 4.60 continued to complex 1/T; series x/3 ... below |x| = 1e-2, as there).
pub fn resonance_avar(sigma: f64, f0_hz: f64, bandwidth_hz: f64, tau_s: f64) -> f64 {
    let (c, s) = resonance_exponent(f0_hz, bandwidth_hz);
    let x = s * tau_s;
    let g = if x.norm() < 1e-2 {
        x * 2.0
            * (1.0 / 3.0 + x * (-0.25 + x * (7.0 / 60.0 + x * (-1.0 / 24.0 + x * 31.0 / 2520.0))))
    } else {
        (1.0 - (3.0 - (-x).exp() * 4.0 + (-x * 2.0).exp()) / (x * 2.0)) * 2.0 / x
    };
    sigma * sigma * (c * g).re
}

/// Exact Allan variance of the sampled resonance (the generator's exact discretisation at `dt_s`),
/// averaged m = tau/dt samples at a time: Re[C sigma^2 (Var(S_m) - Cov(S_m, S'_m)) / m^2] with the
/// sums of [`gauss_markov_avar_sampled`] at the complex ratio lambda = e^{-s dt} (geometric sums
/// hold for any ratio of modulus below 1).
pub fn resonance_avar_sampled(
    sigma: f64,
    f0_hz: f64,
    bandwidth_hz: f64,
    tau_s: f64,
    dt_s: f64,
) -> f64 {
    let (c, s) = resonance_exponent(f0_hz, bandwidth_hz);
    let m = (tau_s / dt_s).round().max(1.0);
    sigma * sigma * (c * geometric_avar_unit((-s * dt_s).exp(), m)).re
}

/// (Var(S_m) - Cov(S_m, S'_m)) / m^2 for a sequence of autocovariance lambda^|j| (any complex ratio
/// of modulus below 1): the sums of [`gauss_markov_avar_sampled`] without its random-walk limit.
pub(crate) fn geometric_avar_unit(lambda: Complex64, m: f64) -> Complex64 {
    let one = Complex64::new(1.0, 0.0);
    let d = (one - lambda) * (one - lambda);
    let lm = one - lambda.powf(m);
    let var_sum = (lambda * ((one - lambda) * m - lm) * 2.0) / d + m;
    let cov = lambda * lm * lm / d;
    (var_sum - cov) / (m * m)
}

/// Variance of the k-fold integral (k = 1..=3) of the stationary resonance at time t:
/// Re[C sigma^2 s^{-2k} V_k(t s)] with the V_k of [`gauss_markov_kfold_variance`] (same series below
/// |x| = 0.5). `None` for k outside 1..=3.
pub fn resonance_kfold_variance(
    sigma: f64,
    f0_hz: f64,
    bandwidth_hz: f64,
    t_s: f64,
    k: i32,
) -> Option<f64> {
    if !(1..=3).contains(&k) {
        return None;
    }
    let (c, s) = resonance_exponent(f0_hz, bandwidth_hz);
    let x = s * t_s;
    let v = if x.norm() < 0.5 {
        let binom = |n: i32, j: i32| factorial(n) / (factorial(j) * factorial(n - j));
        (2 * k..2 * k + 25)
            .map(|n| {
                let sign = if n % 2 == 0 { 1.0 } else { -1.0 };
                x.powi(n) * (2.0 * sign * binom(n - 1, k - 1) / factorial(n))
            })
            .sum()
    } else {
        let e = (-x).exp();
        match k {
            1 => (x - 1.0 + e) * 2.0,
            2 => x.powi(3) * (2.0 / 3.0) - x * x + 2.0 - (x + 1.0) * e * 2.0,
            _ => {
                x.powi(5) / 10.0 - x.powi(4) / 4.0 + x.powi(3) / 3.0 - 2.0
                    + (x * 2.0 + x * x + 2.0) * e
            }
        }
    };
    Some(sigma * sigma * (c * v / s.powi(2 * k)).re)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::TAU;

    #[test]
    fn plateau_constant_is_sqrt_2ln2_over_pi() {
        assert!((FLICKER_PLATEAU_PER_B - (2.0 * LN_2 / PI).sqrt()).abs() < 1e-15);
    }

    #[test]
    fn gauss_markov_limits_match_white_and_random_walk() {
        // docs/model.md §2: T >> T_c behaves like ARW with Q = q_c T_c; T << T_c like RRW q_c^2 T/3,
        // with sigma_b^2 = q_c^2 T_c / 2.
        let (sigma, tc) = (0.3, 10.0);
        let qc2 = 2.0 * sigma * sigma / tc;
        let long = gauss_markov_avar(sigma, tc, 1e5);
        assert!((long / (qc2 * tc * tc / 1e5) - 1.0).abs() < 2e-4);
        let short = gauss_markov_avar(sigma, tc, 1e-3);
        assert!((short / (qc2 * 1e-3 / 3.0) - 1.0).abs() < 1e-4);
        // Both branches of the bracket agree at the switch.
        let a = gauss_markov_avar(sigma, 1.0, 0.0099999);
        let b = gauss_markov_avar(sigma, 1.0, 0.0100001);
        assert!((a / b - 1.0).abs() < 1e-4);
        // Peak 0.6174 sigma at 1.8927 T (docs/model.md §2).
        let peak = gauss_markov_avar(sigma, tc, GAUSS_MARKOV_ADEV_PEAK_TAU_PER_TC * tc).sqrt();
        assert!((peak / sigma - GAUSS_MARKOV_ADEV_PEAK_PER_SIGMA).abs() < 1e-4);
    }

    #[test]
    fn sampled_forms_tend_to_continuous_ones() {
        let dt = 1e-4;
        for tau in [0.1, 1.0, 10.0] {
            let c = gauss_markov_avar(1.0, 2.0, tau);
            let d = gauss_markov_avar_sampled(1.0, 2.0, tau, dt);
            assert!((d / c - 1.0).abs() < 1e-3, "tau {tau}: {d} vs {c}");
            let c = sinusoid_avar(1.0, 0.7, tau);
            let d = sinusoid_avar_sampled(1.0, 0.7, tau, dt);
            assert!((d - c).abs() < 1e-3 * c.max(1e-3), "tau {tau}: {d} vs {c}");
        }
        // Both branches of the sampled Gauss-Markov agree where they switch (m dt / T = 1e-4).
        let tc = 1e4;
        let lo = gauss_markov_avar_sampled(1.0, tc, 0.999e-4 * tc, 1e-3);
        let hi = gauss_markov_avar_sampled(1.0, tc, 1.001e-4 * tc, 1e-3);
        assert!((lo / hi - 1.0).abs() < 5e-3, "{lo} {hi}");
    }

    #[test]
    fn growth_laws_match_theory_table() {
        // docs/model.md §4 and §6: t, t^3/3, t^5/20, t^7/252; constant bias t^3/6 through tilt.
        let t = 60.0;
        assert!((white_kfold_variance(1.0, t, 1) - t).abs() < 1e-9);
        assert!((white_kfold_variance(1.0, t, 2) - t.powi(3) / 3.0).abs() < 1e-6);
        assert!((white_kfold_variance(1.0, t, 3) - t.powi(5) / 20.0).abs() < 1e-3);
        assert!((white_kfold_variance(1.0, t, 4) - t.powi(7) / 252.0).abs() < 1.0);
        // docs/model.md §6: gyro const bias 0.010 deg/s -> g eps t^3/6 = 61.6 m at 60 s.
        let eps = 0.010f64.to_radians();
        assert!((constant_bias_growth(eps, t, Integration::Tilt) - 61.6).abs() < 0.05);
        // docs/model.md §6: N = 0.075 deg/sqrt(s), 60 s -> 80.07 m per horizontal axis (with g = 9.81;
        // 80.04 m with 9.80665); theta 0.01014 rad.
        let n = 0.075f64.to_radians();
        assert!(
            (white_noise_growth_std(n, t, Integration::Tilt) - 80.07 * 9.80665 / 9.81).abs() < 0.01
        );
        assert!((white_noise_growth_std(n, t, Integration::Once) - 0.01014).abs() < 1e-5);
        // docs/model.md §6: gyro RRW K = 1e-3 -> 1034.0 m at 60 s; accel bias RW 1e-3 -> 6.235 m.
        assert!((random_walk_growth_std(1e-3, t, Integration::Tilt) - 1034.0).abs() < 0.5);
        assert!((random_walk_growth_std(1e-3, t, Integration::Twice) - 6.235).abs() < 0.001);
        // Gauss-Markov once: -> 2 sigma^2 T t for t >> T.
        let gm = gauss_markov_growth_std(0.1, 1.0, 1e4, Integration::Once).unwrap();
        assert!((gm / (2.0 * 0.01 * 1.0 * 1e4f64).sqrt() - 1.0).abs() < 1e-4);
        assert!(gauss_markov_growth_std(0.1, 100.0, 60.0, Integration::Twice).is_none());
    }

    #[test]
    fn sinusoid_kfold_integrals_differentiate_back_and_average_over_phase() {
        let (f, phi) = (0.37, 0.9);
        let i = |k: i32, t: f64| {
            if k == 0 {
                return (TAU * f * t + phi).sin();
            }
            let (a, b) = sinusoid_kfold_coefficients(f, t, k).unwrap();
            a * phi.cos() + b * phi.sin()
        };
        for k in 1..=3 {
            assert_eq!(i(k, 0.0), 0.0);
            for &t in &[0.01, 0.3, 1.3, 2.7, 11.0] {
                // Central difference: truncation h^2/6 |d^3 I/dt^3| <= 1e-8 w^2 / 6 ~ 1e-8 and
                // rounding ~1e-16 |I| / h ~ 1e-11, both below the tolerance 1e-7 max(1, |I|).
                let h = 1e-4;
                let d = (i(k, t + h) - i(k, t - h)) / (2.0 * h);
                let want = i(k - 1, t);
                let err = (d - want).abs();
                assert!(
                    err < 1e-7 * want.abs().max(1.0),
                    "k {k} t {t}: {d} vs {want}"
                );
            }
        }
        // Series and direct forms agree where they switch (u = w t = 0.5).
        let t = 0.5 / (TAU * f);
        for k in 2..=3 {
            let (a0, b0) = sinusoid_kfold_coefficients(f, t * (1.0 - 1e-9), k).unwrap();
            let (a1, b1) = sinusoid_kfold_coefficients(f, t * (1.0 + 1e-9), k).unwrap();
            assert!((a0 / a1 - 1.0).abs() < 1e-7 && (b0 / b1 - 1.0).abs() < 1e-7);
        }
        assert!(sinusoid_kfold_coefficients(f, 1.0, 4).is_none());
        // Small t: I_k -> sin(phi) t^k/k! (the sinusoid is its starting value).
        let t = 1e-6;
        for (k, how) in [(1, Integration::Once), (2, Integration::Twice)] {
            let (m, v) = sinusoid_growth(2.0, f, Some(phi), t, how);
            assert_eq!(v, 0.0);
            let expect = 2.0 * phi.sin() * t.powi(k) / factorial(k);
            assert!((m / expect - 1.0).abs() < 1e-5, "k {k}: {m} vs {expect}");
        }
        // Uniform phase: the variance is the phase average of the square (midpoint rule over a
        // full period, exact for a trigonometric polynomial of degree 2), and matches the
        // closed forms of `sinusoid_growth_std`.
        for how in [Integration::Once, Integration::Twice, Integration::Tilt] {
            for &t in &[0.7, 4.2, 20.0] {
                let (m, v) = sinusoid_growth(1.5, f, None, t, how);
                assert_eq!(m, 0.0);
                let n = 64;
                let avg = (0..n)
                    .map(|j| {
                        let p = TAU * (j as f64 + 0.5) / n as f64;
                        sinusoid_growth(1.5, f, Some(p), t, how).0.powi(2)
                    })
                    .sum::<f64>()
                    / n as f64;
                assert!((v / avg - 1.0).abs() < 1e-12, "{how:?} t {t}: {v} vs {avg}");
                let s = sinusoid_growth_std(1.5, f, t, how);
                assert!((v / (s * s) - 1.0).abs() < 1e-9, "{how:?} t {t}");
            }
        }
    }

    #[test]
    fn sampled_sinusoid_law_is_the_rectangle_sum() {
        // Once-integrated: exact (to rounding) against the rectangle sum of point samples.
        let (a, f, phi, dt) = (0.7, 0.13, 1.1, 0.02);
        for n in [1usize, 7, 50, 333, 1000] {
            let t = n as f64 * dt;
            let sum: f64 = (0..n)
                .map(|j| a * (TAU * f * j as f64 * dt + phi).sin() * dt)
                .sum();
            let (m, v) = sinusoid_growth_sampled(a, f, Some(phi), t, dt, Integration::Once);
            assert_eq!(v, 0.0);
            assert!((m - sum).abs() < 1e-12 * a * t, "n {n}: {m} vs {sum}");
        }
        // Continuous limit, and the random phase takes only the gain (x / sin x)^2.
        let c = sinusoid_growth(a, f, Some(phi), 3.0, Integration::Tilt);
        assert_eq!(
            sinusoid_growth_sampled(a, f, Some(phi), 3.0, 0.0, Integration::Tilt),
            c
        );
        let x = PI * f * dt;
        let (_, v0) = sinusoid_growth(a, f, None, 3.0, Integration::Twice);
        let (_, v1) = sinusoid_growth_sampled(a, f, None, 3.0, dt, Integration::Twice);
        assert!((v1 / v0 - (x / x.sin()).powi(2)).abs() < 1e-14);
    }

    #[test]
    fn exact_gauss_markov_integrals_meet_both_limits() {
        let (sigma, tc) = (0.2, 3.0);
        for k in 1..=3 {
            // t >> T: docs/model.md §4 asymptote 2 sigma^2 T * white k-fold (relative error O(T/t)).
            let t = 1e4 * tc;
            let exact = gauss_markov_kfold_variance(sigma, tc, t, k).unwrap();
            let asym = white_kfold_variance((2.0 * sigma * sigma * tc).sqrt(), t, k);
            assert!(
                (exact / asym - 1.0).abs() < 1e-3,
                "k {k}: {exact} vs {asym}"
            );
            // t << T: a random constant sigma, integrated k times: (sigma t^k / k!)^2.
            let t = 1e-4 * tc;
            let exact = gauss_markov_kfold_variance(sigma, tc, t, k).unwrap();
            let constant = (sigma * t.powi(k) / factorial(k)).powi(2);
            assert!(
                (exact / constant - 1.0).abs() < 1e-3,
                "k {k}: {exact} vs {constant}"
            );
            // Series and closed form agree where they switch.
            let below = gauss_markov_kfold_variance(sigma, tc, 0.4999999 * tc, k).unwrap();
            let above = gauss_markov_kfold_variance(sigma, tc, 0.5000001 * tc, k).unwrap();
            assert!(
                (below / above - 1.0).abs() < 1e-5,
                "k {k}: {below} vs {above}"
            );
        }
        // k = 1 is docs/model.md §4's exact form.
        let once = gauss_markov_growth_std(sigma, tc, 7.0, Integration::Once).unwrap();
        assert!(
            (gauss_markov_kfold_variance(sigma, tc, 7.0, 1).unwrap() / (once * once) - 1.0).abs()
                < 1e-12
        );
        assert!(gauss_markov_kfold_variance(sigma, tc, 7.0, 4).is_none());
    }

    /// The resonance's closed forms against brute force from its autocovariance: the sampled Allan
    /// variance as the quadratic form (1/(2m^2)) sum A_w(k) R(k dt), the continuous one as the same
    /// integral (midpoint rule, 2e5 points), and the k-fold integrals' variances as the double
    /// integral of g(u) g(v) R(u - v), g(u) = (t-u)^(k-1)/(k-1)! (midpoint rule, 1200^2 points), on
    /// both sides of the series/closed-form switch. The autocovariance itself is checked against the
    /// damped-oscillator form written out (Maybeck vol. 1, second-order Gauss-Markov).
    #[test]
    fn resonance_closed_forms_match_brute_force() {
        let (sigma, f0, bw) = (2e-3, 3.0, 0.8);
        let zeta = bw / (2.0 * f0);
        let w0 = TAU * f0;
        let wd = w0 * (1.0 - zeta * zeta).sqrt();
        let r = |u: f64| resonance_autocovariance(sigma, f0, bw, u);
        for u in [0.0f64, 0.01, 0.137, 1.3, -0.4] {
            let direct = sigma
                * sigma
                * (-zeta * w0 * u.abs()).exp()
                * ((wd * u).cos() + zeta / (1.0 - zeta * zeta).sqrt() * (wd * u.abs()).sin());
            assert!((r(u) - direct).abs() < 1e-15, "R({u})");
        }
        let dt = 0.01;
        for m in [1i64, 2, 5, 17, 33, 100, 400] {
            let brute: f64 = (-2 * m..=2 * m)
                .map(|k| crate::filter::allan_weight_acf(k, m) * r(k as f64 * dt))
                .sum::<f64>()
                / (2 * m * m) as f64;
            let cf = resonance_avar_sampled(sigma, f0, bw, m as f64 * dt, dt);
            assert!(
                (cf / brute - 1.0).abs() < 1e-9,
                "sampled m {m}: {cf} vs {brute}"
            );
        }
        for tau in [0.003, 0.05, 0.17, 0.5, 2.0, 10.0] {
            let n = 200_000;
            let h = 4.0 * tau / n as f64;
            let brute: f64 = (0..n)
                .map(|i| {
                    let u = -2.0 * tau + (i as f64 + 0.5) * h;
                    let aw = if u.abs() <= tau {
                        2.0 * tau - 3.0 * u.abs()
                    } else {
                        -(2.0 * tau - u.abs())
                    };
                    aw * r(u)
                })
                .sum::<f64>()
                * h
                / (2.0 * tau * tau);
            let cf = resonance_avar(sigma, f0, bw, tau);
            assert!(
                (cf / brute - 1.0).abs() < 1e-6,
                "continuous tau {tau}: {cf} vs {brute}"
            );
        }
        // |s| = w0 = 18.85 /s: t = 0.02 s is on the series side, 0.03 s and beyond on the closed form.
        for k in 1..=3 {
            for t in [0.02, 0.03, 0.3, 2.0] {
                let n = 1200;
                let h = t / n as f64;
                let fact = [1.0, 1.0, 2.0][k as usize - 1];
                let g: Vec<f64> = (0..n)
                    .map(|i| (t - (i as f64 + 0.5) * h).powi(k - 1) / fact)
                    .collect();
                let mut brute = 0.0;
                for i in 0..n {
                    for j in 0..n {
                        brute += g[i] * g[j] * r((i as f64 - j as f64) * h);
                    }
                }
                brute *= h * h;
                let cf = resonance_kfold_variance(sigma, f0, bw, t, k).unwrap();
                assert!(
                    (cf / brute - 1.0).abs() < 1e-4,
                    "k {k}, t {t}: {cf} vs {brute}"
                );
            }
        }
        assert!(resonance_kfold_variance(sigma, f0, bw, 1.0, 4).is_none());
        // Long after 1/bandwidth the angle grows like white noise of density sigma sqrt(B/pi)/f0
        // (docs/model.md §4): the once-integrated variance over t is that density squared times t,
        // less a constant of order sigma^2 / (zeta w0)^2, relative 1/(pi B t) = 2e-4 at t = 2000 s.
        let t = 2000.0;
        let white = (sigma * (bw / std::f64::consts::PI).sqrt() / f0).powi(2) * t;
        let v = resonance_kfold_variance(sigma, f0, bw, t, 1).unwrap();
        assert!((v / white - 1.0).abs() < 1e-3, "{v} vs {white}");
    }
}
