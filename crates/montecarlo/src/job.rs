//! A `simulate` job from its texts, shared by every front end (the CLI's `simulate` and `merge`,
//! the Python package): the scenario for a file (a sensor model alone gets the default static
//! scenario), the experiment and its ablation sub-experiments, running it whole or as a shard,
//! merging shards, and the JSON document of the result (docs/cli.md, `simulate --json`).
//! Front ends read the files and run the ranges (with their own progress or interrupt): the
//! library reads no file and starts no thread pool.

use crate::ablation::{self, AblationRow, TermBatches, TermExperiments};
use crate::experiment::{Experiment, ExperimentError, Overrides};
use crate::nav_quantity::NavQuantity;
use crate::report::{DriftReport, QuantityReport};
use crate::runner::{BatchResult, RunFailure, Shard};
use crate::scenario::{Scenario, ScenarioError};
use crate::shard::{ShardError, ShardFile, SHARD_FORMAT};
use crate::stats::RunMatrix;
use noise::{ConfigError, SensorModel};
use serde::Serialize;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// Scenario and sensor texts as read, with their names (kept verbatim for shard files).
#[derive(Debug, Clone, PartialEq)]
pub struct Inputs {
    pub scenario_source: String,
    pub scenario_toml: String,
    pub sensor_source: String,
    pub sensor_toml: String,
}

/// Scenario keys a front end sets (the CLI's `--duration` / `--rate`).
#[derive(Debug, Clone, Copy, Default)]
pub struct ScenarioEdits {
    pub duration_s: Option<f64>,
    pub rate_hz: Option<f64>,
}

