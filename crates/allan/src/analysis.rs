//! One call for a channel's whole analysis: deviation curve, noise identification, intervals and,
//! for Allan-variance estimators, the IEEE 952 term fit.

use crate::curve;
use crate::fit::Fit;
use crate::null::null_thresholds_until;
use crate::sheet::{sheet_readings, term_status, SheetReadings, TermStatus};
use crate::{AllanPoint, Estimator, Options, Series, TauGrid};
use std::sync::atomic::{AtomicBool, Ordering};

/// A channel's analysis.
#[derive(Clone, Debug)]
pub struct Analysis {
    pub points: Vec<AllanPoint>,
    /// The IEEE 952 fit (Allan-variance estimators only: non-overlapping, overlapping, total).
    pub fit: Option<Fit>,
    /// The spec-sheet readings (with the fit only), intervals at the options' confidence.
    pub sheet: Option<SheetReadings>,
    /// Which fitted terms are resolved, and each one's bound (with the fit only).
    pub terms: Option<[TermStatus; 5]>,
}

/// Analyse rate samples taken every `dt_s` seconds: the deviation at every tau of `grid`, each
/// point's noise type and interval (as `opts` asks), and the IEEE 952 fit. The deviations (one
/// blocked pass) and the per-tau noise identification run side by side; every number is
/// computed by one thread in a fixed order, so the result does not depend on the thread count.
/// `stage` is told when each stage ends ("phase", "deviations", "noise identification",
/// "intervals", "fit"), for progress displays.
pub fn analyse_rate(
    data: Vec<f64>,
    dt_s: f64,
    est: Estimator,
    grid: &TauGrid,
    opts: &Options,
    stage: &(dyn Fn(&str) + Sync),
) -> Analysis {
    let never = AtomicBool::new(false);
    analyse_rate_until(data, dt_s, est, grid, opts, stage, &never)
        .expect("an analysis without a stop request runs to its end")
}

/// [`analyse_rate`] that gives up when `stop` is set (Ctrl-C in a front end): `None` then.
/// The flag is read between the stages and before each simulated null log
/// ([`crate::null::null_thresholds_until`]), so a stop lands within one stage's pass over the
/// samples (the deviations, the noise identification) or one null log per worker thread.
pub fn analyse_rate_until(
    data: Vec<f64>,
    dt_s: f64,
    est: Estimator,
    grid: &TauGrid,
    opts: &Options,
    stage: &(dyn Fn(&str) + Sync),
    stop: &AtomicBool,
) -> Option<Analysis> {
    let series = Series::from_rate(data, dt_s);
    stage("phase");
    analyse_until(&series, est, grid, opts, stage, stop)
}

/// [`analyse_rate`] of a prepared series (rate or phase samples): every stage after the phase.
/// The fitted terms' status needs the null simulation of [`crate::null`] (cached per log
/// length, interval, grid and options).
pub fn analyse(
    series: &Series,
    est: Estimator,
    grid: &TauGrid,
    opts: &Options,
    stage: &(dyn Fn(&str) + Sync),
) -> Analysis {
    let never = AtomicBool::new(false);
    analyse_until(series, est, grid, opts, stage, &never)
        .expect("an analysis without a stop request runs to its end")
}

/// [`analyse`] that gives up when `stop` is set: `None` then ([`analyse_rate_until`]).
pub fn analyse_until(
    series: &Series,
    est: Estimator,
    grid: &TauGrid,
    opts: &Options,
    stage: &(dyn Fn(&str) + Sync),
    stop: &AtomicBool,
) -> Option<Analysis> {
    let stopped = || stop.load(Ordering::Relaxed);
    if stopped() {
        return None;
    }
    let allan_variance = matches!(
        est,
        Estimator::NonOverlapping | Estimator::Overlapping | Estimator::Total
    );
    let (points, fit) = if allan_variance {
        let (p, f) = curve::curve_and_fit(series, est, grid, opts, stage, stop)?;
        (p, Some(f))
    } else {
        (curve::curve(series, est, grid, opts, stage, stop)?, None)
    };
    if stopped() {
        return None;
    }
    let terms = match fit.as_ref() {
        Some(f) => {
            let null = null_thresholds_until(
                series.rate_len(),
                series.tau0_s(),
                est,
                grid,
                opts,
                &|_, _| {},
                stop,
            )?;
            Some(term_status(f, &points, opts.confidence, &null))
        }
        None => None,
    };
    let sheet = fit
        .as_ref()
        .zip(terms.as_ref())
        .map(|(f, t)| sheet_readings(&points, f, opts.confidence, t));
    stage("resolved terms");
    Some(Analysis {
        points,
        fit,
        sheet,
        terms,
    })
}
