//! The drift report: per checkpoint and navigation-error quantity, the simulated statistics beside the law of the
//! active terms, the ratio simulated/law and its 99.9 % confidence interval (docs/cli.md `simulate`
//! JSON fields: `seed`, `runs`, `checkpoints[]` with `t_s` and `channels{name: {mean, std, rms, p50,
//! p95, law_std, ratio}}`; more fields are added, none renamed).

use crate::earth_laws::mixture_laws;
use crate::laws::{Law, LawContext, Term};
use crate::nav_quantity::NavQuantity;
use crate::runner::RunFailure;
use crate::stats::{ratio_interval, summarise, RunMatrix, Z_999};
use noise::TermSelector;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use strapdown::spec::TrajectorySpec;
use strapdown::{EarthModel, Vertical};

/// Stated allowance for the law's own discretisation error, relative, times dt/t: the laws are
/// continuous-time integrals while the mechanisation sums up to three nested rectangle or trapezoid
/// rules per step; each nesting shifts the result by at most about one sample (e.g. Woodman's exact
/// discrete accelerometer sum n(n+1)(2n+1)/6 against n^3/3, eqs 15-17: relative 3/(2n)), so the
/// relative deviation is below 4 dt/t. Added to the statistical interval, never instead of it.
pub const DISCRETISATION_ALLOWANCE_STEPS: f64 = 4.0;

/// Stated allowance for the round Earth's laws, relative: the linearised error model against the
/// nonlinear round-Earth mechanisation it describes (products of errors dropped, the
/// mechanisation's Earth quantities refreshed every few steps). Measured where the Monte Carlo
/// has no statistical spread (deterministic errors): a gyro or accelerometer bias on one axis
/// agrees to 1.3e-3 up to 4 h (strapdown's error_model tests), biases on two axes at once (a gyro
/// scale factor on Earth rate) to 4.1e-3 at 1 h (montecarlo's round_earth_laws tests); 5e-3
/// covers them. Added to the statistical interval, never instead of it (a 200-run interval is
/// some 20 times wider).
pub const ROUND_EARTH_ALLOWANCE: f64 = 5e-3;

/// One navigation-error quantity at one checkpoint.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct QuantityReport {
    pub mean: f64,
    pub std: f64,
    pub rms: f64,
    pub p5: f64,
    pub p50: f64,
    pub p95: f64,
    /// Law: signed mean of the deterministic terms (for horizontal quantities: mean magnitude).
    pub law_mean: Option<f64>,
    /// Law: standard deviation.
    pub law_std: Option<f64>,
    /// Law: rms = sqrt(law_mean^2 + law_std^2) (horizontal: sqrt of the summed component rms^2).
    pub law_rms: Option<f64>,
    /// rms / law_rms.
    pub ratio: Option<f64>,
    /// 99.9 % interval of `ratio` (statistical, from the runs, widened by the discretisation allowance).
    pub ratio_lo: Option<f64>,
    pub ratio_hi: Option<f64>,
    /// mean / law_mean where the law has a non-zero mean (deterministic terms; the horizontal
    /// magnitudes' Rayleigh-type mean), with its 99.9 % interval: standard error std/sqrt(n) from the
    /// runs (central limit theorem), widened by the same discretisation allowance.
    pub mean_ratio: Option<f64>,
    pub mean_ratio_lo: Option<f64>,
    pub mean_ratio_hi: Option<f64>,
    /// Why there is no law, when there is none.
    pub law_note: Option<String>,
    /// On the round Earth, for a static level north-facing IMU: what the flat Earth's closed
    /// forms (Woodman's) would give for the same terms, rms, beside the round Earth's `law_rms`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flat_law_rms: Option<f64>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CheckpointReport {
    pub t_s: f64,
    pub step: u64,
    /// Per quantity by its name (JSON key `channels`, docs/cli.md).
    #[serde(rename = "channels")]
    pub quantities: BTreeMap<String, QuantityReport>,
}

