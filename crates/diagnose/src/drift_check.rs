//! Drift predicted against drift measured (docs/drift.md): the measured logs of one sensor and
//! logs simulated from its model, cut and calibrated by one `Protocol`; per horizon and drift
//! quantity the measured statistics with an interval, the model's distribution of the same
//! statistic, and a verdict.
//!
//! Measured interval: the RMS over n segments is read as an RMS of n_eff independent errors,
//! RMS^2 ~ E[e^2] chi2(n_eff) / n_eff (Gaussian errors), so its 95 % interval is
//! [RMS sqrt(n_eff / chi2_0.975), RMS sqrt(n_eff / chi2_0.025)]. n_eff = n (1 - rho) / (1 + rho)
//! with rho the lag-1 autocorrelation of e^2 over consecutive segments of a log (the AR(1)
//! effective count, e.g. Bayley & Hammersley 1946), clamped to [0, 0.95] and taken as 0 below
//! 8 segments in a log; half-overlapping segments count as half.
//!
//! Model band: `replicates` simulated experiments, each one simulated log per measured log (same
//! length, rate and channels), give the distribution of the same RMS; the band is the
//! distribution-free 95 % prediction interval of those R values (order statistics a and R + 1 - a,
//! a = 0.025 (R + 1), coverage (R + 1 - 2a) / (R + 1) = 95 %). The verdict is "inside" when the
//! measured RMS lies in the band, "above" or "below" otherwise, "not_informed" when a log lacks a
//! channel the quantity comes from or no log is as long as the horizon.
//!
//! Runs that differ among themselves: with two logs or more, the spread of the logs' own RMS,
//! D = the sample variance over the logs of ln(mean square of the log's segments), is set beside
//! its distribution under the model, the same D of each simulated experiment's logs (one sensor
//! model for every log of an experiment). Its p-value (1 + #{D_r >= D}) / (R + 1) is the Monte
//! Carlo test's (the rank of the measured D among R exchangeable replicates; Davison & Hinkley,
//! Bootstrap Methods and their Application, 1997, §4.2.5), at least 1 / (R + 1). Below 0.05 the runs differ beyond the model's own
//! randomness: a run-to-run variation of the sensor (its bias wander, its temperature) that one
//! model with fixed levels cannot hold, whatever its levels; a band from one group of runs then
//! says little about another.
//!
//! Parameter uncertainty: a model that records the data it was fitted on (`FittedOn`) gives each
//! replicate its own levels, drawn by the parametric bootstrap of `bootstrap` (docs/drift.md,
//! "Parameter uncertainty"), so that the band holds the fit's uncertainty too; a model that does
//! not (a datasheet) is taken as exact and every replicate simulates it as it is.

use crate::alternatives::{self, Alternative, Structure};
use crate::bootstrap::{draw_models, draw_models_on, BootstrapError, ParameterSpread};
use crate::drift_joint::{between_logs_joint, joint_check, BetweenLogsJoint, Cell, JointCheck};
use crate::fitted_on::{FittedOn, SpreadFit};
use crate::input::LogInput;
use crate::observer::Observer;
use crate::protocol::{all_segment_errors, Protocol, Quantity, SegmentErrors};
use crate::simulate::{map_static_logs, LogJob, SimSetup};
use noise::SensorModel;
use rayon::prelude::*;
use serde::Serialize;
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, Ordering};

/// Settings of a drift check.
#[derive(Clone, Debug)]
pub struct CheckSettings {
    pub protocol: Protocol,
    /// Simulated experiments for the model's band.
    pub replicates: usize,
    pub seed: u64,
}

/// Measured statistics of |error| over the pooled segments.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Measured {
    /// Mean |error| (Woodman's statistic) and its 95 % interval (normal, standard error
    /// sd(|e|) / sqrt(n_eff)).
    pub mean: f64,
    pub mean_lo: f64,
    pub mean_hi: f64,
    pub p50: f64,
    pub p95: f64,
    pub rms: f64,
    pub rms_lo: f64,
    pub rms_hi: f64,
    pub n_eff: f64,
}

/// The model's statistics under the same protocol.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Model {
    pub mean: f64,
    pub p50: f64,
    pub p95: f64,
    pub rms: f64,
    /// Central 95 % of the RMS over as many segments as measured.
    pub band_lo: f64,
    pub band_hi: f64,
}

/// Where the measurement lies against the model.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    Inside,
    Above,
    Below,
    NotInformed,
}

impl Verdict {
    pub fn name(self) -> &'static str {
        match self {
            Verdict::Inside => "inside",
            Verdict::Above => "above",
            Verdict::Below => "below",
            Verdict::NotInformed => "not_informed",
        }
    }
}

/// One quantity at one horizon.
#[derive(Clone, Debug, Serialize)]
pub struct QuantityCheck {
    pub measured: Option<Measured>,
    pub model: Option<Model>,
    pub verdict: Verdict,
    /// Measured RMS / model RMS.
    pub ratio: Option<f64>,
    /// Why a quantity is not informed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
    /// With two logs or more: how far the logs' own RMS differ among themselves, against the
    /// model's randomness (module doc).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub between_logs: Option<BetweenLogs>,
    /// For a measurement outside the band: the likely cause, from the channels the quantity
    /// comes from, the horizon and the model's terms (a pointer for `diagnose`, not a proof).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub likely_cause: Option<String>,
}

