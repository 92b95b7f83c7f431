//! The drift gap of diagnose (docs/diagnose.md, "Drift in the loop"): the runs' drift under a
//! protocol (`protocol`, the `drift` command's procedure) against the drift of the model's
//! simulated logs, as a z-score per horizon and drift quantity, like the Allan gap per tau.
//!
//! The model's distribution comes from the band's own simulated logs (no further simulation):
//! replicate s pools, for run r, simulated log (s + r) mod seeds at run r's length (`simulate`),
//! so it is distributed exactly as the runs' pooled drift. For each replicate the RMS over its
//! pooled segments; ln RMS is summarised by its mean mu and standard deviation sd over the
//! replicates, sd corrected for the logs the replicates share (by sqrt((seeds - 1) /
//! (seeds - runs)), as the band's spread). The measured pooled RMS gives
//! z = (ln RMS_measured - mu) / (sd sqrt(1 + runs / seeds)): the measurement is one draw of the
//! replicate distribution (sd), the centre is known from seeds / runs independent logs. A
//! log-normal reading of the RMS: the band is exp(mu +- 1.96 sd sqrt(1 + runs / seeds)) and
//! the verdict `inside` when |z| <= 1.96. The drift gap is the RMS of z over the informed
//! (horizon, quantity) pairs.

use crate::drift_check::Verdict;
use crate::input::LogInput;
use crate::protocol::{all_segment_errors, Protocol, Quantity, SegmentErrors};
use noise::Channel;
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
}

impl DriftGap {
    /// The informed (horizon index, quantity, z) whose quantity comes from channel `c`.
    pub(crate) fn of_channel(&self, c: Channel) -> Vec<(usize, Quantity, DriftFit)> {
        let mut out = Vec::new();
        for (h, hz) in self.horizons.iter().enumerate() {
            for q in Quantity::ALL {
                if let Some(d) = hz.quantities.get(q.name()) {
                    if q.needs().contains(&c) {
                        out.push((h, q, d.fit));
                    }
                }
            }
        }
        out
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
        .map(|l| all_segment_errors(&l.channels, l.dt_s, p))
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
    active: &[bool; 6],
) -> DriftGap {
    let seeds = simulated.len();
    let runs = of_run.len();
    let horizons: Vec<DriftGapHorizon> = measured
        .iter()
        .enumerate()
        .map(|(h, meas)| {
            let mut quantities = BTreeMap::new();
            for q in Quantity::ALL {
                let informed = q.needs().iter().all(|c| active[c.index()]);
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
                let all: Vec<f64> = (0..seeds).flat_map(replicate).copied().collect();
                if let Some(d) = quantity_z(values, &ln_rms, &all, runs) {
                    quantities.insert(q.name(), d);
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
    }
}

/// One quantity's z (module doc) from the measured values, the replicates' ln RMS and all the
/// simulated values; None when the model or the measurement has no drift there.
fn quantity_z(measured: &[f64], ln_rms: &[f64], all: &[f64], runs: usize) -> Option<DriftZ> {
    let seeds = ln_rms.len() as f64;
    let mu = stats::mean(ln_rms);
    let var = ln_rms.iter().map(|l| (l - mu) * (l - mu)).sum::<f64>() / (seeds - 1.0);
    let widen = (seeds - 1.0) / (seeds - runs as f64);
    let scale = (var * widen * (1.0 + runs as f64 / seeds)).sqrt();
    let rms = stats::rms(measured);
    let mean_square = all.iter().map(|x| x * x).sum::<f64>() / all.len() as f64;
    if !(rms > 0.0 && scale > 0.0 && mu.is_finite() && mean_square > 0.0) {
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
