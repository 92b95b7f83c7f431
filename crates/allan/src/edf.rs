//! Equivalent degrees of freedom (EDF) and power-law noise identification.
//!
//! - Greenhall's general EDF algorithm: C. A. Greenhall and W. J. Riley, "Uncertainty of
//!   stability variances based on finite differences", PTTI 2003 (Greenhall 2004), eqs (7)–(13)
//!   and Tables 1–3, as implemented in allantools `ci.py::edf_greenhall` (docs/model.md §2.1).
//! - Simple EDF formulas: NIST SP 1065 Table 5 (allantools `edf_simple`).
//! - Total deviation EDF: NIST SP 1065 Table 7 (allantools `edf_totdev`); modified total,
//!   Hadamard total and Theo1: SP 1065 Tables 8, 9 and 10 ([`mtotdev`], [`htotdev`], [`theo1`]).
//! - Noise identification by the lag-1 autocorrelation: W. J. Riley and C. A. Greenhall,
//!   "Power law noise identification using the lag 1 autocorrelation", 2004
//!   (allantools `autocorr_noise_id`).
//!
//! alpha is the exponent of the frequency (rate) PSD: +2 white PM, +1 flicker PM, 0 white FM
//! (ARW), -1 flicker FM (bias instability), -2 random-walk FM (rate random walk).

use crate::{DataKind, EdfMethod, Estimator};

/// The EDF of estimator `est` at averaging factor `m` for noise `alpha`, with `n_phase` phase
/// points (`n_terms`, the number of terms in the sum, is accepted for estimators whose EDF
/// would need it; none of the present formulas does).
pub fn edf_for(
    est: Estimator,
    method: EdfMethod,
    alpha: i32,
    m: usize,
    n_phase: usize,
    n_terms: usize,
) -> f64 {
    let _ = n_terms;
    // allantools passes the number of data points it was given to edf_greenhall; Stable32's
    // bounds are matched (to 3e-4) with N = number of phase points.
    let n = n_phase;
    let g = |d: u32, overlapping: bool, modified: bool| {
        let a = alpha.clamp(1 - 2 * d as i32 + 1, 2);
        greenhall(a, d, m, n, overlapping, modified).unwrap_or_else(|| simple(n, m, a))
    };
    match (est, method) {
        (_, EdfMethod::None) => f64::NAN,
        (Estimator::Overlapping | Estimator::NonOverlapping, EdfMethod::Simple) => {
            simple(n, m, alpha.clamp(-2, 2))
        }
        (Estimator::NonOverlapping, _) => g(2, false, false),
        (Estimator::Overlapping, _) => g(2, true, false),
        (Estimator::Modified, _) => g(2, true, true),
        (Estimator::Hadamard, _) => g(3, false, false),
        (Estimator::OverlappingHadamard, _) => g(3, true, false),
        (Estimator::Total, _) => totdev(n - 1, m, alpha),
        (Estimator::ModifiedTotal, _) => mtotdev(n, m, alpha),
        (Estimator::HadamardTotal, _) if m == 1 => g(3, true, false),
        (Estimator::HadamardTotal, _) => {
            htotdev(n - 1, m, alpha).unwrap_or_else(|| g(3, true, false))
        }
        (Estimator::Theo1, _) => theo1(n, m, alpha),
        (Estimator::TheoH, _) if crate::total::theoh_uses_avar(m, n) => g(2, true, false),
        (Estimator::TheoH, _) => theo1(n, m, alpha),
    }
}

