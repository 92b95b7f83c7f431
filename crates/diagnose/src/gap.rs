//! The gap between a measured Allan curve and a simulated model band (docs/diagnose.md, diagnose step 3).
//!
//! At each tau, z = (ln adev_meas - ln adev_model) / s. `ln adev_model` is the mean of ln adev over
//! the simulated seeds (so the small-EDF bias of ln adev, E[ln chi2_v / v] < 0, is the same on both
//! sides and cancels); s combines the sampling error of the measured point, from its equivalent
//! degrees of freedom (or the band's seed spread where that is larger), with the error of the band
//! centre (seed spread / sqrt(independent simulated logs)).

use montecarlo::stats::quantile_sorted;
use serde::Serialize;

/// |z| above which a tau is in disagreement (docs/cli.md: "contiguous tau ranges with |z| > 3").
pub const DISAGREEMENT_Z: f64 = 3.0;

/// A measured Allan curve: one point per tau, with the equivalent degrees of freedom of each point.
#[derive(Clone, Debug, Serialize)]
pub struct Curve {
    pub tau_s: Vec<f64>,
    pub adev: Vec<f64>,
    pub edf: Vec<f64>,
}

/// The Allan band of a model simulated over many seeds, on the same tau grid as the measurement.
#[derive(Clone, Debug, Serialize)]
pub struct Band {
    pub tau_s: Vec<f64>,
    /// Mean over seeds of ln adev.
    pub ln_mean: Vec<f64>,
    /// Standard deviation over seeds of ln adev (the spread of one realisation).
    pub ln_sd: Vec<f64>,
    /// Mean over seeds of the Allan variance (the additive scale the candidate signatures live on).
    pub avar_mean: Vec<f64>,
    /// 2.5 % and 97.5 % empirical quantiles of adev over seeds (for plots).
    pub adev_lo: Vec<f64>,
    pub adev_hi: Vec<f64>,
    pub seeds: usize,
    /// Independent simulated logs behind the centre: `seeds`, or fewer when each replicate pools
    /// several simulated logs that other replicates share (`simulate`, pooled runs).
    pub centre_logs: f64,
    /// Per seed, its ln adev's deviation from the centre in units of the spread at each tau
    /// ((ln a_si - ln_mean_i) / ln_sd_i; 0 where the spread is 0): how one realisation's errors
    /// at different taus go together (`fit::correlation_factor`). Not serialised.
    #[serde(skip)]
    pub standardised: Vec<Vec<f64>>,
}

impl Band {
    /// Build the band from per-seed Allan deviations (`per_seed[s][i]` = adev of seed s at tau i).
    /// Seeds are combined in index order, so the result does not depend on how they were computed.
    pub fn from_seeds(tau_s: &[f64], per_seed: &[Vec<f64>]) -> Band {
        let s_count = per_seed.len();
        let m = tau_s.len();
        let mut ln_mean = vec![0.0; m];
        let mut ln_sd = vec![0.0; m];
        let mut avar_mean = vec![0.0; m];
        let mut adev_lo = vec![0.0; m];
        let mut adev_hi = vec![0.0; m];
        let mut standardised = vec![vec![0.0; m]; s_count];
        for i in 0..m {
            let mut col: Vec<f64> = per_seed.iter().map(|s| s[i]).collect();
            let lns: Vec<f64> = col.iter().map(|a| a.max(f64::MIN_POSITIVE).ln()).collect();
            let mean = stats::mean(&lns);
            let var = if s_count > 1 {
                stats::sample_variance(&lns)
            } else {
                0.0
            };
            ln_mean[i] = mean;
            ln_sd[i] = var.sqrt();
            for (row, l) in standardised.iter_mut().zip(&lns) {
                row[i] = if ln_sd[i] > 0.0 {
                    (l - mean) / ln_sd[i]
                } else {
                    0.0
                };
            }
            avar_mean[i] = stats::mean_square(&col);
            col.sort_by(f64::total_cmp);
            adev_lo[i] = quantile_sorted(&col, 0.025);
            adev_hi[i] = quantile_sorted(&col, 0.975);
        }
        Band {
            tau_s: tau_s.to_vec(),
            ln_mean,
            ln_sd,
            avar_mean,
            adev_lo,
            adev_hi,
            seeds: s_count,
            centre_logs: s_count as f64,
            standardised,
        }
    }

