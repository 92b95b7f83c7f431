//! Spec-sheet readings of an Allan deviation curve as IEEE 952 and Kalibr practice read them, each
//! either a value with its interval, where the curve resolves it, or an upper bound.
//!
//! - White noise (ARW / VRW), quantisation and rate random walk: the line of the term's slope
//!   (-1/2, -1, +1/2) fitted to the points where that term dominates, read where its value is the
//!   coefficient (tau = 1 s, sqrt 3 s, 3 s; IEEE Std 952-1997 Annex C, Figure C.2; Woodman TR-696
//!   §5.1; the Kalibr / allan_variance_ros practice of fitting the -1/2 and +1/2 lines). "Dominates"
//!   means the term is at least [`DOMINANT_SHARE`] of the fitted IEEE 952 Allan variance there
//!   (crate::fit), and the fitted term itself is resolved (its statistic beyond the null
//!   simulation's threshold, crate::null). The first points
//!   (tau < [`MIN_LINE_FACTOR`] sample intervals) are left out when others remain: there the
//!   curve carries the sensor's filter and the correlation of neighbouring samples.
//!   The line in log-log coordinates with a fixed slope is the weighted mean of
//!   ln(dev / sqrt(g(tau))) (g the term's basis, crate::fit::basis), weights 2 edf (the inverse of
//!   Var(ln dev) = 1/(2 edf), SP 1065 §5.2 with the delta method). Neighbouring Allan points are
//!   correlated, so its standard error is taken as if they were perfectly correlated,
//!   sum(w_i s_i) / sum(w_i) with s_i = 1/sqrt(2 edf_i): an upper bound for any correlation.
//! - Bias instability: the minimum of the deviation (Woodman §5.1; IEEE B = minimum / 0.664), only
//!   where a minimum is resolved: a later point's [`RESOLUTION_CONFIDENCE`] lower bound lies above
//!   the minimum's upper bound (the curve rises significantly after it).
//! - Not resolved: the bound is the largest value the curve allows, the term's line touching
//!   the upper ends of the points' intervals: c_j <= min_i hi_i / sqrt(g_j(tau_i)), since every
//!   term's Allan variance is at most the whole (IEEE 952 Annex C: the terms add in variance).

use crate::chi2::{confidence_interval, normal_ppf};
use crate::fit::{basis, capped_edf, Fit, BI_PLATEAU_FACTOR};
use crate::null::{term_statistics, NullThresholds};
use crate::AllanPoint;
use serde::{Deserialize, Serialize};

/// A term dominates a point when it is at least this share of the fitted Allan variance there
/// (the reading of a line over such points is then biased by at most 1/sqrt(0.8) - 1 = 12 %
/// by the other terms, by the fitted model; on a curve of one term, by nothing).
pub const DOMINANT_SHARE: f64 = 0.8;

/// Points with an averaging factor below this are left out of a line when others remain.
pub const MIN_LINE_FACTOR: usize = 10;

/// Confidence of the intervals that decide whether a minimum is resolved (two-sided 99 % each:
/// a white-noise curve shows a false minimum on a given later point with probability < 0.5 %).
pub const RESOLUTION_CONFIDENCE: f64 = 0.99;

/// A reading: a value with its interval where the curve resolves it, else an upper bound.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Reading {
    /// The value (SI), `None` when the curve does not resolve it.
    pub value: Option<f64>,
    /// Interval of the value at the analysis's confidence level (`NaN` when not resolved).
    pub lo: f64,
    pub hi: f64,
    /// The largest value the curve allows (always given; the reading to quote when `value` is
    /// `None`).
    pub bound: f64,
    /// The taus read: the range of a line's points, or the tau of a minimum (twice); `NaN` when
    /// not resolved.
    pub tau_s: [f64; 2],
    /// Why the reading is not resolved (empty when it is).
    pub why: String,
}

impl Reading {
    fn bound(bound: f64, why: String) -> Reading {
        Reading {
            value: None,
            lo: f64::NAN,
            hi: f64::NAN,
            bound,
            tau_s: [f64::NAN; 2],
            why,
        }
    }
}

