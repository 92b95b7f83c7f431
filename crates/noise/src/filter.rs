//! The exact Allan variance of the noise terms behind a sensor's digital output filter
//! (`crate::terms::output_filter`), at the output rate and after decimation.

use num_complex::Complex64;

/// Exact Allan variance of each noise term after an output filter ([`FilteredAllan::new`]) (and its decimation), at output
/// interval `dt_s` and tau = m dt_s (overlapping-estimator expectation).
///
/// Derivation (ours; checked against brute-force quadratic forms in the tests). The Allan
/// difference of m-averages of the output z is Delta = (1/m) sum_n w_n z_n with w = (-1 x m, +1 x m),
/// and AVAR = E[Delta^2] / 2. Its weights have the autocorrelation
/// A_w(k) = 2m - 3|k| (|k| <= m), -(2m - |k|) (m < |k| < 2m), 0 beyond.
/// - A stationary output of autocovariance R_z gives AVAR = (1/(2 m^2)) sum_k A_w(k) R_z(k).
/// - An output with stationary increments, structure function D_z(k) = E[(z_{n+k} - z_n)^2], gives
///   AVAR = -(1/(4 m^2)) sum_k A_w(k) D_z(k) (sum_k A_w(k) = 0).
///
/// The filter h (internal interval dt_i = dt/D, length L) with autocorrelation A_h(d) = sum_i h_i h_{i+d}
/// turns an internal process x into y = h * x; the output keeps z_n = y_{nD}, so R_z(n) = R_y(nD):
/// - white noise of density N (variance N^2/dt_i per internal sample): R_y(k) = (N^2/dt_i) A_h(k);
/// - Gauss-Markov (sigma, T), phi = e^{-dt_i/T}: R_y(k) = sigma^2 sum_d A_h(d) phi^|k - d|, which for
///   k >= L - 1 is R_y(L - 1) phi^(k - L + 1): beyond the filter's span the output is again a
///   Gauss-Markov process, whose part of the sum is the closed form `gauss_markov_avar_sampled`;
/// - a sinusoid of random phase: R_y(k) = (A^2/2) |H(theta)|^2 cos(theta k), theta = 2 pi f dt_i, so the
///   output is the sinusoid with amplitude A |H(theta)| (`sinusoid_avar_sampled`, aliasing included);
/// - a random walk of density K (step variance s^2 = K^2 dt_i): D_y(k) = s^2 sum_d A_h(d) max(0, |k| - |d|),
///   equal to s^2 (|k| - c_1), c_1 = sum_d A_h(d) |d|, for |k| >= L - 1; the linear part is the random
///   walk's own closed form (`rate_random_walk_avar_sampled`) and the constant part sums to zero.
///
/// Each term is thus its unfiltered closed form at the output rate plus a correction summed over the
/// few lags inside the filter's span.
#[derive(Clone, Debug)]
pub struct FilteredAllan {
    /// A_h(d), d = 0..L-1.
    a_h: Vec<f64>,
    decimation: usize,
    dt_s: f64,
    dt_i: f64,
}

/// A_w(k) of the Allan difference weights at averaging factor m (docs/real-effects.md).
pub(crate) fn allan_weight_acf(k: i64, m: i64) -> f64 {
    let k = k.abs();
    if k <= m {
        (2 * m - 3 * k) as f64
    } else if k < 2 * m {
        -((2 * m - k) as f64)
    } else {
        0.0
    }
}

impl FilteredAllan {
    /// The forms of a filter with autocorrelation `a_h` (A_h(d), d = 0..L-1) and `decimation`, at
    /// output interval `dt_s` and internal interval `dt_i` ([`FilteredAllan::new`], built in
    /// `crate::terms::output_filter`, the filter's file).
    pub(crate) fn from_parts(a_h: Vec<f64>, decimation: usize, dt_s: f64, dt_i: f64) -> Self {
        FilteredAllan {
            a_h,
            decimation,
            dt_s,
            dt_i,
        }
    }

    fn len(&self) -> usize {
        self.a_h.len()
    }

    fn a_h(&self, d: i64) -> f64 {
        self.a_h
            .get(d.unsigned_abs() as usize)
            .copied()
            .unwrap_or(0.0)
    }

    /// First output lag at or beyond the filter's span: n0 D >= L - 1.
    fn n0(&self) -> usize {
        (self.len() - 1).div_ceil(self.decimation)
    }