/// The spread of the logs' RMS among themselves against the model's (module doc).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct BetweenLogs {
    /// Standard deviation over the logs of ln(RMS of the log's segments): measured, and the
    /// median over the simulated experiments.
    pub sd_ln_rms: f64,
    pub model_sd_ln_rms: f64,
    /// Share of simulated experiments whose logs spread as far or further, (1 + k) / (R + 1).
    pub p_value: f64,
    /// p < 0.05: the runs differ beyond the model's randomness.
    pub runs_differ: bool,
}

/// Level of the between-log test (module doc).
const BETWEEN_LOGS_LEVEL: f64 = 0.05;

/// D of the module doc over logs' segment values `per_log` (None with fewer than two logs that
/// hold a segment with a non-zero mean square).
fn ln_ms_variance<'a>(per_log: impl Iterator<Item = &'a [f64]>) -> Option<f64> {
    let ln: Vec<f64> = per_log
        .filter(|v| !v.is_empty())
        .map(|v| stats::mean_square(v).ln())
        .filter(|x| x.is_finite())
        .collect();
    if ln.len() < 2 {
        return None;
    }
    Some(stats::sample_variance(&ln))
}

/// The likely cause of a verdict outside the band (module doc): which channels, which kind of
/// term. Short horizons (up to a minute) are ruled by white noise and fast bias wander, long
/// ones by slow bias wander (Woodman §3.2: white noise grows as sqrt(t), bias terms as t and
/// faster, so the long-horizon drift is the slow terms').
fn likely_cause(
    q: Quantity,
    horizon_s: f64,
    verdict: Verdict,
    model: &SensorModel,
) -> Option<String> {
    let chans: Vec<&str> = q.needs().iter().map(|c| c.name()).collect();
    let list = chans.join(", ");
    let short = horizon_s <= 60.0;
    match verdict {
        Verdict::Above if short => Some(format!(
            "the sensor's white noise or fast bias wander on {list} is above the model's (`imudrift diagnose` on a log measures both)"
        )),
        Verdict::Above => Some(format!(
            "slow bias wander on {list} (bias instability, rate random walk or temperature) larger than the model's; one log's length may not resolve it"
        )),
        Verdict::Below => {
            let (fast, slow) = terms_by_time_scale(model, q.needs());
            let white = if fast.is_empty() {
                "white noise".to_string()
            } else {
                format!(
                    "white noise or short-time stand-ins ({fast}, terms `diagnose` fits for a filter at the shortest averaging times)"
                )
            };
            Some(if slow.is_empty() {
                // No slow term on these channels: the drift is the white noise's (and the
                // stand-ins'), at any horizon.
                format!("the model's {white} on {list} is above the sensor's")
            } else {
                format!(
                    "the model's slow terms on {list} ({slow}) wander further from the calibration than the sensor does{}",
                    if short { format!("; or its {white} is above the sensor's") } else { String::new() }
                )
            })
        }
        _ => None,
    }
}

/// A Gauss-Markov process faster than this, or a sinusoid above its inverse, is a short-time
/// stand-in (what `diagnose` fits for an output filter's shape: correlation times of milliseconds,
/// lines near the filter's cutoff); slower ones, and every random walk, flicker or power-law level and ramp,
/// set the slow wander about the calibration.
const STAND_IN_TIME_S: f64 = 1.0;

/// The stochastic terms on `channels` in two lists, the short-time stand-ins and the slow terms
/// (`STAND_IN_TIME_S`), each as "effect on channel, channel; effect on channel" (one entry per
/// effect, its channels in order).
fn terms_by_time_scale(model: &SensorModel, channels: &[noise::Channel]) -> (String, String) {
    use noise::{Effect, GaussMarkov, Sinusoid, SlowGaussMarkov};
    let mut fast: Vec<(Effect, &str)> = Vec::new();
    let mut slow: Vec<(Effect, &str)> = Vec::new();
    for &c in channels {
        let a = model.axis(c.sensor(), c.axis());
        if let Some(g) = a.get::<GaussMarkov>() {
            let list = if g.tau_s() < STAND_IN_TIME_S {
                &mut fast
            } else {
                &mut slow
            };
            list.push((Effect::GaussMarkov, c.name()));
        }
        if let Some(t) = a.get::<Sinusoid>() {
            if t.frequency_hz() > 1.0 / STAND_IN_TIME_S {
                fast.push((Effect::Sinusoidal, c.name()));
            } else if t.frequency_hz() < 0.01 {
                // A line of a period beyond 100 s is slow wander in the drift (a tone at a few
                // tenths of a hertz integrates to next to nothing).
                slow.push((Effect::Sinusoidal, c.name()));
            }
        }
        if a.get::<SlowGaussMarkov>().is_some() {
            slow.push((Effect::SlowGaussMarkov, c.name()));
        }
        for e in [
            Effect::BiasInstability,
            Effect::PowerLaw,
            Effect::RateRandomWalk,
            Effect::RateRamp,
        ] {
            if a.has(e) {
                slow.push((e, c.name()));
            }
        }
    }
    let grouped = |terms: Vec<(Effect, &str)>| {
        let mut effects: Vec<Effect> = Vec::new();
        for (e, _) in &terms {
            if !effects.contains(e) {
                effects.push(*e);
            }
        }
        effects
            .iter()
            .map(|e| {
                let on: Vec<&str> = terms
                    .iter()
                    .filter(|(f, _)| f == e)
                    .map(|(_, c)| *c)
                    .collect();
                format!("{} on {}", e.name(), on.join(", "))
            })
            .collect::<Vec<String>>()
            .join("; ")
    };
    (grouped(fast), grouped(slow))
}

