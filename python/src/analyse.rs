//! `imudrift.spec`, `imudrift.diagnose` and `imudrift.drift`: the CLI's `spec`, `diagnose` and
//! `drift` through the same library code (`montecarlo::spec_job`, `diagnose::document`), each
//! returning the text of the command's `--json` document. The work runs with the GIL released
//! in a thread pool of the call's own. Ctrl-C: the calling thread checks Python's signals every
//! 100 ms and a pending `KeyboardInterrupt` sets the stop flag the libraries check
//! (`montecarlo::run_range_until`'s `AtomicBool`): `spec`'s drift runs ([`crate::sim::run_job`]),
//! `diagnose` (`diagnose::diagnose_until`) and `drift` (`drift_check::check_drift_until`) stop
//! within a second ([`crate::sim::run_until`]); `spec`'s readback has no stop and ends first.

use crate::sim::{
    argument, check_experiment_size, detached, message, request_error, run_job, run_until, terms,
};
use crate::{invalid, read_log_file, read_options, ReaderArgs};
use diagnose::document::{self, DiagnoseSources, HeldOutChecks, ProtocolSetting};
use diagnose::drift_check::{check_drift_until, CheckError, Models};
use diagnose::protocol::{Calibration, Initialisation, Protocol};
use diagnose::{DiagnoseError, LogInput};
use montecarlo::spec_job::{self, SpecDoc, SpecError, SpecRequest, SpecSetting, SpecSettings};
use noise::SensorModel;
use numpy::PyReadonlyArray1;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use request::diagnose::{DiagnoseRequest, DriftRequest, Earth, ModelUnderTest, ProtocolRequest};
use std::path::PathBuf;

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
    log: logio::Log,
    columns: (serde_json::Value, serde_json::Value),
}

impl OwnedLog {
    fn len(&self) -> usize {
        self.log.len()
    }

    fn input(&self, temperature: bool) -> LogInput<'_> {
        request::logs::log_input(&self.log, temperature)
    }
}

/// Read or take each log, refusing one without a gyro or accelerometer channel, with a constant
/// channel, or with samples that are not finite (`request::logs`).
fn logs_of(py: Python<'_>, logs: Vec<LogArg<'_>>, reader: &ReaderArgs) -> PyResult<Vec<OwnedLog>> {
    let opts = read_options(reader)?;
    let mut out = Vec::new();
    for log in logs {
        let log = match log {
            LogArg::Path(path) => detached(py, || read_log_file(&path, &opts))??,
            LogArg::Arrays(a) => array_log(a)?,
        };
        request::logs::check_imu(&log).map_err(crate::sim::request_error)?;
        let columns = log.columns_json(&crate::read_log_argument);
        out.push(OwnedLog { log, columns });
    }
    if out.is_empty() {
        return Err(invalid("logs: expected at least one log".into()));
    }
    request::logs::refuse_repeated(out.iter().map(|l| &l.log))
        .map_err(crate::sim::request_error)?;
    Ok(out)
}

/// A log given as arrays: its channels named as the reader names them, in SI; its columns are
/// "from the name" with the "default" (SI) unit, as the reader says of such a file.
fn array_log(a: ArrayLog<'_>) -> PyResult<logio::Log> {
    let mut series = Vec::new();
    for (name, array) in &a.channels {
        let v = array
            .as_slice()
            .map_err(|_| {
                invalid(format!(
                    "{}: {name}: expected a 1-D float64 array",
                    a.source
                ))
            })?
            .to_vec();
        series.push((name.clone(), v));
    }
    request::logs::from_series(&a.source, a.rate_hz, series).map_err(crate::sim::request_error)
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
    let dt_s = 1.0 / logs[0].log.rate_hz;
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
    request::diagnose::check_simulation_memory(&logs[0].log.source, longest, threads)
        .map_err(request_error)
}

/// `imudrift.diagnose`'s settings (the CLI's options by their Python names).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct DiagnoseArgs {
    seed: Option<u64>,
    seeds: Option<usize>,
    rounds: Option<usize>,
    horizons: Option<Vec<f64>>,
    min_delta_bic: Option<f64>,
    tau_min: Option<f64>,
    drift_check: bool,
    calibration: Option<String>,
    init: Option<String>,
    threads: Option<usize>,
    latitude: Option<f64>,
}

/// `latitude` (deg), or None for Woodman's flat Earth, as the CLI's `--latitude` /
/// `--flat-earth`.
fn earth(value: Option<f64>) -> Earth {
    value.map_or(Earth::Flat, Earth::Latitude)
}

