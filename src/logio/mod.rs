#![allow(dead_code)] // shared reader: parts are used by diagnose and simulate
//! IMU log reader shared by `allan`, `diagnose` and `simulate`: CSV or gzip-compressed CSV,
//! `#` comment lines, a header row, columns found by name, units mapped to SI.
//!
//! Canonical columns (docs/cli.md): `t` (s), `gx gy gz` (rad/s), `ax ay az` (m/s^2), `temp` (degC).
//! Other names are recognised with their unit suffixes (`columns.rs`: `gyro_x_dps`, `acc_x_g`,
//! `angular_velocity.x`, `timestamp_ns`, ...); `--col gx=NAME` maps a column by hand;
//! `--gyro-unit`, `--accel-unit`, `--time-unit` give units names do not state; `--rate HZ` gives
//! the sample rate when there is no time column. Columns that are none of these are skipped and
//! listed.
//! Errors name the file, the line and the column, and say what was expected.

mod args;
pub mod bag;
mod columns;
mod csv;
mod file;
mod float;
mod units;

pub use args::LogArgs;
pub use columns::{ColumnUse, Skipped, UnitOptions};
pub use csv::parse_log;
pub use file::available_memory_bytes;
pub use units::{AccelUnit, GyroUnit, TimeUnit};

use anyhow::{bail, Context, Result};
use file::{check_fits, FileBytes, GIB};
use std::collections::BTreeMap;
use std::io::Read;
use std::path::Path;

/// Standard gravity for `g` units (m/s^2): the noise crate's one definition.
pub use noise::units::STANDARD_GRAVITY_MPS2;

/// Canonical gyro channel names.
pub const GYRO_CHANNELS: [&str; 3] = [
    noise::CHANNEL_NAMES[0],
    noise::CHANNEL_NAMES[1],
    noise::CHANNEL_NAMES[2],
];
/// Canonical accelerometer channel names.
pub const ACCEL_CHANNELS: [&str; 3] = [
    noise::CHANNEL_NAMES[3],
    noise::CHANNEL_NAMES[4],
    noise::CHANNEL_NAMES[5],
];

/// A log in SI units.
#[derive(Clone, Debug)]
pub struct Log {
    /// Where it came from (file name), for messages.
    pub source: String,
    /// Sample rate, Hz.
    pub rate_hz: f64,
    /// Time column, s (if the file had one).
    pub t_s: Option<Vec<f64>>,
    /// Channels by name (canonical where mapped), SI units for gyro and accel channels.
    pub channels: BTreeMap<String, Vec<f64>>,
    /// Channel names in file order (without `t`).
    pub order: Vec<String>,
    /// How each used column was mapped (file order, `t` included).
    pub columns: Vec<ColumnUse>,
    /// Columns not used, with the reason.
    pub skipped: Vec<Skipped>,
    /// The sensor_msgs/Imu topic, for a bag or MCAP file.
    pub topic: Option<String>,
}

impl Log {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.channels.values().next().map_or(0, Vec::len)
    }

    /// Whether the log has no samples (never true for a log `read_log` returns).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Sample interval, s.
    pub fn dt_s(&self) -> f64 {
        1.0 / self.rate_hz
    }

    /// The column mapping in one line for people: `gyro_x_dps -> gx (deg/s, from the name)`, and
    /// the skipped columns.
    pub fn mapping_text(&self) -> String {
        let used: Vec<String> = self
            .columns
            .iter()
            .map(|c| {
                let how = match (c.channel_from, c.unit_from) {
                    ("--col", "name") => "--col, unit from the name".to_string(),
                    ("--col", u) => format!("--col, unit {u}"),
                    (_, "name") => "from the name".to_string(),
                    (_, u) => format!("unit {u}"),
                };
                format!("{} -> {} ({}, {how})", c.column, c.channel, c.unit)
            })
            .collect();
        let mut s = format!("columns: {}", used.join("; "));
        if !self.skipped.is_empty() {
            let skipped: Vec<String> = self
                .skipped
                .iter()
                .map(|k| format!("{} ({})", k.column, k.reason))
                .collect();
            s.push_str(&format!("\nskipped: {}", skipped.join("; ")));
        }
        s
    }

    /// SI unit of a channel, for tables and plots.
    pub fn unit_of(name: &str) -> &'static str {
        if GYRO_CHANNELS.contains(&name) {
            "rad/s"
        } else if ACCEL_CHANNELS.contains(&name) {
            "m/s^2"
        } else if name == "temp" {
            "degC"
        } else {
            "1"
        }
    }
}