/// Greenhall's EDF (Greenhall 2004 eqs (7)–(13), allantools `edf_greenhall`).
/// d = 2 Allan, 3 Hadamard; requires alpha + 2d > 1. `None` for the case the paper leaves to
/// another formula (alpha = 2 unmodified with ceil(M/S) <= d).
pub fn greenhall(
    alpha: i32,
    d: u32,
    m: usize,
    n: usize,
    overlapping: bool,
    modified: bool,
) -> Option<f64> {
    if alpha + 2 * d as i32 <= 1 {
        return None;
    }
    let mf = m as f64;
    let df = d as f64;
    let f = if modified { 1.0 } else { mf };
    let s = if overlapping { mf } else { 1.0 };
    let l = mf / f + mf * df; // length of the filter applied to the phase samples
    let big_m = 1.0 + (s * (n as f64 - l) / mf).floor();
    if big_m < 1.0 {
        return None;
    }
    let j = big_m.min((df + 1.0) * s);
    const J_MAX: f64 = 100.0;
    let r = big_m / s;
    let inv = if modified {
        // case 1: modified variances, all alpha
        if j <= J_MAX {
            basic_sum(j, big_m, s, 1.0, alpha, d) / (sz(0.0, 1.0, alpha, d).powi(2) * big_m)
        } else if r > df + 1.0 {
            let (a0, a1) = table1(alpha, d)?;
            (a0 - a1 / r) / r
        } else {
            let mp = J_MAX / r;
            basic_sum(J_MAX, J_MAX, mp, 1.0, alpha, d) / (sz(0.0, 1.0, alpha, d).powi(2) * J_MAX)
        }
    } else if alpha <= 0 {
        // case 2: unmodified, alpha <= 0
        if j <= J_MAX {
            let mp = if mf * (df + 1.0) <= J_MAX {
                mf
            } else {
                f64::INFINITY
            };
            basic_sum(j, big_m, s, mp, alpha, d) / (sz(0.0, mp, alpha, d).powi(2) * big_m)
        } else if r > df + 1.0 {
            let (a0, a1) = table2(alpha, d)?;
            (a0 - a1 / r) / r
        } else {
            let mp = J_MAX / r;
            basic_sum(J_MAX, J_MAX, mp, f64::INFINITY, alpha, d)
                / (sz(0.0, f64::INFINITY, alpha, d).powi(2) * J_MAX)
        }
    } else if alpha == 1 {
        // case 3: unmodified, flicker PM
        let (b0, b1) = table3(d);
        if j <= J_MAX {
            basic_sum(j, big_m, s, mf, 1, d) / (sz(0.0, mf, 1, d).powi(2) * big_m)
        } else if r > df + 1.0 {
            let (a0, a1) = table2(alpha, d)?;
            (a0 - a1 / r) / ((b0 + b1 * mf.ln()).powi(2) * r)
        } else {
            let mp = J_MAX / r;
            basic_sum(J_MAX, J_MAX, mp, mp, 1, d) / ((b0 + b1 * mf.ln()).powi(2) * J_MAX)
        }
    } else {
        // case 4: unmodified, white PM
        let k = r.ceil();
        if k <= df {
            return None;
        }
        let a0 = binom(4 * d, 2 * d) / binom(2 * d, d).powi(2);
        let a1 = df / 2.0;
        (a0 - a1 / r) / big_m
    };
    Some(1.0 / inv)
}

fn binom(n: u32, k: u32) -> f64 {
    (0..k).fold(1.0, |acc, i| acc * (n - i) as f64 / (i + 1) as f64)
}

/// Greenhall 2004 eq (10).
fn basic_sum(j: f64, big_m: f64, s: f64, f: f64, alpha: i32, d: u32) -> f64 {
    let first = sz(0.0, f, alpha, d).powi(2);
    let second = (1.0 - j / big_m) * sz(j / s, f, alpha, d).powi(2);
    let mut third = 0.0;
    let mut jj = 1.0;
    while jj < j.trunc() {
        third += 2.0 * (1.0 - jj / big_m) * sz(jj / s, f, alpha, d).powi(2);
        jj += 1.0;
    }
    first + second + third
}

/// Greenhall 2004 eq (9).
fn sz(t: f64, f: f64, alpha: i32, d: u32) -> f64 {
    let x = |u: f64| sx(u, f, alpha);
    match d {
        1 => 2.0 * x(t) - x(t - 1.0) - x(t + 1.0),
        2 => 6.0 * x(t) - 4.0 * x(t - 1.0) - 4.0 * x(t + 1.0) + x(t - 2.0) + x(t + 2.0),
        _ => {
            20.0 * x(t) - 15.0 * x(t - 1.0) - 15.0 * x(t + 1.0)
                + 6.0 * x(t - 2.0)
                + 6.0 * x(t + 2.0)
                - x(t - 3.0)
                - x(t + 3.0)
        }
    }
}

/// Greenhall 2004 eq (8).
fn sx(t: f64, f: f64, alpha: i32) -> f64 {
    if f.is_infinite() {
        return sw(t, alpha + 2);
    }
    f * f * (2.0 * sw(t, alpha) - sw(t - 1.0 / f, alpha) - sw(t + 1.0 / f, alpha))
}

