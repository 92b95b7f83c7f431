//! IEEE 952 noise-term fit of an Allan deviation curve, and the spec-sheet readings.
//!
//! Model (docs/model.md §2, IEEE 952-1997 Annex C via Hou 2004 eqs 4.29, 4.36, 4.38, 4.53, 4.56):
//! sigma^2(tau) = 3 Q^2/tau^2 + N^2/tau + (2 ln 2/pi) B^2 + K^2 tau/3 + R^2 tau^2/2.
//! The five coefficients Q^2, N^2, B^2, K^2, R^2 enter linearly and are non-negative, so the
//! fit is a weighted non-negative least-squares problem. It is solved exactly by trying every
//! subset of active terms (2^5 = 32 small systems; the NNLS optimum is the best feasible
//! subset solution), with weights 1/Var(avar_i), Var(avar) = 2 avar^2/edf (chi-squared with
//! edf degrees of freedom, SP 1065 §5.2). That solution starts a Gauss–Newton refinement of the
//! same weighted least squares in ln(avar) (Var(ln avar) = 2/edf), keeping the coefficients
//! non-negative by dropping a term that reaches zero.
//!
//! Uncertainties: the covariance (A^T W A)^-1 of the active coefficients, scaled by the reduced
//! chi-square when it exceeds 1 and by a factor for the correlation of neighbouring taus
//! (calibrated by simulation, see `correlation_inflation`); a coefficient's standard error is
//! carried to its square root by the delta method.
//!
//! Readings, as a spec sheet takes them from the curve (Woodman TR-696 §5.1, IEEE 952):
//! ARW = value at tau = 1 s of the slope -1/2 line touching the curve from below,
//! bias instability = minimum of the deviation (Woodman) and B = minimum / 0.664 (IEEE),
//! RRW = value at tau = 3 s of the slope +1/2 line touching the curve from below,
//! quantisation = value at tau = sqrt 3 s of the slope -1 line touching the curve.

use crate::AllanPoint;
use serde::{Deserialize, Serialize};

/// sqrt(2 ln 2 / pi): the flicker plateau in units of B (docs/model.md §2, IEEE 952).
pub const BI_PLATEAU_FACTOR: f64 = 0.664_282_470_267_960_1;

/// Names of the five terms, in the docs/cli.md spelling of their parameters.
pub const TERM_NAMES: [&str; 5] = ["q", "n", "b", "k", "r"];

/// Term coefficient with its standard error (both SI: Q in unit*s, N in unit*sqrt(s),
/// B in unit, K in unit/sqrt(s), R in unit/s, where unit is the unit of the rate samples).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Term {
    pub value: f64,
    pub sigma: f64,
}

/// Spec-sheet readings of a curve.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Readings {
    /// Slope -1/2 line touching the curve, at tau = 1 s (ARW / VRW, unit*sqrt(s)).
    pub arw_at_1s: f64,
    /// tau where that line touches, s.
    pub arw_tau_s: f64,
    /// Minimum of the deviation (Woodman's bias stability), unit.
    pub bi_min: f64,
    /// tau of the minimum, s.
    pub bi_min_tau_s: f64,
    /// IEEE coefficient B = minimum / 0.664, unit.
    pub bi_ieee: f64,
    /// Slope +1/2 line touching the curve, at tau = 3 s (RRW K, unit/sqrt(s)).
    pub rrw_at_3s: f64,
    /// tau where that line touches, s.
    pub rrw_tau_s: f64,
    /// Slope -1 line touching the curve, at tau = sqrt 3 s (quantisation Q, unit*s).
    pub q_at_sqrt3s: f64,
}

/// Result of [`fit_ieee952`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Fit {
    pub q: Option<Term>,
    pub n: Option<Term>,
    pub b: Option<Term>,
    pub k: Option<Term>,
    pub r: Option<Term>,
    /// Weighted residual sum of squares (in ln avar) divided by the degrees of freedom,
    /// before any model-error variance was added.
    pub reduced_chi2: f64,
    /// Relative model-error standard deviation added to every point's ln(avar) so that the
    /// reduced chi-square is 1 (0 when the model fits within the statistical scatter).
    pub model_error: f64,
    pub readings: Readings,
}

