//! What diagnose gives: the report types (serialised as the JSON contract, docs/cli.md).

use crate::drift::DriftSummary;
use crate::gap::{Band, Disagreement};
use noise::{Channel, Effect, ImuChannels, SensorModel};
use serde::Serialize;
use std::collections::BTreeMap;

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
    /// Named by the drift loop (`drift_fit`): the drift gap before the round that added it and
    /// after the round's re-simulation (absent otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub drift_gap_before: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub drift_gap_after: Option<f64>,
    /// The fitted level is 0: the change removes the term (never serialised; an effect of size 0
    /// is not a finding, `findings::merge_refinements`).
    #[serde(skip)]
    pub zero_level: bool,
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
/// did not shrink when the corrected model was re-simulated, or withdrawn because a later round
/// refitted its level to 0. Serialised (docs/cli.md) as the effect's name, followed for a
/// rejected one by " rejected: gap did not shrink on re-simulation" and for a withdrawn one by
/// " withdrawn: a later round refitted its level to 0".
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Candidate {
    pub effect: Effect,
    pub rejected: bool,
    pub withdrawn: bool,
}

impl Serialize for Candidate {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        if self.withdrawn {
            s.collect_str(&format_args!(
                "{} withdrawn: a later round refitted its level to 0",
                self.effect
            ))
        } else if self.rejected {
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
    pub channels: BTreeMap<Channel, ChannelReport>,
    pub drift: Vec<DriftRow>,
    /// Several runs pooled: each run's curves, gaps and step-0 findings, in input order (absent
    /// for one log; docs/cli.md).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub runs: Vec<RunReport>,
    /// The drift check in the loop (`Settings::drift_protocol`): the drift gap of the original and
    /// of the corrected model (absent without a protocol).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub drift_check: Option<DriftLoop>,
    /// The structures the drift loop could not tell from the ones it kept, with their weights
    /// (`alternatives`; the corrected model carries them for `drift`'s band).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub alternatives: Vec<crate::alternatives::Alternative>,
    /// Several runs: each channel's run-to-run variation of its slow group, with its test and
    /// interval (`run_spread`; the named ones are in the corrected model as `run_to_run`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub run_to_run: Vec<crate::run_spread::RunSpread>,
    /// Shortest tau analysed, s.
    pub tau_min_s: f64,
    /// The corrected model (written as TOML by the CLI).
    #[serde(skip)]
    pub model_final: SensorModel,
    /// Averaging factors of the tau grid and the bands of one log of the original and corrected
    /// models at each run length (for checking held-out logs).
    #[serde(skip)]
    pub grid_m: Vec<usize>,
    #[serde(skip)]
    pub log_bands: Vec<LogBands>,
}

impl Diagnosis {
    /// What the corrected model's levels and spreads were fitted on (`FittedOn`, its
    /// `[fitted_on]` table): the diagnosed `logs` (as given to the diagnosis) and how each
    /// run-to-run spread was estimated from them.
    pub fn fitted_on(&self, logs: &[crate::input::LogInput]) -> Option<crate::fitted_on::FittedOn> {
        crate::fitted_on::FittedOn::from_logs(logs, self.tau_min_s)
            .map(|f| f.with_run_spreads(self.run_to_run.iter().filter_map(|s| s.fit())))
    }
}

/// The drift check of diagnose: the protocol, and the drift gap of the original model and of the
/// corrected one (`drift_gap`).
#[derive(Clone, Debug, Serialize)]
pub struct DriftLoop {
    pub protocol: crate::protocol::Protocol,
    pub protocol_text: String,
    pub before: crate::drift_gap::DriftGap,
    pub after: crate::drift_gap::DriftGap,
}

/// The bands of one log of a given length, of the original and of the corrected model.
#[derive(Clone, Debug)]
pub struct LogBands {
    pub samples: usize,
    pub initial: ImuChannels<Option<Band>>,
    pub corrected: ImuChannels<Option<Band>>,
}

/// One run of several pooled: its own curve per channel (after step 0's corrections), its gap
/// against one log of the original model (before the corrections) and of the corrected model, and
/// what step 0 found in it (the gaps of a finding are the run's before and after its corrections,
/// against the original model).
#[derive(Clone, Debug, Serialize)]
pub struct RunReport {
    pub samples: usize,
    pub channels: BTreeMap<Channel, RunChannel>,
    pub findings: BTreeMap<Channel, Vec<FoundEffect>>,
}

/// One run's channel.
#[derive(Clone, Debug, Serialize)]
pub struct RunChannel {
    pub tau_s: Vec<f64>,
    pub adev: Vec<f64>,
    pub edf: Vec<f64>,
    pub gap_initial: f64,
    pub gap_final: f64,
}

/// Gap of a held-out log against the model before and after diagnosis.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct HeldOutGap {
    pub gap_model: f64,
    pub gap_corrected: f64,
}
