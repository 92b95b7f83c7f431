//! `imudrift.spec`, `imudrift.diagnose` and `imudrift.drift`: the CLI's `spec`, `diagnose` and
//! `drift` through the same library code (`montecarlo::spec_job`, `diagnose::document`), each
//! returning the text of the command's `--json` document. The work runs with the GIL released
//! in a thread pool of the call's own. Ctrl-C: the calling thread checks Python's signals every
//! [`SIGNAL_POLL`] and a pending `KeyboardInterrupt` sets the stop flag the libraries check
//! (`montecarlo::run_range_until`'s `AtomicBool`): `spec`'s drift runs ([`crate::sim::run_job`]),
//! `diagnose` (`diagnose::diagnose_until`) and `drift` (`drift_check::check_drift_until`) stop
//! within a second ([`run_until`]); `spec`'s readback has no stop and ends first.

use crate::sim::{call_pool, check_experiment_size, detached, message, run_job, terms};
use crate::{invalid, read_log_file, read_options, ReaderArgs};
use diagnose::document::{self, DiagnoseSources, HeldOutChecks, ProtocolSetting};
use diagnose::drift_check::{check_drift_until, CheckError, CheckSettings, Models};
use diagnose::protocol::{Calibration, Initialisation, Protocol};
use diagnose::{DiagnoseError, LogInput};
use montecarlo::spec_job::{self, SpecDoc, SpecError, SpecRequest, SpecSetting, SpecSettings};
use noise::{ImuChannels, SensorModel};
use numpy::PyReadonlyArray1;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

fn model(text: &str, source: &str) -> PyResult<SensorModel> {
    SensorModel::from_text(text, source).map_err(|e| invalid(message(&e)))
}

/// `spec`'s settings by the names of `imudrift.spec`'s arguments.
fn spec_argument(setting: SpecSetting) -> &'static str {
    match setting {
        SpecSetting::Require => "require",
        SpecSetting::Times => "times",
        SpecSetting::Rate => "rate_hz",
        SpecSetting::Runs => "runs",
        SpecSetting::ReadbackDuration => "readback_duration_s",
    }
}

fn spec_error(e: SpecError) -> PyErr {
    invalid(e.render(&spec_argument))
}

/// `imudrift.spec`'s settings (the CLI's options by their Python names).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct SpecArgs {
    require: Vec<String>,
    times: Option<Vec<f64>>,
    rate_hz: f64,
    runs: Option<u64>,
    seed: u64,
    readback: bool,
    readback_duration_s: Option<f64>,
    only: Option<Vec<String>>,
    without: Vec<String>,
    threads: Option<usize>,
}

/// How often a running call checks for Ctrl-C (well under the second it must stop within).
const SIGNAL_POLL: Duration = Duration::from_millis(100);

