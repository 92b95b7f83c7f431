//! imudrift's IMU log reader: CSV or gzip-compressed CSV (`#` comment lines, a header row,
//! columns found by name, units mapped to SI), ROS 1 bags and ROS 2 MCAP files (the
//! `sensor_msgs/Imu` messages of one topic). Any front end (the `imudrift` command, a Python
//! package) reads a log through [`read_log`] with plain [`ReadOptions`].
//!
//! Unlike the other library crates this one does file I/O: reading files is what it is for. It
//! prints nothing.
//!
//! Units: every channel of a [`Log`] is SI (rad/s, m/s^2, s, degC). Canonical columns: `t` (s),
//! `gx gy gz` (rad/s), `ax ay az` (m/s^2), `temp` (degC), in the sensor's own body frame as the
//! log gives it (no frame is changed). Other names are recognised with their unit suffixes
//! (`columns.rs`: `gyro_x_dps`, `acc_x_g`, `angular_velocity.x`, `timestamp_ns`, ...); the
//! column mapping (`ReadOptions::columns`) maps a column by hand; the unit settings give units
//! names do not state; the rate setting gives the sample rate when there is no time column.
//! Columns that are none of these are skipped and listed.
//!
//! Errors ([`LogError`]) name the file, the line (or message) and the column, and say what was
//! expected. They name the reader's settings ([`Setting`]), never a front end's flags: a front
//! end renders them with its own names ([`LogError::render`]).
//!
//! A small CSV log with a time column in seconds, gyro columns in deg/s and accelerometer columns
//! in g, read into SI channels, typed by [`noise::Channel`]:
//!
//! ```
//! use std::io::Write;
//!
//! let mut file = tempfile::Builder::new().suffix(".csv").tempfile().unwrap();
//! writeln!(file, "# a comment line").unwrap();
//! writeln!(file, "t,gyro_x_dps,gyro_y_dps,gyro_z_dps,acc_x_g,acc_y_g,acc_z_g").unwrap();
//! for k in 0..5 {
//!     let t = k as f64 * 0.01;
//!     writeln!(file, "{t},180,0,-90,0,0,-1").unwrap();
//! }
//! file.flush().unwrap();
//! let log = logio::read_log(file.path(), &logio::ReadOptions::default()).unwrap();
//! assert_eq!(log.len(), 5);
//! assert!((log.rate_hz - 100.0).abs() < 1e-9);
//! assert_eq!(log.order_names(), ["gx", "gy", "gz", "ax", "ay", "az"]);
//! let pi = std::f64::consts::PI;
//! let channel = |c| log.channel(c).unwrap();
//! use noise::Channel::{Az, Gx, Gz};
//! assert!(channel(Gx).iter().all(|&w| (w - pi).abs() < 1e-12)); // 180 deg/s
//! assert!(channel(Gz).iter().all(|&w| (w + pi / 2.0).abs() < 1e-12));
//! assert!(channel(Az).iter().all(|&a| (a + 9.80665).abs() < 1e-12)); // -1 g
//! assert!(log.skipped.is_empty());
//! ```

pub mod bag;
mod columns;
mod csv;
mod error;
mod file;
mod float;
mod limits;
mod log;
mod units;

pub use columns::{ColumnUse, Quantity, SkipReason, Skipped, Source, UnitOptions};
pub use csv::parse_log;
pub use error::{byte_size, sig, At, LogError, Problem, Result, Setting, SettingNames};
pub use file::{
    available_memory_bytes, first_block_problem, read_capped, resident_bytes, FIRST_BLOCK_BYTES,
};
pub use limits::{
    has_spread, quote_prefix, spread, valid_rate_hz, valid_value, MAX_ABS_VALUE, MAX_LOG_RATE_HZ,
    MIN_LOG_RATE_HZ, MIN_SPREAD,
};
pub use log::{Log, ReadOptions, SeriesError};
pub use units::{AccelUnit, GyroUnit, TimeUnit};

use file::{check_fits, gunzip, FileBytes};
use noise::{Channel, Sensor};

use std::path::Path;

/// Standard gravity for `g` units (m/s^2): the noise crate's one definition.
pub use noise::units::STANDARD_GRAVITY_MPS2;

