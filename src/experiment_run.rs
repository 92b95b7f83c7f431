//! Running a Monte Carlo experiment from files, shared by `simulate`, `spec` and `merge`: read
//! a scenario (or a sensor alone, with the default static scenario) and its sensor, apply
//! `--duration` / `--rate`, build the experiment and its ablation sub-experiments, check the
//! memory of the per-run values, and run a range of runs with progress.

use crate::files::{self, TextFile};
use anyhow::{bail, Context, Result};
use montecarlo::ablation;
use montecarlo::experiment::{Experiment, ExperimentError, Overrides};
use montecarlo::job::{self, JobError};
use montecarlo::report::DriftReport;
use montecarlo::runner::{run_range, BatchResult};
use montecarlo::scenario::Scenario;
use montecarlo::shard::ShardFile;
use noise::SensorModel;
use std::path::Path;

pub use montecarlo::job::{Inputs, ScenarioEdits};

/// [`ScenarioEdits`] from `--duration` / `--rate` (the rate checked).
pub fn scenario_edits(duration_s: Option<f64>, rate_hz: Option<f64>) -> Result<ScenarioEdits> {
    Ok(ScenarioEdits {
        duration_s,
        rate_hz: rate_hz
            .map(|r| crate::cli::check_rate_hz("--rate", r))
            .transpose()?,
    })
}

/// Read the scenario and its sensor (path relative to the scenario file). A sensor TOML given in
/// place of a scenario gets the default static scenario.
pub fn read_inputs(path: &Path, edits: &ScenarioEdits) -> Result<(Inputs, Scenario)> {
    let TextFile { name: given, text } = files::read_config(path)?;
    let (scenario_source, scenario_toml) = job::scenario_for_file(path, &given, &text);
    let scenario_toml = job::edit_scenario_toml(&scenario_toml, edits)
        .with_context(|| format!("cannot read scenario {scenario_source} as TOML"))?;
    let scenario = Scenario::from_toml_str(&scenario_toml, &scenario_source)?;
    let sensor_path = job::sensor_path(path, &scenario);
    crate::output::note_inputs([&sensor_path]);
    let sensor_source = sensor_path.display().to_string();
    let sensor_toml = files::read_config(&sensor_path)
        .with_context(|| format!("{scenario_source}: key `sensor`: the sensor file"))?
        .text;
    Ok((
        Inputs {
            scenario_source,
            scenario_toml,
            sensor_source,
            sensor_toml,
        },
        scenario,
    ))
}

/// Rebuild the experiment from texts (also used by `merge` on a shard's stored texts).
pub fn experiment_from(inputs: &Inputs, overrides: &Overrides) -> Result<Experiment> {
    Ok(parse_inputs(inputs, overrides)?.2)
}

/// The parsed scenario and model of `inputs`, and the experiment with `overrides`.
pub fn parse_inputs(
    inputs: &Inputs,
    overrides: &Overrides,
) -> Result<(Scenario, SensorModel, Experiment)> {
    job::parse_inputs(inputs, overrides).map_err(with_flag)
}

/// A job error with the command-line option it comes from, when it comes from one.
pub fn with_flag(e: JobError) -> anyhow::Error {
    match e {
        JobError::Experiment(ExperimentError::NoRuns) => {
            anyhow::anyhow!("--runs: expected an integer >= 1")
        }
        other => anyhow::Error::new(other),
    }
}

/// The ablation sub-experiments of `exp` (each active term alone, the model without it).
pub fn ablation_experiments(
    inputs: &Inputs,
    overrides: &Overrides,
) -> Result<Vec<ablation::TermExperiments>> {
    job::ablation_experiments(inputs, overrides).map_err(with_flag)
}

/// A shard file's experiment, resolved against its stored scenario (so that runs and seed
/// compare by value: an explicit `--seed` equal to the scenario's own is the same experiment),
/// with the inputs and overrides it was built from.
pub fn shard_experiment(f: &ShardFile) -> Result<(Inputs, Overrides, Experiment)> {
    job::shard_experiment(f).map_err(with_flag)
}