/// Greenhall 2004 eq (7).
fn sw(t: f64, alpha: i32) -> f64 {
    let tl = |p: i32| {
        if t == 0.0 {
            0.0
        } else {
            t.powi(p) * t.abs().ln()
        }
    };
    match alpha {
        2 => -t.abs(),
        1 => tl(2),
        0 => t.abs().powi(3),
        -1 => tl(4),
        -2 => t.abs().powi(5),
        -3 => tl(6),
        _ => t.abs().powi(7),
    }
}

/// Greenhall 2004 Table 1 (modified variances), (a0, a1).
fn table1(alpha: i32, d: u32) -> Option<(f64, f64)> {
    let rows: [[(f64, f64); 3]; 7] = [
        [
            (2.0 / 3.0, 1.0 / 3.0),
            (7.0 / 9.0, 1.0 / 2.0),
            (22.0 / 25.0, 2.0 / 3.0),
        ],
        [(0.840, 0.345), (0.997, 0.616), (1.141, 0.843)],
        [(1.079, 0.368), (1.033, 0.607), (1.184, 0.848)],
        [(-1.0, -1.0), (1.048, 0.534), (1.180, 0.816)],
        [(-1.0, -1.0), (1.302, 0.535), (1.175, 0.777)],
        [(-1.0, -1.0), (-1.0, -1.0), (1.194, 0.703)],
        [(-1.0, -1.0), (-1.0, -1.0), (1.489, 0.702)],
    ];
    table_lookup(&rows, alpha, d)
}

/// Greenhall 2004 Table 2 (unmodified variances), (a0, a1).
fn table2(alpha: i32, d: u32) -> Option<(f64, f64)> {
    let rows: [[(f64, f64); 3]; 7] = [
        [
            (3.0 / 2.0, 1.0 / 2.0),
            (35.0 / 18.0, 1.0),
            (231.0 / 100.0, 3.0 / 2.0),
        ],
        [(78.6, 25.2), (790.0, 410.0), (9950.0, 6520.0)],
        [
            (2.0 / 3.0, 1.0 / 6.0),
            (2.0 / 3.0, 1.0 / 3.0),
            (7.0 / 9.0, 1.0 / 2.0),
        ],
        [(-1.0, -1.0), (0.852, 0.375), (0.997, 0.617)],
        [(-1.0, -1.0), (1.079, 0.368), (1.033, 0.607)],
        [(-1.0, -1.0), (-1.0, -1.0), (1.053, 0.553)],
        [(-1.0, -1.0), (-1.0, -1.0), (1.302, 0.535)],
    ];
    table_lookup(&rows, alpha, d)
}

fn table_lookup(rows: &[[(f64, f64); 3]; 7], alpha: i32, d: u32) -> Option<(f64, f64)> {
    let row = usize::try_from(2 - alpha).ok()?;
    let col = usize::try_from(d.checked_sub(1)?).ok()?;
    let v = *rows.get(row)?.get(col)?;
    (v.0 >= 0.0).then_some(v)
}

/// Greenhall 2004 Table 3 (flicker PM), (b0, b1).
fn table3(d: u32) -> (f64, f64) {
    [(6.0, 4.0), (15.23, 12.0), (47.8, 40.0)][(d.clamp(1, 3) - 1) as usize]
}

/// NIST SP 1065 Table 5 simple EDF for the overlapping Allan variance; `n` = phase points.
pub fn simple(n: usize, m: usize, alpha: i32) -> f64 {
    let n = n as f64;
    let m = m as f64;
    match alpha {
        2 => (n + 1.0) * (n - 2.0 * m) / (2.0 * (n - m)),
        1 => {
            let a = (n - 1.0) / (2.0 * m);
            let b = (2.0 * m + 1.0) * (n - 1.0) / 4.0;
            (a.ln() * b.ln()).sqrt().exp()
        }
        0 => {
            (3.0 * (n - 1.0) / (2.0 * m) - 2.0 * (n - 2.0) / n)
                * (4.0 * m * m / (4.0 * m * m + 5.0))
        }
        -1 if m == 1.0 => 2.0 * (n - 2.0) / (2.3 * n - 4.9),
        -1 => 5.0 * n * n / (4.0 * m * (n + 3.0 * m)),
        -2 => {
            (n - 2.0) / (m * (n - 3.0).powi(2))
                * ((n - 1.0).powi(2) - 3.0 * m * (n - 1.0) + 4.0 * m * m)
        }
        _ => n - 1.0,
    }
}