/// Run `work` on a thread pool of `threads` workers (None or 0: one per core) with the GIL
/// released, checking for Ctrl-C meanwhile: a `KeyboardInterrupt` (or any error a signal handler
/// raises) sets the stop flag `work` is given, waits for `work` to return (the libraries stop
/// within a second) and is returned. `work`'s `None` is a stop.
fn run_until<T: Send>(
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

/// `imudrift spec SENSOR... --json`: each sensor given as (its text, its source name), the
/// document's text.
#[pyfunction]
pub fn spec_run(
    py: Python<'_>,
    sensors: Vec<(String, String)>,
    settings: SpecArgs,
) -> PyResult<String> {
    if sensors.is_empty() {
        return Err(invalid("sensors: expected at least one sensor".into()));
    }
    let s = SpecSettings::new(&SpecRequest {
        require: settings.require.clone(),
        times_s: settings.times.clone(),
        rate_hz: settings.rate_hz,
        runs: settings.runs,
        readback: settings.readback,
        readback_duration_s: settings.readback_duration_s,
        available_memory_bytes: logio::available_memory_bytes(),
    })
    .map_err(spec_error)?;
    let only = settings
        .only
        .as_deref()
        .map(|t| terms("only", t))
        .transpose()?;
    let filter = noise::TermFilter::new(only.as_deref(), &terms("without", &settings.without)?);
    let seed = settings.seed;
    let mut jobs = Vec::new();
    for (text, source) in &sensors {
        let m = model(text, source)?.filtered(&filter);
        let exp = spec_job::experiment(&m, &s, seed, source).map_err(spec_error)?;
        check_experiment_size(&exp, exp.runs, exp.runs)?;
        jobs.push((m, exp, source.clone()));
    }
    let out = run_job(py, settings.threads, |run| {
        // A failed run is counted in the document (`drift_runs`); the CLI also warns of it on stderr.
        let mut outs = Vec::new();
        for (m, exp, source) in &jobs {
            match spec_job::compare(m, exp, &s, seed, source, run) {
                Ok(Some((out, _failures))) => outs.push(out),
                Ok(None) => return None,
                Err(e) => return Some(Err(e)),
            }
        }
        Some(Ok(outs))
    })?
    .map_err(spec_error)?;
    Ok(SpecDoc::new(seed, &s, out).to_json())
}

/// A log as the Python layer passes it: a file path (read by the CLI's reader), or samples.
#[derive(FromPyObject)]
pub enum LogArg<'py> {
    Path(PathBuf),
    Arrays(ArrayLog<'py>),
}

/// Samples given as arrays: SI channels by name (gx..az, rad/s and m/s^2; temp, degC).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct ArrayLog<'py> {
    source: String,
    rate_hz: f64,
    channels: Vec<(String, PyReadonlyArray1<'py, f64>)>,
}

/// A log read or given, in SI, with its `columns[]` / `skipped_columns[]` JSON.
struct OwnedLog {
    source: String,
    rate_hz: f64,
    channels: BTreeMap<String, Vec<f64>>,
    columns: (serde_json::Value, serde_json::Value),
}

impl OwnedLog {
    fn len(&self) -> usize {
        self.channels.values().next().map_or(0, Vec::len)
    }

    fn input(&self, temperature: bool) -> LogInput<'_> {
        LogInput {
            dt_s: 1.0 / self.rate_hz,
            channels: ImuChannels::from_fn(|c| self.channels.get(c.name()).map(Vec::as_slice)),
            temperature_c: if temperature {
                self.channels.get("temp").map(Vec::as_slice)
            } else {
                None
            },
        }
    }
}

/// Read or take each log, refusing one without a gyro or accelerometer channel, with a constant
/// channel, or with samples that are not finite.
fn logs_of(py: Python<'_>, logs: Vec<LogArg<'_>>, reader: &ReaderArgs) -> PyResult<Vec<OwnedLog>> {
    let opts = read_options(reader)?;
    let mut out = Vec::new();
    for log in logs {
        let owned = match log {
            LogArg::Path(path) => {
                let log = detached(py, || read_log_file(&path, &opts))??;
                let columns = log.columns_json(&crate::read_log_argument);
                OwnedLog {
                    source: log.source,
                    rate_hz: log.rate_hz,
                    channels: log.channels,
                    columns,
                }
            }
            LogArg::Arrays(a) => array_log(a)?,
        };
        check_channels(&owned)?;
        out.push(owned);
    }
    if out.is_empty() {
        return Err(invalid("logs: expected at least one log".into()));
    }
    Ok(out)
}

/// A log given as arrays: its channels named as the reader names them, in SI; its columns are
/// "from the name" with the "default" (SI) unit, as the reader says of such a file.
fn array_log(a: ArrayLog<'_>) -> PyResult<OwnedLog> {
    if !logio::valid_rate_hz(a.rate_hz) {
        return Err(invalid(format!(
            "{}: rate_hz: expected a sample rate in Hz > 0, found {}",
            a.source, a.rate_hz
        )));
    }
    let mut channels = BTreeMap::new();
    let mut columns = Vec::new();
    for (name, array) in &a.channels {
        if !(name == "temp" || noise::Channel::from_name(name).is_some()) {
            return Err(invalid(format!(
                "{}: {name:?} is not one of gx, gy, gz, ax, ay, az, temp",
                a.source
            )));
        }
        let v = array
            .as_slice()
            .map_err(|_| {
                invalid(format!(
                    "{}: {name}: expected a 1-D float64 array",
                    a.source
                ))
            })?
            .to_vec();
        if let Some(i) = v.iter().position(|x| !x.is_finite()) {
            return Err(invalid(format!(
                "{}: {name}[{i}] is {}: every sample must be finite",
                a.source, v[i]
            )));
        }
        let unit = if name == "temp" {
            "degC"
        } else {
            logio::Log::unit_of(name)
        };
        columns.push(serde_json::json!({
            "column": name, "channel": name, "unit": unit,
            "channel_from": "name", "unit_from": "default",
        }));
        channels.insert(name.clone(), v);
    }
    Ok(OwnedLog {
        source: a.source,
        rate_hz: a.rate_hz,
        channels,
        columns: (columns.into(), serde_json::Value::Array(Vec::new())),
    })
}

