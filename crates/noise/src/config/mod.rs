//! Sensor configs in TOML, with units as spec sheets write them, converted into validated SI models.
//!
//! ```toml
//! name = "Xsens MTx"
//! [temperature]                 # optional: constant 25 degC
//! profile = "warmup"            # constant (value) | ramp (start, rate, end?) | warmup (start, end, time_constant) | sinusoid (mean, amplitude, period) | step (start, end, at)
//! start = "20 degC"
//! end = "35 degC"
//! time_constant = "600 s"
//! reference = "25 degC"         # temperature_bias is zero here
//! [gyro.all]                    # every axis, unless the axis table sets the same key
//! white_noise = "0.075 deg/sqrt(s)"
//! [gyro.x]
//! bias_instability = { value = "0.010 deg/s", convention = "allan_minimum" }
//! ```
//! Axis keys: the name of each effect ([`crate::Effect::name`]), read by its own type
//! (`terms/<effect>.rs`, [`crate::TermKind::from_raw`], which documents the key's form; the keys
//! and their units are listed in docs/model.md §2, §2.2). An axis table with another key is an
//! error naming the keys there are.
//!
//! `bias_instability` states its convention (docs/architecture.md, Units):
//! - `{ value, convention = "ieee" }`: value is the IEEE coefficient B (Allan plateau 0.664 B);
//! - `{ value, convention = "allan_minimum" }`: value is the minimum of the axis' Allan deviation, as
//!   Woodman (TR-696 §5.1) and many spec sheets report it; B is solved so that the closed-form Allan
//!   deviation of the whole axis model (white noise, random walks ... included) has that minimum over
//!   the flicker band's plateau, averaging times [30 tau_min, tau_max / 30] (3 s .. 3333 s by default);
//! - `{ model = "random_walk", stability, period }`: Woodman's bias random walk (eq 9).
//!
//! Flicker options: `band = ["0.1 s", "1e5 s"]` (correlation times), `per_decade = 1`.

mod convert;
pub(crate) mod error;
mod raw;
pub(crate) mod read;
mod write;

pub use error::ConfigError;
pub use write::UnitStyle;

use crate::effect::Sensor;
use crate::model::*;
use convert::{convert_temperature, convert_triad};
use raw::RawSensor;
use read::Ctx;

impl SensorModel {
    /// Parse and validate a sensor config. `source_name` (usually the file path) appears in errors.
    pub fn from_toml_str(text: &str, source_name: &str) -> Result<SensorModel, ConfigError> {
        let raw: RawSensor = toml::from_str(text).map_err(|e| ConfigError::Parse {
            file: source_name.to_string(),
            message: with_shape_hint(e.to_string().trim_end()),
        })?;
        let ctx = Ctx {
            file: source_name,
            source: text,
        };
        let (temperature, reference) = convert_temperature(&ctx, raw.temperature.as_ref())?;
        let gyro = convert_triad(&ctx, Sensor::Gyro, raw.gyro.unwrap_or_default())?;
        let accel = convert_triad(&ctx, Sensor::Accel, raw.accel.unwrap_or_default())?;
        Ok(SensorModel {
            name: raw.name,
            description: raw.description,
            gyro,
            accel,
            temperature,
            temperature_reference_c: reference,
        })
    }

    /// A sensor TOML, or a Kalibr / OpenVINS / VINS-Fusion IMU noise file (accepted wherever a
    /// sensor TOML is): a `.yaml` / `.yml` `source`, or text with their keys that is not TOML.
    /// The library reads no files: the front end reads the file and passes its text and name.
    pub fn from_text(text: &str, source: &str) -> Result<SensorModel, ConfigError> {
        if is_noise_file_text(text, source) {
            return Ok(crate::noise_file::read_noise_file(text, source)?);
        }
        SensorModel::from_toml_str(text, source)
    }
}

/// Is this a noise file rather than a sensor TOML (by its name, or by its keys when not TOML)?
pub fn is_noise_file_text(text: &str, source: &str) -> bool {
    let yaml = source.ends_with(".yaml") || source.ends_with(".yml");
    yaml || (crate::noise_file::is_noise_file(text) && text.parse::<toml::Table>().is_err())
}

/// A config file's text; a byte that is not UTF-8 is an error naming its line and column.
pub fn utf8_text(bytes: Vec<u8>, file: &str) -> Result<String, ConfigError> {
    String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let before = &e.as_bytes()[..at];
        let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
        let column = at - before.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1) + 1;
        ConfigError::Parse {
            file: file.to_string(),
            message: format!(
                "line {line}, column {column}: byte 0x{:02x} is not UTF-8; save the file as UTF-8 text",
                e.as_bytes()[at]
            ),
        }
    })
}

/// A TOML error about a value of the wrong shape, with the accepted form and an example added:
/// numbers need their unit, so a bare number is the commonest mistake.
fn with_shape_hint(message: &str) -> String {
    if message.contains("missing field `name`") {
        return format!("{message}\n  a sensor file starts with its name, e.g. name = \"My IMU\"");
    }
    if message.contains("expected i64") {
        return format!(
            "{message}\n  counts (taps, decimation, per_decade) are whole numbers without quotes, e.g. output_filter = {{ kind = \"bartlett\", taps = 8, decimation = 4 }}"
        );
    }
    if !message.contains("expected a string") {
        return message.to_string();
    }
    // toml quotes the offending line as "N | key = value".
    let key = message
        .lines()
        .find_map(|l| l.split_once(" | ").map(|(_, rest)| rest))
        .and_then(|rest| rest.split('=').next())
        .map(|k| k.trim().trim_matches('"'))
        .unwrap_or("");
    // An axis key's example comes from its term (`TermKind::EXAMPLE`).
    let example = match key {
        "name" => Some("name = \"My IMU\""),
        _ => crate::terms::Effect::from_name(key).and_then(|e| e.example()),
    }
    .map_or("e.g. \"0.05 deg/s\"".to_string(), |e| format!("e.g. {e}"));
    format!(
        "{message}\n  values carry their unit in a string, as spec sheets write them: {example}"
    )
}

#[cfg(test)]
mod tests;
