//! `simulate` (whole or as a shard) and `merge`: the request, its inputs read and checked once,
//! the experiment and its ablation sub-experiments, and the size checks before any work. The runs
//! themselves go through `montecarlo::job` with the front end's runner (its progress or Ctrl-C).

use crate::error::{FileError, Remedy, RequestError, Result};
use crate::files::{read_config, shard_bytes, TextFile};
use crate::setting::Setting;
use montecarlo::ablation::TermExperiments;
use montecarlo::experiment::{Experiment, Overrides};
use montecarlo::job::{self, Inputs, JobError, ScenarioEdits};
use montecarlo::runner::Shard;
use montecarlo::scenario::Scenario;
use montecarlo::shard::{ShardFile, SHARD_FORMAT};
use noise::TermSelector;
use std::path::{Path, PathBuf};

/// What is simulated: a scenario (or sensor) file, or a sensor's text with its name (simulated in
/// the default static scenario).
#[derive(Clone, Debug)]
pub enum Subject {
    Path(PathBuf),
    Sensor { text: String, source: String },
}

/// `simulate`'s settings; `None` takes the scenario's value.
#[derive(Clone, Debug)]
pub struct SimulateRequest {
    pub subject: Subject,
    pub runs: Option<u64>,
    pub seed: Option<u64>,
    pub duration_s: Option<f64>,
    pub rate_hz: Option<f64>,
    pub only: Option<Vec<TermSelector>>,
    pub without: Vec<TermSelector>,
    /// The ablation table: `None` as the scenario says.
    pub ablation: Option<bool>,
}

/// A checked `simulate` request: what it was built from, the experiment and its ablation
/// sub-experiments (when asked for).
pub struct SimulateJob {
    pub inputs: Inputs,
    pub overrides: Overrides,
    pub exp: Experiment,
    pub subs: Option<Vec<TermExperiments>>,
    /// The sensor file a scenario file names (for the front end's list of inputs).
    pub sensor_path: Option<PathBuf>,
}

/// Term selectors (`gyro.white_noise`, `accel`) from their texts, named by their setting.
pub fn terms(setting: Setting, texts: &[String]) -> Result<Vec<TermSelector>> {
    texts
        .iter()
        .map(|t| {
            TermSelector::parse(t).map_err(|e| RequestError::Terms {
                setting,
                message: e.to_string(),
            })
        })
        .collect()
}

/// A sample rate, Hz, finite and > 0.
pub fn check_rate(rate_hz: f64) -> Result<f64> {
    if rate_hz.is_finite() && rate_hz > 0.0 {
        Ok(rate_hz)
    } else {
        Err(RequestError::Rate(rate_hz))
    }
}

impl SimulateRequest {
    /// A request for `subject` with every setting as its scenario says.
    pub fn new(subject: Subject) -> Self {
        SimulateRequest {
            subject,
            runs: None,
            seed: None,
            duration_s: None,
            rate_hz: None,
            only: None,
            without: Vec::new(),
            ablation: None,
        }
    }

    /// Read and check everything the request names; build the experiment.
    pub fn validate(&self) -> Result<SimulateJob> {
        if let Some(r) = self.rate_hz {
            check_rate(r)?;
        }
        let edits = ScenarioEdits {
            duration_s: self.duration_s,
            rate_hz: self.rate_hz,
        };
        // Each text is parsed once: the scenario (to find its sensor), then the model.
        let (inputs, scenario, sensor_path) = inputs(&self.subject, &edits)?;
        let overrides = Overrides {
            runs: self.runs,
            seed: self.seed,
            only: self.only.clone(),
            without: self.without.clone(),
        };
        let model = noise::SensorModel::from_text(&inputs.sensor_toml, &inputs.sensor_source)
            .map_err(JobError::from)?;
        let exp = Experiment::new(scenario.clone(), &model, &overrides).map_err(JobError::from)?;
        let subs = match self.ablation.unwrap_or(exp.scenario.ablation) {
            true => Some(
                montecarlo::ablation::experiments(&scenario, &model, &overrides, &exp)
                    .map_err(JobError::from)?,
            ),
            false => None,
        };
        Ok(SimulateJob {
            inputs,
            overrides,
            exp,
            subs,
            sensor_path,
        })
    }
}