/// NIST SP 1065 Table 7: EDF of the total variance, b (T/tau) - c, for white, flicker and
/// random-walk FM; other noise types use the simple formulas. `n` = number of rate points
/// (T/tau = n/m).
pub fn totdev(n: usize, m: usize, alpha: i32) -> f64 {
    let (b, c) = match alpha {
        0 => (1.50, 0.0),
        -1 => (1.17, 0.22),
        -2 => (0.93, 0.36),
        _ => return simple(n, m, alpha),
    };
    b * (n as f64 / m as f64) - c
}

/// NIST SP 1065 Table 8: EDF of the modified total variance, b (N/m) - c, for white and flicker
/// PM, white, flicker and random-walk FM (allantools `edf_mtotdev`); `n` = phase points. Other
/// noise types take the nearest row.
pub fn mtotdev(n: usize, m: usize, alpha: i32) -> f64 {
    let (b, c) = match alpha.clamp(-2, 2) {
        2 => (1.90, 2.10),
        1 => (1.20, 1.40),
        0 => (1.10, 1.20),
        -1 => (0.85, 0.50),
        _ => (0.75, 0.31),
    };
    b * (n as f64 / m as f64) - c
}

/// NIST SP 1065 Table 9 (Howe et al. 2005): EDF of the Hadamard total variance,
/// (T/tau) / (b0 + b1 tau/T), T/tau = n/m with `n` frequency points, for white, flicker and
/// random-walk FM; `None` for other noise types (the caller falls back to the overlapping
/// Hadamard variance's EDF).
pub fn htotdev(n: usize, m: usize, alpha: i32) -> Option<f64> {
    let (b0, b1) = match alpha {
        0 => (0.546, 1.41),
        -1 => (0.667, 2.00),
        -2 => (0.909, 1.00),
        _ => return None,
    };
    let ratio = n as f64 / m as f64;
    Some(ratio / (b0 + b1 / ratio))
}

/// The Hadamard total variance's bias (its expectation over the Hadamard variance's) for
/// white, flicker, random-walk, flicker-walk and random-run FM: 1 + a with a = -0.005, -0.149,
/// -0.229, -0.283, -0.321 (Howe et al. 2005; the factors 0.995 ... 0.679 allantools' `htotdev`
/// quotes from Riley); Stable32 divides it out (checked: its PHASE.DAT table with and without
/// the correction differ by 0.995 in the variance at alpha = 0). 1 for phase noise.
pub fn htotvar_bias(alpha: i32) -> f64 {
    1.0 + match alpha {
        0 => -0.005,
        -1 => -0.149,
        -2 => -0.229,
        -3 => -0.283,
        a if a <= -4 => -0.321,
        _ => 0.0,
    }
}

/// EDF of Theo1 at averaging factor m (`n` phase points), with r = 0.75 m the Theo1 tau in
/// sample intervals: NIST SP 1065 Table 10 (Howe & Tasset 2004), for white and flicker PM,
/// white, flicker and random-walk FM (other noise types take the nearest row):
/// - WPM: 0.86 (N + 1)(N - 4r/3) / (N - r) * r / (r + 1.14)
/// - FPM: (4.798 N^2 - 6.374 N r + 12.387 r) / (sqrt(r + 36.6) (N - r)) * r / (r + 0.3)
/// - WFM: ((4.1 N + 0.8)/r - (3.1 N + 6.5)/N) * r^1.5 / (r^1.5 + 5.2)
/// - FFM: (2 N^2 - 1.3 N r - 3.5 r) / (N r) * r^3 / (r^3 + 2.3)
/// - RWFM: (4.4 N - 2)/(2.9 r) * ((4.4 N - 1)^2 - 8.6 r (4.4 N - 1) + 11.4 r^2) / (4.4 N - 3)^2
pub fn theo1(n: usize, m: usize, alpha: i32) -> f64 {
    let n = n as f64;
    let r = 0.75 * m as f64;
    match alpha.clamp(-2, 2) {
        2 => 0.86 * (n + 1.0) * (n - 4.0 * r / 3.0) / (n - r) * r / (r + 1.14),
        1 => {
            (4.798 * n * n - 6.374 * n * r + 12.387 * r) / ((r + 36.6).sqrt() * (n - r)) * r
                / (r + 0.3)
        }
        0 => ((4.1 * n + 0.8) / r - (3.1 * n + 6.5) / n) * r.powf(1.5) / (r.powf(1.5) + 5.2),
        -1 => (2.0 * n * n - 1.3 * n * r - 3.5 * r) / (n * r) * r.powi(3) / (r.powi(3) + 2.3),
        _ => {
            let a = 4.4 * n - 1.0;
            (4.4 * n - 2.0) / (2.9 * r) * (a * a - 8.6 * r * a + 11.4 * r * r)
                / (4.4 * n - 3.0).powi(2)
        }
    }
}

