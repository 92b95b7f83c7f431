//! One call for a channel's whole analysis: deviation curve, noise identification, intervals and,
//! for Allan-variance estimators, the IEEE 952 term fit.

use crate::curve;
use crate::fit::Fit;
use crate::null::null_thresholds;
use crate::sheet::{sheet_readings, term_status, SheetReadings, TermStatus};
use crate::{AllanPoint, Estimator, Options, Series, TauGrid};

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
    let series = Series::from_rate(data, dt_s);
    stage("phase");
    analyse(&series, est, grid, opts, stage)
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
    let allan_variance = matches!(
        est,
        Estimator::NonOverlapping | Estimator::Overlapping | Estimator::Total
    );
    let (points, fit) = if allan_variance {
        let (p, f) = curve::curve_and_fit(series, est, grid, opts, stage);
        (p, Some(f))
    } else {
        (curve::curve(series, est, grid, opts, stage), None)
    };
    let terms = fit.as_ref().map(|f| {
        let null = null_thresholds(series.rate_len(), series.tau0_s(), est, grid, opts);
        term_status(f, &points, opts.confidence, &null)
    });
    let sheet = fit
        .as_ref()
        .zip(terms.as_ref())
        .map(|(f, t)| sheet_readings(&points, f, opts.confidence, t));
    stage("resolved terms");
    Analysis {
        points,
        fit,
        sheet,
        terms,
    }
}