/// The job's inputs: a scenario file and the sensor it names (relative to it), a sensor file in
/// the default static scenario, or a sensor's text in the default static scenario; `edits`
/// applied to the scenario's text (the text a shard stores).
fn inputs(subject: &Subject, edits: &ScenarioEdits) -> Result<(Inputs, Scenario, Option<PathBuf>)> {
    let (scenario_source, scenario_toml) = match subject {
        Subject::Path(path) => {
            let TextFile { name, text } = read_config(path)?;
            job::scenario_for_file(path, &name, &text)
        }
        Subject::Sensor { source, .. } => {
            let p = Path::new(source);
            let name = |f: Option<&std::ffi::OsStr>, or: &str| {
                f.map_or(or.to_string(), |f| f.to_string_lossy().into_owned())
            };
            (
                format!("default static scenario for {source}"),
                job::default_scenario_toml(
                    &name(p.file_name(), source),
                    &name(p.file_stem(), "sensor"),
                ),
            )
        }
    };
    let scenario_toml = job::edit_scenario_toml(&scenario_toml, edits).map_err(|e| {
        RequestError::ScenarioNotToml {
            source_name: scenario_source.clone(),
            message: e.to_string(),
        }
    })?;
    let scenario = Scenario::from_toml_str(&scenario_toml, &scenario_source)
        .map_err(|e| RequestError::from(JobError::from(e)))?;
    let (sensor_source, sensor_toml, sensor_path) = match subject {
        Subject::Sensor { text, source } => (source.clone(), text.clone(), None),
        Subject::Path(path) => {
            let sensor_path = job::sensor_path(path, &scenario);
            let file = read_config(&sensor_path).map_err(|e| FileError {
                within: Some(format!("{scenario_source}: key `sensor`: the sensor file")),
                ..e
            })?;
            (
                sensor_path.display().to_string(),
                file.text,
                Some(sensor_path),
            )
        }
    };
    Ok((
        Inputs {
            scenario_source,
            scenario_toml,
            sensor_source,
            sensor_toml,
        },
        scenario,
        sensor_path,
    ))
}

impl SimulateJob {
    /// The ablation sub-experiments as the runner takes them.
    pub fn subs(&self) -> Option<&[TermExperiments]> {
        self.subs.as_deref()
    }

    /// Runs of one run index: the experiment's and each ablation sub-experiment's two.
    pub fn runs_per_index(&self) -> u64 {
        1 + 2 * self.subs.as_ref().map_or(0, Vec::len) as u64
    }

    /// Refuse `runs` run indices whose per-run values would not fit in memory or whose work
    /// (ablation sub-runs counted) is beyond [`job::MAX_WORK_SAMPLES`], before any work.
    pub fn check_size(&self, runs: u64) -> Result<()> {
        let all = runs * self.runs_per_index();
        check_experiment(&self.exp, all, all)
    }

    /// The shard file of `shard` without its values yet (its experiment can be checked against
    /// other shards before any work).
    pub fn empty_shard(&self, shard: Shard) -> ShardFile {
        job::empty_shard(
            self.inputs.clone(),
            &self.overrides,
            shard,
            self.subs.is_some(),
        )
    }

    /// The run indices of `shard`, checked for size.
    pub fn shard_runs(&self, shard: Shard) -> Result<std::ops::Range<u64>> {
        let range = shard.runs(self.exp.runs);
        self.check_size(range.end - range.start)?;
        Ok(range)
    }
}

/// A shard `i/k` from its text.
pub fn parse_shard(text: &str) -> Result<Shard> {
    Shard::parse(text).map_err(|_| RequestError::Shard(text.to_string()))
}

/// A shard from its two integers.
pub fn shard(index: u64, count: u64) -> Result<Shard> {
    parse_shard(&format!("{index}/{count}"))
}

/// Refuse `runs` runs of `exp` whose per-run values would not fit in memory, or `all_runs` runs
/// (sub-experiments counted) whose work is beyond [`job::MAX_WORK_SAMPLES`].
pub fn check_experiment(exp: &Experiment, runs: u64, all_runs: u64) -> Result<()> {
    check_memory(exp, runs)?;
    check_work(
        &exp.model,
        all_runs as f64,
        exp.scenario.duration_s * exp.scenario.rate_hz,
        &exp.scenario.name,
        Remedy::Simulate,
    )
}

/// Memory a simulation needs beside its per-run values and what the process holds before it
/// starts: the workers' stacks and sample blocks, the statistics' sorted copy of one series, the
/// report. Measured (peak RSS, `IMUDRIFT_MEMORY_LIMIT` of 60 MB, MTx, 1 s): 2 to 4 MiB; twice
/// that is kept free, so that the limit holds for the whole process.
pub const WORKING_BYTES: u64 = 8 << 20;