/// The whole `simulate` result.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DriftReport {
    pub scenario: String,
    pub sensor: String,
    pub seed: u64,
    /// Runs requested.
    pub runs: u64,
    /// Runs that finished and enter the statistics.
    pub runs_ok: u64,
    pub failed_runs: Vec<RunFailure>,
    pub rate_hz: f64,
    pub duration_s: f64,
    pub scheme: String,
    /// The scenario's trajectory as written, tagged by `kind`, units in the field names
    /// (docs/cli.md).
    pub trajectory: TrajectorySpec,
    /// The Earth the runs and the laws used (the scenario's `[earth]` table).
    #[serde(default)]
    pub earth: EarthReport,
    /// The active error terms after the term switches `only` / `without` (docs/cli.md names).
    pub active_terms: Vec<String>,
    pub only: Option<Vec<TermSelector>>,
    pub without: Vec<TermSelector>,
    /// Confidence level of `ratio_lo` .. `ratio_hi`.
    pub confidence: f64,
    pub checkpoints: Vec<CheckpointReport>,
}

/// The Earth of a report, in the scenario's `[earth]` names: `model` `wgs84` with its place and
/// vertical channel, or `flat`; gravity at the start place either way.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct EarthReport {
    pub model: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub latitude_deg: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub longitude_deg: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub height_m: Option<f64>,
    /// `held` (a known height) or `free` (the unaided vertical channel).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub vertical: Option<String>,
    pub gravity_mps2: f64,
}

impl EarthReport {
    pub fn of(earth: &EarthModel) -> EarthReport {
        let round = earth.round();
        EarthReport {
            model: earth.name().to_string(),
            latitude_deg: round.map(|e| e.place.lat_rad.to_degrees()),
            longitude_deg: round.map(|e| e.place.lon_rad.to_degrees()),
            height_m: round.map(|e| e.place.height_m),
            vertical: round.map(|e| {
                match e.vertical {
                    Vertical::Held => "held",
                    Vertical::Free => "free",
                }
                .to_string()
            }),
            gravity_mps2: earth.gravity_mps2(),
        }
    }

    /// One line for people: `WGS-84 at 45 deg N, 0 deg E, 0 m, height held` or `flat (Woodman), g = 9.80665 m/s^2`.
    pub fn describe(&self) -> String {
        match (self.latitude_deg, self.longitude_deg, self.height_m) {
            (Some(lat), Some(lon), Some(h)) => format!(
                "WGS-84, rotating, at {:.4} deg {}, {:.4} deg {}, {h} m; vertical channel {}",
                lat.abs(),
                if lat < 0.0 { "S" } else { "N" },
                lon.abs(),
                if lon < 0.0 { "W" } else { "E" },
                match self.vertical.as_deref() {
                    Some("free") => "free (unaided, diverging)",
                    _ => "held (known height)",
                }
            ),
            _ => format!(
                "flat, non-rotating (Woodman), g = {} m/s^2",
                self.gravity_mps2
            ),
        }
    }
}

/// Everything a report needs besides the runs.
#[derive(Debug, Clone)]
pub struct ReportMeta {
    pub scenario: String,
    pub sensor: String,
    pub seed: u64,
    pub runs: u64,
    pub rate_hz: f64,
    pub duration_s: f64,
    pub scheme: String,
    pub trajectory: TrajectorySpec,
    pub earth: EarthReport,
    pub only: Option<Vec<TermSelector>>,
    pub without: Vec<TermSelector>,
    pub checkpoint_steps: Vec<u64>,
}

/// The chi-square degrees of freedom one run gives a quantity's square when its errors are
/// Gaussian: 1 for a component, 2 for a horizontal magnitude (north^2 + east^2).
fn dof_per_run(q: NavQuantity) -> f64 {
    match q {
        NavQuantity::PosHorizontal | NavQuantity::VelHorizontal => 2.0,
        _ => 1.0,
    }
}

