//! When a fitted IEEE 952 term counts as resolved: its Wald statistic against the statistic's
//! own null distribution, simulated at the log's length (docs/allan.md "Resolved terms").
//!
//! The statistic of term j is t_j = c_j / sd(c_j), c_j its coefficient (Q^2, N^2, B^2, K^2,
//! R^2) in the weighted linear least squares of the Allan variances on the basis columns of the
//! fit's active terms and j (unconstrained, so t_j is signed and observed on every curve;
//! weights 1 / (m_i^2 (2 / edf_i + f^2)), m_i the fitted model's variance, f the fit's model
//! error: Var(avar) = 2 avar^2 / edf, SP 1065 §5.2). Its null distribution is not the normal one: neighbouring Allan points are correlated
//! and the long taus have few degrees of freedom (on 10-minute white-noise logs the fit's own
//! sigma <= value/2 rule claimed Q on 12 % and B on 8 % of logs). So it is simulated: the same
//! analysis (deviations, noise identification, EDF, fit, statistic) on `replicates` logs of the
//! null model at the log's length, sample interval and grid:
//! - for Q, B, K and R: white rate noise (the model without the term, for a log whose curve is
//!   white noise: the question each of these terms answers is whether the curve departs from it);
//! - for N: white angle noise (quantisation alone; the model without white rate noise).
//!
//! The threshold is the (1 - rate / family) quantile of the simulated statistics (`family` the
//! number of term claims the rate covers, 5 terms x the log's channels: Bonferroni). That
//! quantile (e.g. 1 - 0.01/30) lies beyond what a few hundred replicates reach, so the tail is
//! extrapolated by peaks over threshold (Pickands 1975; Davison & Smith 1990, JRSS B 52): beyond
//! the empirical (1 - p) quantile u (p = [`TAIL_SHARE`]) the excesses are taken as exponential
//! (the generalised Pareto law with shape 0) with their mean excess as scale, so
//! P(t > u + x) = p exp(-x / scale). The exponential tail is heavier than the normal one, so for
//! the near-normal statistics of Q and B it is conservative, and it follows the skewed K and R
//! statistics, whose tails a normal fitted by moments understated (3 false claims in 400 logs
//! where at most 0.5 were allowed; crates/allan/tests/null_terms.rs measures the rate).
//!
//! The thresholds depend only on the length, interval, estimator, grid and options, so they are
//! computed once per combination in a process and shared by the log's channels.

pub use crate::claims::ClaimLevel;
use crate::fit::{basis, capped_edf, scaled_ls, Fit, ScaledLs};
use crate::null_table::{Family, Grid};
use crate::{AllanPoint, EdfMethod, Estimator, Options, Series, TauGrid};
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

/// The share of the simulated statistics that forms the tail fitted beyond the empirical
/// quantile (peaks over threshold; 20 of the default 200 replicates).
pub const TAIL_SHARE: f64 = 0.1;

/// The null distribution's upper tail of the five statistics and the thresholds drawn from it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct NullThresholds {
    /// The empirical (1 - [`TAIL_SHARE`]) quantile of the simulated statistics.
    pub tail_start: [f64; 5],
    /// The mean excess of the statistics beyond it (the exponential tail's scale).
    pub tail_scale: [f64; 5],
    /// The statistic a term must exceed to count as resolved.
    pub threshold: [f64; 5],
}