    fn m(&self, tau_s: f64) -> i64 {
        (tau_s / self.dt_s).round().max(1.0) as i64
    }

    /// (1/(2 m^2)) sum_{|n| < n_max} A_w(n) r(n), r even.
    fn stationary_sum(m: i64, n_max: usize, r: impl Fn(usize) -> f64) -> f64 {
        let top = (n_max as i64).min(2 * m);
        let mut s = allan_weight_acf(0, m) * r(0);
        for n in 1..top {
            s += 2.0 * allan_weight_acf(n, m) * r(n as usize);
        }
        s / (2.0 * (m * m) as f64)
    }

    /// White noise of density N (internal rate).
    pub fn white_noise(&self, n: f64, tau_s: f64) -> f64 {
        let var = n * n / self.dt_i;
        let d = self.decimation;
        let n_max = (self.len() - 1) / d + 1;
        Self::stationary_sum(self.m(tau_s), n_max, |k| var * self.a_h[k * d])
    }

    /// Sinusoid of amplitude A and frequency f (random phase).
    pub fn sinusoid(&self, amplitude: f64, frequency_hz: f64, tau_s: f64) -> f64 {
        let theta = std::f64::consts::TAU * frequency_hz * self.dt_i;
        let gain2: f64 = self.a_h[0]
            + 2.0
                * (1..self.len())
                    .map(|d| self.a_h[d] * (theta * d as f64).cos())
                    .sum::<f64>();
        crate::closed_form::sinusoid_avar_sampled(
            amplitude * gain2.max(0.0).sqrt(),
            frequency_hz,
            tau_s,
            self.dt_s,
        )
    }

    /// First-order Gauss-Markov of stationary std `sigma` and correlation time `tc_s`.
    pub fn gauss_markov(&self, sigma: f64, tc_s: f64, tau_s: f64) -> f64 {
        let dt = self.dt_s;
        self.exponential(
            Complex64::new(sigma * sigma, 0.0),
            Complex64::new(1.0 / tc_s, 0.0),
            tau_s,
            |v, tau| {
                crate::closed_form::gauss_markov_avar_sampled(v.re.max(0.0).sqrt(), tc_s, tau, dt)
            },
        )
    }

    /// Resonance (second-order Gauss-Markov) of std `sigma`, natural frequency `f0_hz` and
    /// half-power bandwidth `bandwidth_hz` (autocovariance Re[sigma^2 C e^{-s|u|}],
    /// [`crate::closed_form::resonance_exponent`]).
    pub fn resonance(&self, sigma: f64, f0_hz: f64, bandwidth_hz: f64, tau_s: f64) -> f64 {
        let (c, s) = crate::closed_form::resonance_exponent(f0_hz, bandwidth_hz);
        let lambda_o = (-s * self.dt_s).exp();
        self.exponential(c * sigma * sigma, s, tau_s, |v, tau| {
            let m = (tau / self.dt_s).round().max(1.0);
            (v * crate::closed_form::geometric_avar_unit(lambda_o, m)).re
        })
    }