/// NIST SP 1065 §5.2.11: the total variance is biased low for flicker and random-walk FM by
/// the factor 1 - a tau/T, a = 1/(3 ln 2) (FFM) and 0.750 (RWFM); Stable32 divides it out
/// (verified against its OCXO total-deviation table). Returns the factor (1 for other noise).
pub fn totvar_bias(alpha: i32, m: usize, n_rate: usize) -> f64 {
    let a = match alpha {
        -1 => 1.0 / (3.0 * std::f64::consts::LN_2),
        -2 => 0.750,
        _ => return 1.0,
    };
    1.0 - a * m as f64 / n_rate as f64
}

/// A lag-1 ACF noise identification with its evidence: the integer alpha, the continuous
/// estimate p = -2 (rho + d) (+2 for phase data) it is rounded from (Riley & Greenhall 2004,
/// allantools `autocorr_noise_id`'s `alpha`), and the standard error of p.
///
/// Standard error: under white noise the lag-1 autocorrelation r1 of n values has standard
/// deviation 1/sqrt(n) (Bartlett 1946; Box, Jenkins & Reinsel, Time Series Analysis, §6.2.1;
/// Riley & Greenhall use the same 1/sqrt(N) scatter to explain why the method needs N >= 30);
/// rho = r1 / (1 + r1) and p = -2 rho - 2 d carry it as se(p) = 2 / ((1 + r1)^2 sqrt(n)) (delta
/// method), n the number of values of the differenced series the decision was made on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NoiseId {
    pub alpha: i32,
    pub estimate: f64,
    pub se: f64,
}

impl NoiseId {
    /// The identification from rho at difference order d on `len` values.
    fn new(rho: f64, d: usize, len: usize, phase_add: i32) -> NoiseId {
        let r1 = rho / (1.0 - rho);
        NoiseId {
            alpha: -(2.0 * rho).round_ties_even() as i32 - 2 * d as i32 + phase_add,
            estimate: -2.0 * (rho + d as f64) + phase_add as f64,
            se: 2.0 / ((1.0 + r1).powi(2) * (len as f64).sqrt()),
        }
    }

    /// Whether this identification departs significantly from `held`: its estimate lies
    /// outside held's rounding band (+-1/2) by more than `z` standard errors.
    pub fn departs_from(&self, held: i32, z: f64) -> bool {
        (self.estimate - held as f64).abs() > 0.5 + z * self.se
    }
}

/// Lag-1 autocorrelation noise identification (Riley & Greenhall 2004, allantools
/// `autocorr_noise_id` with dmin = 0): returns the integer alpha, or `None` when fewer than 30
/// points remain after averaging / decimating by `m`.
pub fn autocorr_noise_id(data: &[f64], m: usize, kind: DataKind, d_max: u32) -> Option<i32> {
    autocorr_noise_id_detail(data, m, kind, d_max).map(|id| id.alpha)
}

/// [`autocorr_noise_id`] with its evidence ([`NoiseId`]).
pub fn autocorr_noise_id_detail(
    data: &[f64],
    m: usize,
    kind: DataKind,
    d_max: u32,
) -> Option<NoiseId> {
    let mut x: Vec<f64> = match kind {
        DataKind::Phase => {
            let x: Vec<f64> = data.iter().step_by(m.max(1)).copied().collect();
            if x.len() < 30 {
                return None;
            }
            detrend(&x, 2)
        }
        DataKind::Rate => {
            let m = m.max(1);
            let blocks = data.len() / m;
            if blocks < 30 {
                return None;
            }
            // Averages over blocks of m (allantools averages the frequency data by af); m = 1
            // uses the data in place. Then a linear detrend and the lag-1 ACF of the detrended
            // series and its differences, each a single pass without allocation.
            let averaged: Vec<f64>;
            let y: &[f64] = if m == 1 {
                &data[..blocks]
            } else {
                averaged = data[..blocks * m]
                    .chunks_exact(m)
                    .map(stats::mean)
                    .collect();
                &averaged
            };
            return rate_noise_id_detail_fn(y.len(), |k| y[k], d_max);
        }
    };
    let phase_add = if kind == DataKind::Phase { 2 } else { 0 };
    let mut d = 0u32;
    loop {
        let r1 = lag1_acf(&x);
        let rho = r1 / (1.0 + r1);
        if rho < 0.25 || d >= d_max {
            // alpha = -round(2 rho) - 2 d (+2 for phase); numpy rounds half to even.
            return Some(NoiseId::new(rho, d as usize, x.len(), phase_add));
        }
        x = x.windows(2).map(|w| w[1] - w[0]).collect();
        d += 1;
        if x.len() < 2 {
            return None;
        }
    }
}

