//! `imudrift.simulate`, `simulate_shard` and `merge`: the CLI's `simulate`, `simulate --shard`
//! and `merge` through the same library code (`montecarlo::job`). The work runs with the GIL
//! released on a thread pool of the call's own (dropped when the call returns, so a process
//! forked afterwards inherits no pool), and Ctrl-C stops it: the calling thread checks Python's
//! signals every [`SIGNAL_POLL`] while the runs go on, and a pending `KeyboardInterrupt` stops
//! the runner before its next run (`montecarlo::run_range_until`).

use crate::{invalid, LogUnreadable};
use montecarlo::experiment::{Experiment, ExperimentError, Overrides};
use montecarlo::job::{self, Inputs, JobError, ScenarioEdits, Simulated};
use montecarlo::shard::{ShardFile, SHARD_FORMAT};
use montecarlo::{NavQuantity, Shard};
use numpy::{IntoPyArray, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// How often a running call checks for Ctrl-C (well under the second it must stop within).
const SIGNAL_POLL: Duration = Duration::from_millis(100);

/// Most bytes of a sensor model or scenario file (the CLI's limit, `src/files.rs`).
const MAX_CONFIG_BYTES: u64 = 16 << 20;

/// An error and its causes as the CLI prints them (`error: {e:#}`: joined by ": ").
pub use noise::text::error_chain as message;

/// A job error as `InvalidInput`, named by the Python argument where it comes from one.
fn job_error(e: JobError) -> PyErr {
    match e {
        JobError::Experiment(ExperimentError::NoRuns) => {
            invalid("runs: expected an integer >= 1".into())
        }
        other => invalid(message(&other)),
    }
}

/// A file that cannot be read (an `OSError`) or whose text is not usable (a `ValueError`).
pub enum ReadError {
    Unreadable(String),
    Invalid(String),
}

impl ReadError {
    /// The error with `prefix: ` before its message.
    fn within(self, prefix: &str) -> ReadError {
        match self {
            ReadError::Unreadable(m) => ReadError::Unreadable(format!("{prefix}: {m}")),
            ReadError::Invalid(m) => ReadError::Invalid(format!("{prefix}: {m}")),
        }
    }
}

impl From<ReadError> for PyErr {
    fn from(e: ReadError) -> PyErr {
        match e {
            ReadError::Unreadable(m) => LogUnreadable::new_err(m),
            ReadError::Invalid(m) => invalid(m),
        }
    }
}

/// A text file read as the CLI reads a sensor model or scenario: its name and text.
pub fn read_config(path: &Path) -> Result<(String, String), ReadError> {
    let name = path.display().to_string();
    let bytes = logio::read_capped(path, MAX_CONFIG_BYTES).map_err(|e| {
        ReadError::Unreadable(format!(
            "cannot read {name} as a sensor model, scenario or noise file: {e}"
        ))
    })?;
    let text = noise::utf8_text(bytes, &name).map_err(|e| ReadError::Invalid(message(&e)))?;
    Ok((name, text))
}

/// What is simulated: a scenario (or sensor) file, or a sensor's text with its name.
#[derive(FromPyObject)]
pub enum Subject {
    /// (sensor text, its source name): simulated in the default static scenario.
    Sensor(String, String),
    Path(std::path::PathBuf),
}

/// The job's inputs, as `imudrift simulate` reads them from the same file (with `--duration`,
/// `--rate`), or a sensor's text in the default static scenario.
fn inputs(subject: &Subject, edits: &ScenarioEdits) -> Result<Inputs, ReadError> {
    let (scenario_source, scenario_toml) = match subject {
        Subject::Path(path) => {
            let (given, text) = read_config(path)?;
            job::scenario_for_file(path, &given, &text)
        }
        Subject::Sensor(_, source) => {
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
        ReadError::Invalid(format!(
            "cannot read scenario {scenario_source} as TOML: {e}"
        ))
    })?;
    let (sensor_source, sensor_toml) = match subject {
        Subject::Sensor(text, source) => (source.clone(), text.clone()),
        Subject::Path(path) => {
            let scenario =
                montecarlo::scenario::Scenario::from_toml_str(&scenario_toml, &scenario_source)
                    .map_err(|e| ReadError::Invalid(message(&e)))?;
            read_config(&job::sensor_path(path, &scenario)).map_err(|e| {
                e.within(&format!("{scenario_source}: key `sensor`: the sensor file"))
            })?
        }
    };
    Ok(Inputs {
        scenario_source,
        scenario_toml,
        sensor_source,
        sensor_toml,
    })
}

/// The experiment of a call, with what it was built from and its ablation sub-experiments.
struct Job {
    inputs: Inputs,
    overrides: Overrides,
    exp: Experiment,
    subs: Option<Vec<montecarlo::ablation::TermExperiments>>,
}

/// The call's settings (the CLI's options of `simulate`, by their Python names).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct Settings {
    runs: Option<u64>,
    seed: Option<u64>,
    duration_s: Option<f64>,
    rate_hz: Option<f64>,
    only: Option<Vec<String>>,
    without: Vec<String>,
    /// None: as the scenario says.
    ablation: Option<bool>,
    threads: Option<usize>,
}