/// A log without a gyro or accelerometer channel, or with a constant one, says nothing.
fn check_channels(log: &OwnedLog) -> PyResult<()> {
    if noise::Channel::ALL
        .iter()
        .all(|c| !log.channels.contains_key(c.name()))
    {
        return Err(invalid(format!(
            "{}: no gyro or accelerometer channel (expected gx gy gz ax ay az, or map columns with columns={{\"gx\": NAME}})",
            log.source
        )));
    }
    for c in noise::Channel::ALL {
        let Some(d) = log.channels.get(c.name()) else {
            continue;
        };
        if let Some(&first) = d.first() {
            if d.iter().all(|&v| v == first) {
                return Err(invalid(format!(
                    "{}: channel {} is constant ({first}): it has no noise to analyse (a stuck or disconnected sensor, or a column of zeros?); leave it out",
                    log.source,
                    c.name()
                )));
            }
        }
    }
    Ok(())
}

/// The protocol's settings by the names of the Python arguments.
fn protocol_argument(setting: ProtocolSetting) -> &'static str {
    match setting {
        ProtocolSetting::Horizons => "horizons",
        ProtocolSetting::CalibrationWindow => "calibration window:",
        ProtocolSetting::LevelWindow => "init level:",
    }
}

/// A time given as a text with its unit ("10 min"), in seconds, for the argument `name`
/// (`noise::units::duration_s`, the CLI's reading of a duration).
#[pyfunction]
pub fn seconds_of(name: &str, text: &str) -> PyResult<f64> {
    noise::units::duration_s(text).map_err(|e| invalid(format!("{name} {text:?}: {e}")))
}

/// `calibration`: none, log-mean or window:TIME (the CLI's `--calibration`).
fn calibration(text: &str) -> PyResult<Calibration> {
    Calibration::parse(text, &noise::units::duration_s)
        .map_err(|e| invalid(format!("calibration {text:?}: {e}")))
}

/// `init`: perfect or level:TIME (the CLI's `--init`).
fn initialisation(text: &str) -> PyResult<Initialisation> {
    Initialisation::parse(text, &noise::units::duration_s)
        .map_err(|e| invalid(format!("init {text:?}: {e}")))
}

/// The protocol fits the logs' sampling, and the model's output filter their rate.
fn check_logs(
    logs: &[OwnedLog],
    protocol: &Protocol,
    model: &SensorModel,
    model_name: &str,
) -> PyResult<()> {
    let dt_s = 1.0 / logs[0].rate_hz;
    let longest = logs.iter().map(OwnedLog::len).max().unwrap_or(0);
    document::check_sampling(protocol, dt_s, longest)
        .map_err(|e| invalid(e.render(&protocol_argument)))?;
    noise::ImuErrors::check_rate(model, dt_s).map_err(|e| {
        invalid(format!(
            "{model_name}: {e}; the logs are at {}",
            noise::text::rate(1.0 / dt_s)
        ))
    })
}

/// Each worker of a diagnosis holds a simulated six-channel log of the longest run's length
/// (and its phase, 16 bytes a sample): refuse logs whose simulation would not fit rather than be
/// killed for memory halfway (the CLI's check).
fn check_memory(logs: &[OwnedLog], threads: Option<usize>) -> PyResult<()> {
    let threads = threads
        .filter(|&n| n > 0)
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let longest = logs.iter().map(OwnedLog::len).max().unwrap_or(0);
    let need = threads as u64 * 6 * longest as u64 * 16;
    if let Some(available) = logio::available_memory_bytes() {
        if need > available {
            return Err(invalid(format!(
                "{}: simulating logs of {longest} samples on {threads} threads needs about {:.1} GiB and {:.1} GiB is available: use fewer threads or a shorter log",
                logs[0].source,
                need as f64 / (1u64 << 30) as f64,
                available as f64 / (1u64 << 30) as f64
            )));
        }
    }
    Ok(())
}

/// `imudrift.diagnose`'s settings (the CLI's options by their Python names).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct DiagnoseArgs {
    seed: u64,
    seeds: usize,
    rounds: usize,
    horizons: Vec<f64>,
    min_delta_bic: f64,
    tau_min: f64,
    drift_check: bool,
    calibration: Option<String>,
    init: Option<String>,
    threads: Option<usize>,
    latitude: Option<f64>,
}

