//! What diagnose takes and gives: the log input, settings, errors, and the report types
//! (serialised as the JSON contract, docs/cli.md).

use crate::drift::{DriftSummary, CHANNELS};
use crate::gap::{gap, Band, Disagreement};
use crate::measure::*;
use crate::simulate::SimError;
use noise::{Effect, SensorModel};
use serde::Serialize;
use std::collections::BTreeMap;

/// The measured log, SI, channels in the order gx gy gz ax ay az (None: not in the log).
#[derive(Clone, Copy, Debug)]
pub struct LogInput<'a> {
    pub dt_s: f64,
    pub channels: [Option<&'a [f64]>; 6],
    pub temperature_c: Option<&'a [f64]>,
}

/// Settings of the workflow.
#[derive(Clone, Debug)]
pub struct Settings {
    /// Master seed of the simulated logs (written into the report).
    pub seed: u64,
    /// Simulated logs per band.
    pub seeds: usize,
    /// Add-and-resimulate rounds at most.
    pub max_rounds: usize,
    /// Drift horizons, seconds (docs/cli.md: 60 s and 1 h).
    pub horizons_s: Vec<f64>,
    /// An effect is named only if it lowers BIC by at least this much. Above 10 is "very strong"
    /// evidence on the Kass & Raftery (1995) scale; 16 sets the false-alarm rate: for one parameter and
    /// M ~ 15 taus it needs delta chi2 >= 18.7, a chi2_1 tail of 1.5e-5 if nothing is missing, so about
    /// 1e-3 per 6-channel log over the ~8 candidates per channel (measured on clean logs: see the
    /// hidden-effect tests; the tails of ln adev at small EDF are heavier than Gaussian).
    pub min_delta_bic: f64,
    /// Candidates whose BIC is within this of the best are reported as indistinguishable from it
    /// (below 6 the evidence for the best is not "strong", Kass & Raftery 1995).
    pub ambiguity_delta_bic: f64,
    /// Effects a channel may take in one round before the model is re-simulated.
    pub effects_per_round: usize,
    /// Taus below this are left out (e.g. where a sensor's internal anti-alias filter shapes the curve,
    /// an effect outside the candidate set), s.
    pub tau_min_s: f64,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            seed: 1,
            seeds: 16,
            max_rounds: 6,
            horizons_s: vec![60.0, 3600.0],
            min_delta_bic: 16.0,
            ambiguity_delta_bic: 6.0,
            effects_per_round: 3,
            tau_min_s: 0.0,
        }
    }
}

/// Errors of the workflow (inputs the caller has to fix, or a failed simulation).
#[derive(Debug, thiserror::Error)]
pub enum DiagnoseError {
    #[error("the log has no gyro or accelerometer channel (expected columns gx gy gz ax ay az)")]
    NoChannels,
    #[error("channel {channel} has {got} samples, channel {first} has {expected}: all channels must have the same length")]
    Length {
        channel: &'static str,
        got: usize,
        first: &'static str,
        expected: usize,
    },
    #[error(
        "the log is too short for an Allan analysis ({samples} samples; at least 64 are needed)"
    )]
    TooShort { samples: usize },
    #[error("sample interval must be positive and finite, got {0} s")]
    BadInterval(f64),
    #[error("the temperature column has {got} samples, the log {expected}")]
    TemperatureLength { got: usize, expected: usize },
    #[error("no Allan point at or above --tau-min {tau_min_s} s")]
    NoTaus { tau_min_s: f64 },
    #[error("a log checked against the diagnosis must have its rate and length: got {samples} samples at {dt_s} s, expected {expected_samples} at {expected_dt_s} s")]
    CheckShape {
        samples: usize,
        dt_s: f64,
        expected_samples: usize,
        expected_dt_s: f64,
    },
    #[error(transparent)]
    Simulation(#[from] SimError),
}

/// An effect's SI parameters (docs/cli.md names), and for an output filter its kind, serialised
/// first in the same JSON object (`{"kind": "bartlett", "taps": 8, ...}`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Parameters {
    pub values: BTreeMap<String, f64>,
    pub kind: Option<&'static str>,
}