/// The protocol's settings as the request layer takes them.
fn protocol_request(
    calibration_text: Option<&str>,
    init_text: Option<&str>,
    horizons_s: Option<Vec<f64>>,
    overlapping: bool,
    latitude: Option<f64>,
) -> PyResult<ProtocolRequest> {
    Ok(ProtocolRequest {
        calibration: calibration_text.map(calibration).transpose()?,
        initialisation: init_text.map(initialisation).transpose()?,
        horizons_s,
        overlapping,
        earth: earth(latitude),
    })
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
    let request = DiagnoseRequest {
        logs: logs.len(),
        seed: settings.seed,
        seeds: settings.seeds,
        rounds: settings.rounds,
        min_delta_bic: settings.min_delta_bic,
        tau_min_s: settings.tau_min,
        drift_check: settings.drift_check,
        protocol: protocol_request(
            settings.calibration.as_deref(),
            settings.init.as_deref(),
            settings.horizons.clone(),
            false,
            settings.latitude,
        )?,
    };
    let s = request.validate().map_err(request_error)?;
    let protocol = request
        .protocol
        .protocol(&s.horizons_s)
        .map_err(request_error)?;
    let (model_text, model_name) = model_arg;
    let m = model(&model_text, &model_name)?;
    let logs = logs_of(py, logs, &reader)?;
    let held = if check.is_empty() {
        Vec::new()
    } else {
        logs_of(py, check, &reader)?
    };
    check_logs(&logs, &protocol, &m, &model_name)?;
    check_memory(&logs, settings.threads)?;
    let inputs: Vec<LogInput> = logs.iter().map(|l| l.input(true)).collect();
    let sources: Vec<String> = logs.iter().map(|l| l.log.source.clone()).collect();
    let (result, checks) = run_until(py, settings.threads, |stop| {
        let result = match diagnose::diagnose_until(&inputs, &m, &s, &(), stop) {
            Ok(r) => r,
            Err(DiagnoseError::Stopped) => return None,
            Err(e) => {
                return Some(Err(format!(
                    "diagnosing {} against {model_name}: {}",
                    sources.join(", "),
                    request::diagnose::diagnose_error(&e, &argument)
                )))
            }
        };
        let mut checks: HeldOutChecks = Vec::new();
        for h in &held {
            match result.check(&h.input(true)) {
                Ok(gaps) => checks.push((h.log.source.clone(), gaps)),
                Err(e) => return Some(Err(format!("checking {}: {}", h.log.source, message(&e)))),
            }
        }
        Some(Ok((result, checks)))
    })?
    .map_err(invalid)?;
    let fitted_on = result.fitted_on(&inputs);
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
    d.set_item(
        "corrected_source",
        request::diagnose::diagnosed_model_name(&model_name),
    )?;
    Ok(d)
}

/// `imudrift.drift`'s settings (the CLI's options by their Python names).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct DriftArgs {
    calibration: Option<String>,
    init: Option<String>,
    horizons: Option<Vec<f64>>,
    overlap: bool,
    replicates: Option<usize>,
    exact_parameters: bool,
    one_structure: bool,
    seed: Option<u64>,
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
    let s = DriftRequest {
        protocol: protocol_request(
            settings.calibration.as_deref(),
            settings.init.as_deref(),
            settings.horizons.clone(),
            settings.overlap,
            settings.latitude,
        )?,
        replicates: settings.replicates,
        seed: settings.seed,
    }
    .validate()
    .map_err(request_error)?;
    let protocol = &s.protocol;
    let (model_text, model_name) = model_arg;
    let ModelUnderTest {
        model: m,
        fitted_on: fitted,
        alternatives,
    } = ModelUnderTest::read(
        &request::TextFile {
            name: model_name.clone(),
            text: model_text,
        },
        settings.exact_parameters,
        settings.one_structure,
    )
    .map_err(request_error)?;
    let logs = logs_of(py, logs, &reader)?;
    check_logs(&logs, protocol, &m, &model_name)?;
    let inputs: Vec<LogInput> = logs.iter().map(|l| l.input(false)).collect();
    let models = Models::fitted(&m, &alternatives, fitted.as_ref());
    let result = run_until(py, settings.threads, |stop| {
        match check_drift_until(&inputs, models, &s, &(), stop) {
            Err(CheckError::Stopped) => None,
            r => Some(r),
        }
    })?
    .map_err(|e| {
        let msg = request::diagnose::check_error(&e, &argument);
        invalid(format!(
            "checking the drift of {} log(s) against {model_name}: {msg}",
            logs.len()
        ))
    })?;
    let sources: Vec<String> = logs.iter().map(|l| l.log.source.clone()).collect();
    let doc = document::drift_document(&result, &sources, &model_name)
        .map_err(|e| invalid(format!("cannot serialise the drift check: {e}")))?;
    Ok(doc.to_string())
}
