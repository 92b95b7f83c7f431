//! The drift gap of diagnose (docs/diagnose.md, "Drift in the loop"): the runs' drift under a
//! protocol (`protocol`, the `drift` command's procedure) against the drift of the model's
//! simulated logs, as a z-score per horizon and drift quantity, like the Allan gap per tau.
//!
//! The model's distribution comes from the band's own simulated logs (no further simulation):
//! replicate s pools, for run r, simulated log (s + r) mod seeds at run r's length (`simulate`),
//! so it is distributed exactly as the runs' pooled drift. Its centre mu is the mean over the
//! replicates of ln RMS (the RMS over the replicate's pooled segments). Its spread comes from the
//! independent logs, not from the replicates (which share logs, and whose sample spread rests on
//! about seeds / runs logs): the pooled mean square MS = sum_r n_r MS_r / N (n_r segments of run
//! r, N in all) has mean sum_r n_r m_r / N and variance sum_r n_r^2 v_r / N^2, m and v the mean
//! and variance over the simulated logs of one log's mean square at run r's length; read as a
//! gamma variable of shape a = mean^2 / variance (the chi-squared form of a mean square of
//! Gaussian errors, NIST SP 1065 §5.2 for the Allan variance alike), ln RMS = ln MS / 2 has the
//! standard deviation sd = sqrt(psi'(a)) / 2 (`gap::ln_adev_se`'s log-gamma moment). The
//! measured pooled RMS gives z = (ln RMS_measured - mu) / (sd sqrt(1 + runs / seeds)): the
//! measurement is one draw (sd), the centre is known from seeds / runs independent logs. The
//! band is exp(mu +- 1.96 sd sqrt(1 + runs / seeds)), the verdict `inside` when |z| <= 1.96.
//! The drift gap is the RMS of z over the informed (horizon, quantity) pairs.

use crate::drift_check::Verdict;
use crate::input::LogInput;
use crate::protocol::{all_segment_errors, Protocol, Quantity, SegmentErrors};
use noise::{Channel, ImuChannels};
use serde::Serialize;
use std::collections::BTreeMap;

/// Two-sided 95 % normal quantile: the band and the verdict.
pub const Z_95: f64 = 1.959_963_984_540_054;

/// One quantity at one horizon.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct DriftZ {
    pub measured_rms: f64,
    /// exp(mu): the model's typical RMS.
    pub model_rms: f64,
    pub band_lo: f64,
    pub band_hi: f64,
    pub z: f64,
    pub verdict: Verdict,
    /// What the fit needs (not serialised): ln RMS measured, mu, the z scale, and the mean square
    /// of the model's segment errors.
    #[serde(skip)]
    pub fit: DriftFit,
}

/// The numbers a candidate's drift likelihood is computed from.
#[derive(Clone, Copy, Debug, Default)]
pub struct DriftFit {
    pub ln_measured: f64,
    pub ln_model: f64,
    pub scale: f64,
    pub mean_square: f64,
}

impl DriftFit {
    /// z when the model's mean square changes by `delta` (the replicates' ln RMS moves by half the
    /// log of the mean square's ratio; their spread kept, as the Allan band's in `fit`).
    pub fn z(&self, delta: f64) -> f64 {
        let ratio = ((self.mean_square + delta) / self.mean_square).max(1e-6);
        (self.ln_measured - self.ln_model - 0.5 * ratio.ln()) / self.scale
    }
}

/// One horizon: its measured segments and the informed quantities (JSON names).
#[derive(Clone, Debug, Serialize)]
pub struct DriftGapHorizon {
    pub t_s: f64,
    pub segments: usize,
    pub quantities: BTreeMap<&'static str, DriftZ>,
}

/// The drift gap of a model.
#[derive(Clone, Debug, Serialize)]
pub struct DriftGap {
    /// RMS of z over the informed (horizon, quantity) pairs (0 when none is informed).
    pub gap: f64,
    /// How many (horizon, quantity) pairs lie outside the model's 95 % band.
    pub outside: usize,
    pub horizons: Vec<DriftGapHorizon>,
    /// The informed (horizon index, quantity) pairs, horizons in order and quantities in
    /// `Quantity::ALL` order, and the correlation of their pooled mean squares over the model's
    /// simulated logs (module doc; not serialised).
    #[serde(skip)]
    pub(crate) pairs: Vec<(usize, Quantity)>,
    #[serde(skip)]
    pub(crate) correlation: Vec<Vec<f64>>,
}