/// One horizon.
#[derive(Clone, Debug, Serialize)]
pub struct HorizonCheck {
    pub t_s: f64,
    /// Measured segments, all logs.
    pub segments: usize,
    pub channels: BTreeMap<&'static str, QuantityCheck>,
}

/// The whole check.
#[derive(Clone, Debug, Serialize)]
pub struct DriftCheck {
    pub protocol: Protocol,
    pub protocol_text: String,
    pub seed: u64,
    pub replicates: usize,
    pub logs: usize,
    /// How the model's levels were drawn per replicate; absent when they are taken as exact.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub parameters: Option<ParameterSpread>,
    /// The structures the band averages over (`alternatives`), with their weights and
    /// replicates; absent when the model has one structure.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub structures: Vec<StructureShare>,
    pub horizons: Vec<HorizonCheck>,
    /// Every informed cell judged together (`drift_joint`, docs/drift.md); absent without one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub joint: Option<JointCheck>,
    /// The between-log tests of every cell judged together (`drift_joint::between_logs_joint`,
    /// docs/drift.md "Runs that differ among themselves"); absent for one log.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub between_logs_joint: Option<BetweenLogsJoint>,
}

/// One structure's share of the band: what it is, its weight and its simulated experiments.
#[derive(Clone, Debug, Serialize)]
pub struct StructureShare {
    pub label: String,
    pub weight: f64,
    pub replicates: usize,
}

/// Errors of a drift check.
#[derive(Debug, thiserror::Error)]
pub enum CheckError {
    #[error("no logs to check")]
    NoLogs,
    #[error("the logs have different sample intervals ({0} s and {1} s); pool logs of one rate")]
    Rates(f64, f64),
    /// The setting `replicates` is below 10.
    #[error("replicates = {0}: at least 10 simulated experiments are needed for a 95 % band")]
    Replicates(usize),
    #[error("simulated log {run}: {quantity} is not finite")]
    NotFinite { run: u64, quantity: &'static str },
    #[error("drawing the model's levels: {0}")]
    Bootstrap(#[from] BootstrapError),
    /// A structure of the model's `[[alternatives]]` that cannot run at the logs' rate.
    #[error("[[alternatives]] structure \"{label}\": {message}")]
    Structure { label: String, message: String },
    /// The front end's stop flag was set (Ctrl-C): no check.
    #[error("stopped")]
    Stopped,
}

fn abs_sorted(v: &[f64]) -> Vec<f64> {
    let mut a: Vec<f64> = v.iter().map(|x| x.abs()).collect();
    a.sort_by(f64::total_cmp);
    a
}

/// The AR(1) effective count of segments (module doc), over the logs' own segment sequences.
fn effective_count(per_log: &[&[f64]], overlapping: bool) -> f64 {
    let n: usize = per_log.iter().map(|v| v.len()).sum();
    let (mut num, mut den) = (0.0, 0.0);
    for v in per_log.iter().filter(|v| v.len() >= 8) {
        let sq: Vec<f64> = v.iter().map(|x| x * x).collect();
        let m = stats::mean(&sq);
        num += sq.windows(2).map(|w| (w[0] - m) * (w[1] - m)).sum::<f64>();
        den += sq.iter().map(|x| (x - m) * (x - m)).sum::<f64>();
    }
    let rho = if den > 0.0 {
        (num / den).clamp(0.0, 0.95)
    } else {
        0.0
    };
    let n_eff = n as f64 * (1.0 - rho) / (1.0 + rho);
    (if overlapping { n_eff / 2.0 } else { n_eff }).max(1.0)
}

/// Check the measured logs' drift against the model's under `settings.protocol`, the model's
/// levels taken as exact. `observer` is told the number of simulated logs done.
pub fn check_drift(
    logs: &[LogInput],
    model_sensor: &SensorModel,
    settings: &CheckSettings,
    observer: &dyn Observer,
) -> Result<DriftCheck, CheckError> {
    check_drift_fitted(logs, model_sensor, None, settings, observer)
}

/// [`check_drift`] for a model fitted on `fitted_on` (None: taken as exact): each replicate draws
/// its levels by the parametric bootstrap (module doc). Its logs like the fitted ones are the runs
/// after the replicates' own (`replicates` x `logs`) of the seed; `observer` counts both, of
/// [`simulated_logs`] in all.
pub fn check_drift_fitted(
    logs: &[LogInput],
    model_sensor: &SensorModel,
    fitted_on: Option<&FittedOn>,
    settings: &CheckSettings,
    observer: &dyn Observer,
) -> Result<DriftCheck, CheckError> {
    check_drift_averaged(logs, model_sensor, &[], fitted_on, settings, observer)
}

/// [`check_drift_fitted`] averaged over the model's structures (`alternatives`): the replicates
/// shared out among them by weight, each structure's levels drawn by its own bootstrap (at least
/// `alternatives::MIN_BOOTSTRAP` replicates of it when there are several), the bootstraps' runs
/// one after the other after the replicates' own. With no alternatives, exactly
/// [`check_drift_fitted`].
pub fn check_drift_averaged(
    logs: &[LogInput],
    model_sensor: &SensorModel,
    alternatives: &[Alternative],
    fitted_on: Option<&FittedOn>,
    settings: &CheckSettings,
    observer: &dyn Observer,
) -> Result<DriftCheck, CheckError> {
    let never = AtomicBool::new(false);
    let models = Models::fitted(model_sensor, alternatives, fitted_on);
    check_drift_until(logs, models, settings, observer, &never)
}

/// The model a drift check takes: the sensor model, its `[[alternatives]]` structures, the
/// data it was fitted on (None: its levels taken as exact) and how its run-to-run spreads were
/// estimated (each experiment draws its spreads from them, `run_spread::draw_spreads`; empty:
/// the spreads taken as exact).
#[derive(Clone, Copy)]
pub struct Models<'a> {
    pub model: &'a SensorModel,
    pub alternatives: &'a [Alternative],
    pub fitted_on: Option<&'a FittedOn>,
    pub run_spreads: &'a [SpreadFit],
}

impl<'a> Models<'a> {
    /// A model with its structures and the data it was fitted on, the spreads as that data
    /// records them (`FittedOn::run_to_run`).
    pub fn fitted(
        model: &'a SensorModel,
        alternatives: &'a [Alternative],
        fitted_on: Option<&'a FittedOn>,
    ) -> Models<'a> {
        Models {
            model,
            alternatives,
            fitted_on,
            run_spreads: fitted_on.map_or(&[], |f| &f.run_to_run),
        }
    }
}

