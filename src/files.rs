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

/// Most bytes of a sensor model, scenario or noise file (16 MiB; the shipped ones are a few KiB):
/// a larger file, or a device or pipe giving more, is refused before it is read.
pub const MAX_CONFIG_BYTES: u64 = 16 << 20;

/// Read a text file of at most `max_bytes` ([`MAX_CONFIG_BYTES`] for a config, [`shard_bytes`]
/// for a shard; `logio::read_capped`: the size of a regular file is checked before a byte is
/// read, a device or a pipe is read with the bound). Errors name the file and what it is read as
/// (`what`); a byte that is not UTF-8 is reported with its line and column (`noise::utf8_text`).
pub fn read_text(path: &Path, what: &str, max_bytes: u64) -> Result<TextFile> {
    let name = path.display().to_string();
    let bytes = logio::read_capped(path, max_bytes)
        .with_context(|| format!("cannot read {name} as {what}"))?;
    let text = noise::utf8_text(bytes, &name)?;
    Ok(TextFile { name, text })
}

/// [`read_text`] of a sensor model, scenario or noise file.
pub fn read_config(path: &Path) -> Result<TextFile> {
    read_text(
        path,
        "a sensor model, scenario or noise file",
        MAX_CONFIG_BYTES,
    )
}

/// Most bytes of shard files read together: a third of the memory available (their text, the
/// values parsed from it and the merged values each take about as much), or 8 GiB when the
/// memory available is not known.
pub fn shard_bytes() -> u64 {
    logio::available_memory_bytes().map_or(8 << 30, |a| a / 3)
}

/// The sensor model of a file read with [`read_config`]: a sensor TOML, or a Kalibr / OpenVINS /
/// VINS-Fusion IMU noise file (`noise::SensorModel::from_text`).
pub fn sensor_model_of(file: &TextFile) -> Result<SensorModel> {
    Ok(SensorModel::from_text(&file.text, &file.name)?)
}

/// Read a sensor model file (see [`sensor_model_of`]).
pub fn sensor_model(path: &Path) -> Result<SensorModel> {
    sensor_model_of(&read_config(path)?)
}