/// Why a job cannot be built from its texts.
#[derive(Debug, thiserror::Error)]
pub enum JobError {
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    #[error(transparent)]
    Sensor(#[from] ConfigError),
    #[error(transparent)]
    Experiment(#[from] ExperimentError),
}

/// Whether a TOML text is a sensor model rather than a scenario: no `sensor` key, and sensor
/// tables (`[gyro]`, `[accel]`, `[temperature]`) or nothing but a name and a description (an
/// ideal sensor).
pub fn is_sensor_toml(text: &str) -> bool {
    text.parse::<toml::Table>().is_ok_and(|t| {
        !t.contains_key("sensor")
            && (["gyro", "accel", "temperature"]
                .iter()
                .any(|k| t.contains_key(*k))
                || (t.contains_key("name") && t.keys().all(|k| k == "name" || k == "description")))
    })
}

/// The default static scenario for a sensor file (every other key takes its documented default).
pub fn default_scenario_toml(sensor_file: &str, stem: &str) -> String {
    format!(
        "# The default static scenario of `imudrift simulate SENSOR.toml`: the sensor lying still and level.\n\
         name = {name:?}\n\
         description = {desc:?}\n\
         sensor = {sensor_file:?}\n",
        name = format!("{stem}-static"),
        desc = format!("{stem}: default static scenario (still and level)"),
    )
}

/// The scenario of a file read from `path` (named `given` in messages) with text `text`: its own
/// text, or the default static scenario when it is a sensor model (TOML or noise file); returns
/// the scenario's source name and text.
pub fn scenario_for_file(path: &Path, given: &str, text: &str) -> (String, String) {
    if is_sensor_toml(text) || noise::is_noise_file_text(text, given) {
        let file = path
            .file_name()
            .map(|f| f.to_string_lossy().into_owned())
            .unwrap_or_else(|| given.to_string());
        let stem = path
            .file_stem()
            .map(|f| f.to_string_lossy().into_owned())
            .unwrap_or_else(|| "sensor".into());
        (
            format!("default static scenario for {given}"),
            default_scenario_toml(&file, &stem),
        )
    } else {
        (given.to_string(), text.to_string())
    }
}

/// The sensor file of a scenario read from `scenario_path` (a relative path is relative to the
/// scenario file's directory).
pub fn sensor_path(scenario_path: &Path, scenario: &Scenario) -> PathBuf {
    match scenario_path.parent() {
        Some(dir) if scenario.sensor.is_relative() => dir.join(&scenario.sensor),
        _ => scenario.sensor.clone(),
    }
}

/// A scenario text with `edits` applied (the edited text is what a shard stores). The error is
/// the text's: it is not TOML.
pub fn edit_scenario_toml(text: &str, edits: &ScenarioEdits) -> Result<String, toml::de::Error> {
    if edits.duration_s.is_none() && edits.rate_hz.is_none() {
        return Ok(text.to_string());
    }
    let mut table: toml::Table = text.parse()?;
    if let Some(d) = edits.duration_s {
        table.insert("duration_s".into(), toml::Value::Float(d));
    }
    if let Some(r) = edits.rate_hz {
        table.insert("rate_hz".into(), toml::Value::Float(r));
    }
    // A table of parsed values always serialises.
    Ok(toml::to_string(&table).unwrap_or_default())
}

/// The parsed scenario and model of `inputs`, and the experiment with `overrides`.
pub fn parse_inputs(
    inputs: &Inputs,
    overrides: &Overrides,
) -> Result<(Scenario, SensorModel, Experiment), JobError> {
    let scenario = Scenario::from_toml_str(&inputs.scenario_toml, &inputs.scenario_source)?;
    let model = SensorModel::from_text(&inputs.sensor_toml, &inputs.sensor_source)?;
    let exp = Experiment::new(scenario.clone(), &model, overrides)?;
    Ok((scenario, model, exp))
}

/// The ablation sub-experiments of the experiment of `inputs` (each active term alone, the model
/// without it).
pub fn ablation_experiments(
    inputs: &Inputs,
    overrides: &Overrides,
) -> Result<Vec<TermExperiments>, JobError> {
    let (scenario, model, exp) = parse_inputs(inputs, overrides)?;
    Ok(ablation::experiments(&scenario, &model, overrides, &exp)?)
}

/// A shard file's inputs and overrides as stored.
pub fn shard_inputs(f: &ShardFile) -> (Inputs, Overrides) {
    let inputs = Inputs {
        scenario_source: f.scenario_source.clone(),
        scenario_toml: f.scenario_toml.clone(),
        sensor_source: f.sensor_source.clone(),
        sensor_toml: f.sensor_toml.clone(),
    };
    let overrides = Overrides {
        runs: f.runs,
        seed: f.seed,
        only: f.only.clone(),
        without: f.without.clone(),
    };
    (inputs, overrides)
}

/// A shard file's experiment, resolved against its stored scenario (so that runs and seed
/// compare by value: an explicit seed equal to the scenario's own is the same experiment).
pub fn shard_experiment(f: &ShardFile) -> Result<(Inputs, Overrides, Experiment), JobError> {
    let (inputs, overrides) = shard_inputs(f);
    let exp = parse_inputs(&inputs, &overrides)?.2;
    Ok((inputs, overrides, exp))
}

/// Most samples a front end lets a job compute (runs x steps x the largest output-filter
/// decimation: every internal sample of the noise processes and every mechanisation step
/// counts), about 3 h on 2 cores at 1e7 steps/s per core: work beyond it is refused before it
/// starts.
pub const MAX_WORK_SAMPLES: f64 = 1e11;

/// The largest output-filter decimation of `model` (1 without a filter): the internal samples
/// per output sample.
pub fn max_decimation(model: &SensorModel) -> f64 {
    noise::Sensor::ALL
        .iter()
        .flat_map(|&s| model.triad(s).axes.iter())
        .filter_map(|axis| axis.get::<noise::OutputFilter>())
        .map(|f| f64::from(f.decimation()))
        .fold(1.0, f64::max)
}

/// The work of `runs` runs of `exp`, in samples as [`MAX_WORK_SAMPLES`] counts them.
pub fn work_samples(exp: &Experiment, runs: u64) -> f64 {
    runs as f64 * exp.scenario.duration_s * exp.scenario.rate_hz * max_decimation(&exp.model)
}

/// Most memory a front end lets the per-run values of one job take (8 GiB; less where less is
/// available).
pub const MAX_VALUE_BYTES: u64 = 8 << 30;

/// Bytes of the per-run values of `runs` runs of `exp` (8 per run, checkpoint and quantity).
pub fn value_bytes(exp: &Experiment, runs: u64) -> u64 {
    let per_run = (exp.scenario.checkpoint_steps.len() * NavQuantity::ALL.len() * 8) as u64;
    runs.saturating_mul(per_run)
}

/// Runs a range of an experiment's runs (the front end's pool, progress and interrupt; the label
/// names the job in progress output); `None` when it was stopped.
pub type RunRange<'a> = dyn Fn(&Experiment, Range<u64>, &str) -> Option<BatchResult> + 'a;

/// A finished simulation: the report, the ablation table when asked for, and the per-run values.
#[derive(Debug, Clone)]
pub struct Simulated {
    pub report: DriftReport,
    pub ablation: Option<Vec<AblationRow>>,
    pub matrix: RunMatrix,
}

/// Run every run of `exp` and of its ablation sub-experiments `subs` (`None`: no ablation table);
/// `None` when stopped.
pub fn simulate(
    exp: &Experiment,
    subs: Option<&[TermExperiments]>,
    run: &RunRange<'_>,
) -> Option<Simulated> {
    let result = run(exp, 0..exp.runs, "simulate")?;
    let report = exp.report(&result.matrix, &result.failures);
    let ablation = match subs {
        None => None,
        Some(subs) => {
            let mut per_term = Vec::new();
            for t in subs {
                let one = |e: &Experiment| -> Option<DriftReport> {
                    let r = run(e, 0..e.runs, &t.term)?;
                    Some(e.report(&r.matrix, &r.failures))
                };
                per_term.push((t.term.clone(), one(&t.only)?, one(&t.without)?));
            }
            Some(ablation::rows(&report, &per_term))
        }
    };
    Some(Simulated {
        report,
        ablation,
        matrix: result.matrix,
    })
}

/// A shard file of `shard` without its values yet (its experiment can be checked against other
/// shards before any work).
pub fn empty_shard(
    inputs: Inputs,
    overrides: &Overrides,
    shard: Shard,
    with_ablation: bool,
) -> ShardFile {
    ShardFile {
        format: SHARD_FORMAT.into(),
        scenario_source: inputs.scenario_source,
        scenario_toml: inputs.scenario_toml,
        sensor_source: inputs.sensor_source,
        sensor_toml: inputs.sensor_toml,
        runs: overrides.runs,
        seed: overrides.seed,
        only: overrides.only.clone(),
        without: overrides.without.clone(),
        shard,
        matrix: RunMatrix::new(0, 0),
        failures: Vec::new(),
        ablation: with_ablation.then(Vec::new),
    }
}

/// Run the shard's slice of `exp` and of every ablation sub-experiment `subs` into `file` (from
/// [`empty_shard`]); `None` when stopped.
pub fn fill_shard(
    file: &mut ShardFile,
    exp: &Experiment,
    subs: Option<&[TermExperiments]>,
    run: &RunRange<'_>,
) -> Option<()> {
    let range = file.shard.runs(exp.runs);
    let result = run(exp, range.clone(), "shard")?;
    // The shard's slice of every ablation sub-experiment, so that a merge rebuilds the table.
    let batch = |e: &Experiment, label: &str| -> Option<ablation::Batch> {
        let r = run(e, range.clone(), label)?;
        Some(ablation::Batch {
            matrix: r.matrix,
            failures: r.failures,
        })
    };
    file.ablation = match subs {
        None => None,
        Some(subs) => {
            let mut out = Vec::new();
            for t in subs {
                out.push(TermBatches {
                    term: t.term.clone(),
                    only: batch(&t.only, &t.term)?,
                    without: batch(&t.without, &t.term)?,
                });
            }
            Some(out)
        }
    };
    file.matrix = result.matrix;
    file.failures = result.failures;
    Some(())
}

/// Why shards cannot be merged; `name`s are the shards' names as the front end gave them.
#[derive(Debug, thiserror::Error)]
pub enum MergeError {
    #[error("{name}: the stored scenario")]
    Stored {
        name: String,
        #[source]
        source: Box<JobError>,
    },
    #[error("{first} and {other} belong to different experiments or splits (scenario, sensor, runs, seed, terms, ablation and k must match)")]
    Different { first: String, other: String },
    #[error("{name}: not a consistent shard file")]
    Inconsistent {
        name: String,
        #[source]
        source: ShardError,
    },
    #[error("shard {index}/{count} given twice: {first} and {second}")]
    Twice {
        index: u64,
        count: u64,
        first: String,
        second: String,
    },
    #[error("shard {index}/{count} is missing: all {count} shards are needed")]
    Missing { index: usize, count: u64 },
    #[error("{what}: shard matrices have different shapes or overlapping runs")]
    Shapes { what: String },
    #[error("{name}: key `ablation`: expected the terms {terms:?} (in that order)")]
    AblationTerms { name: String, terms: Vec<String> },
    #[error(transparent)]
    Job(Box<JobError>),
}

impl From<JobError> for MergeError {
    fn from(e: JobError) -> MergeError {
        MergeError::Job(Box::new(e))
    }
}

/// Number of ablation terms a shard carries.
fn ablation_len(f: &ShardFile) -> usize {
    f.ablation.as_ref().map_or(0, Vec::len)
}

/// Every shard belongs to the first one's experiment `exp` and split, is consistent in itself,
/// and each of the k shards is given once (checked in the order their errors are reported).
pub fn check_shards(files: &[(String, ShardFile)], exp: &Experiment) -> Result<(), MergeError> {
    let Some((first_name, first)) = files.first() else {
        return Err(MergeError::Missing { index: 0, count: 1 });
    };
    for (name, f) in files {
        let (_, _, e) = shard_experiment(f).map_err(|source| MergeError::Stored {
            name: name.clone(),
            source: Box::new(source),
        })?;
        if !first.same_experiment(f) || (e.runs, e.seed) != (exp.runs, exp.seed) {
            return Err(MergeError::Different {
                first: first_name.clone(),
                other: name.clone(),
            });
        }
        f.check(
            exp.runs,
            exp.scenario.checkpoint_steps.len(),
            NavQuantity::ALL.len(),
        )
        .map_err(|source| MergeError::Inconsistent {
            name: name.clone(),
            source,
        })?;
    }
    let count = first.shard.count;
    let mut seen: Vec<Option<&String>> = vec![None; count as usize];
    for (name, f) in files {
        if let Some(other) = seen[f.shard.index as usize].replace(name) {
            return Err(MergeError::Twice {
                index: f.shard.index,
                count,
                first: other.clone(),
                second: name.clone(),
            });
        }
    }
    if let Some(index) = seen.iter().position(Option::is_none) {
        return Err(MergeError::Missing { index, count });
    }
    Ok(())
}

/// Per-run values of one experiment from every shard, merged in run-index order.
fn merge_parts(
    parts: Vec<(RunMatrix, Vec<RunFailure>)>,
    what: &str,
) -> Result<(RunMatrix, Vec<RunFailure>), MergeError> {
    let mut failures: Vec<_> = parts.iter().flat_map(|(_, f)| f.clone()).collect();
    failures.sort_by_key(|f| f.run);
    let matrix =
        RunMatrix::merge(parts.into_iter().map(|(m, _)| m).collect()).ok_or_else(|| {
            MergeError::Shapes {
                what: what.to_string(),
            }
        })?;
    Ok((matrix, failures))
}

/// The ablation sub-experiments' reports (each term alone, the model without it) from every
/// shard's slices of them.
fn merged_ablation(
    files: &[(String, ShardFile)],
    inputs: &Inputs,
    overrides: &Overrides,
) -> Result<Vec<(String, DriftReport, DriftReport)>, MergeError> {
    let subs = ablation_experiments(inputs, overrides)?;
    let terms: Vec<String> = subs.iter().map(|t| t.term.clone()).collect();
    let mut per_term = Vec::new();
    for (i, sub) in subs.iter().enumerate() {
        let mut only = Vec::new();
        let mut without = Vec::new();
        for (name, f) in files {
            let t = f
                .ablation
                .as_ref()
                .and_then(|a| a.get(i))
                .filter(|t| t.term == sub.term && ablation_len(f) == subs.len())
                .ok_or_else(|| MergeError::AblationTerms {
                    name: name.clone(),
                    terms: terms.clone(),
                })?;
            only.push((t.only.matrix.clone(), t.only.failures.clone()));
            without.push((t.without.matrix.clone(), t.without.failures.clone()));
        }
        let (m, f) = merge_parts(only, &sub.term)?;
        let only_report = sub.only.report(&m, &f);
        let (m, f) = merge_parts(without, &sub.term)?;
        let without_report = sub.without.report(&m, &f);
        per_term.push((sub.term.clone(), only_report, without_report));
    }
    Ok(per_term)
}

/// The shards of one experiment `exp` (built by [`shard_experiment`] from the first, with its
/// `inputs` and `overrides`) merged into exactly what one [`simulate`] computes.
pub fn merge(
    files: Vec<(String, ShardFile)>,
    inputs: &Inputs,
    overrides: &Overrides,
    exp: &Experiment,
) -> Result<Simulated, MergeError> {
    check_shards(&files, exp)?;
    let per_term = match files.first().and_then(|(_, f)| f.ablation.as_ref()) {
        None => None,
        Some(_) => Some(merged_ablation(&files, inputs, overrides)?),
    };
    let (matrix, failures) = merge_parts(
        files
            .into_iter()
            .map(|(_, f)| (f.matrix, f.failures))
            .collect(),
        "simulate",
    )?;
    let report = exp.report(&matrix, &failures);
    let ablation = per_term.map(|per_term| ablation::rows(&report, &per_term));
    Ok(Simulated {
        report,
        ablation,
        matrix,
    })
}

/// Every run of a report failed: nothing to report.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("every one of the {runs} runs failed ({first}): no drift statistics to report; the model's values are probably far too large (check their units)")]
pub struct AllRunsFailed {
    pub runs: u64,
    /// The first failure's message.
    pub first: String,
}

/// `Err` when no run of `report` finished.
pub fn check_some_runs(report: &DriftReport) -> Result<(), AllRunsFailed> {
    if report.runs_ok > 0 {
        return Ok(());
    }
    Err(AllRunsFailed {
        runs: report.runs,
        first: report
            .failed_runs
            .first()
            .map_or("no run finished".to_string(), |f| f.message.clone()),
    })
}

/// A statistic of a report that is not a number: the runs' values were finite, but their
/// squares or sums overflowed (e.g. a bias of 1e200 mg).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("the {statistic} of {quantity} at t = {t_s} s over the {runs} runs is {value}: the runs' values (mean {}) overflow the statistics; the model's values are probably far too large (check their units)", noise::text::sig(*.mean, 3))]
pub struct NotFinite {
    pub statistic: &'static str,
    pub quantity: String,
    pub t_s: f64,
    pub runs: u64,
    pub value: f64,
    pub mean: f64,
}

/// `Err` naming the first statistic of `report` that is not a number (never a table of NaN or
/// a JSON of nulls).
pub fn check_finite(report: &DriftReport) -> Result<(), NotFinite> {
    for cp in &report.checkpoints {
        for (name, c) in &cp.quantities {
            let optional = [
                ("law_mean", c.law_mean),
                ("law_std", c.law_std),
                ("law_rms", c.law_rms),
                ("ratio", c.ratio),
                ("ratio_lo", c.ratio_lo),
                ("ratio_hi", c.ratio_hi),
                ("mean_ratio", c.mean_ratio),
                ("mean_ratio_lo", c.mean_ratio_lo),
                ("mean_ratio_hi", c.mean_ratio_hi),
            ];
            let values = [
                ("mean", Some(c.mean)),
                ("std", Some(c.std)),
                ("rms", Some(c.rms)),
                ("p5", Some(c.p5)),
                ("p50", Some(c.p50)),
                ("p95", Some(c.p95)),
            ];
            let bad = values
                .into_iter()
                .chain(optional)
                .find_map(|(s, v)| v.filter(|v| !v.is_finite()).map(|v| (s, v)));
            if let Some((statistic, value)) = bad {
                return Err(NotFinite {
                    statistic,
                    quantity: name.to_string(),
                    t_s: cp.t_s,
                    runs: report.runs_ok,
                    value,
                    mean: c.mean,
                });
            }
        }
    }
    Ok(())
}

/// The scenario's published reference value beside the simulated one (JSON key `reference`).
#[derive(Serialize, Debug, Clone)]
pub struct ReferenceOut {
    /// The quantity's name (JSON key `channel`, docs/cli.md).
    #[serde(rename = "channel")]
    pub quantity: String,
    pub statistic: String,
    pub t_s: f64,
    pub value: f64,
    pub source: String,
    pub simulated: f64,
    #[serde(skip)]
    pub note: Option<String>,
}

/// The scenario's reference (if it has one) at the checkpoint nearest its time.
pub fn reference_out(report: &DriftReport, exp: &Experiment) -> Option<ReferenceOut> {
    let r = exp.scenario.reference.as_ref()?;
    let cp = report
        .checkpoints
        .iter()
        .min_by(|a, b| (a.t_s - r.t_s).abs().total_cmp(&(b.t_s - r.t_s).abs()))?;
    let c = cp
        .quantities
        .get(NavQuantity::from_name(&r.quantity)?.name())?;
    let simulated = match r.statistic.as_str() {
        "mean" => c.mean,
        "rms" => c.rms,
        "p50" => c.p50,
        _ => c.p95,
    };
    Some(ReferenceOut {
        quantity: r.quantity.clone(),
        statistic: r.statistic.clone(),
        t_s: cp.t_s,
        value: r.value,
        source: r.source.clone(),
        simulated,
        note: r.note.clone(),
    })
}

/// Probability that a correct model's ratio falls outside its 99.9 % interval.
pub const FLAG_PROBABILITY: f64 = 0.001;

/// The `*` flags of a set of ratio intervals: how many there are, how many are outside, and how
/// many a correct model gives on average (each interval misses with probability 0.1 %; the
/// intervals share their runs, so the count is not binomial, but its mean is n x 0.001 and the
/// chance of at least one is at most that, by the union bound).
#[derive(Serialize, Clone, Copy, Debug, Default, PartialEq)]
pub struct FlagCount {
    pub intervals: usize,
    pub outside: usize,
    pub expected_outside: f64,
}

impl FlagCount {
    pub fn of<'a>(cs: impl Iterator<Item = &'a QuantityReport>) -> FlagCount {
        let mut f = FlagCount::default();
        for c in cs {
            if let (Some(_), Some(lo), Some(hi)) = (c.ratio, c.ratio_lo, c.ratio_hi) {
                f.intervals += 1;
                f.outside += usize::from(!(lo <= 1.0 && 1.0 <= hi));
            }
        }
        f.expected_outside = f.intervals as f64 * FLAG_PROBABILITY;
        f
    }
}

#[derive(Serialize)]
struct Document<'a> {
    #[serde(flatten)]
    report: &'a DriftReport,
    #[serde(skip_serializing_if = "Option::is_none")]
    reference: Option<ReferenceOut>,
    #[serde(skip_serializing_if = "Option::is_none")]
    ablation: Option<&'a [AblationRow]>,
    /// The `*` flags over every checkpoint and quantity, with their expected count.
    ratio_flags: FlagCount,
}