/// The Wald statistic of each term j (q, n, b, k, r) of `fit` on `points` (module docs); 0
/// where the system is singular.
pub fn term_statistics(points: &[AllanPoint], fit: &Fit) -> [f64; 5] {
    let pts: Vec<&AllanPoint> = points
        .iter()
        .filter(|p| p.dev.is_finite() && p.dev > 0.0)
        .collect();
    let top = pts.iter().map(|p| p.dev * p.dev).fold(0.0f64, f64::max);
    if pts.is_empty() || top <= 0.0 {
        return [0.0; 5];
    }
    // Variances relative to the largest (t is unchanged by a common scale).
    let y: Vec<f64> = pts.iter().map(|p| p.dev * p.dev / top).collect();
    let w: Vec<f64> = pts
        .iter()
        .zip(&y)
        .map(|(p, yi)| {
            let m = fit.model_dev(p.tau_s).powi(2) / top;
            let v = if m > 0.0 { m } else { *yi };
            // Var(avar) = avar^2 Var(ln avar), Var(ln avar) = 2/edf plus the fit's model-error
            // variance (crate::fit: the share of the curve the five terms do not describe).
            1.0 / (v * v * (2.0 / capped_edf(p) + fit.model_error.powi(2)))
        })
        .collect();
    let g: Vec<[f64; 5]> = pts.iter().map(|p| basis(p.tau_s)).collect();
    let active = fit.terms().map(|t| t.is_some());
    std::array::from_fn(|j| {
        let idx: Vec<usize> = (0..5).filter(|&i| active[i] || i == j).collect();
        wald(&g, &y, &w, &idx, j).unwrap_or(0.0)
    })
}

/// c_j / sd(c_j) of the weighted least squares of y on the columns `idx` (crate::fit's
/// column-scaled system: the ratio is the same in scaled variables).
fn wald(g: &[[f64; 5]], y: &[f64], w: &[f64], idx: &[usize], j: usize) -> Option<f64> {
    if idx.len() > y.len() {
        return None;
    }
    let ScaledLs { inv, atb, .. } = scaled_ls(g, y, w, idx)?;
    let a = idx.iter().position(|&c| c == j)?;
    let c: f64 = (0..idx.len()).map(|b| inv[a][b] * atb[b]).sum();
    let sd = inv[a][a].sqrt();
    (sd > 0.0).then(|| c / sd)
}

type Key = (usize, u64, Estimator, String, String);

static CACHE: Mutex<Option<HashMap<Key, NullThresholds>>> = Mutex::new(None);

/// The shipped table (`crate::null_table`, generated by `scripts/null_table.sh`).
pub fn families() -> &'static [Family] {
    crate::null_table_data::FAMILIES
}

/// The thresholds from the shipped table ([`crate::null_table`]) for a log of `n_rate` rate
/// samples analysed with `est`, `grid` and `opts`, where the table covers the analysis: adev,
/// oadev or totdev on the octave or decade grid, Greenhall EDF with the noise identified per tau,
/// Stable32's stop ratio and (totdev) its bias correction, `opts.claims.table` set. `None`
/// elsewhere (the caller simulates).
pub fn tabulated_thresholds(
    n_rate: usize,
    est: Estimator,
    grid: &TauGrid,
    opts: &Options,
) -> Option<NullThresholds> {
    let covered = opts.claims.table
        && opts.claims.replicates > 0
        && opts.edf == EdfMethod::Greenhall
        && opts.alpha.is_none()
        && opts.stable32_stop
        && opts.totvar_bias_correction;
    if !covered {
        return None;
    }
    let g = Grid::of(grid)?;
    let family = families().iter().find(|f| f.est == est && f.grid == g)?;
    let (start, scale) = family.tail_at(n_rate)?;
    let r = family.replicates;
    let share = (TAIL_SHARE * r as f64).floor() / r as f64;
    Some(thresholds_of(start, scale, share, &opts.claims))
}

/// The thresholds for a log of `n_rate` rate samples every `tau0_s` seconds analysed with
/// `est`, `grid` and `opts`: from the shipped table where it covers the combination
/// ([`tabulated_thresholds`]: no simulation), else simulated ([`simulated_thresholds`], cached
/// per combination).
pub fn null_thresholds(
    n_rate: usize,
    tau0_s: f64,
    est: Estimator,
    grid: &TauGrid,
    opts: &Options,
) -> NullThresholds {
    null_thresholds_with(n_rate, tau0_s, est, grid, opts, &|_, _| {})
}