/// Term selectors (`gyro.white_noise`, `accel`) named by the argument that gave them.
pub fn terms(arg: &str, texts: &[String]) -> PyResult<Vec<noise::TermSelector>> {
    texts
        .iter()
        .map(|t| noise::TermSelector::parse(t).map_err(|e| invalid(format!("{arg}: {e}"))))
        .collect()
}

fn job_of(subject: &Subject, s: &Settings) -> PyResult<Job> {
    if let Some(r) = s.rate_hz.filter(|r| !(r.is_finite() && *r > 0.0)) {
        return Err(invalid(format!(
            "rate_hz: expected a sample rate in Hz > 0, found {r}"
        )));
    }
    let edits = ScenarioEdits {
        duration_s: s.duration_s,
        rate_hz: s.rate_hz,
    };
    let inputs = inputs(subject, &edits)?;
    let overrides = Overrides {
        runs: s.runs,
        seed: s.seed,
        only: s.only.as_deref().map(|t| terms("only", t)).transpose()?,
        without: terms("without", &s.without)?,
    };
    let exp = job::parse_inputs(&inputs, &overrides).map_err(job_error)?.2;
    let subs = match s.ablation.unwrap_or(exp.scenario.ablation) {
        true => Some(job::ablation_experiments(&inputs, &overrides).map_err(job_error)?),
        false => None,
    };
    Ok(Job {
        inputs,
        overrides,
        exp,
        subs,
    })
}

/// Refuse `runs` runs of the job (its ablation sub-runs counted) whose per-run values would not
/// fit in memory or whose work is beyond the CLI's limit (`montecarlo::job`), before any work.
fn check_size(job: &Job, runs: u64) -> PyResult<()> {
    let all_runs = runs * (1 + 2 * job.subs.as_ref().map_or(0, Vec::len) as u64);
    check_experiment_size(&job.exp, runs, all_runs)
}

/// Refuse `runs` runs of `exp` whose per-run values would not fit in memory, or `all_runs` runs
/// (sub-experiments counted) whose work is beyond the CLI's limit (`montecarlo::job`).
pub fn check_experiment_size(exp: &Experiment, runs: u64, all_runs: u64) -> PyResult<()> {
    let gib = |b: f64| b / f64::from(1u32 << 30);
    let bytes = job::value_bytes(exp, runs);
    let limit = logio::available_memory_bytes()
        .map_or(job::MAX_VALUE_BYTES, |a| a.min(job::MAX_VALUE_BYTES));
    if bytes > limit {
        return Err(invalid(format!(
            "runs: {runs} runs x {} checkpoints keep {:.2} GiB of per-run values (limit {:.2} GiB); split them with simulate_shard and merge, or use fewer checkpoints",
            exp.scenario.checkpoint_steps.len(),
            gib(bytes as f64),
            gib(limit as f64)
        )));
    }
    let work = job::work_samples(exp, all_runs);
    if work.is_nan() || work > job::MAX_WORK_SAMPLES {
        return Err(invalid(format!(
            "{}: {all_runs} run(s) are {work:.2e} samples of work (limit {:.0e}, about 3 h on 2 cores): use fewer runs, a shorter duration_s or a lower rate_hz (or split the runs with simulate_shard)",
            exp.scenario.name,
            job::MAX_WORK_SAMPLES
        )));
    }
    Ok(())
}