/// The JSON document of a simulation (`imudrift simulate --json`, docs/cli.md): the report, the
/// scenario's reference, the ablation table and the ratio flags; every checkpoint's `channels`
/// has `heading_rad` beside `yaw_rad`.
pub fn document(
    report: &DriftReport,
    exp: &Experiment,
    ablation: Option<&[AblationRow]>,
) -> serde_json::Value {
    let doc = Document {
        report,
        reference: reference_out(report, exp),
        ablation,
        ratio_flags: FlagCount::of(
            report
                .checkpoints
                .iter()
                .flat_map(|cp| cp.quantities.values()),
        ),
    };
    // Plain data (strings, numbers, maps) always serialises.
    let mut value = serde_json::to_value(&doc).unwrap_or_default();
    with_heading_alias(&mut value);
    value
}

/// Every checkpoint's `channels` gains `heading_rad` beside `yaw_rad` (the same values): one name
/// for the heading error in every command (`drift` says `heading_rad`), the old key kept for the
/// scripts that read it (docs/cli.md, "Contract changes").
fn with_heading_alias(doc: &mut serde_json::Value) {
    let Some(cps) = doc
        .get_mut("checkpoints")
        .and_then(serde_json::Value::as_array_mut)
    else {
        return;
    };
    for cp in cps {
        if let Some(ch) = cp
            .get_mut("channels")
            .and_then(serde_json::Value::as_object_mut)
        {
            if let Some(yaw) = ch.get(NavQuantity::Yaw.name()).cloned() {
                ch.insert(NavQuantity::Yaw.label().into(), yaw);
            }
        }
    }
}