/// [`check_drift_averaged`] that a front end can stop (Ctrl-C): once `stop` is set no further
/// log is simulated (a stop lands within one simulated log per worker thread) and the result
/// is [`CheckError::Stopped`]. The same inputs give the same check as [`check_drift_averaged`].
pub fn check_drift_until(
    logs: &[LogInput],
    models: Models,
    settings: &CheckSettings,
    observer: &dyn Observer,
    stop: &AtomicBool,
) -> Result<DriftCheck, CheckError> {
    let Models {
        model: model_sensor,
        alternatives,
        fitted_on,
        run_spreads,
    } = models;
    let stopped = || stop.load(Ordering::Relaxed);
    let dt_s = check_inputs(logs, settings)?;
    let p = &settings.protocol;
    // Measured segments per horizon, per log (kept apart for the effective count).
    let by_log: Vec<Vec<SegmentErrors>> = logs
        .par_iter()
        .map(|l| all_segment_errors(&l.channels.0, dt_s, p))
        .collect();
    if stopped() {
        return Err(CheckError::Stopped);
    }
    let plan = StructurePlan::new(model_sensor, alternatives, settings.replicates);
    // The model itself is checked by the caller; an alternative's output filter may not fit.
    for s in plan.structures.iter().skip(1) {
        noise::ImuErrors::check_rate(&s.model, dt_s).map_err(|e| CheckError::Structure {
            label: s.label.clone(),
            message: e.to_string(),
        })?;
    }
    let progress = Progress {
        done: std::sync::atomic::AtomicUsize::new(0),
        total: plan.simulated_logs(logs.len(), fitted_on),
        observer,
    };
    let (mut models, mut parameters) = plan.draw(
        fitted_on,
        (settings.seed, (settings.replicates * logs.len()) as u64),
        &|| progress.tick(),
        stop,
    )?;
    if !run_spreads.is_empty() {
        if models.is_empty() {
            models = vec![model_sensor.clone(); settings.replicates];
        }
        let drawn = crate::run_spread::draw_spreads(&mut models, run_spreads, settings.seed);
        if let Some(p) = parameters.as_mut() {
            p.run_to_run = spread_summaries(model_sensor, run_spreads, &drawn);
        }
    }
    let model_of = |r: usize| models.get(r).unwrap_or(model_sensor);
    let experiment = Experiment {
        logs,
        model: model_sensor,
        settings,
        simulated: simulate_experiments(logs, &model_of, settings, dt_s, &progress, stop)
            .ok_or(CheckError::Stopped)?,
    };
    let mut horizons = Vec::new();
    let mut per_log_by_horizon = Vec::new();
    for (hi, &h) in p.horizons_s.iter().enumerate() {
        if stopped() {
            return Err(CheckError::Stopped);
        }
        let per_log: Vec<SegmentErrors> = by_log.iter().map(|l| l[hi].clone()).collect();
        horizons.push(experiment.check_horizon(hi, h, &per_log)?);
        per_log_by_horizon.push(per_log);
    }
    let joint = experiment.joint(&horizons);
    let between_logs_joint = experiment.between_joint(&horizons, &per_log_by_horizon);
    Ok(DriftCheck {
        protocol: p.clone(),
        protocol_text: p.describe(),
        seed: settings.seed,
        replicates: settings.replicates,
        logs: logs.len(),
        parameters,
        structures: plan.shares(),
        horizons,
        joint,
        between_logs_joint,
    })
}