/// The four readings of a curve (SI, in the coefficients' units: Q unit*s, N unit*sqrt(s), the
/// minimum in unit, K unit/sqrt(s)).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SheetReadings {
    /// Quantisation: the -1 line at tau = sqrt 3 s.
    pub q: Reading,
    /// White noise (ARW / VRW): the -1/2 line at tau = 1 s.
    pub arw: Reading,
    /// Bias instability: the minimum of the deviation (IEEE B = minimum / 0.664).
    pub bi_min: Reading,
    /// Rate random walk: the +1/2 line at tau = 3 s.
    pub rrw: Reading,
}

/// A fitted term's status: resolved (quote the value) or not (quote the bound).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TermStatus {
    pub resolved: bool,
    /// The largest value of the coefficient the curve allows (SI).
    pub bound: f64,
    /// The term's Wald statistic on the curve ([`crate::null::term_statistics`]).
    pub statistic: f64,
    /// The statistic's threshold from the null simulation ([`crate::null`]).
    pub threshold: f64,
}

/// The status of the five fitted terms (q, n, b, k, r) of `fit` on `points`: resolved when the
/// fit has the term, its statistic exceeds the null's threshold and its one-sigma interval
/// excludes zero (a value quoted as v +- s with s >= v would show an interval containing zero,
/// issue 24); bounds from the intervals at `confidence`.
pub fn term_status(
    fit: &Fit,
    points: &[AllanPoint],
    confidence: f64,
    null: &NullThresholds,
) -> [TermStatus; 5] {
    let usable = usable(points);
    let stat = term_statistics(points, fit);
    std::array::from_fn(|j| TermStatus {
        resolved: fit.terms()[j].is_some_and(|t| t.sigma < t.value) && stat[j] > null.threshold[j],
        bound: tangent_bound(&usable, j, confidence),
        statistic: stat[j],
        threshold: null.threshold[j],
    })
}

/// The readings of `points` with the fit made of them and its terms' status, intervals at
/// `confidence`.
pub fn sheet_readings(
    points: &[AllanPoint],
    fit: &Fit,
    confidence: f64,
    status: &[TermStatus; 5],
) -> SheetReadings {
    let usable = usable(points);
    let line = |j: usize| line_reading(&usable, fit, j, confidence, status[j].resolved);
    SheetReadings {
        q: line(0),
        arw: line(1),
        bi_min: minimum_reading(&usable, confidence),
        rrw: line(3),
    }
}

/// The points a reading may use: finite positive deviations with at least 9 bins (Woodman §5.1).
fn usable(points: &[AllanPoint]) -> Vec<&AllanPoint> {
    points
        .iter()
        .filter(|p| p.dev.is_finite() && p.dev > 0.0 && p.woodman_ok())
        .collect()
}

/// A point's degrees of freedom (capped at the white-FM value, [`crate::fit::capped_edf`]).
fn edf_of(p: &AllanPoint) -> f64 {
    capped_edf(p)
}

/// The upper end of a point's interval at `confidence` from its capped EDF (the deviation
/// itself when it has no EDF).
fn upper(p: &AllanPoint, confidence: f64) -> f64 {
    let hi = confidence_interval(p.dev, edf_of(p), confidence).1;
    if hi.is_finite() {
        // The wider of the stated interval and the capped one.
        hi.max(p.hi)
    } else {
        p.dev
    }
}

/// Coefficient j's largest value the curve allows: its line touching the intervals' upper ends.
fn tangent_bound(points: &[&AllanPoint], j: usize, confidence: f64) -> f64 {
    points
        .iter()
        .map(|p| upper(p, confidence) / basis(p.tau_s)[j].sqrt())
        .fold(f64::INFINITY, f64::min)
}

/// Term j's share of the fitted Allan variance at tau.
fn share(fit: &Fit, j: usize, tau_s: f64) -> f64 {
    let total = fit.model_dev(tau_s).powi(2);
    fit.term_dev(j, tau_s).map_or(0.0, |d| d * d / total)
}