/// `latitude` (deg, -89..89), or None for Woodman's flat Earth, as the CLI's `--latitude` /
/// `--flat-earth`.
fn latitude(value: Option<f64>) -> PyResult<Option<f64>> {
    match value {
        Some(v) if !(v.is_finite() && v.abs() <= 89.0) => Err(invalid(format!(
            "latitude {v}: expected a latitude in [-89, 89] deg (the north-east-down frame is singular at the poles), or None for the flat Earth"
        ))),
        v => Ok(v),
    }
}

fn check_diagnose_args(a: &DiagnoseArgs) -> PyResult<()> {
    use diagnose::settings::{MAX_ROUNDS, MAX_SEEDS};
    if a.seeds < 2 {
        return Err(invalid(format!(
            "seeds {}: at least 2 simulated logs are needed for a band",
            a.seeds
        )));
    }
    if a.seeds > MAX_SEEDS {
        return Err(invalid(format!(
            "seeds {}: expected at most {MAX_SEEDS} simulated logs per band",
            a.seeds
        )));
    }
    if a.rounds > MAX_ROUNDS {
        return Err(invalid(format!(
            "rounds {}: expected at most {MAX_ROUNDS}",
            a.rounds
        )));
    }
    if !a.min_delta_bic.is_finite() || a.min_delta_bic < 0.0 {
        return Err(invalid(format!(
            "min_delta_bic {}: expected a number >= 0",
            a.min_delta_bic
        )));
    }
    if !(a.tau_min.is_finite() && a.tau_min >= 0.0) {
        return Err(invalid(format!(
            "tau_min {}: expected a time >= 0",
            a.tau_min
        )));
    }
    if let Some(h) = a.horizons.iter().find(|h| !(h.is_finite() && **h > 0.0)) {
        return Err(invalid(format!("horizons: expected times > 0, found {h}")));
    }
    Ok(())
}

/// A diagnose error, one about a setting named by the Python argument that sets it.
fn diagnose_error(e: DiagnoseError) -> String {
    match e {
        DiagnoseError::NoTaus { tau_min_s } => format!("no Allan point at or above tau_min {tau_min_s} s"),
        DiagnoseError::SeedsForRuns { seeds, runs } => format!(
            "seeds {seeds} for {runs} logs: a band pooled over {runs} runs needs more simulated logs than runs (e.g. seeds={})",
            (runs + 1).max(16)
        ),
        e => message(&e),
    }
}

/// `imudrift diagnose LOG... --model MODEL --json`: `document` (the JSON text) and `corrected`
/// (the corrected model's TOML), for logs given as paths or arrays and a model as (text, source).
#[pyfunction]
pub fn diagnose_run<'py>(
    py: Python<'py>,
    logs: Vec<LogArg<'py>>,
    model_arg: (String, String),
    reader: ReaderArgs,
    settings: DiagnoseArgs,
    check: Vec<LogArg<'py>>,
) -> PyResult<Bound<'py, PyDict>> {
    check_diagnose_args(&settings)?;
    let (model_text, model_name) = model_arg;
    let m = model(&model_text, &model_name)?;
    let logs = logs_of(py, logs, &reader)?;
    let held = if check.is_empty() {
        Vec::new()
    } else {
        logs_of(py, check, &reader)?
    };
    let asked = settings.drift_check || settings.calibration.is_some() || settings.init.is_some();
    let protocol = Protocol {
        calibration: settings
            .calibration
            .as_deref()
            .map(calibration)
            .transpose()?
            .unwrap_or(Calibration::LogMean),
        initialisation: settings
            .init
            .as_deref()
            .map(initialisation)
            .transpose()?
            .unwrap_or(Initialisation::Perfect),
        horizons_s: settings.horizons.clone(),
        overlapping: false,
        latitude_deg: latitude(settings.latitude)?,
    };
    check_logs(&logs, &protocol, &m, &model_name)?;
    check_memory(&logs, settings.threads)?;
    let inputs: Vec<LogInput> = logs.iter().map(|l| l.input(true)).collect();
    let s = diagnose::Settings {
        seed: settings.seed,
        seeds: settings.seeds,
        max_rounds: settings.rounds,
        horizons_s: settings.horizons.clone(),
        min_delta_bic: settings.min_delta_bic,
        tau_min_s: settings.tau_min,
        latitude_deg: protocol.latitude_deg,
        drift_protocol: (asked || logs.len() > 1).then_some(protocol),
        ..diagnose::Settings::default()
    };
    let sources: Vec<String> = logs.iter().map(|l| l.source.clone()).collect();
    let (result, checks) = run_until(py, settings.threads, |stop| {
        let result = match diagnose::diagnose_until(&inputs, &m, &s, &(), stop) {
            Ok(r) => r,
            Err(DiagnoseError::Stopped) => return None,
            Err(e) => {
                return Some(Err(format!(
                    "diagnosing {} against {model_name}: {}",
                    sources.join(", "),
                    diagnose_error(e)
                )))
            }
        };
        let mut checks: HeldOutChecks = Vec::new();
        for h in &held {
            match result.check(&h.input(true)) {
                Ok(gaps) => checks.push((h.source.clone(), gaps)),
                Err(e) => return Some(Err(format!("checking {}: {}", h.source, message(&e)))),
            }
        }
        Some(Ok((result, checks)))
    })?
    .map_err(invalid)?;
    let fitted_on = diagnose::fitted_on::FittedOn::from_logs(&inputs, s.tau_min_s);
    let style = noise::UnitStyle::from_config_text(&model_text);
    let corrected = document::corrected_model_toml(&result, &m, &style, fitted_on.as_ref());
    let doc = document::diagnose_document(
        &result,
        DiagnoseSources {
            logs: &sources,
            columns: logs[0].columns.clone(),
            model: &model_name,
        },
        &corrected,
        &checks,
    )
    .map_err(|e| invalid(format!("cannot serialise the diagnosis: {e}")))?;
    let d = PyDict::new(py);
    d.set_item("document", doc.to_string())?;
    d.set_item("corrected", corrected)?;
    Ok(d)
}

