//! Step 1 of the workflow: the measured Allan deviations on the common grid.

use crate::gap::{Band, Curve};
use crate::input::LogInput;
use allan::{DataKind, Estimator, TauGrid};
use noise::ImuChannels;

/// One channel's measurement on the common grid: indices into the grid it has valid points at.
pub(crate) struct Measured {
    pub(crate) idx: Vec<usize>,
    pub(crate) curve: Curve,
    pub(crate) lo: Vec<f64>,
    pub(crate) hi: Vec<f64>,
}

/// Measured Allan deviations of every channel in the log on the octave grid, and the grid's averaging
/// factors. Points without a positive deviation and EDF, or below `tau_min_s`, are left out.
pub(crate) fn measure(
    log: &LogInput,
    tau_min_s: f64,
) -> (Vec<usize>, ImuChannels<Option<Measured>>) {
    let mut grid_m: Vec<usize> = Vec::new();
    let mut points: [Vec<allan::AllanPoint>; 6] = Default::default();
    for c in 0..6 {
        if let Some(s) = log.channels[c] {
            points[c] = allan::deviation(
                s,
                DataKind::Rate,
                log.dt_s,
                Estimator::Overlapping,
                &TauGrid::Octave,
            );
            if grid_m.is_empty() {
                grid_m = points[c].iter().map(|p| p.m).collect();
            }
        }
    }
    let measured = ImuChannels::from_fn(|ch| {
        let c = ch.index();
        log.channels[c]?;
        let mut idx = Vec::new();
        let (mut tau, mut adev, mut edf, mut lo, mut hi) = (vec![], vec![], vec![], vec![], vec![]);
        for p in &points[c] {
            let Some(i) = grid_m.iter().position(|&m| m == p.m) else {
                continue;
            };
            let valid = p.dev > 0.0 && p.dev.is_finite() && p.edf > 0.0 && p.edf.is_finite();
            if valid && p.tau_s >= tau_min_s {
                idx.push(i);
                tau.push(p.tau_s);
                adev.push(p.dev);
                edf.push(p.edf);
                lo.push(p.lo);
                hi.push(p.hi);
            }
        }
        Some(Measured {
            idx,
            curve: Curve {
                tau_s: tau,
                adev,
                edf,
            },
            lo,
            hi,
        })
    });
    (grid_m, measured)
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
    }
}