/// [`null_thresholds`] telling `tick(done, total)` after each simulated null log, for progress
/// displays (never called when the table answers).
pub fn null_thresholds_with(
    n_rate: usize,
    tau0_s: f64,
    est: Estimator,
    grid: &TauGrid,
    opts: &Options,
    tick: &(dyn Fn(usize, usize) + Sync),
) -> NullThresholds {
    let never = AtomicBool::new(false);
    null_thresholds_until(n_rate, tau0_s, est, grid, opts, tick, &never)
        .expect("a simulation without a stop request runs to its end")
}

/// [`null_thresholds_with`] that gives up when `stop` is set (read before each null log, one
/// atomic load each): `None` then, and nothing is cached.
pub fn null_thresholds_until(
    n_rate: usize,
    tau0_s: f64,
    est: Estimator,
    grid: &TauGrid,
    opts: &Options,
    tick: &(dyn Fn(usize, usize) + Sync),
    stop: &AtomicBool,
) -> Option<NullThresholds> {
    if opts.claims.replicates == 0 {
        return Some(NullThresholds {
            tail_start: [f64::NAN; 5],
            tail_scale: [f64::NAN; 5],
            threshold: [f64::INFINITY; 5],
        });
    }
    if let Some(t) = tabulated_thresholds(n_rate, est, grid, opts) {
        return Some(t);
    }
    let key: Key = (
        n_rate,
        tau0_s.to_bits(),
        est,
        format!("{grid:?}"),
        format!("{opts:?}"),
    );
    if let Some(t) = CACHE
        .lock()
        .ok()
        .and_then(|c| c.as_ref().and_then(|m| m.get(&key).copied()))
    {
        return Some(t);
    }
    let t = simulated_thresholds_until(n_rate, tau0_s, est, grid, opts, tick, stop)?;
    if let Ok(mut c) = CACHE.lock() {
        c.get_or_insert_with(HashMap::new).insert(key, t);
    }
    Some(t)
}

/// One null log's statistics: those of Q, B, K, R from white rate noise, N's from white angle
/// noise (its rate samples are the angle's differences over the interval). Replicate `i` is a
/// function of `i` alone, so a table built from replicates 0..R and a simulation of 0..r share
/// their first r logs.
pub fn replicate(
    i: usize,
    n_rate: usize,
    tau0_s: f64,
    est: Estimator,
    grid: &TauGrid,
    o: &Options,
) -> [f64; 5] {
    let never = AtomicBool::new(false);
    replicate_until(i, n_rate, tau0_s, est, grid, o, &never)
        .expect("a null log without a stop request runs to its end")
}

/// [`replicate`] that gives up when `stop` is set (`None` then): the flag is read by each of
/// its two logs' curves (per factor), so a stop lands within one pass over a log's samples.
fn replicate_until(
    i: usize,
    n_rate: usize,
    tau0_s: f64,
    est: Estimator,
    grid: &TauGrid,
    o: &Options,
    stop: &AtomicBool,
) -> Option<[f64; 5]> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(0x6e75_6c6c ^ i as u64);
    let mut draw =
        |n: usize| -> Vec<f64> { (0..n).map(|_| StandardNormal.sample(&mut rng)).collect() };
    let stats_of = |data: Vec<f64>| {
        let series = Series::from_rate(data, tau0_s);
        let (points, fit) = crate::curve::curve_and_fit(&series, est, grid, o, &|_| {}, stop)?;
        Some(term_statistics(&points, &fit))
    };
    let white = stats_of(draw(n_rate))?;
    if stop.load(Ordering::Relaxed) {
        return None;
    }
    let angle = draw(n_rate + 1);
    let white_angle = stats_of(angle.windows(2).map(|a| (a[1] - a[0]) / tau0_s).collect())?;
    let mut t = white;
    t[1] = white_angle[1];
    Some(t)
}

/// The upper tail of simulated null statistics: the empirical (1 - [`TAIL_SHARE`]) quantile and
/// the mean excess beyond it, per term (`None` for fewer than 20 statistics: no tail to fit).
pub fn tail_of(stats: &[[f64; 5]]) -> Option<([f64; 5], [f64; 5])> {
    let r = stats.len();
    let exceed = (TAIL_SHARE * r as f64).floor() as usize;
    if exceed < 2 {
        return None;
    }
    let mut start = [f64::NAN; 5];
    let mut scale = [f64::NAN; 5];
    for j in 0..5 {
        let mut v: Vec<f64> = stats.iter().map(|s| s[j]).collect();
        v.sort_by(f64::total_cmp);
        start[j] = v[r - exceed - 1];
        let excess: Vec<f64> = v[r - exceed..].iter().map(|x| x - start[j]).collect();
        scale[j] = ::stats::mean(&excess);
    }
    Some((start, scale))
}