impl DriftGap {
    /// The informed (horizon index, quantity, z) whose quantity comes from channel `c`.
    pub(crate) fn of_channel(&self, c: Channel) -> Vec<(usize, Quantity, DriftFit)> {
        self.pairs
            .iter()
            .filter(|(_, q)| q.needs().contains(&c))
            .filter_map(|&(h, q)| {
                let d = self.horizons[h].quantities.get(q.name())?;
                Some((h, q, d.fit))
            })
            .collect()
    }

    /// The correlation matrix of the pairs of [`DriftGap::of_channel`], in its order.
    pub(crate) fn correlation_of_channel(&self, c: Channel) -> Vec<Vec<f64>> {
        let mine: Vec<usize> = (0..self.pairs.len())
            .filter(|&i| self.pairs[i].1.needs().contains(&c))
            .collect();
        mine.iter()
            .map(|&i| mine.iter().map(|&j| self.correlation[i][j]).collect())
            .collect()
    }

    /// Sum of z^2 over every informed pair.
    pub fn chi2(&self) -> f64 {
        self.horizons
            .iter()
            .flat_map(|h| h.quantities.values())
            .map(|d| d.z * d.z)
            .sum()
    }

    /// The channels the quantities outside the band come from.
    pub(crate) fn channels_outside(&self) -> Vec<Channel> {
        let mut out: Vec<Channel> = Vec::new();
        for h in &self.horizons {
            for q in Quantity::ALL {
                let outside = h
                    .quantities
                    .get(q.name())
                    .is_some_and(|d| d.verdict != Verdict::Inside);
                for c in q.needs().iter().filter(|_| outside) {
                    if !out.contains(c) {
                        out.push(*c);
                    }
                }
            }
        }
        out.sort_by_key(|c| c.index());
        out
    }
}

/// The measured segment errors of the runs under `p`, per horizon, runs pooled in order.
pub(crate) fn measured(logs: &[LogInput], p: &Protocol) -> Vec<SegmentErrors> {
    use rayon::prelude::*;
    let per_run: Vec<Vec<SegmentErrors>> = logs
        .par_iter()
        .map(|l| all_segment_errors(&l.channels.0, l.dt_s, p))
        .collect();
    (0..p.horizons_s.len())
        .map(|h| {
            let mut all = SegmentErrors {
                horizon_s: p.horizons_s[h],
                ..Default::default()
            };
            per_run.iter().for_each(|r| all.extend(&r[h]));
            all
        })
        .collect()
}

/// The drift gap of the measured segments `measured` (per horizon) against the simulated logs'
/// `simulated[s][d][h]` (log s at distinct run length d, horizon h), `of_run[r]` the length index
/// of run r; `active` the channels the runs have.
pub(crate) fn drift_gap(
    measured: &[SegmentErrors],
    simulated: &[Vec<Vec<SegmentErrors>>],
    of_run: &[usize],
    active: &ImuChannels<bool>,
) -> DriftGap {
    let seeds = simulated.len();
    let runs = of_run.len();
    let mut pairs = Vec::new();
    let horizons: Vec<DriftGapHorizon> = measured
        .iter()
        .enumerate()
        .map(|(h, meas)| {
            let mut quantities = BTreeMap::new();
            for q in Quantity::ALL {
                let informed = q.needs().iter().all(|&c| active[c]);
                let values = meas.values(q);
                if !informed || values.is_empty() || seeds <= runs {
                    continue;
                }
                let replicate = |s: usize| {
                    (0..runs).flat_map(move |r| simulated[(s + r) % seeds][of_run[r]][h].values(q))
                };
                let ln_rms: Vec<f64> = (0..seeds)
                    .map(|s| {
                        let v: Vec<f64> = replicate(s).copied().collect();
                        stats::rms(&v).ln()
                    })
                    .collect();
                let spread = pooled_mean_square(simulated, of_run, h, q);
                if let Some(d) = quantity_z(values, &ln_rms, spread, runs) {
                    quantities.insert(q.name(), d);
                    pairs.push((h, q));
                }
            }
            DriftGapHorizon {
                t_s: meas.horizon_s,
                segments: meas.len(),
                quantities,
            }
        })
        .collect();
    let z: Vec<f64> = horizons
        .iter()
        .flat_map(|h| h.quantities.values().map(|d| d.z))
        .collect();
    DriftGap {
        gap: crate::gap::rms(&z),
        outside: z.iter().filter(|z| z.abs() > Z_95).count(),
        horizons,
        correlation: pooled_correlation(simulated, of_run, &pairs),
        pairs,
    }
}