/// The model's structures and how many replicates each gets.
struct StructurePlan {
    structures: Vec<Structure>,
    counts: Vec<usize>,
}

impl StructurePlan {
    fn new(model: &SensorModel, alternatives: &[Alternative], replicates: usize) -> StructurePlan {
        let structures = alternatives::structures(model, alternatives);
        let weights: Vec<f64> = structures.iter().map(|s| s.weight).collect();
        let counts = alternatives::allocate(&weights, replicates);
        StructurePlan { structures, counts }
    }

    /// The channels where structure `s` differs from the model's own (structure 0).
    fn changed(&self, s: usize) -> noise::ImuChannels<bool> {
        let (own, this) = (&self.structures[0].model, &self.structures[s].model);
        noise::ImuChannels::from_fn(|c| {
            own.axis(c.sensor(), c.axis()) != this.axis(c.sensor(), c.axis())
        })
    }

    /// Replicates of structure `s`'s own bootstrap: for the model's structure all the replicates
    /// (every structure takes its other channels' levels from it), for another at least
    /// `alternatives::MIN_BOOTSTRAP` of its changed channels (the draws are centred on their
    /// mean, which a handful of replicates would pin to the fitted levels).
    fn bootstrap_replicates(&self, s: usize) -> usize {
        match (s, self.counts[s]) {
            (0, _) => self.counts.iter().sum(),
            (_, 0) => 0,
            (_, n) => n.max(alternatives::MIN_BOOTSTRAP),
        }
    }

    /// The logs simulated with `logs` measured logs, the bootstraps' included (a structure's own
    /// bootstrap simulates only its changed channels, counted as whole logs).
    fn simulated_logs(&self, logs: usize, fitted_on: Option<&FittedOn>) -> usize {
        let boot: usize = (0..self.counts.len())
            .map(|s| self.bootstrap_replicates(s))
            .sum();
        self.counts.iter().sum::<usize>() * logs + boot * fitted_on.map_or(0, |f| f.samples.len())
    }

    /// Each replicate's model, in replicate order (empty: every replicate simulates the model as
    /// it is), and the model's own level spread. With a fitted-on table the model's bootstrap
    /// draws every replicate's levels; the replicates of another structure take its changed
    /// channels from that structure's own bootstrap, on the channels it changes. The bootstraps'
    /// runs start at `first_run` of `seed`, the model's first, then each structure's.
    fn draw(
        &self,
        fitted_on: Option<&FittedOn>,
        (seed, first_run): (u64, u64),
        tick: &(dyn Fn() + Sync),
        stop: &AtomicBool,
    ) -> Result<(Vec<SensorModel>, Option<ParameterSpread>), CheckError> {
        let bootstrap = |e: BootstrapError| match e {
            BootstrapError::Stopped => CheckError::Stopped,
            e => CheckError::Bootstrap(e),
        };
        let Some(f) = fitted_on else {
            if self.structures.len() == 1 {
                return Ok((Vec::new(), None));
            }
            let models = self
                .structures
                .iter()
                .zip(&self.counts)
                .flat_map(|(s, &n)| std::iter::repeat_n(s.model.clone(), n))
                .collect();
            return Ok((models, None));
        };
        let logs = f.samples.len() as u64;
        let all = self.bootstrap_replicates(0);
        let own = draw_models(
            &self.structures[0].model,
            f,
            (seed, first_run, all),
            tick,
            Some(stop),
        )
        .map_err(bootstrap)?;
        let mut next_run = first_run + all as u64 * logs;
        let mut models = own.models;
        let mut r = self.counts[0];
        for s in 1..self.structures.len() {
            let n = self.counts[s];
            if n == 0 {
                continue;
            }
            let changed = self.changed(s);
            let reps = self.bootstrap_replicates(s);
            let d = draw_models_on(
                &self.structures[s].model,
                f,
                changed,
                (seed, next_run, reps),
                tick,
                Some(stop),
            )
            .map_err(bootstrap)?;
            next_run += reps as u64 * logs;
            for drawn in d.models.iter().take(n) {
                for c in noise::Channel::ALL.into_iter().filter(|&c| changed[c]) {
                    *models[r].axis_mut(c.sensor(), c.axis()) =
                        drawn.axis(c.sensor(), c.axis()).clone();
                }
                r += 1;
            }
        }
        Ok((models, Some(own.spread)))
    }

    /// The structures' shares for the report (empty with one structure).
    fn shares(&self) -> Vec<StructureShare> {
        if self.structures.len() == 1 {
            return Vec::new();
        }
        self.structures
            .iter()
            .zip(&self.counts)
            .map(|(s, &n)| StructureShare {
                label: s.label.clone(),
                weight: s.weight,
                replicates: n,
            })
            .collect()
    }
}