impl Fit {
    /// The terms in the order q, n, b, k, r.
    pub fn terms(&self) -> [Option<Term>; 5] {
        [self.q, self.n, self.b, self.k, self.r]
    }

    /// The model Allan deviation at tau.
    pub fn model_dev(&self, tau_s: f64) -> f64 {
        let c = self.terms().map(|t| t.map_or(0.0, |t| t.value * t.value));
        basis(tau_s)
            .iter()
            .zip(c)
            .map(|(g, c)| g * c)
            .sum::<f64>()
            .sqrt()
    }

    /// The model deviation of one term alone (index into q, n, b, k, r).
    pub fn term_dev(&self, term: usize, tau_s: f64) -> Option<f64> {
        let t = self.terms()[term]?;
        Some((basis(tau_s)[term] * t.value * t.value).sqrt())
    }
}

/// The Allan variance of each term per unit coefficient^2 at tau (docs/model.md §2 table).
pub fn basis(tau_s: f64) -> [f64; 5] {
    [
        3.0 / (tau_s * tau_s),
        1.0 / tau_s,
        BI_PLATEAU_FACTOR * BI_PLATEAU_FACTOR,
        tau_s / 3.0,
        tau_s * tau_s / 2.0,
    ]
}

/// A point's degrees of freedom for the fit and the readings: its EDF (without one, the number of
/// terms), at most the white-FM value 1.5 (bins + 1). Greenhall's EDF of the Allan variance of
/// rate noise with alpha <= 0 (white, flicker and random-walk FM, the noises of an IMU's rate
/// at averaging times of many samples) is at most about 1.5 N/m (NIST SP 1065 Table 5, white FM:
/// edf = [3(N-1)/(2m) - 2(N-2)/N] 4m^2/(4m^2+5)); only PM-type noise (alpha > 0) has more. The
/// lag-1 ACF identification with few blocks can return alpha = 1 on white rate noise (seen:
/// 10-minute white-noise logs at 100 Hz, 58 and 117 blocks), whose EDF is then several times too
/// large; the cap keeps such a point from weighing more than white noise allows.
pub fn capped_edf(p: &AllanPoint) -> f64 {
    let edf = if p.edf.is_finite() && p.edf > 0.0 {
        p.edf
    } else {
        p.n_terms.max(1) as f64
    };
    edf.min(1.5 * (p.bins as f64 + 1.0))
}

/// Which terms the fit may use (all by default).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FitTerms(pub [bool; 5]);

impl Default for FitTerms {
    fn default() -> Self {
        FitTerms([true; 5])
    }
}

/// Fit all five IEEE 952 terms to a deviation curve.
pub fn fit_ieee952(points: &[AllanPoint]) -> Fit {
    fit_ieee952_terms(points, FitTerms::default())
}