/// Refuse to write shard `file` (of experiment `exp`) into `dir` when the directory holds a
/// shard of another experiment (scenario, sensor, runs, seed, terms, ablation or k differ): a
/// shard directory holds the shards of one experiment, and `merge` needs them all alike.
pub fn refuse_other_experiments(dir: &Path, file: &ShardFile, exp: &Experiment) -> Result<()> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Ok(());
    };
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        if !(name.starts_with("shard-") && name.ends_with(".json")) {
            continue;
        }
        let path = entry.path();
        let text = files::read_text(
            &path,
            "an imudrift shard file (in the --out directory)",
            files::shard_bytes(),
        )?
        .text;
        let Ok(other) = serde_json::from_str::<ShardFile>(&text) else {
            continue;
        };
        let same = file.same_experiment(&other)
            && shard_experiment(&other)
                .is_ok_and(|(_, _, e)| (e.runs, e.seed) == (exp.runs, exp.seed));
        if !same {
            bail!(
                "--out {}: {} is a shard of another experiment or split (scenario, sensor, runs, seed, terms, ablation and k must match); a shard directory holds the shards of one experiment: choose another --out or remove it",
                dir.display(),
                path.display()
            );
        }
    }
    Ok(())
}

pub use montecarlo::job::{max_decimation, MAX_WORK_SAMPLES};

/// Refuse `runs` runs of `samples` output samples of `model` when they are more work than
/// [`MAX_WORK_SAMPLES`]; `what` names the job and `remedy` the options that shrink it.
pub fn check_work(
    model: &SensorModel,
    runs: f64,
    samples: f64,
    what: &str,
    remedy: &str,
) -> Result<()> {
    let decimation = max_decimation(model);
    let work = runs * samples * decimation;
    if work.is_nan() || work > MAX_WORK_SAMPLES {
        let filter = if decimation > 1.0 {
            format!(" x decimation {decimation}")
        } else {
            String::new()
        };
        bail!(
            "{what}: {runs:.3e} run(s) x {samples:.3e} samples{filter} are {work:.2e} samples of work (limit {MAX_WORK_SAMPLES:.0e}, about 3 h on 2 cores): {remedy}"
        );
    }
    Ok(())
}

/// [`check_work`] for `runs` runs of `exp` (before they are simulated; `merge` does no such work).
pub fn check_experiment_work(exp: &Experiment, runs: u64) -> Result<()> {
    check_work(
        &exp.model,
        runs as f64,
        exp.scenario.duration_s * exp.scenario.rate_hz,
        &exp.scenario.name,
        "use fewer --runs, a shorter --duration or a lower --rate (or split the runs with --shard i/k)",
    )
}

/// Memory for the per-run values above which `simulate` asks for shards instead (8 GiB).
use montecarlo::job::MAX_VALUE_BYTES;

/// Refuse a run range whose per-run values (8 bytes per run, checkpoint and quantity) would not fit.
pub fn check_memory(exp: &Experiment, runs: u64) -> Result<()> {
    let bytes = job::value_bytes(exp, runs);
    let limit = logio::available_memory_bytes().map_or(MAX_VALUE_BYTES, |a| a.min(MAX_VALUE_BYTES));
    if bytes > limit {
        bail!(
            "--runs: {runs} runs x {} checkpoints keep {} of per-run values (limit {}); split them with --shard i/k and `imudrift merge`, or use fewer checkpoints",
            exp.scenario.checkpoint_steps.len(),
            crate::fmt::bytes(bytes as f64),
            if limit == MAX_VALUE_BYTES {
                "8 GiB".to_string()
            } else {
                format!("{}, the memory available", crate::fmt::bytes(limit as f64))
            }
        );
    }
    Ok(())
}

/// Run `exp` over `runs`, with progress on stderr (`crate::progress`).
pub fn execute(exp: &Experiment, runs: std::ops::Range<u64>, label: &str) -> BatchResult {
    let kernel = exp.kernel();
    let progress = crate::progress::Progress::new(label, "runs", runs.end - runs.start);
    let result = run_range(&kernel, runs, &|done| progress.set(done));
    progress.finish();
    result
}

/// Refuse a report with a statistic that is not a number (`montecarlo::job::check_finite`): an
/// error naming the statistic, the navigation-error quantity and the time.
pub fn check_finite(report: &DriftReport) -> Result<()> {
    Ok(job::check_finite(report)?)
}