/// How each spread's draws spread over the replicates (the JSON `parameters.run_to_run[]`).
fn spread_summaries(
    model: &SensorModel,
    fits: &[SpreadFit],
    drawn: &[Vec<f64>],
) -> Vec<crate::bootstrap::SpreadDraws> {
    fits.iter()
        .zip(drawn)
        .map(|(f, d)| {
            let mut v = d.clone();
            v.sort_by(f64::total_cmp);
            let axis = model.axis(f.channel.sensor(), f.channel.axis());
            crate::bootstrap::SpreadDraws {
                channel: f.channel,
                effects: f.effects.clone(),
                model: f
                    .effects
                    .iter()
                    .find_map(|e| axis.run_to_run().get(e).copied())
                    .unwrap_or(0.0),
                share_zero: v.iter().filter(|&&x| x == 0.0).count() as f64 / v.len().max(1) as f64,
                p2_5: stats::quantile(&v, 0.025),
                p50: stats::quantile(&v, 0.5),
                p97_5: stats::quantile(&v, 0.975),
            }
        })
        .collect()
}

/// The logs a drift check simulates: `replicates` experiments of `logs` logs, and with a fitted
/// model as many times its fitted logs.
pub fn simulated_logs(logs: usize, fitted_on: Option<&FittedOn>, replicates: usize) -> usize {
    replicates * (logs + fitted_on.map_or(0, |f| f.samples.len()))
}

/// The logs [`check_drift_averaged`] simulates.
pub fn simulated_logs_averaged(
    logs: usize,
    model: &SensorModel,
    alternatives: &[Alternative],
    fitted_on: Option<&FittedOn>,
    replicates: usize,
) -> usize {
    StructurePlan::new(model, alternatives, replicates).simulated_logs(logs, fitted_on)
}

/// Simulated logs counted for the observer, from worker threads.
struct Progress<'a> {
    done: std::sync::atomic::AtomicUsize,
    total: usize,
    observer: &'a dyn Observer,
}

impl Progress<'_> {
    fn tick(&self) {
        let k = self.done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
        self.observer.simulated(k, self.total);
    }
}

/// The logs' common sample interval, once the logs and the settings are checked.
fn check_inputs(logs: &[LogInput], settings: &CheckSettings) -> Result<f64, CheckError> {
    let first = logs.first().ok_or(CheckError::NoLogs)?;
    for l in logs {
        if (l.dt_s - first.dt_s).abs() > 1e-9 * first.dt_s {
            return Err(CheckError::Rates(first.dt_s, l.dt_s));
        }
    }
    if settings.replicates < 10 {
        return Err(CheckError::Replicates(settings.replicates));
    }
    Ok(first.dt_s)
}

/// The segment errors of every simulated experiment: replicate r, log l is montecarlo run
/// r * logs + l of the seed, one simulated log of replicate r's model (`model_of(r)`) as long as
/// measured log l, with its channels.
fn simulate_experiments<'m>(
    logs: &[LogInput],
    model_of: &(dyn Fn(usize) -> &'m SensorModel + Sync),
    settings: &CheckSettings,
    dt_s: f64,
    progress: &Progress,
    stop: &AtomicBool,
) -> Option<Vec<Vec<SegmentErrors>>> {
    let jobs: Vec<(usize, usize)> = (0..settings.replicates)
        .flat_map(|r| (0..logs.len()).map(move |l| (r, l)))
        .collect();
    let log_jobs: Vec<LogJob> = jobs
        .iter()
        .map(|&(r, l)| {
            let log = &logs[l];
            let samples = log
                .channels
                .values()
                .iter()
                .flatten()
                .map(|c| c.len())
                .min()
                .unwrap_or(0);
            LogJob {
                model: model_of(r),
                setup: SimSetup {
                    latitude_deg: settings.protocol.latitude_deg,
                    ..SimSetup::plain(
                        dt_s,
                        samples,
                        noise::ImuChannels::from_fn(|c| log.channels[c].is_some()),
                    )
                    .stopped_by(Some(stop))
                },
                seed: settings.seed,
                run: (r * logs.len() + l) as u64,
            }
        })
        .collect();
    map_static_logs(&log_jobs, |j, sim| {
        let active = &log_jobs[j].setup.active;
        let chans = noise::ImuChannels::from_fn(|c| active[c].then(|| sim[c].as_slice())).0;
        let out = all_segment_errors(&chans, dt_s, &settings.protocol);
        progress.tick();
        out
    })
}

/// The measured logs and the simulated experiments of one check.
struct Experiment<'a> {
    logs: &'a [LogInput<'a>],
    model: &'a SensorModel,
    settings: &'a CheckSettings,
    /// Per simulated log (replicate-major), the segment errors per horizon.
    simulated: Vec<Vec<SegmentErrors>>,
}

