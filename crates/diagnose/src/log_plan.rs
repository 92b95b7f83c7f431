//! A sensor model's log plan (`imudrift plan`): for each axis and noise term of the model, where
//! the term is read off the Allan deviation of a static log, how long the log must be to read it
//! to a target relative uncertainty, and what a given length gives (the method and its sources:
//! `allan::plan`, Greenhall & Riley 2003, NIST SP 1065 5.3).

use allan::plan::{plan_term, Curve, PlanTerm, TermPlan};
use noise::closed_form::rate_random_walk_avar_sampled;
use noise::{Sensor, SensorModel};
use serde::Serialize;

/// Longest averaging time searched for a reading, s (about 12 days).
pub const MAX_TAU_S: f64 = 1e6;
/// Sample rates a plan accepts, Hz (the reading of white noise needs samples well below 1 s).
pub const MIN_RATE_HZ: f64 = 1e-2;
pub const MAX_RATE_HZ: f64 = 1e6;
/// Longest log a plan reasons about, s.
pub const MAX_DURATION_S: f64 = 1e10;

/// The plan of one axis.
#[derive(Serialize, Debug, Clone)]
pub struct AxisPlan {
    pub sensor: &'static str,
    pub axis: &'static str,
    pub terms: Vec<TermPlan>,
}

/// The plan of a model (the `imudrift plan --json` document, docs/cli.md).
#[derive(Serialize, Debug, Clone)]
pub struct PlanDoc {
    pub sensor: String,
    pub rate_hz: f64,
    pub target_uncertainty: f64,
    pub duration_s: Option<f64>,
    /// The longest of the required durations: a log this long reads every readable term.
    pub required_duration_s: Option<f64>,
    pub axes: Vec<AxisPlan>,
}

/// The plan of one axis of `model`.
fn plan_axis(
    model: &SensorModel,
    sensor: Sensor,
    axis: usize,
    dt_s: f64,
    target: f64,
    duration_s: Option<f64>,
) -> Vec<TermPlan> {
    let m = model.axis(sensor, axis);
    let total = |t: f64| m.allan_variance_sampled(t, dt_s);
    let mut out = Vec::new();
    let mut term = |kind: PlanTerm, f: &dyn Fn(f64) -> f64| {
        let curve = Curve {
            total: &total,
            term: f,
        };
        out.push(plan_term(kind, &curve, dt_s, target, duration_s, MAX_TAU_S));
    };
    if let Some(n) = m.white_noise_density() {
        // The Allan variance of sampled white noise is exactly N^2 / tau (IEEE 952 annex C), before
        // or after the output filter (`AxisModel::white_noise_density`).
        term(PlanTerm::WhiteNoise, &|t| n * n / t);
    }
    if let Some(bi) = m.get::<noise::BiasInstability>() {
        term(PlanTerm::BiasInstability, &|t| bi.avar_sampled(t, dt_s));
    }
    if let Some(k) = m
        .get::<noise::RateRandomWalk>()
        .map(noise::RateRandomWalk::density)
    {
        term(PlanTerm::RateRandomWalk, &|t| {
            rate_random_walk_avar_sampled(k, t, dt_s)
        });
    }
    out
}

/// The plan of `model` for a static log at `rate_hz` (within [`MIN_RATE_HZ`]..[`MAX_RATE_HZ`],
/// checked by the caller), each reading to relative uncertainty `target` (in (0, 1)), and what a
/// log of `duration_s` gives. `None` when the model has no white noise, bias instability or rate
/// random walk to plan for.
pub fn plan(
    model: &SensorModel,
    rate_hz: f64,
    target: f64,
    duration_s: Option<f64>,
) -> Option<PlanDoc> {
    let dt_s = 1.0 / rate_hz;
    let mut axes = Vec::new();
    for (sensor, name) in [(Sensor::Gyro, "gyro"), (Sensor::Accel, "accel")] {
        for (axis, axis_name) in ["x", "y", "z"].into_iter().enumerate() {
            let terms = plan_axis(model, sensor, axis, dt_s, target, duration_s);
            if !terms.is_empty() {
                axes.push(AxisPlan {
                    sensor: name,
                    axis: axis_name,
                    terms,
                });
            }
        }
    }
    if axes.is_empty() {
        return None;
    }
    let required_duration_s = axes
        .iter()
        .flat_map(|a| a.terms.iter().filter_map(|t| t.required_duration_s))
        .max_by(f64::total_cmp);
    Some(PlanDoc {
        sensor: model.name.clone(),
        rate_hz,
        target_uncertainty: target,
        duration_s,
        required_duration_s,
        axes,
    })
}