/// The call's own rayon pool of `threads` workers (None or 0: one per core), dropped when the
/// call returns: no library code runs in the process-wide rayon pool, whose threads a forked
/// child would not have (its first parallel call would then wait for ever).
pub fn call_pool(threads: Option<usize>) -> PyResult<rayon::ThreadPool> {
    let n = threads.unwrap_or(0);
    let max = std::thread::available_parallelism().map_or(1, |n| n.get()) * 4;
    if n > max.max(64) {
        return Err(invalid(format!(
            "threads {n}: expected at most {} (0 or None uses every core)",
            max.max(64)
        )));
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .map_err(|e| {
            pyo3::exceptions::PyOSError::new_err(format!("cannot start the worker threads: {e}"))
        })
}

/// `work` with the GIL released, in a pool of the call's own ([`call_pool`], one worker per
/// core): for the calls without a Ctrl-C check (reading a log, an Allan analysis, a merge).
pub fn detached<T: Send>(py: Python<'_>, work: impl FnOnce() -> T + Send) -> PyResult<T> {
    let pool = call_pool(None)?;
    Ok(py.detach(|| pool.install(work)))
}

/// Run `work` on a thread pool of `threads` workers (None or 0: one per core) with the GIL
/// released, checking for Ctrl-C meanwhile: a `KeyboardInterrupt` (or any error a signal handler
/// raises) stops the runs and is returned.
pub fn run_job<T: Send>(
    py: Python<'_>,
    threads: Option<usize>,
    work: impl FnOnce(&job::RunRange<'_>) -> Option<T> + Send,
) -> PyResult<T> {
    let pool = call_pool(threads)?;
    let stop = AtomicBool::new(false);
    let run = |e: &Experiment, runs: std::ops::Range<u64>, _label: &str| {
        montecarlo::run_range_until(&e.kernel(), runs, &|_| {}, &stop)
    };
    py.detach(|| {
        std::thread::scope(|scope| {
            let (tx, rx) = std::sync::mpsc::channel();
            // The work runs in the call's pool, so that its own parallel parts (a readback, a
            // diagnosis) use it too, and never the process-wide rayon pool.
            let worker = scope.spawn(move || {
                let _ = tx.send(pool.install(|| work(&run)));
            });
            loop {
                match rx.recv_timeout(SIGNAL_POLL) {
                    Ok(Some(done)) => return Ok(done),
                    Ok(None) => {
                        return Err(pyo3::exceptions::PyKeyboardInterrupt::new_err(
                            "interrupted",
                        ))
                    }
                    Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {
                        if let Err(e) = Python::attach(|py| py.check_signals()) {
                            stop.store(true, Ordering::Relaxed);
                            let _ = worker.join();
                            return Err(e);
                        }
                    }
                    Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
                        return Err(pyo3::exceptions::PyRuntimeError::new_err(
                            "the simulation's worker thread panicked",
                        ))
                    }
                }
            }
        })
    })
}

/// The result as the Python layer takes it: `document` (the `simulate --json` text), `values`
/// (runs x checkpoints x quantities), `run_ids`, `t_s` and `quantities`.
fn result_dict<'py>(
    py: Python<'py>,
    sim: Simulated,
    exp: &Experiment,
) -> PyResult<Bound<'py, PyDict>> {
    job::check_some_runs(&sim.report).map_err(|e| invalid(e.to_string()))?;
    let doc = job::document(&sim.report, exp, sim.ablation.as_deref());
    let d = PyDict::new(py);
    d.set_item("document", doc.to_string())?;
    let m = &sim.matrix;
    let (runs, cps, qs) = (m.runs(), m.checkpoints, m.quantities);
    let mut flat = vec![0.0; runs * cps * qs];
    for c in 0..cps {
        for q in 0..qs {
            for (r, v) in m.series(c, q).iter().enumerate() {
                flat[(r * cps + c) * qs + q] = *v;
            }
        }
    }
    let values = flat.into_pyarray(py).reshape([runs, cps, qs])?;
    d.set_item("values", values)?;
    d.set_item("run_ids", m.run_ids.clone().into_pyarray(py))?;
    let t: Vec<f64> = sim.report.checkpoints.iter().map(|c| c.t_s).collect();
    d.set_item("t_s", t.into_pyarray(py))?;
    d.set_item(
        "quantities",
        NavQuantity::ALL.map(NavQuantity::name).to_vec(),
    )?;
    Ok(d)
}