/// Fit the allowed IEEE 952 terms to a deviation curve (points with a non-finite or zero
/// deviation are ignored; points without an EDF are weighted with edf = number of terms).
pub fn fit_ieee952_terms(points: &[AllanPoint], allowed: FitTerms) -> Fit {
    let pts: Vec<&AllanPoint> = points
        .iter()
        .filter(|p| p.dev.is_finite() && p.dev > 0.0)
        .collect();
    // The weights below are 1 / (var_ln avar^2), and the normal equations square them again:
    // an Allan variance beyond about 1e+-75 overflows or underflows f64 there (IEEE 754: 1.8e308,
    // 4.9e-324; a log of values near 1e90 got a fit with no term at all). Such a curve is fitted
    // scaled by 4^-m into range and its terms scaled back by 2^m: powers of two, exact in binary
    // floating point, and a curve already in range (every sensor's) is not scaled at all.
    let y: Vec<f64> = pts.iter().map(|p| p.dev * p.dev).collect();
    let m = range_exponent(&y);
    let y: Vec<f64> = y.iter().map(|v| v * 0.25f64.powi(m)).collect();
    let edf: Vec<f64> = pts.iter().map(|p| capped_edf(p)).collect();
    let g: Vec<[f64; 5]> = pts.iter().map(|p| basis(p.tau_s)).collect();

    // Start: linear NNLS with weights from the measured variances; then the maximum-likelihood
    // refinement in ln(avar), whose variance is 2/edf whatever the level (weighting by the model
    // in the linear domain would make over-shooting cheap). When the model cannot describe the
    // curve (reduced chi-square > 1: filters, correlated noise the five terms lack), a relative
    // model-error variance f^2 is added to every point, chosen so the reduced chi-square is 1
    // (the "extra variance" of a random-effects fit); otherwise the few points with huge EDF
    // would dictate the fit.
    let base: Vec<f64> = edf.iter().map(|d| 2.0 / d).collect();
    let mut var_ln = base.clone();
    let mut best = Solution::empty();
    let mut model_error = 0.0f64;
    let mut raw_reduced_chi2 = f64::NAN;
    for _ in 0..4 {
        let w: Vec<f64> = y
            .iter()
            .zip(&var_ln)
            .map(|(e, v)| 1.0 / (v * e * e))
            .collect();
        let start = nnls_subsets(&g, &y, &w, allowed.0);
        best = refine_log(&g, &y, &var_ln, start);
        let n_active = best.active.iter().filter(|&&a| a).count();
        let dof = pts.len().saturating_sub(n_active).max(1) as f64;
        let r2: Vec<f64> = g
            .iter()
            .zip(&y)
            .map(|(gi, yi)| {
                let m: f64 = gi.iter().zip(&best.coef).map(|(a, c)| a * c).sum();
                (yi.ln() - m.max(1e-300).ln()).powi(2)
            })
            .collect();
        let chi2_at = |f2: f64| r2.iter().zip(&base).map(|(r, v)| r / (v + f2)).sum::<f64>() / dof;
        if raw_reduced_chi2.is_nan() {
            raw_reduced_chi2 = chi2_at(0.0);
        }
        if chi2_at(0.0) <= 1.0 {
            break;
        }
        let f2 = unit_chi2_variance(chi2_at);
        if (f2.sqrt() - model_error).abs() <= 1e-3 * f2.sqrt() {
            break;
        }
        model_error = f2.sqrt();
        var_ln = base.iter().map(|v| v + f2).collect();
    }
    let n_active = best.active.iter().filter(|&&a| a).count();
    let dof = pts.len().saturating_sub(n_active).max(1);
    let inflate = (best.rss / dof as f64).max(1.0) * correlation_inflation(&pts);
    let reduced_chi2 = raw_reduced_chi2;
    let terms = best.terms(inflate).map(|t| {
        t.map(|t| Term {
            value: t.value * 2f64.powi(m),
            sigma: t.sigma * 2f64.powi(m),
        })
    });
    Fit {
        q: terms[0],
        n: terms[1],
        b: terms[2],
        k: terms[3],
        r: terms[4],
        reduced_chi2,
        model_error,
        readings: readings(points),
    }
}

/// The fit's coefficients refitted on parts of the curve: how much each one depends on which taus
/// it is fitted to. Where the five terms do not describe the curve (reduced chi-square far above
/// what the five-term model's own logs give), the statistical sigma says little about that; the
/// spread of the refits says how much a coefficient moves with the taus, i.e. what the misfit
/// means for the number printed.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SubrangeSpread {
    /// Per term (q, n, b, k, r): the smallest and largest value over the refits (a refit without
    /// the term counts as 0), SI; NaN for a term the whole fit does not have.
    pub lo: [f64; 5],
    pub hi: [f64; 5],
    /// The number of refits (0: too few points to leave a part out).
    pub refits: usize,
}

