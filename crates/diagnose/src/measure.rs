//! Step 1 of the workflow: the measured Allan deviations on the common grid, of one log or pooled
//! over several runs of one sensor (docs/diagnose.md, "Several runs").
//!
//! Pooling: at each tau the runs' overlapping Allan variances are averaged with weights equal to
//! their numbers of overlapping terms (the pooled estimator is then the overlapping estimator of
//! all the runs' difference terms together, NIST SP 1065 eq (14) summed over runs), and their
//! equivalent degrees of freedom add up (independent runs: the pooled chi-squared variable is the
//! sum of the runs', SP 1065 §5.2). A point only one run has is that run's point unchanged.

use crate::gap::{Band, Curve};
use crate::input::LogInput;
use allan::{AllanPoint, DataKind, Estimator, TauGrid};
use noise::{Channel, ImuChannels};

/// One channel's measurement on the common grid: indices into the grid it has valid points at.
#[derive(Clone, Debug)]
pub(crate) struct Measured {
    pub(crate) idx: Vec<usize>,
    pub(crate) curve: Curve,
    pub(crate) lo: Vec<f64>,
    pub(crate) hi: Vec<f64>,
}

/// The measurement of one or several runs: the grid's averaging factors, the pooled curve of
/// every channel, each run's own curve, and the weight of each run in the pooled Allan variance
/// per channel, grid index and run (its overlapping terms, 0 where it has no valid point): the
/// band pools its simulated runs with the same weights.
pub(crate) struct Runs {
    pub(crate) grid_m: Vec<usize>,
    pub(crate) pooled: ImuChannels<Option<Measured>>,
    pub(crate) runs: Vec<ImuChannels<Option<Measured>>>,
    pub(crate) weights: ImuChannels<Vec<Vec<f64>>>,
}

/// Every channel's overlapping Allan points of a log on the octave grid (Greenhall EDF).
fn points(log: &LogInput) -> ImuChannels<Vec<AllanPoint>> {
    ImuChannels::from_fn(|c| {
        log.channels[c].map_or_else(Vec::new, |s| {
            allan::deviation(
                s,
                DataKind::Rate,
                log.dt_s,
                Estimator::Overlapping,
                &TauGrid::Octave,
            )
        })
    })
}

fn valid(p: &AllanPoint) -> bool {
    p.dev > 0.0 && p.dev.is_finite() && p.edf > 0.0 && p.edf.is_finite()
}

/// The pooled point of the runs' valid points at one averaging factor (module doc).
fn pool_point(points: &[&AllanPoint]) -> AllanPoint {
    if let [one] = points {
        return (*one).clone();
    }
    let devs: Vec<f64> = points.iter().map(|p| p.dev).collect();
    let weights: Vec<f64> = points.iter().map(|p| p.n_terms as f64).collect();
    let avar = stats::weighted_mean_square(&devs, &weights);
    let edf: f64 = points.iter().map(|p| p.edf).sum();
    let dev = avar.sqrt();
    let (lo, hi) = allan::chi2::confidence_interval(dev, edf, allan::ONE_SIGMA_CI);
    AllanPoint {
        dev,
        edf,
        lo,
        hi,
        n_terms: points.iter().map(|p| p.n_terms).sum(),
        bins: points.iter().map(|p| p.bins).sum(),
        ..points[0].clone()
    }
}

/// A channel's curve from its points on the grid, leaving out invalid points and taus below
/// `tau_min_s`.
fn curve_of(points: &[AllanPoint], grid_m: &[usize], tau_min_s: f64) -> Measured {
    let mut idx = Vec::new();
    let (mut tau, mut adev, mut edf, mut lo, mut hi) = (vec![], vec![], vec![], vec![], vec![]);
    for p in points {
        let Some(i) = grid_m.iter().position(|&m| m == p.m) else {
            continue;
        };
        if valid(p) && p.tau_s >= tau_min_s {
            idx.push(i);
            tau.push(p.tau_s);
            adev.push(p.dev);
            edf.push(p.edf);
            lo.push(p.lo);
            hi.push(p.hi);
        }
    }
    Measured {
        idx,
        curve: Curve {
            tau_s: tau,
            adev,
            edf,
        },
        lo,
        hi,
    }
}

/// Measured Allan deviations of every channel of one log on the octave grid, and the grid's
/// averaging factors. Points without a positive deviation and EDF, or below `tau_min_s`, are left out.
pub(crate) fn measure(
    log: &LogInput,
    tau_min_s: f64,
) -> (Vec<usize>, ImuChannels<Option<Measured>>) {
    let r = measure_runs(std::slice::from_ref(log), tau_min_s);
    (r.grid_m, r.pooled)
}