/// `imudrift simulate SUBJECT [options]`: every run, the report and the per-run values.
#[pyfunction]
pub fn simulate_run<'py>(
    py: Python<'py>,
    subject: Subject,
    settings: Settings,
) -> PyResult<Bound<'py, PyDict>> {
    let job = job_of(&subject, &settings)?;
    check_size(&job, job.exp.runs)?;
    let sim = run_job(py, settings.threads, |run| {
        job::simulate(&job.exp, job.subs.as_deref(), run)
    })?;
    result_dict(py, sim, &job.exp)
}

/// `imudrift simulate SUBJECT --shard index/count`: the shard file's bytes (JSON, the format
/// `imudrift merge` reads).
#[pyfunction]
pub fn simulate_shard_bytes<'py>(
    py: Python<'py>,
    subject: Subject,
    index: u64,
    count: u64,
    settings: Settings,
) -> PyResult<Bound<'py, PyBytes>> {
    if count == 0 || index >= count {
        return Err(invalid(format!(
            "shard {index}/{count}: expected integers 0 <= index < count"
        )));
    }
    let job = job_of(&subject, &settings)?;
    let shard = Shard { index, count };
    let range = shard.runs(job.exp.runs);
    check_size(&job, range.end - range.start)?;
    let mut file = job::empty_shard(
        job.inputs.clone(),
        &job.overrides,
        shard,
        job.subs.is_some(),
    );
    let file = run_job(py, settings.threads, |run| {
        job::fill_shard(&mut file, &job.exp, job.subs.as_deref(), run).map(|()| file)
    })?;
    let bytes =
        serde_json::to_vec(&file).map_err(|e| invalid(format!("cannot write the shard: {e}")))?;
    Ok(PyBytes::new(py, &bytes))
}

/// `imudrift merge`: shard files' bytes (all k shards of one job, any order) merged into exactly
/// what one `simulate` computes.
#[pyfunction]
pub fn merge_shards<'py>(py: Python<'py>, shards: Vec<Vec<u8>>) -> PyResult<Bound<'py, PyDict>> {
    if shards.is_empty() {
        return Err(invalid(
            "merge: expected the shards of a job, got none".into(),
        ));
    }
    let mut files = Vec::new();
    for (i, bytes) in shards.iter().enumerate() {
        let name = format!("shards[{i}]");
        let file: ShardFile = serde_json::from_slice(bytes)
            .map_err(|e| invalid(format!("{name}: not an imudrift shard file: {e}")))?;
        if file.format != SHARD_FORMAT {
            return Err(invalid(format!(
                "{name}: key `format`: expected `{SHARD_FORMAT}`, got `{}`",
                file.format
            )));
        }
        files.push((name, file));
    }
    let (inputs, overrides, exp) = job::shard_experiment(&files[0].1)
        .map_err(|e| invalid(format!("shards[0]: the stored scenario: {}", message(&e))))?;
    let sim = detached(py, || job::merge(files, &inputs, &overrides, &exp))?
        .map_err(|e| invalid(message(&e)))?;
    result_dict(py, sim, &exp)
}