impl Experiment<'_> {
    /// Horizon `hi` (`h` seconds): every quantity, from the measured logs' segments `per_log`.
    fn check_horizon(
        &self,
        hi: usize,
        h: f64,
        per_log: &[SegmentErrors],
    ) -> Result<HorizonCheck, CheckError> {
        let mut pooled = SegmentErrors {
            horizon_s: h,
            ..Default::default()
        };
        per_log.iter().for_each(|s| pooled.extend(s));
        let segments = pooled.len();
        let mut channels = BTreeMap::new();
        for q in Quantity::ALL {
            let missing: Vec<&str> = q
                .needs()
                .iter()
                .filter(|&&c| self.logs.iter().any(|l| l.channels[c].is_none()))
                .map(|c| c.name())
                .collect();
            let check = if !missing.is_empty() || segments == 0 {
                not_informed(&self.settings.protocol, h, &missing)
            } else {
                let measured =
                    measured_stats(&pooled, per_log, q, self.settings.protocol.overlapping);
                let model = self.model_stats(hi, q)?;
                let mut check = compare(q, h, measured, model, self.model);
                check.between_logs = self.between_logs(hi, q, per_log);
                check
            };
            channels.insert(q.name(), check);
        }
        Ok(HorizonCheck {
            t_s: h,
            segments,
            channels,
        })
    }

    /// The between-log test of quantity `q` at horizon `hi` (module doc).
    fn between_logs(
        &self,
        hi: usize,
        q: Quantity,
        per_log: &[SegmentErrors],
    ) -> Option<BetweenLogs> {
        let d = ln_ms_variance(per_log.iter().map(|s| s.values(q)))?;
        let mut null: Vec<f64> = self
            .simulated
            .chunks(self.logs.len())
            .filter_map(|rep| ln_ms_variance(rep.iter().map(|s| s[hi].values(q))))
            .collect();
        if null.is_empty() {
            return None;
        }
        null.sort_by(f64::total_cmp);
        let k = null.iter().filter(|&&x| x >= d).count();
        let p_value = (1 + k) as f64 / (null.len() + 1) as f64;
        // D is a variance of ln(mean square) = 2 ln(RMS): sd of ln(RMS) = sqrt(D) / 2.
        Some(BetweenLogs {
            sd_ln_rms: d.sqrt() / 2.0,
            model_sd_ln_rms: stats::quantile(&null, 0.5).sqrt() / 2.0,
            p_value,
            runs_differ: p_value < BETWEEN_LOGS_LEVEL,
        })
    }

    /// The model's statistics of quantity `q` at horizon `hi`: the RMS of each replicate (its logs
    /// pooled), and all segments pooled.
    fn model_stats(&self, hi: usize, q: Quantity) -> Result<Model, CheckError> {
        let mut all = Vec::new();
        for (r, rep) in self.simulated.chunks(self.logs.len()).enumerate() {
            for (l, s) in rep.iter().enumerate() {
                let v = s[hi].values(q);
                if v.iter().any(|x| !x.is_finite()) {
                    // The run number of `simulate_experiments`.
                    return Err(CheckError::NotFinite {
                        run: (r * self.logs.len() + l) as u64,
                        quantity: q.name(),
                    });
                }
                all.extend_from_slice(v);
            }
        }
        let mut rep_rms = self.replicate_rms(hi, q);
        rep_rms.sort_by(f64::total_cmp);
        // Distribution-free 95 % prediction interval from R exchangeable replicates: the
        // order statistics X_(a) and X_(R+1-a) cover a new measurement with probability
        // (R + 1 - 2a) / (R + 1) (e.g. Wilks 1941); a = 0.025 (R + 1), between order
        // statistics by linear interpolation, makes it 95 % for any R (at least 1: the
        // extremes, for R < 39).
        let (band_lo, band_hi) = crate::drift_joint::band(&rep_rms);
        let all_sorted = abs_sorted(&all);
        Ok(Model {
            mean: stats::mean(&all_sorted),
            p50: stats::quantile(&all_sorted, 0.5),
            p95: stats::quantile(&all_sorted, 0.95),
            rms: stats::rms(&all),
            band_lo,
            band_hi,
        })
    }

    /// Each simulated experiment's RMS of quantity `q` at horizon `hi` (its logs pooled), in
    /// replicate order.
    fn replicate_rms(&self, hi: usize, q: Quantity) -> Vec<f64> {
        self.simulated
            .chunks(self.logs.len())
            .map(|rep| {
                let v: Vec<f64> = rep.iter().flat_map(|e| e[hi].values(q)).copied().collect();
                stats::rms(&v)
            })
            .collect()
    }

    /// The between-log tests of every cell of `horizons` that has one, judged together
    /// (`drift_joint::between_logs_joint`); `per_log` the measured logs' segments per horizon.
    fn between_joint(
        &self,
        horizons: &[HorizonCheck],
        per_log: &[Vec<SegmentErrors>],
    ) -> Option<BetweenLogsJoint> {
        let mut cells = Vec::new();
        for (hi, h) in horizons.iter().enumerate() {
            for q in Quantity::ALL {
                if h.channels[q.name()].between_logs.is_none() {
                    continue;
                }
                let Some(measured) = ln_ms_variance(per_log[hi].iter().map(|s| s.values(q))) else {
                    continue;
                };
                let simulated: Option<Vec<f64>> = self
                    .simulated
                    .chunks(self.logs.len())
                    .map(|rep| ln_ms_variance(rep.iter().map(|s| s[hi].values(q))))
                    .collect();
                if let Some(simulated) = simulated {
                    cells.push(Cell {
                        t_s: h.t_s,
                        quantity: q.name(),
                        measured,
                        simulated,
                    });
                }
            }
        }
        between_logs_joint(&cells)
    }

    /// Every informed cell of `horizons` judged together (`drift_joint`).
    fn joint(&self, horizons: &[HorizonCheck]) -> Option<JointCheck> {
        let mut cells = Vec::new();
        for (hi, h) in horizons.iter().enumerate() {
            for q in Quantity::ALL {
                let c = &h.channels[q.name()];
                if let (Verdict::Above | Verdict::Below | Verdict::Inside, Some(m)) =
                    (c.verdict, c.measured)
                {
                    cells.push(Cell {
                        t_s: h.t_s,
                        quantity: q.name(),
                        measured: m.rms,
                        simulated: self.replicate_rms(hi, q),
                    });
                }
            }
        }
        joint_check(&cells)
    }
}