impl From<BTreeMap<String, f64>> for Parameters {
    fn from(values: BTreeMap<String, f64>) -> Self {
        Parameters { values, kind: None }
    }
}

impl std::ops::Deref for Parameters {
    type Target = BTreeMap<String, f64>;
    fn deref(&self) -> &Self::Target {
        &self.values
    }
}

impl Serialize for Parameters {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut map =
            s.serialize_map(Some(self.values.len() + usize::from(self.kind.is_some())))?;
        if let Some(k) = self.kind {
            map.serialize_entry("kind", k)?;
        }
        for (k, v) in &self.values {
            map.serialize_entry(k, v)?;
        }
        map.end()
    }
}

/// A named effect: what, how much (95 % interval), and the gap around it.
#[derive(Clone, Debug, Serialize)]
pub struct FoundEffect {
    pub effect: Effect,
    /// SI parameters (docs/cli.md names).
    pub parameters: Parameters,
    /// 95 % profile-likelihood interval of each parameter.
    pub parameters_lo: BTreeMap<String, f64>,
    pub parameters_hi: BTreeMap<String, f64>,
    /// Whether the model lacks the term or has it at another level.
    pub kind: FindingKind,
    /// The model's own parameters when `kind` is [`FindingKind::WrongLevel`].
    pub model_parameters: Option<BTreeMap<String, f64>>,
    /// Channel gap (RMS z) with the model before and after the round that added the effect (both
    /// simulated; effects found in the same round share them), and as the closed forms predicted it
    /// right after adding this effect.
    pub gap_before: f64,
    pub gap_predicted: f64,
    pub gap_after: f64,
    /// BIC improvement over the unchanged model.
    pub delta_bic: f64,
    /// Other candidates the data cannot tell from this one (BIC within `ambiguity_delta_bic`).
    pub cannot_tell_from: Vec<Effect>,
    /// Round in which it was found (1 = first; 0: by a time-domain detector before the Allan
    /// rounds, see `detect`).
    pub round: usize,
    /// True when the effect is a stand-in: a term fitted to the Allan curve where no physical
    /// candidate explained the gap (a sinusoid or Gauss-Markov process at the shortest taus, where a
    /// sensor's own filtering acts, is reported as such).
    pub stand_in: bool,
    /// Later rounds that refitted its level after re-simulation.
    pub refinements: usize,
}

/// How a named effect differs from the model.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FindingKind {
    /// The model lacks the term.
    Missing,
    /// The model has the term at another level.
    WrongLevel,
}

impl std::fmt::Display for FindingKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            FindingKind::Missing => "missing",
            FindingKind::WrongLevel => "wrong_level",
        })
    }
}

/// A weighed candidate: the effect, and whether it was named and then rejected because the gap
/// did not shrink when the corrected model was re-simulated. Serialised (docs/cli.md) as the
/// effect's name, followed for a rejected one by " rejected: gap did not shrink on re-simulation".
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Candidate {
    pub effect: Effect,
    pub rejected: bool,
}

impl Serialize for Candidate {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        if self.rejected {
            s.collect_str(&format_args!(
                "{} rejected: gap did not shrink on re-simulation",
                self.effect
            ))
        } else {
            s.serialize_str(self.effect.name())
        }
    }
}

/// Why a candidate was weighed: its BIC gain and fitted parameters (every candidate, every round).
#[derive(Clone, Debug, Serialize)]
pub struct CandidateRecord {
    pub round: usize,
    pub effect: Candidate,
    /// BIC (the selection criterion) and AIC improvement over the model without it (both with the
    /// shape-search cost); `delta_aic` is NaN on the record of a rejected round.
    pub delta_bic: f64,
    pub delta_aic: f64,
    pub parameters: BTreeMap<String, f64>,
}

/// Curves of one channel for plots: measured with 1-sigma interval, band before and after.
#[derive(Clone, Debug, Serialize)]
pub struct ChannelCurves {
    pub tau_s: Vec<f64>,
    pub adev: Vec<f64>,
    pub adev_lo: Vec<f64>,
    pub adev_hi: Vec<f64>,
    pub edf: Vec<f64>,
    pub band_initial: BandView,
    pub band_final: BandView,
}