fn finite(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

/// Build the report from the per-run values (run-index order) and the active terms.
pub fn build_report(
    meta: &ReportMeta,
    terms: &[Term],
    mixture: &[(f64, Vec<Term>)],
    ctx: &LawContext,
    matrix: &RunMatrix,
    failures: &[RunFailure],
) -> DriftReport {
    let dt_s = 1.0 / meta.rate_hz;
    let times: Vec<f64> = meta
        .checkpoint_steps
        .iter()
        .map(|&step| step as f64 * dt_s)
        .collect();
    let all = mixture_laws(terms, mixture, ctx, &times);
    // The flat Earth's laws beside the round Earth's, where they hold (static level north-facing).
    let flat: Option<Vec<Vec<Law>>> = (ctx.earth.round().is_some()
        && ctx.static_level
        && ctx.attitude == strapdown::Attitude::identity())
    .then(|| {
        let flat_ctx = LawContext {
            earth: EarthModel::Flat {
                gravity_mps2: ctx.gravity_mps2,
            },
            ..ctx.clone()
        };
        mixture_laws(terms, mixture, &flat_ctx, &times)
    });
    let checkpoints = meta
        .checkpoint_steps
        .iter()
        .enumerate()
        .map(|(cp, &step)| {
            let t_s = times[cp];
            let laws = &all[cp];
            let allowance = DISCRETISATION_ALLOWANCE_STEPS / step as f64
                + if meta.earth.model == "wgs84" {
                    ROUND_EARTH_ALLOWANCE
                } else {
                    0.0
                };
            let quantities = NavQuantity::ALL
                .iter()
                .map(|&q| {
                    let s = summarise(matrix.series(cp, q as usize));
                    let law = &laws[q as usize];
                    let mut r = QuantityReport {
                        mean: s.mean,
                        std: s.std,
                        rms: s.rms,
                        p5: s.p5,
                        p50: s.p50,
                        p95: s.p95,
                        law_mean: None,
                        law_std: None,
                        law_rms: None,
                        ratio: None,
                        ratio_lo: None,
                        ratio_hi: None,
                        mean_ratio: None,
                        mean_ratio_lo: None,
                        mean_ratio_hi: None,
                        law_note: None,
                        flat_law_rms: flat
                            .as_ref()
                            .and_then(|f| f[cp][q as usize].rms())
                            .and_then(finite),
                    };
                    // The law's own stated uncertainty (0 for the flat closed forms).
                    let allowance = match law {
                        Law::Value { allowance: own, .. } => allowance + own,
                        Law::NotApplicable(_) => allowance,
                    };
                    match law {
                        Law::Value { mean, std, .. } => {
                            let law_rms = law.rms().unwrap_or(f64::NAN);
                            r.law_mean = finite(*mean);
                            r.law_std = finite(*std);
                            r.law_rms = finite(law_rms);
                            if law_rms > 0.0 && s.count > 1 {
                                let (lo, hi) =
                                    ratio_interval(&s, law_rms, Z_999, allowance, dof_per_run(q));
                                r.ratio = finite(s.rms / law_rms);
                                r.ratio_lo = finite(lo);
                                r.ratio_hi = finite(hi);
                            } else if law_rms == 0.0 {
                                r.law_note =
                                    Some("law is zero: no active term drives this channel".into());
                            }
                        }
                        Law::NotApplicable(why) => r.law_note = Some(why.clone()),
                    }
                    if let (Some(m), true) = (r.law_mean, s.count > 1) {
                        if m != 0.0 {
                            let half = Z_999 * s.std / (s.count as f64).sqrt() / m.abs();
                            let ratio = s.mean / m;
                            r.mean_ratio = finite(ratio);
                            r.mean_ratio_lo = finite((ratio - half) * (1.0 - allowance));
                            r.mean_ratio_hi = finite((ratio + half) * (1.0 + allowance));
                        }
                    }
                    (q.name().to_string(), r)
                })
                .collect();
            CheckpointReport {
                t_s,
                step,
                quantities,
            }
        })
        .collect();
    DriftReport {
        scenario: meta.scenario.clone(),
        sensor: meta.sensor.clone(),
        seed: meta.seed,
        runs: meta.runs,
        runs_ok: matrix.runs() as u64,
        failed_runs: failures.to_vec(),
        rate_hz: meta.rate_hz,
        duration_s: meta.duration_s,
        scheme: meta.scheme.clone(),
        trajectory: meta.trajectory.clone(),
        earth: meta.earth.clone(),
        active_terms: terms
            .iter()
            .map(|t| t.name.clone())
            .collect::<std::collections::BTreeSet<_>>()
            .into_iter()
            .collect(),
        only: meta.only.clone(),
        without: meta.without.clone(),
        confidence: 0.999,
        checkpoints,
    }
}