    /// Band centre as an Allan deviation (exp of the mean ln adev).
    pub fn centre(&self) -> Vec<f64> {
        self.ln_mean.iter().map(|l| l.exp()).collect()
    }
}

/// Trigamma function psi'(x), x > 0: recurrence psi'(x) = psi'(x+1) + 1/x^2 up to x >= 10, then the
/// asymptotic series (Abramowitz & Stegun 6.4.12): 1/x + 1/(2x^2) + 1/(6x^3) - 1/(30x^5) + 1/(42x^7) - 1/(30x^9).
pub fn trigamma(mut x: f64) -> f64 {
    let mut acc = 0.0;
    while x < 10.0 {
        acc += 1.0 / (x * x);
        x += 1.0;
    }
    let x2 = 1.0 / (x * x);
    acc + 1.0 / x
        + x2 / 2.0
        + (1.0 / x) * x2 * (1.0 / 6.0 - x2 * (1.0 / 30.0 - x2 * (1.0 / 42.0 - x2 / 30.0)))
}

/// Standard error of ln adev for a point with `edf` equivalent degrees of freedom.
/// NIST SP 1065 eq (45) (docs/model.md §2.1): avar_hat = avar * chi2_v / v. ln of a chi2_v / v variable has
/// variance psi'(v/2) (log-gamma moments), so ln adev = ln(avar)/2 has sd sqrt(psi'(v/2))/2; for large v
/// this is the familiar 1/sqrt(2v).
pub fn ln_adev_se(edf: f64) -> f64 {
    if edf.is_nan() || edf <= 0.0 || !edf.is_finite() {
        return f64::INFINITY;
    }
    trigamma(edf / 2.0).sqrt() / 2.0
}

/// A contiguous tau range where |z| > 3.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Disagreement {
    pub tau_lo_s: f64,
    pub tau_hi_s: f64,
    /// Index range [first, last] into the tau grid.
    pub first: usize,
    pub last: usize,
    /// +1: the measurement is above the model (something missing); -1: below (too much in the model).
    pub sign: i32,
    pub max_abs_z: f64,
}

/// Per-tau and per-channel gap.
#[derive(Clone, Debug, Serialize)]
pub struct Gap {
    pub z: Vec<f64>,
    /// The standard error s used at each tau.
    pub s: Vec<f64>,
    /// RMS of z over tau (the channel's gap).
    pub rms: f64,
    pub disagreements: Vec<Disagreement>,
}

/// Standard error of the difference at each tau: measured point and band centre (seed spread /
/// sqrt(seeds)). The measured point's error is the larger of the EDF-based value and the seed spread of
/// the simulated band (the model's own sampling spread at that tau): the EDF rests on a noise-type
/// identification (lag-1 ACF, Riley 2004) that needs about 30 averages and can fail at the longest taus,
/// where a misidentified type overstates the EDF several-fold and would raise false alarms.
pub fn standard_errors(measured: &Curve, band: &Band) -> Vec<f64> {
    measured
        .edf
        .iter()
        .zip(&band.ln_sd)
        .map(|(&edf, &sd)| {
            let s_meas = ln_adev_se(edf).max(sd);
            (s_meas * s_meas + sd * sd / band.centre_logs.max(1.0)).sqrt()
        })
        .collect()
}

/// z-scores of the measurement against a predicted ln adev (`ln_model`) with standard errors `s`.
pub fn z_scores(measured: &Curve, ln_model: &[f64], s: &[f64]) -> Vec<f64> {
    measured
        .adev
        .iter()
        .zip(ln_model)
        .zip(s)
        .map(|((&a, &l), &s)| (a.max(f64::MIN_POSITIVE).ln() - l) / s)
        .collect()
}

