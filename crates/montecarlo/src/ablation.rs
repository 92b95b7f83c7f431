//! Ablation: each active error term alone, and the model without it, as Woodman did by
//! "selectively removing sensor noise" from his simulations (TR-696 §6.2): which term dominates
//! the horizontal drift, and when. The sub-experiments are built from the parsed scenario and
//! model (no re-parse); shards carry their slices of them so a merge gives the same table.

use crate::experiment::{Experiment, Overrides};
use crate::nav_quantity::NavQuantity;
use crate::report::DriftReport;
use crate::runner::RunFailure;
use crate::scenario::Scenario;
use crate::stats::RunMatrix;
use noise::{Effect, Sensor, SensorModel, TermSelector};
use serde::{Deserialize, Serialize};

/// One row of the ablation table.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AblationRow {
    pub term: String,
    /// Mean horizontal error at the last checkpoint with only this term.
    pub only_mean_m: f64,
    /// Its share of the full model's mean square horizontal error, only_rms^2 / full_rms^2.
    pub only_share: f64,
    /// Mean horizontal error at the last checkpoint with every term but this one.
    pub without_mean_m: f64,
    /// Horizontal rms with only this term, at every checkpoint.
    pub only_rms_m: Vec<f64>,
}

/// The two sub-experiments of one term.
pub struct TermExperiments {
    pub term: String,
    pub only: Experiment,
    pub without: Experiment,
}

/// Per-run values of a slice of one sub-experiment's runs (what a shard stores).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Batch {
    pub matrix: RunMatrix,
    pub failures: Vec<RunFailure>,
}

/// A shard's slices of one term's two sub-experiments.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TermBatches {
    pub term: String,
    pub only: Batch,
    pub without: Batch,
}

/// The terms an ablation covers: the experiment's active sensor error terms, sorted by name as
/// the report lists them (the initial alignment errors are not a sensor term).
pub fn terms(exp: &Experiment) -> Vec<TermSelector> {
    let active: std::collections::BTreeSet<&str> =
        exp.terms.iter().map(|t| t.name.as_str()).collect();
    let mut terms: Vec<TermSelector> = Sensor::ALL
        .into_iter()
        .flat_map(|s| {
            Effect::ALL
                .into_iter()
                .map(move |e| TermSelector::term(s, e))
        })
        .filter(|t| active.contains(t.text()))
        .collect();
    terms.sort_by(|a, b| a.text().cmp(b.text()));
    terms
}

/// For each term of [`terms`], the experiment with only that term and the one without it, both
/// with `overrides` (runs, seed, switches) otherwise as the full experiment.
pub fn experiments(
    scenario: &Scenario,
    model: &SensorModel,
    overrides: &Overrides,
    full: &Experiment,
) -> Result<Vec<TermExperiments>, crate::experiment::ExperimentError> {
    terms(full)
        .into_iter()
        .map(|term| {
            let only = Experiment::new(
                scenario.clone(),
                model,
                &Overrides {
                    only: Some(vec![term.clone()]),
                    ..overrides.clone()
                },
            )?;
            let mut without = overrides.without.clone();
            without.push(term.clone());
            let without = Experiment::new(
                scenario.clone(),
                model,
                &Overrides {
                    without,
                    ..overrides.clone()
                },
            )?;
            Ok(TermExperiments {
                term: term.text().to_string(),
                only,
                without,
            })
        })
        .collect()
}

fn last_horizontal(r: &DriftReport) -> (f64, f64) {
    r.checkpoints.last().map_or((f64::NAN, f64::NAN), |cp| {
        let c = &cp.quantities[NavQuantity::PosHorizontal.name()];
        (c.mean, c.rms)
    })
}

/// The table from the full report and, per term, the reports with only it and without it.
pub fn rows(
    full: &DriftReport,
    per_term: &[(String, DriftReport, DriftReport)],
) -> Vec<AblationRow> {
    let (_, full_rms) = last_horizontal(full);
    per_term
        .iter()
        .map(|(term, only, without)| {
            let (only_mean_m, only_rms) = last_horizontal(only);
            AblationRow {
                term: term.clone(),
                only_mean_m,
                only_share: (only_rms / full_rms).powi(2),
                without_mean_m: last_horizontal(without).0,
                only_rms_m: only
                    .checkpoints
                    .iter()
                    .map(|c| c.quantities[NavQuantity::PosHorizontal.name()].rms)
                    .collect(),
            }
        })
        .collect()
}

/// The term with the largest horizontal mean square alone, per checkpoint, merged into time spans:
/// (term, first t_s, last t_s). Woodman: accelerometer noise dominates only the first ~0.3 s.
pub fn dominant_spans(report: &DriftReport, rows: &[AblationRow]) -> Vec<(String, f64, f64)> {
    let mut spans: Vec<(String, f64, f64)> = Vec::new();
    for (i, cp) in report.checkpoints.iter().enumerate() {
        let Some(best) = rows
            .iter()
            .max_by(|a, b| a.only_rms_m[i].total_cmp(&b.only_rms_m[i]))
        else {
            continue;
        };
        match spans.last_mut() {
            Some(last) if last.0 == best.term => last.2 = cp.t_s,
            _ => spans.push((best.term.clone(), cp.t_s, cp.t_s)),
        }
    }
    spans
}