/// `imudrift.drift`'s settings (the CLI's options by their Python names).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct DriftArgs {
    calibration: String,
    init: String,
    horizons: Vec<f64>,
    overlap: bool,
    replicates: usize,
    exact_parameters: bool,
    one_structure: bool,
    seed: u64,
    threads: Option<usize>,
    latitude: Option<f64>,
}

/// `imudrift drift LOG... --model MODEL --json`: the document's text.
#[pyfunction]
pub fn drift_run<'py>(
    py: Python<'py>,
    logs: Vec<LogArg<'py>>,
    model_arg: (String, String),
    reader: ReaderArgs,
    settings: DriftArgs,
) -> PyResult<String> {
    if settings.replicates < 10 || settings.replicates > 100_000 {
        return Err(invalid(format!(
            "replicates {}: expected 10 to 100000 simulated experiments",
            settings.replicates
        )));
    }
    if let Some(h) = settings
        .horizons
        .iter()
        .find(|h| !(h.is_finite() && **h > 0.0))
    {
        return Err(invalid(format!("horizons: expected times > 0, found {h}")));
    }
    let protocol = Protocol {
        calibration: calibration(&settings.calibration)?,
        initialisation: initialisation(&settings.init)?,
        horizons_s: settings.horizons.clone(),
        overlapping: settings.overlap,
        latitude_deg: latitude(settings.latitude)?,
    };
    let (model_text, model_name) = model_arg;
    let m = model(&model_text, &model_name)?;
    let fitted = document::fitted_on_of(&model_text, &model_name, settings.exact_parameters)
        .map_err(|e| invalid(format!("{model_name}: {}", message(&e))))?;
    let alternatives = document::alternatives_of(&model_text, &model_name, settings.one_structure)
        .map_err(|e| invalid(format!("{model_name}: {}", message(&e))))?;
    let logs = logs_of(py, logs, &reader)?;
    check_logs(&logs, &protocol, &m, &model_name)?;
    let inputs: Vec<LogInput> = logs.iter().map(|l| l.input(false)).collect();
    let s = CheckSettings {
        protocol,
        replicates: settings.replicates,
        seed: settings.seed,
    };
    let models = Models {
        model: &m,
        alternatives: &alternatives,
        fitted_on: fitted.as_ref(),
    };
    let result = run_until(py, settings.threads, |stop| {
        match check_drift_until(&inputs, models, &s, &(), stop) {
            Err(CheckError::Stopped) => None,
            r => Some(r),
        }
    })?
    .map_err(|e| {
        let msg = match e {
            CheckError::Replicates(n) => format!(
                "replicates {n}: at least 10 simulated experiments are needed for a 95 % band"
            ),
            e => message(&e),
        };
        invalid(format!(
            "checking the drift of {} log(s) against {model_name}: {msg}",
            logs.len()
        ))
    })?;
    let sources: Vec<String> = logs.iter().map(|l| l.source.clone()).collect();
    let doc = document::drift_document(&result, &sources, &model_name)
        .map_err(|e| invalid(format!("cannot serialise the drift check: {e}")))?;
    Ok(doc.to_string())
}