/// The lag-1 ACF loop of `autocorr_noise_id` for frequency data: linear detrend, then the ACF
/// of the detrended series and of its first, second, ... differences. `y(k)` gives the k-th of
/// `n` (averaged) values. Two passes over the data in all: one for the line, one that
/// accumulates the ACF sums of every difference order at once.
#[inline(always)]
pub fn rate_noise_id_fn(n: usize, y: impl Fn(usize) -> f64, d_max: u32) -> Option<i32> {
    rate_noise_id_detail_fn(n, y, d_max).map(|id| id.alpha)
}

/// [`rate_noise_id_fn`] with its evidence ([`NoiseId`]).
#[inline(always)]
pub fn rate_noise_id_detail_fn(n: usize, y: impl Fn(usize) -> f64, d_max: u32) -> Option<NoiseId> {
    let d_max = d_max.min(3) as usize;
    if n < d_max + 2 {
        return None;
    }
    // Least-squares line in the centred index t_k = k - c: a = mean, b = sum(t y) / sum(t^2),
    // sum(t^2) = n (n^2 - 1) / 12.
    // Four lanes (k mod 4): independent addition chains, added in a fixed order (so the mean
    // `a` below is not `stats::mean`'s left-to-right sum: this pass is the hot one).
    let c = (n as f64 - 1.0) / 2.0;
    let (mut syl, mut styl) = ([0.0f64; 4], [0.0f64; 4]);
    let groups = n / 4;
    for g in 0..groups {
        for l in 0..4 {
            let k = 4 * g + l;
            let v = y(k);
            syl[l] += v;
            styl[l] += (k as f64 - c) * v;
        }
    }
    for k in 4 * groups..n {
        let v = y(k);
        syl[0] += v;
        styl[0] += (k as f64 - c) * v;
    }
    let sy = (syl[0] + syl[1]) + (syl[2] + syl[3]);
    let sty = (styl[0] + styl[1]) + (styl[2] + styl[3]);
    let nf = n as f64;
    let a = sy / nf;
    let b = sty / (nf * (nf * nf - 1.0) / 12.0);
    let e = |k: usize| y(k) - a - b * (k as f64 - c);
    // For difference order d, z^d_k over k < n - d; per order: S1, S2, P = sum z_k z_{k+1},
    // the first and the last value. The loop is written once per number of orders (const
    // generic) so the orders are computed in straight-line code. Order 0 alone first: most
    // taus of an IMU log are white-noise dominated (rho < 0.25 at d = 0) and stop there; the
    // higher orders are summed (with order 0 again) only when needed. Each order's sums are
    // accumulated by the same code whatever the number of orders, so the result is the same.
    let rho_of = |sums: &AcfSums, d: usize| -> f64 {
        let (s1, s2, p, first, prev) = sums;
        // ACF about the mean mu: sum (z_k - mu)(z_{k+1} - mu)
        //   = P - mu (S1 - z_last) - mu (S1 - z_0) + (len - 1) mu^2.
        let lf = (n - d) as f64;
        let mu = s1[d] / lf;
        let num = p[d] - mu * (s1[d] - prev[d]) - mu * (s1[d] - first[d]) + (lf - 1.0) * mu * mu;
        let den = s2[d] - lf * mu * mu;
        let r1 = num / den;
        r1 / (1.0 + r1)
    };
    let alpha = |rho: f64, d: usize| Some(NoiseId::new(rho, d, n - d, 0));
    let rho = rho_of(&acf_sums::<1>(n, e), 0);
    if rho < 0.25 || d_max == 0 {
        return alpha(rho, 0);
    }
    let sums = match d_max {
        1 => acf_sums::<2>(n, e),
        2 => acf_sums::<3>(n, e),
        _ => acf_sums::<4>(n, e),
    };
    for d in 1..=d_max {
        let rho = rho_of(&sums, d);
        if rho < 0.25 || d >= d_max {
            return alpha(rho, d);
        }
    }
    None
}

