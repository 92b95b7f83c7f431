//! `imudrift.Sensor`: a sensor model read by the library's reader (`noise::SensorModel::from_text`:
//! a sensor TOML, or a Kalibr / OpenVINS / VINS-Fusion noise file), written back as TOML
//! (`SensorModel::to_toml_string`) or as a noise file (`noise::noise_file`).

use crate::invalid;
use crate::sim::message;
use noise::noise_file::{axis_noise_values, write_noise_file, Flavor, Inflation, NoiseValues};
use noise::SensorModel;
use pyo3::prelude::*;
use pyo3::types::PyDict;

fn model(text: &str, source: &str) -> PyResult<SensorModel> {
    SensorModel::from_text(text, source).map_err(|e| invalid(message(&e)))
}

/// The (text, source name) of a sensor model named by one argument: a path object (`is_path`) is
/// read as a file; a text as `request::files::SensorSource::of_argument` says (an existing path
/// is the file, a directory one that cannot be read; a line that is neither a path nor a
/// model's text is a missing file). Each file is read with the CLI's size bound; one that cannot
/// be read is a `LogUnreadable` (an `OSError`) naming it.
#[pyfunction]
pub fn sensor_source(arg: &str, is_path: bool) -> PyResult<(String, String)> {
    let source = if is_path {
        request::SensorSource::Path(arg.into())
    } else {
        request::SensorSource::of_argument(arg).map_err(crate::sim::request_error)?
    };
    let file = source
        .read()
        .map_err(|e| crate::sim::request_error(e.into()))?;
    Ok((file.text, file.name))
}

/// The model of a text (checked as the CLI checks it): its `name` and its canonical `toml`.
#[pyfunction]
pub fn sensor_parse<'py>(
    py: Python<'py>,
    text: &str,
    source: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let m = model(text, source)?;
    let d = PyDict::new(py);
    d.set_item("name", &m.name)?;
    d.set_item("toml", m.to_toml_string())?;
    Ok(d)
}

/// The TOML text of a sensor given as a dict (its JSON text): the same keys and values as the
/// TOML file (docs/model.md).
#[pyfunction]
pub fn sensor_toml_of_json(json: &str) -> PyResult<String> {
    let value: serde_json::Value =
        serde_json::from_str(json).map_err(|e| invalid(format!("sensor dict: {e}")))?;
    let table = toml::Value::try_from(value).map_err(|e| {
        invalid(format!(
            "sensor dict: not a TOML document ({e}); None has no TOML form"
        ))
    })?;
    toml::to_string(&table).map_err(|e| invalid(format!("sensor dict: {e}")))
}

/// Longest averaging time over which a model without a rate random walk is bounded by one (s).
const BOUND_TAU_MAX_S: f64 = 1e4;

/// The noise file of a model (`flavor` kalibr, openvins or vins-fusion) at sample rate `rate_hz`:
/// per axis the white-noise density and the rate random walk, or where the model has none the
/// largest one its Allan curve allows at octave averaging times from 1 / rate to 1e4 s.
#[pyfunction]
pub fn sensor_noise_file(
    text: &str,
    source: &str,
    flavor: &str,
    rate_hz: f64,
    rostopic: &str,
) -> PyResult<String> {
    let flavor = match flavor {
        "kalibr" => Flavor::Kalibr,
        "openvins" => Flavor::OpenVins,
        "vins-fusion" => Flavor::VinsFusion,
        _ => {
            return Err(invalid(format!(
                "flavor {flavor:?}: expected \"kalibr\", \"openvins\" or \"vins-fusion\""
            )))
        }
    };
    if !(rate_hz.is_finite() && rate_hz > 0.0) {
        return Err(invalid(format!(
            "rate_hz: expected a sample rate in Hz > 0, found {rate_hz}"
        )));
    }
    let m = model(text, source)?;
    let taus: Vec<f64> = (0..64)
        .map(|k| 2f64.powi(k) / rate_hz)
        .take_while(|&t| t <= BOUND_TAU_MAX_S)
        .collect();
    let how_tau = |t: f64| format!("{t} s");
    let per: Vec<_> = noise::Channel::ALL
        .iter()
        .map(|c| {
            axis_noise_values(
                m.axis(c.sensor(), c.axis()),
                &taus,
                "sensor model",
                &how_tau,
            )
            .ok_or_else(|| {
                invalid(format!(
                    "{source}: channel {} has no white noise: a noise file needs a noise density",
                    c.name()
                ))
            })
        })
        .collect::<PyResult<_>>()?;
    let values = NoiseValues::from_channels(
        |c| per[c.index()].clone(),
        rostopic.to_string(),
        rate_hz,
        format!("the sensor model {} ({source})", m.name),
    );
    Ok(write_noise_file(&values, flavor, Inflation::NONE))
}

/// `imudrift plan SENSOR --json`: the log plan of a model (`diagnose::log_plan`), as its JSON text.
#[pyfunction]
pub fn sensor_plan(
    text: &str,
    source: &str,
    uncertainty: f64,
    duration_s: Option<f64>,
    rate_hz: f64,
) -> PyResult<String> {
    use diagnose::log_plan::{MAX_DURATION_S, MAX_RATE_HZ, MIN_RATE_HZ};
    let m = model(text, source)?;
    if !(uncertainty.is_finite() && uncertainty > 0.0 && uncertainty < 1.0) {
        return Err(invalid(format!(
            "uncertainty: expected a fraction in (0, 1) or a percentage such as \"10%\", found {uncertainty}"
        )));
    }
    if !(rate_hz.is_finite() && (MIN_RATE_HZ..=MAX_RATE_HZ).contains(&rate_hz)) {
        return Err(invalid(format!(
            "rate_hz: expected {MIN_RATE_HZ} to {MAX_RATE_HZ} Hz, found {rate_hz}"
        )));
    }
    if let Some(d) = duration_s {
        if !(d.is_finite() && d <= MAX_DURATION_S && d * rate_hz >= 3.0) {
            return Err(invalid(format!(
                "duration_s: expected at least 3 samples and at most {MAX_DURATION_S:e} s (about 300 years), found {d:e} s"
            )));
        }
    }
    let doc = diagnose::log_plan::plan(&m, rate_hz, uncertainty, duration_s).ok_or_else(|| {
        invalid(format!(
            "{source}: the model has no white noise, bias instability or rate random walk to plan for"
        ))
    })?;
    serde_json::to_string(&doc).map_err(|e| invalid(format!("plan: {e}")))
}
