//! `imudrift.simulate`, `simulate_shard` and `merge`: the CLI's `simulate`, `simulate --shard`
//! and `merge` through the same library code (`montecarlo::job`). The work runs with the GIL
//! released on a thread pool of the call's own (dropped when the call returns, so a process
//! forked afterwards inherits no pool), and Ctrl-C stops it: the calling thread checks Python's
//! signals every [`SIGNAL_POLL`] while the runs go on, and a pending `KeyboardInterrupt` stops
//! the runner before its next run (`montecarlo::run_range_until`).

use crate::{invalid, LogUnreadable};
use montecarlo::experiment::Experiment;
use montecarlo::job::{self, Simulated};
use montecarlo::NavQuantity;
use numpy::{IntoPyArray, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use request::simulate::{MergeRequest, ShardInput, SimulateJob, SimulateRequest, Subject};
use request::{RequestError, Setting};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// How often a running call checks for Ctrl-C (well under the second it must stop within).
const SIGNAL_POLL: Duration = Duration::from_millis(100);

/// An error and its causes as the CLI prints them (`error: {e:#}`: joined by ": ").
pub use noise::text::error_chain as message;

/// The Python name of a request's setting (its argument), for the request layer's messages.
pub fn argument(s: Setting) -> &'static str {
    match s {
        Setting::Shard => "simulate_shard",
        other => other.name(),
    }
}

/// A request error as Python raises it: a file the system cannot read is `LogUnreadable` (an
/// `OSError`), anything else `InvalidInput` (a `ValueError`); settings named by [`argument`].
pub fn request_error(e: RequestError) -> PyErr {
    let m = e.render(&argument);
    if e.is_unreadable() {
        LogUnreadable::new_err(m)
    } else {
        invalid(m)
    }
}

/// What is simulated: a scenario (or sensor) file, or a sensor's text with its name.
#[derive(FromPyObject)]
pub enum SubjectArg {
    /// (sensor text, its source name): simulated in the default static scenario.
    Sensor(String, String),
    Path(std::path::PathBuf),
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
    let setting = if arg == "only" {
        Setting::Only
    } else {
        Setting::Without
    };
    request::simulate::terms(setting, texts).map_err(request_error)
}

/// The checked job of a call (`request::simulate`).
fn job_of(subject: SubjectArg, s: &Settings) -> PyResult<SimulateJob> {
    SimulateRequest {
        subject: match subject {
            SubjectArg::Sensor(text, source) => Subject::Sensor { text, source },
            SubjectArg::Path(p) => Subject::Path(p),
        },
        runs: s.runs,
        seed: s.seed,
        duration_s: s.duration_s,
        rate_hz: s.rate_hz,
        only: s.only.as_deref().map(|t| terms("only", t)).transpose()?,
        without: terms("without", &s.without)?,
        ablation: s.ablation,
    }
    .validate()
    .map_err(request_error)
}

/// Refuse `runs` runs of `exp` whose per-run values would not fit in memory, or `all_runs` runs
/// (sub-experiments counted) whose work is beyond the limit (`request::simulate`).
pub fn check_experiment_size(exp: &Experiment, runs: u64, all_runs: u64) -> PyResult<()> {
    request::simulate::check_experiment(exp, runs, all_runs).map_err(request_error)
}

/// The call's own rayon pool of `threads` workers (None or 0: one per core), dropped when the
/// call returns: no library code runs in the process-wide rayon pool, whose threads a forked
/// child would not have (its first parallel call would then wait for ever).
pub fn call_pool(threads: Option<usize>) -> PyResult<rayon::ThreadPool> {
    request::pool::pool(threads).map_err(request_error)
}

/// `work` with the GIL released, in a pool of the call's own ([`call_pool`], one worker per
/// core): for the calls without a Ctrl-C check (reading a log, an Allan analysis, a merge).
pub fn detached<T: Send>(py: Python<'_>, work: impl FnOnce() -> T + Send) -> PyResult<T> {
    let pool = call_pool(None)?;
    Ok(py.detach(|| pool.install(work)))
}

