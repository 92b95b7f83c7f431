//! A channel's deviation curve with its noise identification and intervals, and the IEEE 952
//! fit of it: the part of the analysis the null simulation ([`crate::null`]) repeats.

use crate::fit::{fit_ieee952, Fit};
use crate::{AllanPoint, EdfMethod, Estimator, Options, Series, TauGrid};
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};

/// The deviation curve with its intervals and the IEEE 952 fit (no readings: the null
/// simulation runs this on its logs).
pub(crate) fn curve_and_fit(
    series: &Series,
    est: Estimator,
    grid: &TauGrid,
    opts: &Options,
    stage: &(dyn Fn(&str) + Sync),
    stop: &AtomicBool,
) -> Option<(Vec<AllanPoint>, Fit)> {
    let points = curve(series, est, grid, opts, stage, stop)?;
    let fit = fit_ieee952(&points);
    stage("fit");
    Some((points, fit))
}

/// The deviations, the noise identification and the intervals; `None` when `stop` is set (read
/// before each factor's deviation pass or group of them, and before each factor's noise
/// identification).
pub(crate) fn curve(
    series: &Series,
    est: Estimator,
    grid: &TauGrid,
    opts: &Options,
    stage: &(dyn Fn(&str) + Sync),
    stop: &AtomicBool,
) -> Option<Vec<AllanPoint>> {
    let stopped = || stop.load(Ordering::Relaxed);
    let ms = series.grid_m(est, grid, opts.stable32_stop);
    let identify = opts.edf != EdfMethod::None && opts.alpha.is_none();
    let d = est.difference_order();
    let (points, alphas) = rayon::join(
        || {
            let r = series.raw_points_until(est, &ms, stop);
            stage("deviations");
            r
        },
        || -> Option<Vec<(usize, Option<i32>)>> {
            if identify {
                let r = ms
                    .par_iter()
                    .map(|&m| (!stopped()).then(|| (m, series.noise_id(m, d))))
                    .collect();
                stage("noise identification");
                r
            } else {
                Some(ms.iter().map(|&m| (m, opts.alpha)).collect())
            }
        },
    );
    let (mut points, alphas) = (points?, alphas?);
    if opts.edf != EdfMethod::None {
        let alphas: Vec<Option<i32>> = points
            .iter()
            .map(|p| alphas.iter().find(|(m, _)| *m == p.m).and_then(|(_, a)| *a))
            .collect();
        series.attach_intervals_with_alphas(est, &mut points, &alphas, opts);
    }
    stage("intervals");
    Some(points)
}