type AcfSums = ([f64; 4], [f64; 4], [f64; 4], [f64; 4], [f64; 4]);

/// (S1, S2, P, first, last) of the difference sequences of orders 0..D-1 of e(0..n).
#[inline(always)]
fn acf_sums<const D: usize>(n: usize, e: impl Fn(usize) -> f64) -> AcfSums {
    let mut s1 = [0.0f64; 4];
    let mut s2 = [0.0f64; 4];
    let mut p = [0.0f64; 4];
    let mut first = [0.0f64; 4];
    let mut prev = [0.0f64; 4];
    // Sliding window of the last values: w[0] = e(k), w[1] = e(k-1), ...
    let mut w = [0.0f64; 4];
    let diff = |w: &[f64; 4], d: usize| -> f64 {
        // d-th backward difference ending at k (= forward difference at k - d)
        match d {
            0 => w[0],
            1 => w[0] - w[1],
            2 => w[0] - 2.0 * w[1] + w[2],
            _ => w[0] - 3.0 * w[1] + 3.0 * w[2] - w[3],
        }
    };
    // Prologue: the first D samples start the sequences of increasing order.
    for k in 0..D.min(n) {
        w = [e(k), w[0], w[1], w[2]];
        for d in 0..=k {
            let z = diff(&w, d);
            s1[d] += z;
            s2[d] += z * z;
            if k == d {
                first[d] = z;
            } else {
                p[d] += prev[d] * z;
            }
            prev[d] = z;
        }
    }
    // Main loop in groups of four samples, one accumulator lane per position in the group
    // (independent addition chains instead of one latency-bound chain per sum), lanes added in
    // a fixed order at the end.
    let mut l1 = [[0.0f64; 4]; D];
    let mut l2 = [[0.0f64; 4]; D];
    let mut lp = [[0.0f64; 4]; D];
    let mut k = D;
    while k + 4 <= n {
        // ev[3 + j] = e(k + j), ev[2] = e(k - 1), ... (the window w holds the last four)
        let ev = [w[2], w[1], w[0], e(k), e(k + 1), e(k + 2), e(k + 3)];
        for d in 0..D {
            let mut zp = prev[d];
            for l in 0..4 {
                let j = 3 + l;
                let z = match d {
                    0 => ev[j],
                    1 => ev[j] - ev[j - 1],
                    2 => ev[j] - 2.0 * ev[j - 1] + ev[j - 2],
                    _ => ev[j] - 3.0 * ev[j - 1] + 3.0 * ev[j - 2] - ev[j - 3],
                };
                l1[d][l] += z;
                l2[d][l] += z * z;
                lp[d][l] += zp * z;
                zp = z;
            }
            prev[d] = zp;
        }
        w = [ev[6], ev[5], ev[4], ev[3]];
        k += 4;
    }
    for d in 0..D {
        let sum = |a: &[f64; 4]| (a[0] + a[1]) + (a[2] + a[3]);
        s1[d] += sum(&l1[d]);
        s2[d] += sum(&l2[d]);
        p[d] += sum(&lp[d]);
    }
    for k in k..n {
        w = [e(k), w[0], w[1], w[2]];
        for d in 0..D {
            let z = diff(&w, d);
            s1[d] += z;
            s2[d] += z * z;
            p[d] += prev[d] * z;
            prev[d] = z;
        }
    }
    (s1, s2, p, first, prev)
}

/// Riley 2004 eq (2): lag-1 autocorrelation about the mean.
fn lag1_acf(x: &[f64]) -> f64 {
    let mu = stats::mean(x);
    let a: f64 = x.windows(2).map(|w| (w[0] - mu) * (w[1] - mu)).sum();
    let b: f64 = x.iter().map(|v| (v - mu) * (v - mu)).sum();
    a / b
}

/// Remove the least-squares polynomial of degree `deg` (1 or 2) in the sample index.
fn detrend(x: &[f64], deg: usize) -> Vec<f64> {
    let n = x.len();
    // Centre and scale the abscissa to [-1, 1] for a well-conditioned normal system.
    let c = (n as f64 - 1.0) / 2.0;
    let h = c.max(1.0);
    let k = deg + 1;
    let mut ata = [[0.0f64; 3]; 3];
    let mut atb = [0.0f64; 3];
    for (i, &v) in x.iter().enumerate() {
        let t = (i as f64 - c) / h;
        let p = [1.0, t, t * t];
        for r in 0..k {
            atb[r] += p[r] * v;
            for s in 0..k {
                ata[r][s] += p[r] * p[s];
            }
        }
    }
    let coef = solve_small(ata, atb, k);
    x.iter()
        .enumerate()
        .map(|(i, &v)| {
            let t = (i as f64 - c) / h;
            let fit = coef[0] + coef[1] * t + if k > 2 { coef[2] * t * t } else { 0.0 };
            v - fit
        })
        .collect()
}