    /// A stationary input of autocovariance Re[coef e^{-s|u|}] (Re s > 0): the first-order
    /// Gauss-Markov process (real s = 1/T) and the resonance. `far(v, tau)` is the Allan variance of
    /// the sampled output-rate sequence of autocovariance Re[v lambda_o^|n|], lambda_o = e^{-s dt}.
    fn exponential(
        &self,
        coef: Complex64,
        s: Complex64,
        tau_s: f64,
        far: impl Fn(Complex64, f64) -> f64,
    ) -> f64 {
        let l = self.len() as i64;
        let d = self.decimation;
        let phi = (-s * self.dt_i).exp();
        // R_y(k) = coef sum_{|j| < L} A_h(j) phi^|k-j|, k = 0..L-1 (complex: the real part is the
        // autocovariance), by the two one-sided recursions S1(k) = phi S1(k-1) + A_h(k) (j <= k)
        // and S2(k) = phi (A_h(k+1) + S2(k+1)) (j > k): O(L) instead of O(L^2).
        let span = (l - 1) as usize;
        let mut s1 = vec![Complex64::new(0.0, 0.0); 2 * span + 1];
        let mut acc = Complex64::new(0.0, 0.0);
        for (i, v) in s1.iter_mut().enumerate() {
            acc = acc * phi + self.a_h(i as i64 - span as i64);
            *v = acc;
        }
        let mut s2 = vec![Complex64::new(0.0, 0.0); l as usize];
        for k in (0..span).rev() {
            s2[k] = phi * (s2[k + 1] + self.a_h(k as i64 + 1));
        }
        let r_y: Vec<Complex64> = (0..l as usize)
            .map(|k| coef * (s1[k + span] + s2[k]))
            .collect();
        let n0 = self.n0();
        let phi_o = (-s * self.dt_s).exp();
        // R_z(n): direct inside the span, geometric beyond (R_y(k) = R_y(L-1) phi^(k-L+1)).
        let r_z = |n: usize| -> Complex64 {
            let k = n * d;
            if k < l as usize {
                r_y[k]
            } else {
                r_y[l as usize - 1] * phi.powi((k - (l as usize - 1)) as i32)
            }
        };
        let m = self.m(tau_s);
        let span = (l - 1) as f64 * self.dt_i * s.re;
        if span <= 2.0 {
            // Far field: the output-rate process of autocovariance Re[v phi_o^n] for n >= n0, in
            // closed form, plus the correction inside the span.
            let v = r_z(n0) / phi_o.powi(n0 as i32);
            far(v, tau_s) + Self::stationary_sum(m, n0, |n| (r_z(n) - v * phi_o.powi(n as i32)).re)
        } else {
            // Decay short against the span: R_z falls below 1e-18 of R_z(n0) within 42 / Re s
            // beyond it; summed directly.
            let n1 = n0 + (42.0 / (s.re * self.dt_s)).ceil() as usize + 1;
            Self::stationary_sum(m, n1, |n| r_z(n).re)
        }
    }