/// Each simulated log's mean square of every pair at length index `d` (`[log][pair]`).
fn log_mean_squares(
    simulated: &[Vec<Vec<SegmentErrors>>],
    d: usize,
    pairs: &[(usize, Quantity)],
) -> Vec<Vec<f64>> {
    simulated
        .iter()
        .map(|log| {
            pairs
                .iter()
                .map(|&(h, q)| {
                    let v = log[d][h].values(q);
                    // No segment: 0 (module doc's sums over none).
                    if v.is_empty() {
                        0.0
                    } else {
                        stats::mean_square(v)
                    }
                })
                .collect()
        })
        .collect()
}

/// The correlation of the pooled mean squares of `pairs` (module doc): the covariance of two
/// pairs' pooled mean squares is sum_r n_ri n_rj c_d(r)(i, j) / (N_i N_j), c_d the covariance over
/// the simulated logs of one log's mean squares at run r's length (the runs independent; N_i
/// cancels in the correlation); a pair without spread is taken as fully correlated with every
/// other (the conservative side: `drift_fit` then weighs it least).
fn pooled_correlation(
    simulated: &[Vec<Vec<SegmentErrors>>],
    of_run: &[usize],
    pairs: &[(usize, Quantity)],
) -> Vec<Vec<f64>> {
    let k = pairs.len();
    let mut cov = vec![vec![0.0; k]; k];
    let logs = simulated.len() as f64;
    for &d in of_run {
        let ms = log_mean_squares(simulated, d, pairs);
        let n: Vec<f64> = pairs
            .iter()
            .map(|&(h, _)| simulated.first().map_or(0, |log| log[d][h].len()) as f64)
            .collect();
        let mean: Vec<f64> = (0..k)
            .map(|i| stats::mean(&ms.iter().map(|m| m[i]).collect::<Vec<f64>>()))
            .collect();
        for i in 0..k {
            for j in 0..k {
                let c = ms
                    .iter()
                    .map(|m| (m[i] - mean[i]) * (m[j] - mean[j]))
                    .sum::<f64>()
                    / (logs - 1.0);
                cov[i][j] += n[i] * n[j] * c;
            }
        }
    }
    (0..k)
        .map(|i| {
            (0..k)
                .map(|j| {
                    let r = cov[i][j] / (cov[i][i] * cov[j][j]).sqrt();
                    if i == j {
                        1.0
                    } else if r.is_finite() {
                        r.clamp(-1.0, 1.0)
                    } else {
                        1.0
                    }
                })
                .collect()
        })
        .collect()
}

/// The pooled mean square's mean and variance (module doc) of quantity `q` at horizon `h`, from
/// each simulated log's own mean square at each run's length.
fn pooled_mean_square(
    simulated: &[Vec<Vec<SegmentErrors>>],
    of_run: &[usize],
    h: usize,
    q: Quantity,
) -> (f64, f64) {
    let (mut n_all, mut mean, mut var) = (0.0, 0.0, 0.0);
    for &d in of_run {
        let ms: Vec<f64> = log_mean_squares(simulated, d, &[(h, q)])
            .into_iter()
            .map(|m| m[0])
            .collect();
        let n = simulated.first().map_or(0, |log| log[d][h].len()) as f64;
        let m = stats::mean(&ms);
        let v = stats::sample_variance(&ms);
        n_all += n;
        mean += n * m;
        var += n * n * v;
    }
    (mean / n_all, var / (n_all * n_all))
}

