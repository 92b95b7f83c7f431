//! Reading input files that are not logs (sensor models, scenarios, shard files) through the
//! request layer (`request::files`: each with its size bound, errors naming the file); logs are
//! read by `log_input.rs` through the `logio` crate.

use anyhow::Result;
use noise::SensorModel;
use std::path::Path;

pub use request::files::{shard_bytes, TextFile, MAX_CONFIG_BYTES};

/// Read a text file of at most `max_bytes` (`request::files::read_text`).
pub fn read_text(path: &Path, what: &'static str, max_bytes: u64) -> Result<TextFile> {
    Ok(request::files::read_text(path, what, max_bytes)?)
}

/// A sensor model, scenario or noise file.
pub fn read_config(path: &Path) -> Result<TextFile> {
    Ok(request::files::read_config(path)?)
}

/// The sensor model of a file read with [`read_config`]: a sensor TOML, or a Kalibr / OpenVINS /
/// VINS-Fusion IMU noise file (`noise::SensorModel::from_text`).
pub fn sensor_model_of(file: &TextFile) -> Result<SensorModel> {
    Ok(request::files::model_of(file)?)
}

/// Read a sensor model file (see [`sensor_model_of`]).
pub fn sensor_model(path: &Path) -> Result<SensorModel> {
    sensor_model_of(&read_config(path)?)
}