/// A quantity the logs cannot inform: they lack one of its channels (`missing`), or no log holds
/// a segment of `h` seconds.
fn not_informed(p: &Protocol, h: f64, missing: &[&str]) -> QuantityCheck {
    QuantityCheck {
        measured: None,
        model: None,
        verdict: Verdict::NotInformed,
        ratio: None,
        likely_cause: None,
        between_logs: None,
        note: Some(if missing.is_empty() {
            match p.lead_s() {
                w if w > 0.0 => format!("no log holds a {h} s segment after the {w} s window"),
                _ => format!("no log is {h} s long"),
            }
        } else {
            format!("the logs lack {}", missing.join(", "))
        }),
    }
}

/// The measured statistics of quantity `q` over the pooled segments, with intervals from the
/// effective count of the logs' own segment sequences (`per_log`; module doc).
fn measured_stats(
    pooled: &SegmentErrors,
    per_log: &[SegmentErrors],
    q: Quantity,
    overlapping: bool,
) -> Measured {
    let values = pooled.values(q);
    let sorted = abs_sorted(values);
    let r = stats::rms(values);
    let seqs: Vec<&[f64]> = per_log.iter().map(|s| s.values(q)).collect();
    let n_eff = effective_count(&seqs, overlapping);
    let lo_q = allan::chi2::chi2_ppf(0.975, n_eff);
    let hi_q = allan::chi2::chi2_ppf(0.025, n_eff);
    let mean = stats::mean(&sorted);
    // One segment (or none) has no spread to estimate: 0 (the sample deviation's NaN would
    // make the interval NaN).
    let sd = if sorted.len() < 2 {
        0.0
    } else {
        stats::sample_std(&sorted)
    };
    let half = 1.959_963_984_540_054 * sd / n_eff.sqrt();
    Measured {
        mean,
        mean_lo: mean - half,
        mean_hi: mean + half,
        p50: stats::quantile(&sorted, 0.5),
        p95: stats::quantile(&sorted, 0.95),
        rms: r,
        rms_lo: r * (n_eff / lo_q).sqrt(),
        rms_hi: r * (n_eff / hi_q).sqrt(),
        n_eff,
    }
}

/// The measured RMS against the model's band: the verdict, and outside the band its likely cause.
fn compare(
    q: Quantity,
    h: f64,
    measured: Measured,
    model: Model,
    model_sensor: &SensorModel,
) -> QuantityCheck {
    let r = measured.rms;
    let verdict = if r > model.band_hi {
        Verdict::Above
    } else if r < model.band_lo {
        Verdict::Below
    } else {
        Verdict::Inside
    };
    QuantityCheck {
        measured: Some(measured),
        ratio: Some(r / model.rms),
        model: Some(model),
        verdict,
        note: None,
        between_logs: None,
        likely_cause: likely_cause(q, h, verdict, model_sensor),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use noise::{GaussMarkov, RateRandomWalk, Sensor, Sinusoid};

    /// Below the band, the likely cause names the slow terms of the quantity's channels (a slow
    /// Gauss-Markov process, a random walk), not a tone of a few tenths of a hertz; a millisecond
    /// Gauss-Markov process is a short-time stand-in, named with the white noise where the
    /// channels have no slow term.
    #[test]
    fn below_names_the_slow_terms_not_the_tones() {
        let mut m = SensorModel::default();
        m.axis_mut(Sensor::Accel, 0)
            .set_term(Sinusoid::new(8e-3, 0.564, None).unwrap());
        m.axis_mut(Sensor::Accel, 0)
            .set_term(RateRandomWalk::new(5e-4).unwrap());
        m.axis_mut(Sensor::Accel, 1)
            .set_term(GaussMarkov::new(7e-3, 499.0).unwrap());
        m.axis_mut(Sensor::Gyro, 2)
            .set_term(GaussMarkov::new(5e-4, 0.004).unwrap());
        let pos = likely_cause(Quantity::PosHorizontal, 10.0, Verdict::Below, &m).unwrap();
        assert!(pos.contains("rate_random_walk on ax"), "{pos}");
        assert!(pos.contains("gauss_markov on ay"), "{pos}");
        assert!(!pos.contains("sinusoidal"), "{pos}");
        let heading = likely_cause(Quantity::Heading, 60.0, Verdict::Below, &m).unwrap();
        assert!(
            heading.contains("short-time stand-ins (gauss_markov on gz"),
            "{heading}"
        );
        assert!(!heading.contains("slow terms"), "{heading}");
        // Without a slow term on gz, at 10 min too it is the white noise (and the stand-in).
        let long = likely_cause(Quantity::Heading, 600.0, Verdict::Below, &m).unwrap();
        assert!(
            long.starts_with("the model's white noise or short-time"),
            "{long}"
        );
    }
}