/// Gaussian elimination with partial pivoting on a k x k system (k <= 3).
fn solve_small(mut a: [[f64; 3]; 3], mut b: [f64; 3], k: usize) -> [f64; 3] {
    for col in 0..k {
        let piv = (col..k)
            .max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))
            .unwrap_or(col);
        a.swap(col, piv);
        b.swap(col, piv);
        for row in col + 1..k {
            let fct = a[row][col] / a[col][col];
            let pivot_row = a[col];
            for (dst, src) in a[row][col..k].iter_mut().zip(&pivot_row[col..k]) {
                *dst -= fct * src;
            }
            b[row] -= fct * b[col];
        }
    }
    let mut x = [0.0f64; 3];
    for row in (0..k).rev() {
        let mut s = b[row];
        for c2 in row + 1..k {
            s -= a[row][c2] * x[c2];
        }
        x[row] = s / a[row][row];
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rate_noise_id(y: &[f64], d_max: u32) -> Option<i32> {
        rate_noise_id_fn(y.len(), |k| y[k], d_max)
    }

    /// allantools' allocation-based procedure, for comparison.
    fn reference_rate_id(y: &[f64], d_max: u32) -> i32 {
        let mut x = detrend(y, 1);
        let mut d = 0;
        loop {
            let r1 = lag1_acf(&x);
            let rho = r1 / (1.0 + r1);
            if rho < 0.25 || d >= d_max {
                return -(2.0 * rho).round_ties_even() as i32 - 2 * d as i32;
            }
            x = x.windows(2).map(|w| w[1] - w[0]).collect();
            d += 1;
        }
    }

    #[test]
    fn single_pass_noise_id_matches_reference() {
        // White, random-walk and doubly integrated sequences with a trend: every noise class.
        let mut s = 12345u64;
        let mut u = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let white: Vec<f64> = (0..5000).map(|k| u() + 1e-4 * k as f64).collect();
        let mut acc = 0.0;
        let walk: Vec<f64> = white
            .iter()
            .map(|w| {
                acc += w;
                acc
            })
            .collect();
        let mut acc2 = 0.0;
        let walk2: Vec<f64> = walk
            .iter()
            .map(|w| {
                acc2 += w;
                acc2
            })
            .collect();
        let diffs: Vec<f64> = white.windows(2).map(|w| w[1] - w[0]).collect();
        for y in [&white, &walk, &walk2, &diffs] {
            for d_max in [2, 3] {
                assert_eq!(rate_noise_id(y, d_max), Some(reference_rate_id(y, d_max)));
            }
        }
        assert_eq!(rate_noise_id(&white, 2), Some(0));
        assert_eq!(rate_noise_id(&walk, 2), Some(-2));
        assert_eq!(rate_noise_id(&diffs, 2), Some(2));
    }

    #[test]
    fn greenhall_matches_allantools() {
        // allantools 2024.06 ci.edf_greenhall(alpha, d, m, N, overlapping, modified), printed
        // with repr(); tolerance 1e-12: same algorithm, only summation order differs.
        const REL_TOL: f64 = 1e-12;
        let cases: [(i32, u32, usize, usize, bool, bool, f64); 8] = [
            (0, 2, 1, 1000, true, false, 781.2476904305386),
            (0, 2, 16, 1000, true, false, 86.2817100528823),
            (-1, 2, 64, 20000, true, false, 364.9539502822036),
            (-2, 2, 256, 20000, false, false, 68.54335260115606),
            (1, 2, 8, 20000, true, false, 5614.854141227932),
            (2, 2, 4, 20000, false, false, 2570.66451701427),
            (0, 2, 32, 20000, true, true, 602.5346713637169),
            (-2, 3, 128, 20000, true, false, 148.92533461424443),
        ];
        for (alpha, d, m, n, ov, md, want) in cases {
            let got = greenhall(alpha, d, m, n, ov, md).unwrap();
            assert!(
                ((got - want) / want).abs() < REL_TOL,
                "{alpha} {d} {m}: {got} vs {want}"
            );
        }
    }
}