/// Run `work` on a thread pool of `threads` workers (None or 0: one per core) with the GIL
/// released, checking for Ctrl-C meanwhile: a `KeyboardInterrupt` (or any error a signal handler
/// raises) sets the stop flag `work` is given, waits for `work` to return (the libraries stop
/// within a second) and is returned. `work`'s `None` is a stop.
pub fn run_until<T: Send>(
    py: Python<'_>,
    threads: Option<usize>,
    work: impl FnOnce(&AtomicBool) -> Option<T> + Send,
) -> PyResult<T> {
    let pool = call_pool(threads)?;
    let stop = AtomicBool::new(false);
    py.detach(|| {
        std::thread::scope(|scope| {
            let (tx, rx) = std::sync::mpsc::channel();
            let stop = &stop;
            let worker = scope.spawn(move || {
                let _ = tx.send(pool.install(|| work(stop)));
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
                            "the worker thread panicked",
                        ))
                    }
                }
            }
        })
    })
}

/// [`run_until`] for Monte Carlo runs: `work` gets a runner that stops at the flag
/// (`montecarlo::run_range_until`).
pub fn run_job<T: Send>(
    py: Python<'_>,
    threads: Option<usize>,
    work: impl FnOnce(&job::RunRange<'_>) -> Option<T> + Send,
) -> PyResult<T> {
    run_until(py, threads, |stop| {
        let run = |e: &Experiment, runs: std::ops::Range<u64>, _label: &str| {
            montecarlo::run_range_until(&e.kernel(), runs, &|_| {}, stop)
        };
        work(&run)
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
        NavQuantity::ALL.map(NavQuantity::label).to_vec(),
    )?;
    Ok(d)
}

/// `imudrift simulate SUBJECT [options]`: every run, the report and the per-run values.
#[pyfunction]
pub fn simulate_run<'py>(
    py: Python<'py>,
    subject: SubjectArg,
    settings: Settings,
) -> PyResult<Bound<'py, PyDict>> {
    let job = job_of(subject, &settings)?;
    job.check_size(job.exp.runs).map_err(request_error)?;
    let sim = run_job(py, settings.threads, |run| {
        job::simulate(&job.exp, job.subs(), run)
    })?;
    result_dict(py, sim, &job.exp)
}

/// `imudrift simulate SUBJECT --shard index/count`: the shard file's bytes (JSON, the format
/// `imudrift merge` reads).
#[pyfunction]
pub fn simulate_shard_bytes<'py>(
    py: Python<'py>,
    subject: SubjectArg,
    index: u64,
    count: u64,
    settings: Settings,
) -> PyResult<Bound<'py, PyBytes>> {
    let shard = request::simulate::shard(index, count).map_err(request_error)?;
    let job = job_of(subject, &settings)?;
    job.shard_runs(shard).map_err(request_error)?;
    let mut file = job.empty_shard(shard);
    let file = run_job(py, settings.threads, |run| {
        job::fill_shard(&mut file, &job.exp, job.subs(), run).map(|()| file)
    })?;
    let bytes =
        serde_json::to_vec(&file).map_err(|e| invalid(format!("cannot write the shard: {e}")))?;
    Ok(PyBytes::new(py, &bytes))
}

/// `imudrift merge`: shard files' bytes (all k shards of one job, any order) merged into exactly
/// what one `simulate` computes.
#[pyfunction]
pub fn merge_shards<'py>(py: Python<'py>, shards: Vec<Vec<u8>>) -> PyResult<Bound<'py, PyDict>> {
    let shards = shards
        .into_iter()
        .enumerate()
        .map(|(i, bytes)| ShardInput::Bytes {
            name: format!("shards[{i}]"),
            bytes,
        })
        .collect();
    let job = MergeRequest { shards }.validate().map_err(request_error)?;
    let exp = job.exp.clone();
    let sim = detached(py, || job.merge())?.map_err(request_error)?;
    result_dict(py, sim, &exp)
}