/// Refuse a run range whose per-run values (8 bytes per run, checkpoint and quantity) would not
/// fit in the memory available (`logio::available_memory_bytes`) less what the process holds
/// already (`logio::resident_bytes`: the limit bounds the whole process) and [`WORKING_BYTES`],
/// and at most
/// [`job::MAX_VALUE_BYTES`].
pub fn check_memory(exp: &Experiment, runs: u64) -> Result<()> {
    let bytes = job::value_bytes(exp, runs);
    let held = logio::resident_bytes().unwrap_or(0);
    let limit = logio::available_memory_bytes().map_or(job::MAX_VALUE_BYTES, |a| {
        a.saturating_sub(held)
            .saturating_sub(WORKING_BYTES)
            .min(job::MAX_VALUE_BYTES)
    });
    if bytes > limit {
        return Err(RequestError::Memory {
            runs,
            checkpoints: exp.scenario.checkpoint_steps.len(),
            bytes,
            limit,
        });
    }
    Ok(())
}

/// Refuse `runs` runs of `samples` output samples of `model` when they are more work than
/// [`job::MAX_WORK_SAMPLES`] (an output filter's decimation counted); `what` names the job.
pub fn check_work(
    model: &noise::SensorModel,
    runs: f64,
    samples: f64,
    what: &str,
    remedy: Remedy,
) -> Result<()> {
    let decimation = job::max_decimation(model);
    let work = runs * samples * decimation;
    if work.is_nan() || work > job::MAX_WORK_SAMPLES {
        return Err(RequestError::Work {
            what: what.to_string(),
            runs,
            samples,
            decimation,
            work,
            remedy,
        });
    }
    Ok(())
}

/// A shard file as a merge request names it: a file, or its bytes with a name for messages.
#[derive(Clone, Debug)]
pub enum ShardInput {
    Path(PathBuf),
    Bytes { name: String, bytes: Vec<u8> },
}

/// `merge`: the shard files of one job (all k of them, any order).
#[derive(Clone, Debug)]
pub struct MergeRequest {
    pub shards: Vec<ShardInput>,
}

/// A checked merge: the shard files, and the job they were cut from.
pub struct MergeJob {
    pub files: Vec<(String, ShardFile)>,
    pub inputs: Inputs,
    pub overrides: Overrides,
    pub exp: Experiment,
}

impl MergeRequest {
    /// Read every shard (together at most [`shard_bytes`], each file's size checked before it is
    /// read), check each is one, rebuild the job from the first and check the merged values fit.
    pub fn validate(self) -> Result<MergeJob> {
        if self.shards.is_empty() {
            return Err(RequestError::NoShards);
        }
        let mut files = Vec::new();
        let mut left = shard_bytes();
        for shard in self.shards {
            let (name, bytes) = match shard {
                ShardInput::Path(path) => {
                    let text = crate::files::read_text(
                        &path,
                        "an imudrift shard file (the shards together at most a third of the memory available)",
                        left,
                    )?;
                    (text.name, text.text.into_bytes())
                }
                ShardInput::Bytes { name, bytes } => (name, bytes),
            };
            left = left.saturating_sub(bytes.len() as u64);
            let file: ShardFile =
                serde_json::from_slice(&bytes).map_err(|e| RequestError::NotShard {
                    name: name.clone(),
                    message: e.to_string(),
                })?;
            if file.format != SHARD_FORMAT {
                return Err(RequestError::ShardFormat {
                    name,
                    found: file.format,
                });
            }
            files.push((name, file));
        }
        let (name, first) = &files[0];
        let (inputs, overrides, exp) =
            job::shard_experiment(first).map_err(|e| RequestError::StoredScenario {
                name: name.clone(),
                source: Box::new(e),
            })?;
        // The merged values must fit, as for `simulate` itself (which would have asked for shards).
        let a_len = first.ablation.as_ref().map_or(0, Vec::len);
        check_memory(&exp, exp.runs * (1 + 2 * a_len as u64))?;
        Ok(MergeJob {
            files,
            inputs,
            overrides,
            exp,
        })
    }
}

impl MergeJob {
    /// Exactly what one `simulate` of the job computes.
    pub fn merge(self) -> Result<job::Simulated> {
        job::merge(self.files, &self.inputs, &self.overrides, &self.exp).map_err(|e| match e {
            job::MergeError::Job(e) => RequestError::Job(e),
            other => RequestError::Merge(Box::new(other)),
        })
    }
}