/// A bag or MCAP file's IMU topic as a log: channels gx..az in SI (sensor_msgs/Imu is SI by
/// definition, REP 103), times from header.stamp, the same rate and uniformity checks as a CSV.
fn read_bag(path: &Path, format: bag::Format, opts: &ReadOptions) -> Result<Log> {
    let source = path.display().to_string();
    if !opts.columns.is_empty() {
        return Err(LogError::new(&source, Problem::ColumnsInBag));
    }
    let units = opts.units;
    if units.gyro.is_some_and(|u| u != GyroUnit::RadPerS)
        || units.accel.is_some_and(|u| u != AccelUnit::MPerS2)
    {
        return Err(LogError::new(&source, Problem::UnitsInBag));
    }
    let series = bag::read_imu(path, format, opts.topic.as_deref())?;
    let t = series.t_s();
    let topic = series.topic.clone();
    let locate = |k: usize| At::Message {
        topic: topic.clone(),
        index: k + 1,
    };
    let rate_hz = csv::rate_of(Some(&t), opts.rate_hz, &source, &locate)?;
    let mut channels = noise::ImuChannels::<Option<Vec<f64>>>::default();
    let mut order = Vec::new();
    let mut columns = Vec::new();
    let bag::ImuSeries { gyro, accel, .. } = series;
    for (channel, data) in Channel::ALL.into_iter().zip(gyro.into_iter().chain(accel)) {
        let (field, unit) = match channel.sensor() {
            Sensor::Gyro => ("angular_velocity", "rad/s"),
            Sensor::Accel => ("linear_acceleration", "m/s^2"),
        };
        columns.push(ColumnUse {
            column: format!("{topic} {field}.{}", noise::AXIS_NAMES[channel.axis()]),
            quantity: Quantity::Imu(channel),
            channel: channel.name(),
            unit,
            channel_from: Source::ImuMessage,
            unit_from: Source::Rep103,
            to_si: 1.0,
        });
        order.push(Quantity::Imu(channel));
        channels[channel] = Some(data);
    }
    Ok(Log {
        source,
        rate_hz,
        t_s: Some(t),
        channels,
        temperature_c: None,
        order,
        columns,
        skipped: Vec::new(),
        topic: Some(topic),
    })
}

/// Read a log file: CSV, gzip-compressed CSV, a ROS 1 bag or a ROS 2 MCAP file (or a ROS 2 bag
/// directory holding one MCAP file).
pub fn read_log(path: &Path, opts: &ReadOptions) -> Result<Log> {
    // A ROS 2 bag is a directory (metadata.yaml and the storage file): read its one MCAP file.
    if path.is_dir() {
        return read_log(&bag::bag_directory_file(path)?, opts);
    }
    let source = path.display().to_string();
    let raw = FileBytes::open(path)
        .map_err(|e| LogError::new(&source, Problem::Unreadable).caused_by(e))?;
    if let Some(format) = bag::format_of(&raw[..raw.len().min(16)]) {
        drop(raw);
        return read_bag(path, format, opts);
    }
    if opts.topic.is_some() {
        return Err(LogError::new(&source, Problem::TopicInCsv));
    }
    // What the machine can hold: a log and its parsed columns must fit, or the read is refused
    // before it starts rather than ending in an out-of-memory kill.
    let available = available_memory_bytes();
    let gzip = raw.starts_with(&[0x1f, 0x8b]);
    // A binary file, a sparse file or a device of zeros is refused from its first block, before
    // the rest is read (a 10 GiB sparse file was read whole first).
    let first = &raw[..raw.len().min(FIRST_BLOCK_BYTES as usize)];
    if let Some(problem) = first_block_problem(first, false).filter(|_| !gzip) {
        return Err(LogError::content(
            &source,
            format!("{problem} (expected a CSV log with a header such as `t,gx,gy,gz,ax,ay,az`)"),
        ));
    }
    if gzip {
        let out = gunzip(&raw, &source, available)?;
        check_fits(&out, &source, available)?;
        parse_log(&out, &source, opts)
    } else {
        check_fits(&raw, &source, available)?;
        parse_log(&raw, &source, opts)
    }
}

#[cfg(test)]
mod tests;