/// The thresholds of a fitted exponential tail at `level`: P(t > u + x) = share exp(-x / scale)
/// = rate / family, share the fraction of statistics beyond u.
pub fn thresholds_of(
    tail_start: [f64; 5],
    tail_scale: [f64; 5],
    share: f64,
    level: &ClaimLevel,
) -> NullThresholds {
    let per_claim = level.rate / level.family.max(1) as f64;
    NullThresholds {
        tail_start,
        tail_scale,
        threshold: std::array::from_fn(|j| {
            tail_start[j] + tail_scale[j] * (share / per_claim).ln().max(0.0)
        }),
    }
}

/// The statistics of `replicates` null logs (replicates 0..`replicates`, in parallel; the result
/// does not depend on the thread count). `tick(done, total)` after each.
pub fn null_statistics(
    n_rate: usize,
    tau0_s: f64,
    est: Estimator,
    grid: &TauGrid,
    opts: &Options,
    replicates: usize,
    tick: &(dyn Fn(usize, usize) + Sync),
) -> Vec<[f64; 5]> {
    let never = AtomicBool::new(false);
    null_statistics_until(n_rate, tau0_s, est, grid, opts, replicates, tick, &never)
        .expect("a simulation without a stop request runs to its end")
}

/// [`null_statistics`] that gives up when `stop` is set (read before each null log and by its
/// curves, per factor): `None`.
#[allow(clippy::too_many_arguments)]
pub fn null_statistics_until(
    n_rate: usize,
    tau0_s: f64,
    est: Estimator,
    grid: &TauGrid,
    opts: &Options,
    replicates: usize,
    tick: &(dyn Fn(usize, usize) + Sync),
    stop: &AtomicBool,
) -> Option<Vec<[f64; 5]>> {
    let done = std::sync::atomic::AtomicUsize::new(0);
    (0..replicates)
        .into_par_iter()
        .map(|i| {
            if stop.load(Ordering::Relaxed) {
                return None;
            }
            let s = replicate_until(i, n_rate, tau0_s, est, grid, opts, stop)?;
            let d = done.fetch_add(1, Ordering::Relaxed) + 1;
            tick(d, replicates);
            Some(s)
        })
        .collect()
}

/// The thresholds simulated at the log's length: `opts.claims.replicates` null logs through the
/// whole analysis (the reference the table is built from and checked against).
pub fn simulated_thresholds(
    n_rate: usize,
    tau0_s: f64,
    est: Estimator,
    grid: &TauGrid,
    opts: &Options,
) -> NullThresholds {
    let never = AtomicBool::new(false);
    simulated_thresholds_until(n_rate, tau0_s, est, grid, opts, &|_, _| {}, &never)
        .expect("a simulation without a stop request runs to its end")
}

fn simulated_thresholds_until(
    n_rate: usize,
    tau0_s: f64,
    est: Estimator,
    grid: &TauGrid,
    opts: &Options,
    tick: &(dyn Fn(usize, usize) + Sync),
    stop: &AtomicBool,
) -> Option<NullThresholds> {
    let level = opts.claims;
    let r = level.replicates;
    let stats = null_statistics_until(n_rate, tau0_s, est, grid, opts, r, tick, stop)?;
    Some(match tail_of(&stats) {
        Some((start, scale)) => {
            let share = (TAIL_SHARE * r as f64).floor() / r as f64;
            thresholds_of(start, scale, share, &level)
        }
        None => NullThresholds {
            tail_start: [f64::NAN; 5],
            tail_scale: [f64::NAN; 5],
            threshold: [f64::INFINITY; 5],
        },
    })
}