/// Parts of the curve left out in turn by [`subrange_spread`]: each quarter of its taus.
pub const SUBRANGE_PARTS: usize = 4;

/// The fit of `points` refitted [`SUBRANGE_PARTS`] times, each time without one contiguous part
/// (a quarter) of its taus: a leave-one-block-out (delete-d jackknife over tau blocks, Efron &
/// Tibshirani, *An Introduction to the Bootstrap*, 1993, §11.7), blocks because neighbouring
/// Allan points are correlated. Each part holds at least 2 points; fewer than 8 usable points:
/// no refit.
pub fn subrange_spread(points: &[AllanPoint], fit: &Fit) -> SubrangeSpread {
    let pts: Vec<AllanPoint> = points
        .iter()
        .filter(|p| p.dev.is_finite() && p.dev > 0.0)
        .cloned()
        .collect();
    let n = pts.len();
    let has = fit.terms().map(|t| t.is_some());
    let mut lo = has.map(|h| if h { f64::INFINITY } else { f64::NAN });
    let mut hi = has.map(|h| if h { f64::NEG_INFINITY } else { f64::NAN });
    if n < 2 * SUBRANGE_PARTS {
        return SubrangeSpread {
            lo: [f64::NAN; 5],
            hi: [f64::NAN; 5],
            refits: 0,
        };
    }
    for part in 0..SUBRANGE_PARTS {
        let (a, b) = (part * n / SUBRANGE_PARTS, (part + 1) * n / SUBRANGE_PARTS);
        let rest: Vec<AllanPoint> = pts[..a].iter().chain(&pts[b..]).cloned().collect();
        let refit = fit_ieee952(&rest);
        for (j, t) in refit.terms().iter().enumerate() {
            if has[j] {
                let v = t.map_or(0.0, |t| t.value);
                lo[j] = lo[j].min(v);
                hi[j] = hi[j].max(v);
            }
        }
    }
    SubrangeSpread {
        lo,
        hi,
        refits: SUBRANGE_PARTS,
    }
}

/// The m by which a curve of Allan variances `y` is scaled (by 4^-m) for the fit: 0 when its
/// largest value lies within 1e-50 ..= 1e50, else the one bringing it near 1.
fn range_exponent(y: &[f64]) -> i32 {
    let top = y.iter().copied().fold(0.0f64, f64::max);
    if top == 0.0 || (1e-50..=1e50).contains(&top) {
        return 0;
    }
    (top.log2() / 2.0).round() as i32
}

/// Variance inflation for the correlation of Allan estimates at neighbouring taus (the
/// covariance above treats them as independent). Rule: 2 x (points per octave, at least 1).
/// Calibrated on 20 generated logs with Q, N, B, K (tests/fit_generated.rs,
/// `calibration_many_seeds`; white-dominated configuration, N = 1e-3, K = 3e-6): without it the
/// RMS of (estimate - truth)/sigma was 1.40 on an octave grid and 1.62 on a 5-per-decade grid
/// (1.5 points per octave); the rule gives factors 2 and 3, i.e. RMS 0.99 and 0.94. On the
/// test's present configuration (each term dominating a range, N = 3e-4, K = 6e-6) the RMS is
/// 1.21: the stated sigmas are then about 20 % optimistic.
fn correlation_inflation(pts: &[&AllanPoint]) -> f64 {
    let (lo, hi) = pts.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), p| {
        (lo.min(p.tau_s), hi.max(p.tau_s))
    });
    if pts.len() < 2 || hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
        return 2.0;
    }
    let per_octave = (pts.len() - 1) as f64 / (hi / lo).log2();
    2.0 * per_octave.max(1.0)
}

struct Solution {
    coef: [f64; 5],
    cov: [[f64; 5]; 5],
    active: [bool; 5],
    rss: f64,
}