/// One quantity's z (module doc) from the measured values, the replicates' ln RMS and the pooled
/// mean square's (mean, variance); None when the model or the measurement has no drift there.
fn quantity_z(
    measured: &[f64],
    ln_rms: &[f64],
    (mean_square, var_ms): (f64, f64),
    runs: usize,
) -> Option<DriftZ> {
    let seeds = ln_rms.len() as f64;
    let mu = stats::mean(ln_rms);
    let shape = mean_square * mean_square / var_ms;
    let sd = crate::gap::trigamma(shape).sqrt() / 2.0;
    let scale = sd * (1.0 + runs as f64 / seeds).sqrt();
    let rms = stats::rms(measured);
    if !(rms > 0.0 && scale > 0.0 && scale.is_finite() && mu.is_finite() && mean_square > 0.0) {
        return None;
    }
    let fit = DriftFit {
        ln_measured: rms.ln(),
        ln_model: mu,
        scale,
        mean_square,
    };
    let z = fit.z(0.0);
    Some(DriftZ {
        measured_rms: rms,
        model_rms: mu.exp(),
        band_lo: (mu - Z_95 * scale).exp(),
        band_hi: (mu + Z_95 * scale).exp(),
        z,
        verdict: if z > Z_95 {
            Verdict::Above
        } else if z < -Z_95 {
            Verdict::Below
        } else {
            Verdict::Inside
        },
        fit,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Segment errors of one log: `n` heading errors of standard deviation `sigma`.
    fn log(noise: &[f64], sigma: f64) -> Vec<Vec<SegmentErrors>> {
        vec![vec![SegmentErrors {
            horizon_s: 60.0,
            heading_rad: noise.iter().map(|x| sigma * x).collect(),
            ..Default::default()
        }]]
    }

    /// The pairs' correlation: a quantity that is another's copy (times 3) is fully correlated
    /// with it, an independent one hardly (|r| < 0.5 over 32 simulated logs: the sampling sd of
    /// r is about 0.18), and the diagonal is 1.
    #[test]
    fn the_pairs_correlation_comes_from_the_simulated_logs() {
        let normals = crate::testutil::normals(40 * 32 * 2, 5);
        let simulated: Vec<Vec<Vec<SegmentErrors>>> = (0..32)
            .map(|s| {
                let a: Vec<f64> = normals[40 * s..40 * (s + 1)].to_vec();
                let b: Vec<f64> = normals[40 * (32 + s)..40 * (33 + s)].to_vec();
                vec![vec![SegmentErrors {
                    horizon_s: 60.0,
                    roll_rad: a.iter().map(|x| 3.0 * x).collect(),
                    heading_rad: a,
                    pitch_rad: b,
                    ..Default::default()
                }]]
            })
            .collect();
        let pairs = [
            (0, Quantity::Heading),
            (0, Quantity::Roll),
            (0, Quantity::Pitch),
        ];
        let r = pooled_correlation(&simulated, &[0, 0], &pairs);
        for (i, row) in r.iter().enumerate() {
            assert_eq!(row[i], 1.0);
        }
        assert!((r[0][1] - 1.0).abs() < 1e-9, "{r:?}");
        assert!(r[0][2].abs() < 0.5 && r[1][2].abs() < 0.5, "{r:?}");
    }

    /// Heading errors of 40 segments per run, 3 runs, 32 simulated logs: the same distribution
    /// measured lies inside (|z| well below 4, a 6e-5 two-sided tail), the spread is the gamma
    /// (chi-squared) one of 120 squared Gaussian errors (sd of ln RMS = sqrt(psi'(60)) / 2 =
    /// 0.065, within 30 %: its variance is estimated from 32 logs), and three times the error
    /// is far above.
    #[test]
    fn a_measurement_like_the_model_lies_inside_and_a_larger_one_above() {
        let normals = crate::testutil::normals(40 * 35, 11);
        let simulated: Vec<Vec<Vec<SegmentErrors>>> = (0..32)
            .map(|s| log(&normals[40 * s..40 * (s + 1)], 1e-3))
            .collect();
        let of_run = [0, 0, 0];
        let mut active = ImuChannels::<bool>::default();
        active[Channel::Gz] = true;
        let measured = |scale: f64| {
            let mut m = SegmentErrors {
                horizon_s: 60.0,
                ..Default::default()
            };
            for r in 0..3 {
                m.extend(&log(&normals[40 * (32 + r)..40 * (33 + r)], scale * 1e-3)[0][0]);
            }
            vec![m]
        };
        let like = drift_gap(&measured(1.0), &simulated, &of_run, &active);
        let z = like.horizons[0].quantities["heading_rad"];
        assert!(z.z.abs() < 4.0, "{z:?}");
        let sd = z.fit.scale / (1.0 + 3.0 / 32.0f64).sqrt();
        let expected = crate::gap::trigamma(60.0).sqrt() / 2.0;
        assert!((sd / expected - 1.0).abs() < 0.3, "{sd} vs {expected}");
        assert_eq!(like.horizons[0].quantities.len(), 1, "heading only");
        let above = drift_gap(&measured(3.0), &simulated, &of_run, &active);
        let z = above.horizons[0].quantities["heading_rad"];
        assert_eq!(z.verdict, Verdict::Above, "{z:?}");
        assert_eq!(above.outside, 1);
    }
}