/// Band centre and 95 % seed range.
#[derive(Clone, Debug, Serialize)]
pub struct BandView {
    pub centre: Vec<f64>,
    pub lo: Vec<f64>,
    pub hi: Vec<f64>,
}

/// Everything diagnose says about one channel.
#[derive(Clone, Debug, Serialize)]
pub struct ChannelReport {
    pub gap_initial: f64,
    pub gap_final: f64,
    pub effects: Vec<FoundEffect>,
    pub z_initial: Vec<f64>,
    pub z_final: Vec<f64>,
    pub disagreements_initial: Vec<Disagreement>,
    pub disagreements_final: Vec<Disagreement>,
    /// One sentence: agrees, or what remains unexplained.
    pub verdict: String,
    pub candidates: Vec<CandidateRecord>,
    pub curves: ChannelCurves,
}

/// Drift over one horizon: measured-log segments vs the model before and after.
#[derive(Clone, Debug, Serialize)]
pub struct DriftRow {
    pub horizon_s: f64,
    pub measured: DriftSummary,
    pub model_initial: DriftSummary,
    pub model_final: DriftSummary,
}

/// The result of diagnose.
#[derive(Clone, Debug, Serialize)]
pub struct Diagnosis {
    pub seed: u64,
    pub seeds: usize,
    pub rounds: usize,
    pub dt_s: f64,
    pub samples: usize,
    pub channels: BTreeMap<String, ChannelReport>,
    pub drift: Vec<DriftRow>,
    /// Shortest tau analysed, s.
    pub tau_min_s: f64,
    /// The corrected model (written as TOML by the CLI).
    #[serde(skip)]
    pub model_final: SensorModel,
    /// Averaging factors of the tau grid and the bands of the original and corrected models (for
    /// checking held-out logs).
    #[serde(skip)]
    pub grid_m: Vec<usize>,
    #[serde(skip)]
    pub bands_initial: [Option<Band>; 6],
    #[serde(skip)]
    pub bands_final: [Option<Band>; 6],
}

/// Gap of a held-out log against the model before and after diagnosis.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct HeldOutGap {
    pub gap_model: f64,
    pub gap_corrected: f64,
}

impl Diagnosis {
    /// The gap of another log of the same rate and length (data the diagnosis did not see) against the
    /// original model's band and the corrected model's band, per channel.
    pub fn check(&self, log: &LogInput) -> Result<BTreeMap<String, HeldOutGap>, DiagnoseError> {
        let samples = validate(log)?;
        if samples != self.samples || (log.dt_s - self.dt_s).abs() > 1e-12 * self.dt_s {
            return Err(DiagnoseError::CheckShape {
                samples,
                dt_s: log.dt_s,
                expected_samples: self.samples,
                expected_dt_s: self.dt_s,
            });
        }
        // The same time-domain corrections as the diagnosed log (outliers, temperature, transient).
        let pre = crate::detect::preprocess(
            log.channels,
            log.temperature_c,
            log.dt_s,
            &crate::detect::model_levels(&self.model_final),
        );
        let corrected = LogInput {
            dt_s: log.dt_s,
            channels: std::array::from_fn(|c| pre.channels[c].as_deref()),
            temperature_c: log.temperature_c,
        };
        let (grid_m, measured) = measure(&corrected, self.tau_min_s);
        let mut out = BTreeMap::new();
        for c in 0..6 {
            let (Some(m), Some(b0), Some(b1)) = (
                measured[c].as_ref(),
                self.bands_initial[c].as_ref(),
                self.bands_final[c].as_ref(),
            ) else {
                continue;
            };
            if grid_m != self.grid_m {
                return Err(DiagnoseError::CheckShape {
                    samples,
                    dt_s: log.dt_s,
                    expected_samples: self.samples,
                    expected_dt_s: self.dt_s,
                });
            }
            out.insert(
                CHANNELS[c].to_string(),
                HeldOutGap {
                    gap_model: gap(&m.curve, &restrict(b0, &m.idx)).rms,
                    gap_corrected: gap(&m.curve, &restrict(b1, &m.idx)).rms,
                },
            );
        }
        Ok(out)
    }
}
