//! One fully specified Monte Carlo experiment: scenario + sensor model + overrides (runs, seed,
//! term switches). Built identically by `simulate`, by each shard and by `merge`, so that every
//! path produces the same report from the same per-run values.

use crate::drift::{calibrated_at_start, law_terms, DriftKernel};
use crate::laws::{LawContext, Term};
use crate::report::{build_report, DriftReport, ReportMeta};
use crate::runner::RunFailure;
use crate::scenario::Scenario;
use crate::stats::RunMatrix;
use noise::{SensorModel, TermFilter, TermSelector};

/// A front end's overrides of a scenario's settings.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Overrides {
    /// Replaces the scenario's `runs`.
    pub runs: Option<u64>,
    /// Replaces the scenario's `seed`.
    pub seed: Option<u64>,
    /// Replaces the scenario's `terms.only`.
    pub only: Option<Vec<TermSelector>>,
    /// Added to the scenario's `terms.without`.
    pub without: Vec<TermSelector>,
}

/// Why an experiment cannot be built from a scenario, a model and overrides.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ExperimentError {
    /// The run count (an override; a scenario's own `runs` is checked when it is read) is 0.
    #[error("the number of runs must be at least 1")]
    NoRuns,
    /// A generated scenario (spec's drift scenario) is not valid.
    #[error(transparent)]
    Scenario(#[from] crate::scenario::ScenarioError),
    /// The model cannot run at the scenario's rate (an output filter that does not fit it).
    #[error(transparent)]
    Rate(#[from] noise::process::RateError),
}

/// A ready experiment.
#[derive(Debug, Clone)]
pub struct Experiment {
    pub scenario: Scenario,
    /// The sensor model after the term switches.
    pub model: SensorModel,
    pub runs: u64,
    pub seed: u64,
    /// The term switches in effect (the override's `only`, else the scenario's; the scenario's
    /// `without` and then the override's).
    pub only: Option<Vec<TermSelector>>,
    pub without: Vec<TermSelector>,
    pub terms: Vec<Term>,
    /// The run-to-run mixture of the laws (docs/model.md §2.3): the law terms of the model at each
    /// node of `SensorModel::run_to_run_quadrature`, with its weight; empty when no level varies
    /// between runs (the laws are then those of `terms`).
    pub mixture: Vec<(f64, Vec<Term>)>,
    pub law_context: LawContext,
}

impl Experiment {
    /// Apply the overrides and term switches.
    pub fn new(
        scenario: Scenario,
        model: &SensorModel,
        overrides: &Overrides,
    ) -> Result<Experiment, ExperimentError> {
        let runs = overrides.runs.unwrap_or(scenario.runs);
        if runs == 0 {
            return Err(ExperimentError::NoRuns);
        }
        let seed = overrides.seed.unwrap_or(scenario.seed);
        let only = overrides.only.clone().or_else(|| scenario.only.clone());
        let mut without = scenario.without.clone();
        without.extend(overrides.without.iter().cloned());
        let filter = TermFilter::new(only.as_deref(), &without);
        let model = model.filtered(&filter);
        noise::ImuErrors::check_rate(&model, scenario.dt_s())?;
        let terms_of = |model: &SensorModel| {
            let (terms, law_context) = law_terms(
                model,
                &scenario.trajectory_spec,
                &scenario.alignment,
                &scenario.earth,
                scenario.dt_s(),
            );
            let terms = if scenario.bias_calibrated_at_start {
                calibrated_at_start(terms, scenario.bias_calibration_window_s)
            } else {
                terms
            };
            (terms, law_context)
        };
        let (terms, law_context) = terms_of(&model);
        let mixture = model
            .run_to_run_quadrature()
            .into_iter()
            .map(|(w, m)| (w, terms_of(&m).0))
            .collect();
        Ok(Experiment {
            scenario,
            model,
            runs,
            seed,
            only,
            without,
            terms,
            mixture,
            law_context,
        })
    }

    pub fn kernel(&self) -> DriftKernel {
        DriftKernel::new(&self.scenario, self.model.clone(), self.seed)
    }

    pub fn meta(&self) -> ReportMeta {
        ReportMeta {
            scenario: self.scenario.name.clone(),
            sensor: self.model.name.clone(),
            seed: self.seed,
            runs: self.runs,
            rate_hz: self.scenario.rate_hz,
            duration_s: self.scenario.duration_s,
            scheme: self.scenario.scheme.name().into(),
            trajectory: self.scenario.trajectory_spec.clone(),
            earth: crate::report::EarthReport::of(&self.scenario.earth),
            only: self.only.clone(),
            without: self.without.clone(),
            checkpoint_steps: self.scenario.checkpoint_steps.clone(),
        }
    }

    pub fn report(&self, matrix: &RunMatrix, failures: &[RunFailure]) -> DriftReport {
        build_report(
            &self.meta(),
            &self.terms,
            &self.mixture,
            &self.law_context,
            matrix,
            failures,
        )
    }
}
