//! Reading input files: the one place a command reads a file that is not a log (sensor models,
//! scenarios, shard files; logs are read by `log_input.rs` through the `logio` crate). The
//! libraries parse text and take the file's name for their messages; every error here names the
//! file.

use anyhow::{Context, Result};
use noise::SensorModel;
use std::path::Path;

/// A text file as read: its name as given (for messages) and its text.
pub struct TextFile {
    pub name: String,
    pub text: String,
}

/// Read a text file. Errors name the file; a byte that is not UTF-8 is reported with its line
/// and column (`noise::utf8_text`).
pub fn read_text(path: &Path) -> Result<TextFile> {
    let name = path.display().to_string();
    let bytes = std::fs::read(path).with_context(|| format!("cannot read {name}"))?;
    let text = noise::utf8_text(bytes, &name)?;
    Ok(TextFile { name, text })
}

/// The sensor model of a file read with [`read_text`]: a sensor TOML, or a Kalibr / OpenVINS /
/// VINS-Fusion IMU noise file (`noise::SensorModel::from_text`).
pub fn sensor_model_of(file: &TextFile) -> Result<SensorModel> {
    Ok(SensorModel::from_text(&file.text, &file.name)?)
}

/// Read a sensor model file (see [`sensor_model_of`]).
pub fn sensor_model(path: &Path) -> Result<SensorModel> {
    sensor_model_of(&read_text(path)?)
}
