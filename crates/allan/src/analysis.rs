//! One call for a channel's whole analysis: deviation curve, noise identification, intervals and,
//! for Allan-variance estimators, the IEEE 952 term fit.

use crate::fit::{fit_ieee952, Fit};
use crate::sheet::{sheet_readings, term_status, SheetReadings, TermStatus};
use crate::{AllanPoint, EdfMethod, Estimator, Options, Series, TauGrid};
use rayon::prelude::*;

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
pub fn analyse(
    series: &Series,
    est: Estimator,
    grid: &TauGrid,
    opts: &Options,
    stage: &(dyn Fn(&str) + Sync),
) -> Analysis {
    let ms = series.grid_m(est, grid, opts.stable32_stop);
    let identify = opts.edf != EdfMethod::None && opts.alpha.is_none();
    let d = est.difference_order();
    let (mut points, alphas) = rayon::join(
        || {
            let r = series.raw_points(est, &ms);
            stage("deviations");
            r
        },
        || -> Vec<(usize, Option<i32>)> {
            if identify {
                let r = ms.par_iter().map(|&m| (m, series.noise_id(m, d))).collect();
                stage("noise identification");
                r
            } else {
                ms.iter().map(|&m| (m, opts.alpha)).collect()
            }
        },
    );
    if opts.edf != EdfMethod::None {
        let alphas: Vec<Option<i32>> = points
            .iter()
            .map(|p| alphas.iter().find(|(m, _)| *m == p.m).and_then(|(_, a)| *a))
            .collect();
        series.attach_intervals_with_alphas(est, &mut points, &alphas, opts);
    }
    stage("intervals");
    let allan_variance = matches!(
        est,
        Estimator::NonOverlapping | Estimator::Overlapping | Estimator::Total
    );
    let fit = allan_variance.then(|| fit_ieee952(&points));
    let sheet = fit
        .as_ref()
        .map(|f| sheet_readings(&points, f, opts.confidence));
    let terms = fit
        .as_ref()
        .map(|f| term_status(f, &points, opts.confidence));
    stage("fit");
    Analysis {
        points,
        fit,
        sheet,
        terms,
    }
}