/// RMS of a set of z-scores; a channel with no tau to judge has no gap (0, not the NaN of
/// `stats::rms` on an empty set).
pub fn rms(z: &[f64]) -> f64 {
    if z.is_empty() {
        0.0
    } else {
        stats::rms(z)
    }
}

/// Contiguous runs of |z| > DISAGREEMENT_Z with one sign.
pub fn disagreements(tau_s: &[f64], z: &[f64]) -> Vec<Disagreement> {
    let mut out: Vec<Disagreement> = Vec::new();
    for (i, &zi) in z.iter().enumerate() {
        if zi.abs() <= DISAGREEMENT_Z || !zi.is_finite() {
            continue;
        }
        let sign = if zi > 0.0 { 1 } else { -1 };
        match out.last_mut() {
            Some(d) if d.last + 1 == i && d.sign == sign => {
                d.last = i;
                d.tau_hi_s = tau_s[i];
                d.max_abs_z = d.max_abs_z.max(zi.abs());
            }
            _ => out.push(Disagreement {
                tau_lo_s: tau_s[i],
                tau_hi_s: tau_s[i],
                first: i,
                last: i,
                sign,
                max_abs_z: zi.abs(),
            }),
        }
    }
    out
}

/// The gap of a measurement against a band (docs/diagnose.md diagnose step 3).
pub fn gap(measured: &Curve, band: &Band) -> Gap {
    let s = standard_errors(measured, band);
    let z = z_scores(measured, &band.ln_mean, &s);
    Gap {
        rms: rms(&z),
        disagreements: disagreements(&measured.tau_s, &z),
        z,
        s,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trigamma_matches_known_values() {
        // psi'(1) = pi^2/6, psi'(1/2) = pi^2/2 (A&S 6.4.2, 6.4.4); psi'(x) ~ 1/x for large x.
        let pi2 = std::f64::consts::PI.powi(2);
        assert!((trigamma(1.0) - pi2 / 6.0).abs() < 1e-10);
        assert!((trigamma(0.5) - pi2 / 2.0).abs() < 1e-10);
        assert!((trigamma(1e6) * 1e6 - 1.0).abs() < 1e-6);
    }

    #[test]
    fn ln_adev_se_tends_to_large_edf_form() {
        for v in [50.0, 1e3, 1e5] {
            let se = ln_adev_se(v);
            let approx = 1.0 / (2.0 * v).sqrt();
            assert!(
                (se / approx - 1.0).abs() < 2.0 / v,
                "v {v}: {se} vs {approx}"
            );
        }
    }

    #[test]
    fn disagreement_ranges_split_on_sign_and_gaps() {
        let tau = [1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0];
        let z = [0.5, 4.0, 5.0, -4.0, 1.0, 3.5, 0.0];
        let d = disagreements(&tau, &z);
        assert_eq!(d.len(), 3);
        assert_eq!((d[0].first, d[0].last, d[0].sign), (1, 2, 1));
        assert_eq!(
            (d[0].tau_lo_s, d[0].tau_hi_s, d[0].max_abs_z),
            (2.0, 4.0, 5.0)
        );
        assert_eq!((d[1].first, d[1].last, d[1].sign), (3, 3, -1));
        assert_eq!((d[2].first, d[2].last), (5, 5));
    }

    #[test]
    fn band_from_seeds_is_order_statistics_of_seeds() {
        let tau = [1.0];
        let seeds: Vec<Vec<f64>> = (1..=5).map(|k| vec![k as f64]).collect();
        let b = Band::from_seeds(&tau, &seeds);
        let lns: Vec<f64> = (1..=5).map(|k| (k as f64).ln()).collect();
        let mean = stats::mean(&lns);
        assert!((b.ln_mean[0] - mean).abs() < 1e-15);
        assert!((b.avar_mean[0] - 11.0).abs() < 1e-12); // (1+4+9+16+25)/5
        assert!((b.adev_lo[0] - 1.1).abs() < 1e-12); // 0.025*4 = 0.1 of the way from 1 to 2
    }
}