/// [`measure`] of several runs of one sensor (same rate and channels): the grid is the longest
/// run's, the pooled curve as in the module doc.
pub(crate) fn measure_runs(logs: &[LogInput], tau_min_s: f64) -> Runs {
    use rayon::prelude::*;
    let per_run: Vec<ImuChannels<Vec<AllanPoint>>> = logs.par_iter().map(points).collect();
    let longest = (0..per_run.len())
        .max_by_key(|&r| {
            let longest_curve = per_run[r].values().iter().map(Vec::len).max();
            (longest_curve, std::cmp::Reverse(r))
        })
        .unwrap_or(0);
    let grid_m: Vec<usize> = per_run
        .get(longest)
        .and_then(|p| p.values().iter().find(|v| !v.is_empty()))
        .map(|v| v.iter().map(|p| p.m).collect())
        .unwrap_or_default();
    let mut weights: ImuChannels<Vec<Vec<f64>>> = ImuChannels::default();
    let mut pooled_points: ImuChannels<Vec<AllanPoint>> = ImuChannels::default();
    for c in Channel::ALL {
        if logs.first().is_none_or(|l| l.channels[c].is_none()) {
            continue;
        }
        for &m in &grid_m {
            let at: Vec<Option<&AllanPoint>> = per_run
                .iter()
                .map(|p| p[c].iter().find(|p| p.m == m).filter(|p| valid(p)))
                .collect();
            weights[c].push(
                at.iter()
                    .map(|p| p.map_or(0.0, |p| p.n_terms as f64))
                    .collect(),
            );
            let present: Vec<&AllanPoint> = at.into_iter().flatten().collect();
            if !present.is_empty() {
                pooled_points[c].push(pool_point(&present));
            }
        }
    }
    let channel = |points: &ImuChannels<Vec<AllanPoint>>, c: Channel| {
        logs.first()?.channels[c]?;
        Some(curve_of(&points[c], &grid_m, tau_min_s))
    };
    Runs {
        pooled: ImuChannels::from_fn(|c| channel(&pooled_points, c)),
        runs: per_run
            .iter()
            .map(|p| ImuChannels::from_fn(|c| channel(p, c)))
            .collect(),
        weights,
        grid_m,
    }
}

/// Restrict a band to a channel's valid grid indices.
pub(crate) fn restrict(band: &Band, idx: &[usize]) -> Band {
    let pick = |v: &[f64]| idx.iter().map(|&i| v[i]).collect::<Vec<f64>>();
    Band {
        tau_s: pick(&band.tau_s),
        ln_mean: pick(&band.ln_mean),
        ln_sd: pick(&band.ln_sd),
        avar_mean: pick(&band.avar_mean),
        adev_lo: pick(&band.adev_lo),
        adev_hi: pick(&band.adev_hi),
        seeds: band.seeds,
        centre_logs: band.centre_logs,
        standardised: band.standardised.iter().map(|row| pick(row)).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(m: usize, dev: f64, edf: f64, n_terms: usize) -> AllanPoint {
        AllanPoint {
            tau_s: m as f64 * 0.01,
            m,
            dev,
            n_terms,
            edf,
            lo: 0.9 * dev,
            hi: 1.1 * dev,
            bins: n_terms / m,
            alpha: 0,
        }
    }

    /// One run's point is kept bit for bit; two runs' variances average with their overlapping
    /// terms as weights, their EDF add, and the interval is the chi-squared one of the sum.
    #[test]
    fn pooled_points_weigh_variances_by_terms_and_add_edf() {
        let a = point(4, 2.0, 10.0, 300);
        assert_eq!(pool_point(&[&a]), a);
        let b = point(4, 1.0, 30.0, 100);
        let p = pool_point(&[&a, &b]);
        let avar = (300.0 * 4.0 + 100.0 * 1.0) / 400.0;
        assert!((p.dev - f64::sqrt(avar)).abs() < 1e-15);
        assert_eq!((p.edf, p.n_terms, p.m), (40.0, 400, 4));
        let (lo, hi) = allan::chi2::confidence_interval(p.dev, 40.0, allan::ONE_SIGMA_CI);
        assert_eq!((p.lo, p.hi), (lo, hi));
    }

    /// Runs of one length pooled: each tau's weights are the runs' overlapping terms, the EDF of a
    /// pooled point is the sum of the runs', and a run alone is measured as before.
    #[test]
    fn runs_pool_on_the_longest_grid() {
        let x = crate::testutil::normals(8192, 1);
        let y = crate::testutil::normals(4096, 2);
        fn log(s: &[f64]) -> LogInput<'_> {
            LogInput {
                dt_s: 0.01,
                channels: ImuChannels::from_fn(|c| (c == Channel::Gx).then_some(s)),
                temperature_c: None,
            }
        }
        let (one, two) = (log(&x), log(&y));
        let (grid1, alone) = measure(&one, 0.0);
        let r = measure_runs(&[two, one], 0.0);
        assert_eq!(r.grid_m, grid1, "the longest run's grid");
        let alone = alone[noise::Channel::Gx].as_ref().unwrap();
        let run1 = r.runs[1][noise::Channel::Gx].as_ref().unwrap();
        assert_eq!(run1.curve.adev, alone.curve.adev);
        let pooled = r.pooled[noise::Channel::Gx].as_ref().unwrap();
        let run0 = r.runs[0][noise::Channel::Gx].as_ref().unwrap();
        for (k, &i) in pooled.idx.iter().enumerate() {
            let w = &r.weights[Channel::Gx][i];
            let e0 = run0
                .idx
                .iter()
                .position(|&j| j == i)
                .map_or(0.0, |j| run0.curve.edf[j]);
            let e1 = alone
                .idx
                .iter()
                .position(|&j| j == i)
                .map_or(0.0, |j| alone.curve.edf[j]);
            assert!((pooled.curve.edf[k] - (e0 + e1)).abs() < 1e-9 * pooled.curve.edf[k]);
            assert_eq!(w[1] > 0.0, e1 > 0.0);
            assert_eq!(w[0] > 0.0, e0 > 0.0);
        }
    }
}