/// The line of term j (slope of its basis) through the points it dominates.
fn line_reading(
    points: &[&AllanPoint],
    fit: &Fit,
    j: usize,
    confidence: f64,
    resolved: bool,
) -> Reading {
    let z = normal_ppf(0.5 + 0.5 * confidence);
    let bound = tangent_bound(points, j, confidence);
    let name = ["quantisation", "white noise", "", "rate random walk"][j];
    if fit.terms()[j].is_none() {
        return Reading::bound(bound, format!("the IEEE 952 fit has no {name} term"));
    }
    if !resolved {
        return Reading::bound(
            bound,
            format!(
                "the fitted {name} term is within what logs of {} alone give",
                if j == 1 {
                    "quantisation noise"
                } else {
                    "white noise"
                }
            ),
        );
    }
    let dominated: Vec<&AllanPoint> = points
        .iter()
        .copied()
        .filter(|p| share(fit, j, p.tau_s) >= DOMINANT_SHARE)
        .collect();
    let late: Vec<&AllanPoint> = dominated
        .iter()
        .copied()
        .filter(|p| p.m >= MIN_LINE_FACTOR)
        .collect();
    let line = if late.is_empty() { dominated } else { late };
    if line.is_empty() {
        return Reading::bound(
            bound,
            format!(
                "{name} is less than {:.0} % of the curve at every tau",
                100.0 * DOMINANT_SHARE
            ),
        );
    }
    let (mut sw, mut swx, mut sws) = (0.0, 0.0, 0.0);
    for p in &line {
        let w = 2.0 * edf_of(p);
        sw += w;
        swx += w * (p.dev / basis(p.tau_s)[j].sqrt()).ln();
        sws += w / w.sqrt();
    }
    let (mean, se) = (swx / sw, sws / sw);
    Reading {
        value: Some(mean.exp()),
        lo: (mean - z * se).exp(),
        hi: (mean + z * se).exp(),
        bound,
        tau_s: [line[0].tau_s, line[line.len() - 1].tau_s],
        why: String::new(),
    }
}

/// The minimum of the curve, where the curve rises significantly after it.
fn minimum_reading(points: &[&AllanPoint], confidence: f64) -> Reading {
    let bound = points
        .iter()
        .map(|p| upper(p, confidence))
        .fold(f64::INFINITY, f64::min);
    let Some((i, low)) = points
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.dev.total_cmp(&b.1.dev))
    else {
        return Reading::bound(bound, "the curve has no usable point".into());
    };
    let ci = |p: &AllanPoint| confidence_interval(p.dev, edf_of(p), RESOLUTION_CONFIDENCE);
    let top = ci(low).1;
    if i + 1 == points.len() {
        return Reading::bound(
            bound,
            format!(
                "the curve still falls at {}, its longest tau with 9 or more non-overlapping averages (Woodman §5.1; a longer tau has too few to read a minimum from)",
                tau_text(low.tau_s)
            ),
        );
    }
    if !points[i + 1..].iter().any(|p| ci(p).0 > top) {
        return Reading::bound(
            bound,
            format!(
                "the curve does not rise significantly after its lowest point (tau = {})",
                tau_text(low.tau_s)
            ),
        );
    }
    let (lo, hi) = confidence_interval(low.dev, edf_of(low), confidence);
    Reading {
        value: Some(low.dev),
        lo: lo.min(low.lo),
        hi: hi.max(low.hi),
        bound,
        tau_s: [low.tau_s; 2],
        why: String::new(),
    }
}

/// IEEE B of a minimum reading (minimum / 0.664, docs/model.md §2).
pub fn ieee_b(minimum: f64) -> f64 {
    minimum / BI_PLATEAU_FACTOR
}

/// A tau for a message: up to 6 significant digits, no trailing zeros ("1310.72 s").
fn tau_text(tau_s: f64) -> String {
    format!(
        "{} s",
        format!("{tau_s:.6}")
            .trim_end_matches('0')
            .trim_end_matches('.')
    )
}