/// Reader options.
#[derive(Clone, Debug, Default)]
pub struct ReadOptions {
    pub rate_hz: Option<f64>,
    /// Units the command line gives (each applies to every column of its kind whose name does
    /// not state one).
    pub units: UnitOptions,
    /// (canonical name, file column) pairs.
    pub columns: Vec<(String, String)>,
    /// The sensor_msgs/Imu topic of a bag or MCAP file (default: the only one).
    pub topic: Option<String>,
}

/// A bag or MCAP file's IMU topic as a log: channels gx..az in SI (sensor_msgs/Imu is SI by
/// definition, REP 103), times from header.stamp, the same rate and uniformity checks as a CSV.
fn read_bag(path: &Path, format: bag::Format, opts: &ReadOptions) -> Result<Log> {
    let source = path.display().to_string();
    if !opts.columns.is_empty() {
        bail!("{source}: --col maps CSV columns; a bag's sensor_msgs/Imu fields are always angular_velocity and linear_acceleration");
    }
    let units = opts.units;
    if units.gyro.is_some_and(|u| u != GyroUnit::RadPerS)
        || units.accel.is_some_and(|u| u != AccelUnit::MPerS2)
    {
        bail!("{source}: sensor_msgs/Imu is in rad/s and m/s^2 (ROS REP 103); leave --gyro-unit and --accel-unit out");
    }
    let series = bag::read_imu(path, format, opts.topic.as_deref())?;
    let t = series.t_s();
    let topic = series.topic.clone();
    let locate = |k: usize| format!("{source}: topic {topic} message {}", k + 1);
    let rate_hz = csv::rate_of(Some(&t), opts.rate_hz, &source, &locate)?;
    let mut channels = BTreeMap::new();
    let mut order = Vec::new();
    let mut columns = Vec::new();
    let [gx, gy, gz] = series.gyro;
    let [ax, ay, az] = series.accel;
    for (i, data) in [gx, gy, gz, ax, ay, az].into_iter().enumerate() {
        let name = noise::CHANNEL_NAMES[i];
        let field = if i < 3 {
            "angular_velocity"
        } else {
            "linear_acceleration"
        };
        columns.push(ColumnUse {
            column: format!("{topic} {field}.{}", ["x", "y", "z"][i % 3]),
            channel: name,
            unit: if i < 3 { "rad/s" } else { "m/s^2" },
            channel_from: "sensor_msgs/Imu",
            unit_from: "REP 103",
            to_si: 1.0,
        });
        order.push(name.to_string());
        channels.insert(name.to_string(), data);
    }
    Ok(Log {
        source,
        rate_hz,
        t_s: Some(t),
        channels,
        order,
        columns,
        skipped: Vec::new(),
        topic: Some(topic),
    })
}

/// Read a log file: CSV, gzip-compressed CSV, a ROS 1 bag or a ROS 2 MCAP file.
pub fn read_log(path: &Path, opts: &ReadOptions) -> Result<Log> {
    // A ROS 2 bag is a directory (metadata.yaml and the storage file): read its one MCAP file.
    if path.is_dir() {
        return read_log(&bag::bag_directory_file(path)?, opts);
    }
    let source = path.display().to_string();
    let raw = FileBytes::open(path).with_context(|| format!("cannot read {source}"))?;
    if let Some(format) = bag::format_of(&raw[..raw.len().min(16)]) {
        drop(raw);
        return read_bag(path, format, opts);
    }
    if opts.topic.is_some() {
        bail!("{source}: --topic applies to ROS bags and MCAP files; this is a CSV log");
    }
    // What the machine can hold: a log and its parsed columns must fit, or the read is refused
    // before it starts rather than ending in an out-of-memory kill.
    let available = available_memory_bytes();
    if raw.starts_with(&[0x1f, 0x8b]) {
        let limit = available.map_or(u64::MAX, |a| a / 3);
        let mut out = Vec::with_capacity(raw.len().saturating_mul(4).min(limit as usize));
        flate2::read::MultiGzDecoder::new(&raw[..])
            .take(limit)
            .read_to_end(&mut out)
            .with_context(|| format!("{source}: not a valid gzip file"))?;
        if out.len() as u64 == limit {
            bail!(
                "{source}: decompresses to more than {:.1} GiB, a third of the memory available ({:.1} GiB): split the log or analyse it on a larger machine",
                limit as f64 / GIB,
                available.unwrap_or(0) as f64 / GIB
            );
        }
        check_fits(&out, &source, available)?;
        parse_log(&out, &source, opts)
    } else {
        check_fits(&raw, &source, available)?;
        parse_log(&raw, &source, opts)
    }
}

#[cfg(test)]
mod tests;