impl Solution {
    fn empty() -> Solution {
        Solution {
            coef: [0.0; 5],
            cov: [[0.0; 5]; 5],
            active: [false; 5],
            rss: f64::INFINITY,
        }
    }

    /// The terms (square roots of the positive active coefficients) with their standard errors,
    /// the covariance scaled by `inflate`.
    fn terms(&self, inflate: f64) -> [Option<Term>; 5] {
        let mut terms: [Option<Term>; 5] = [None; 5];
        for (j, t) in terms.iter_mut().enumerate() {
            if self.active[j] && self.coef[j] > 0.0 {
                let value = self.coef[j].sqrt();
                let sigma_c = (self.cov[j][j] * inflate).sqrt();
                // delta method: d sqrt(c) = dc / (2 sqrt c)
                *t = Some(Term {
                    value,
                    sigma: sigma_c / (2.0 * value),
                });
            }
        }
        terms
    }
}

/// The model variance sum_j c_j g_j(tau) of one point.
fn model(c: &[f64; 5], gi: &[f64; 5]) -> f64 {
    gi.iter().zip(c).map(|(a, b)| a * b).sum()
}

/// The extra relative variance f^2 at which the reduced chi-square `chi2_at(f^2)` (decreasing in
/// f^2) is 1: bracketed by quadrupling from 1 (up to 1e6), then 60 bisections.
fn unit_chi2_variance(chi2_at: impl Fn(f64) -> f64) -> f64 {
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    while chi2_at(hi) > 1.0 && hi < 1e6 {
        hi *= 4.0;
    }
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if chi2_at(mid) > 1.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Normal equations (J^T W J, J^T W r) of the log residuals r_i = ln y_i - ln m_i in the scaled
/// variables u_j = c_j / coef_j of the active coefficients `idx` (relative steps).
fn log_normal_equations(
    g: &[[f64; 5]],
    y: &[f64],
    w: &[f64],
    coef: &[f64; 5],
    idx: &[usize],
) -> (Vec<Vec<f64>>, Vec<f64>) {
    let k = idx.len();
    let mut jtj = vec![vec![0.0f64; k]; k];
    let mut jtr = vec![0.0f64; k];
    for ((gi, yi), wi) in g.iter().zip(y).zip(w) {
        let m = model(coef, gi);
        let r = yi.ln() - m.ln();
        let jac: Vec<f64> = idx.iter().map(|&j| gi[j] * coef[j] / m).collect();
        for a in 0..k {
            jtr[a] += wi * jac[a] * r;
            for b in 0..k {
                jtj[a][b] += wi * jac[a] * jac[b];
            }
        }
    }
    (jtj, jtr)
}

/// Gauss–Newton on sum_i (ln y_i - ln m_i(c))^2 / var_ln_i over the active coefficients, with
/// step halving; a coefficient driven to zero leaves the active set.
fn refine_log(g: &[[f64; 5]], y: &[f64], var_ln: &[f64], start: Solution) -> Solution {
    let w: Vec<f64> = var_ln.iter().map(|v| 1.0 / v).collect();
    let cost = |c: &[f64; 5]| -> f64 {
        g.iter()
            .zip(y)
            .zip(&w)
            .map(|((gi, yi), wi)| {
                let m = model(c, gi);
                if m > 0.0 {
                    wi * (yi.ln() - m.ln()).powi(2)
                } else {
                    f64::INFINITY
                }
            })
            .sum()
    };
    let mut coef = start.coef;
    let mut active = start.active;
    let mut current = cost(&coef);
    if !current.is_finite() {
        return start;
    }
    let mut cov = [[0.0f64; 5]; 5];
    for _ in 0..100 {
        let idx: Vec<usize> = (0..5).filter(|&j| active[j]).collect();
        let k = idx.len();
        if k == 0 {
            break;
        }
        // Normal equations in scaled variables u_j = c_j / coef_j (relative steps).
        let (jtj, jtr) = log_normal_equations(g, y, &w, &coef, &idx);
        let Some(inv) = invert(&jtj) else { break };
        for a in 0..k {
            for b in 0..k {
                cov[idx[a]][idx[b]] = inv[a][b] * coef[idx[a]] * coef[idx[b]];
            }
        }
        let du: Vec<f64> = (0..k)
            .map(|a| (0..k).map(|b| inv[a][b] * jtr[b]).sum())
            .collect();
        let mut step = 1.0;
        let mut accepted = false;
        while step > 1e-6 {
            let mut trial = coef;
            for (a, &j) in idx.iter().enumerate() {
                trial[j] = coef[j] * (1.0 + step * du[a]);
            }
            if let Some(a) = (0..k).find(|&a| trial[idx[a]] <= 0.0) {
                // Would cross zero: try the model without that term.
                let mut dropped = coef;
                dropped[idx[a]] = 0.0;
                let cd = cost(&dropped);
                if cd <= current * (1.0 + 1e-12) {
                    coef = dropped;
                    active[idx[a]] = false;
                    current = cd;
                    accepted = true;
                    break;
                }
                step *= 0.5;
                continue;
            }
            let ct = cost(&trial);
            if ct <= current {
                let converged = current - ct <= 1e-12 * current.max(1e-300);
                coef = trial;
                current = ct;
                accepted = !converged;
                break;
            }
            step *= 0.5;
        }
        if !accepted {
            break;
        }
    }
    for j in 0..5 {
        if !active[j] {
            coef[j] = 0.0;
            cov[j] = [0.0; 5];
            for row in cov.iter_mut() {
                row[j] = 0.0;
            }
        }
    }
    Solution {
        coef,
        cov,
        active,
        rss: current,
    }
}

/// A weighted least-squares system in column-scaled variables u_a = c_{idx a} * scale_a.
pub(crate) struct ScaledLs {
    /// s_a = sqrt(sum_i w_i g_i[idx a]^2) (column scaling for conditioning).
    pub scale: Vec<f64>,
    /// (A^T W A)^-1 in the scaled variables.
    pub inv: Vec<Vec<f64>>,
    /// A^T W y in the scaled variables.
    pub atb: Vec<f64>,
}

/// The normal equations of y on the columns `idx` of g with weights w, column-scaled and
/// inverted; `None` when a column is empty or the system singular.
pub(crate) fn scaled_ls(g: &[[f64; 5]], y: &[f64], w: &[f64], idx: &[usize]) -> Option<ScaledLs> {
    let k = idx.len();
    let scale: Vec<f64> = idx
        .iter()
        .map(|&j| {
            g.iter()
                .zip(w)
                .map(|(gi, wi)| wi * gi[j] * gi[j])
                .sum::<f64>()
                .sqrt()
        })
        .collect();
    if scale.iter().any(|s| s.is_nan() || *s <= 0.0) {
        return None;
    }
    let mut ata = vec![vec![0.0f64; k]; k];
    let mut atb = vec![0.0f64; k];
    for ((gi, yi), wi) in g.iter().zip(y).zip(w) {
        for a in 0..k {
            let ga = gi[idx[a]] / scale[a];
            atb[a] += wi * ga * yi;
            for b in 0..k {
                ata[a][b] += wi * ga * gi[idx[b]] / scale[b];
            }
        }
    }
    let inv = invert(&ata)?;
    Some(ScaledLs { scale, inv, atb })
}

/// Exact NNLS over 5 columns by enumerating the active sets.
fn nnls_subsets(g: &[[f64; 5]], y: &[f64], w: &[f64], allowed: [bool; 5]) -> Solution {
    let mut best = Solution::empty();
    // Smaller active sets first; a larger one wins only if it lowers the weighted residual by
    // more than rounding (each weighted residual is O(1), so 1e-9 per point is rounding).
    let mut masks: Vec<u32> = (0u32..32).collect();
    masks.sort_by_key(|m| m.count_ones());
    let rounding = 1e-9 * y.len() as f64;
    for mask in masks {
        let active: [bool; 5] = std::array::from_fn(|j| mask & (1 << j) != 0);
        if (0..5).any(|j| active[j] && !allowed[j]) {
            continue;
        }
        let idx: Vec<usize> = (0..5).filter(|&j| active[j]).collect();
        let k = idx.len();
        if k > y.len() {
            continue;
        }
        let mut coef = [0.0f64; 5];
        let mut cov = [[0.0f64; 5]; 5];
        if k > 0 {
            let Some(ScaledLs { scale, inv, atb }) = scaled_ls(g, y, w, &idx) else {
                continue;
            };
            let sol: Vec<f64> = (0..k)
                .map(|a| (0..k).map(|b| inv[a][b] * atb[b]).sum())
                .collect();
            if sol.iter().any(|&c| c <= 0.0) {
                continue;
            }
            for a in 0..k {
                coef[idx[a]] = sol[a] / scale[a];
                for b in 0..k {
                    cov[idx[a]][idx[b]] = inv[a][b] / (scale[a] * scale[b]);
                }
            }
        }
        let rss: f64 = g
            .iter()
            .zip(y)
            .zip(w)
            .map(|((gi, yi), wi)| {
                let m: f64 = gi.iter().zip(&coef).map(|(a, c)| a * c).sum();
                wi * (yi - m) * (yi - m)
            })
            .sum();
        if rss < best.rss - rounding || !best.rss.is_finite() {
            best = Solution {
                coef,
                cov,
                active,
                rss,
            };
        }
    }
    best
}

/// Gauss–Jordan inverse with partial pivoting; `None` if singular.
fn invert(a: &[Vec<f64>]) -> Option<Vec<Vec<f64>>> {
    let k = a.len();
    let mut m: Vec<Vec<f64>> = a
        .iter()
        .enumerate()
        .map(|(i, row)| {
            let mut r = row.clone();
            r.extend((0..k).map(|j| if i == j { 1.0 } else { 0.0 }));
            r
        })
        .collect();
    for col in 0..k {
        let piv = (col..k).max_by(|&i, &j| m[i][col].abs().total_cmp(&m[j][col].abs()))?;
        if m[piv][col].abs() < 1e-300 {
            return None;
        }
        m.swap(col, piv);
        let p = m[col][col];
        for v in m[col].iter_mut() {
            *v /= p;
        }
        let pivot_row = m[col].clone();
        for (r, row) in m.iter_mut().enumerate() {
            if r != col {
                let f = row[col];
                for (dst, src) in row.iter_mut().zip(&pivot_row) {
                    *dst -= f * src;
                }
            }
        }
    }
    let inv: Vec<Vec<f64>> = m.into_iter().map(|r| r[k..].to_vec()).collect();
    // Reject numerically singular systems (the inverse must reproduce the identity).
    let ok = (0..k).all(|i| {
        (0..k).all(|j| {
            let v: f64 = (0..k).map(|l| a[i][l] * inv[l][j]).sum();
            (v - if i == j { 1.0 } else { 0.0 }).abs() < 1e-6
        })
    });
    ok.then_some(inv)
}

/// The spec-sheet readings of a curve (tangent lines and minimum).
pub fn readings(points: &[AllanPoint]) -> Readings {
    let pts: Vec<&AllanPoint> = points
        .iter()
        .filter(|p| p.dev.is_finite() && p.dev > 0.0)
        .collect();
    let argmin = |f: &dyn Fn(&AllanPoint) -> f64| -> (f64, f64) {
        pts.iter()
            .map(|p| (f(p), p.tau_s))
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .unwrap_or((f64::NAN, f64::NAN))
    };
    let (arw, arw_tau) = argmin(&|p| p.dev * p.tau_s.sqrt());
    let (bi, bi_tau) = argmin(&|p| p.dev);
    let (rrw, rrw_tau) = argmin(&|p| p.dev * (3.0 / p.tau_s).sqrt());
    let (q, _) = argmin(&|p| p.dev * p.tau_s / 3f64.sqrt());
    Readings {
        arw_at_1s: arw,
        arw_tau_s: arw_tau,
        bi_min: bi,
        bi_min_tau_s: bi_tau,
        bi_ieee: bi / BI_PLATEAU_FACTOR,
        rrw_at_3s: rrw,
        rrw_tau_s: rrw_tau,
        q_at_sqrt3s: q,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(tau_s: f64, dev: f64, edf: f64) -> AllanPoint {
        AllanPoint {
            tau_s,
            m: 1,
            dev,
            n_terms: 1000,
            edf,
            lo: f64::NAN,
            hi: f64::NAN,
            bins: 1000,
            alpha: 0,
        }
    }

    #[test]
    fn plateau_factor_is_sqrt_2ln2_over_pi() {
        let exact = (2.0 * std::f64::consts::LN_2 / std::f64::consts::PI).sqrt();
        assert!((BI_PLATEAU_FACTOR - exact).abs() < 1e-16);
    }

    #[test]
    fn exact_model_curve_is_recovered() {
        // A noiseless curve of the model itself: the fit must return the coefficients to
        // rounding (1e-6 relative allows for the conditioning of the 5-term system).
        let truth = [2e-4, 1e-3, 1e-4, 3e-6, 1e-8];
        let pts: Vec<AllanPoint> = (0..40)
            .map(|i| {
                let tau = 0.01 * 10f64.powf(i as f64 / 7.0);
                let var: f64 = basis(tau).iter().zip(truth).map(|(g, c)| g * c * c).sum();
                point(tau, var.sqrt(), 1000.0)
            })
            .collect();
        let fit = fit_ieee952(&pts);
        for (t, want) in fit.terms().iter().zip(truth) {
            let got = t.unwrap().value;
            assert!(((got - want) / want).abs() < 1e-6, "{got} vs {want}");
        }
        assert!(fit.reduced_chi2 < 1e-12);
    }

    /// A curve of deviations near 1e90 (or 1e-90) is fitted as the same curve near 1: its
    /// squared weights overflowed (underflowed) and the fit had no term at all.
    #[test]
    fn curves_far_from_unit_scale_are_fitted_alike() {
        let truth = [2e-4, 1e-3, 1e-4, 3e-6, 1e-8];
        for scale in [1e90, 1e-90, 1e60] {
            let pts: Vec<AllanPoint> = (0..40)
                .map(|i| {
                    let tau = 0.01 * 10f64.powf(i as f64 / 7.0);
                    let var: f64 = basis(tau).iter().zip(&truth).map(|(g, c)| g * c * c).sum();
                    point(tau, var.sqrt() * scale, 1000.0)
                })
                .collect();
            let fit = fit_ieee952(&pts);
            for (t, want) in fit.terms().iter().zip(truth) {
                let got = t.expect("every term present").value / scale;
                assert!(
                    ((got - want) / want).abs() < 1e-6,
                    "{scale}: {got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn absent_terms_stay_absent_and_readings_follow_definitions() {
        // Pure white noise N = 0.01: only n is fitted; the -1/2 line at 1 s reads N exactly;
        // the minimum is at the longest tau.
        let pts: Vec<AllanPoint> = (0..20)
            .map(|i| point(2f64.powi(i), 0.01 / 2f64.powi(i).sqrt(), 500.0))
            .collect();
        let fit = fit_ieee952(&pts);
        assert!(fit.q.is_none() && fit.b.is_none() && fit.k.is_none() && fit.r.is_none());
        assert!((fit.n.unwrap().value - 0.01).abs() < 1e-12);
        assert!((fit.readings.arw_at_1s - 0.01).abs() < 1e-15);
        assert_eq!(fit.readings.bi_min_tau_s, 2f64.powi(19));
        assert!((fit.readings.bi_ieee * BI_PLATEAU_FACTOR - fit.readings.bi_min).abs() < 1e-18);
    }
}