    /// Random walk of density K (rate random walk, Woodman's bias random walk).
    pub fn random_walk(&self, k: f64, tau_s: f64) -> f64 {
        let s2 = k * k * self.dt_i;
        let l = self.len() as i64;
        let c1: f64 = 2.0 * (1..l).map(|j| self.a_h(j) * j as f64).sum::<f64>();
        let d = self.decimation as i64;
        let d_y = |kk: i64| -> f64 {
            s2 * (-(l - 1)..l)
                .map(|j| self.a_h(j) * (kk.abs() - j.abs()).max(0) as f64)
                .sum::<f64>()
        };
        let m = self.m(tau_s);
        let n0 = self.n0() as i64;
        let top = n0.min(2 * m);
        // -(1/(4m^2)) sum_{|n| < top} A_w(n) (D_z(n) - D_far(n)), D_far(n) = s^2 (|n| D - c1).
        let diff = |n: i64| d_y(n * d) - s2 * ((n.abs() * d) as f64 - c1);
        let mut s = allan_weight_acf(0, m) * diff(0);
        for n in 1..top {
            s += 2.0 * allan_weight_acf(n, m) * diff(n);
        }
        crate::closed_form::rate_random_walk_avar_sampled(k, tau_s, self.dt_s)
            - s / (4.0 * (m * m) as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::terms::output_filter::{FilterKind, OutputFilter};

    /// Raw-sample weights of m^2-scaled... the Allan difference sum_n w_n z_n written on the internal
    /// samples x (index 0 = the earliest sample any output uses).
    fn raw_weights(h: &[f64], d: usize, m: usize) -> Vec<f64> {
        let l = h.len();
        let n_out = 2 * m;
        let len = (n_out - 1) * d + l;
        let mut u = vec![0.0; len];
        for n in 0..n_out {
            let w = if n < m { -1.0 } else { 1.0 };
            // z_n = y_{(L-1) + nD} = sum_i h_i x_{(L-1) + nD - i}
            for (i, hi) in h.iter().enumerate() {
                u[(l - 1) + n * d - i] += w * hi;
            }
        }
        u
    }

    fn brute(u: &[f64], m: usize, cov: impl Fn(i64) -> f64) -> f64 {
        let mut v = 0.0;
        for (a, ua) in u.iter().enumerate() {
            for (b, ub) in u.iter().enumerate() {
                v += ua * ub * cov(a as i64 - b as i64);
            }
        }
        v / (2.0 * (m * m) as f64)
    }

    #[test]
    fn exact_allan_variance_matches_brute_force_quadratic_forms() {
        let dt = 0.01;
        let filters = [
            OutputFilter::new(FilterKind::MovingAverage { taps: 4 }, 1).unwrap(),
            OutputFilter::new(FilterKind::Bartlett { taps: 7 }, 3).unwrap(),
            OutputFilter::new(FilterKind::LowPass1 { cutoff_hz: 30.0 }, 2).unwrap(),
            OutputFilter::new(FilterKind::LowPass2 { cutoff_hz: 12.0 }, 1).unwrap(),
            OutputFilter::new(FilterKind::MovingAverage { taps: 1 }, 1).unwrap(),
        ];
        for f in &filters {
            let h = f.impulse_response(dt);
            let fa = FilteredAllan::new(f, dt);
            let d = f.decimation() as usize;
            let dt_i = f.internal_dt(dt);
            for m in [1usize, 2, 3, 5, 8, 13] {
                let tau = m as f64 * dt;
                let u = raw_weights(&h, d, m);
                let close = |a: f64, b: f64, what: &str| {
                    assert!(
                        (a - b).abs() <= 1e-7 * b.abs().max(1e-300), // rounding of sums near a response null
                        "{f:?} m {m} {what}: exact {a} vs brute force {b}"
                    )
                };
                // White noise, N = 2 (variance N^2/dt_i).
                let var = 4.0 / dt_i;
                let b = brute(&u, m, |k| if k == 0 { var } else { 0.0 });
                close(fa.white_noise(2.0, tau), b, "white");
                // Gauss-Markov, long and short against the span.
                for tc in [0.5, 0.004, 0.0007] {
                    let phi = (-dt_i / tc).exp();
                    let b = brute(&u, m, |k| 0.09 * phi.powi(k.abs() as i32));
                    close(fa.gauss_markov(0.3, tc, tau), b, &format!("GM T={tc}"));
                }
                // Resonance (second-order Gauss-Markov), narrow and broad, slow and fast.
                for (f0, bw) in [(3.0, 0.5), (20.0, 1.5), (41.0, 30.0), (0.2, 0.01)] {
                    let b = brute(&u, m, |k| {
                        crate::closed_form::resonance_autocovariance(0.3, f0, bw, k as f64 * dt_i)
                    });
                    close(
                        fa.resonance(0.3, f0, bw, tau),
                        b,
                        &format!("resonance {f0} Hz / {bw} Hz"),
                    );
                }
                // Sinusoid of random phase.
                for fr in [3.0, 41.0, 170.0] {
                    let th = std::f64::consts::TAU * fr * dt_i;
                    let b = brute(&u, m, |k| 0.5 * 0.49 * (th * k as f64).cos());
                    close(fa.sinusoid(0.7, fr, tau), b, &format!("sinusoid {fr} Hz"));
                }
                // Random walk (s^2 = K^2 dt_i): Var = -(1/2) sum u_a u_b s^2 |a-b|.
                let s2 = 0.25 * dt_i;
                let b = brute(&u, m, |k| -0.5 * s2 * k.abs() as f64);
                close(fa.random_walk(0.5, tau), b, "random walk");
            }
        }
    }

    #[test]
    fn noise_bandwidths() {
        // Moving average of L at rate fs: fs/(2L). First-order low-pass: (pi/2) f_c as f_c << fs.
        let dt = 0.001;
        let ma = OutputFilter::new(FilterKind::MovingAverage { taps: 10 }, 1).unwrap();
        assert!((ma.noise_bandwidth_hz(dt) - 50.0).abs() < 1e-9);
        let lp = OutputFilter::new(FilterKind::LowPass1 { cutoff_hz: 2.0 }, 1).unwrap();
        let b = lp.noise_bandwidth_hz(dt);
        assert!(
            (b / (std::f64::consts::FRAC_PI_2 * 2.0) - 1.0).abs() < 1e-2,
            "{b}"
        );
        // Second-order Butterworth: the continuous ENBW is (pi / (2 sqrt 2)) / sin(pi/4)... = 1.1107 f_c.
        let lp2 = OutputFilter::new(FilterKind::LowPass2 { cutoff_hz: 2.0 }, 1).unwrap();
        let b2 = lp2.noise_bandwidth_hz(dt);
        assert!((b2 / (1.110_72 * 2.0) - 1.0).abs() < 1e-2, "{b2}");
        // Unit DC gain for every kind.
        for f in [ma, lp, lp2] {
            let s: f64 = f.impulse_response(dt).iter().sum();
            assert!((s - 1.0).abs() < 1e-12);
        }
    }
}
