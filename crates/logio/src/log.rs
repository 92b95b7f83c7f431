//! The log a reader returns (SI units, channels by name) and the settings a reader is told.

use crate::columns::{ColumnUse, Skipped, Source, UnitOptions};
use crate::error::SettingNames;
use noise::{Channel, Sensor};
use std::collections::BTreeMap;

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
    /// the skipped columns; settings named by `names`.
    pub fn mapping_text(&self, names: SettingNames) -> String {
        let used: Vec<String> = self
            .columns
            .iter()
            .map(|c| {
                let unit_from = c.unit_from.render(names);
                let how = match (c.channel_from, c.unit_from) {
                    (Source::Setting(s), Source::Name) => {
                        format!("{}, unit from the name", names(s))
                    }
                    (Source::Setting(s), _) => format!("{}, unit {unit_from}", names(s)),
                    (_, Source::Name) => "from the name".to_string(),
                    (_, _) => format!("unit {unit_from}"),
                };
                format!("{} -> {} ({}, {how})", c.column, c.channel, c.unit)
            })
            .collect();
        let mut s = format!("columns: {}", used.join("; "));
        if !self.skipped.is_empty() {
            let skipped: Vec<String> = self
                .skipped
                .iter()
                .map(|k| format!("{} ({})", k.column, k.reason_text(names)))
                .collect();
            s.push_str(&format!("\nskipped: {}", skipped.join("; ")));
        }
        s
    }

    /// `columns[]` and `skipped_columns[]` of the commands' JSON (docs/cli.md, "Log files"):
    /// each used column's channel and unit and where they came from, each skipped column's
    /// reason; settings named by `names`.
    pub fn columns_json(&self, names: SettingNames) -> (serde_json::Value, serde_json::Value) {
        let columns = self
            .columns
            .iter()
            .map(|c| {
                serde_json::json!({
                    "column": c.column,
                    "channel": c.channel,
                    "unit": c.unit,
                    "channel_from": c.channel_from.render(names),
                    "unit_from": c.unit_from.render(names),
                })
            })
            .collect();
        let skipped = self
            .skipped
            .iter()
            .map(|s| serde_json::json!({"column": s.column, "reason": s.reason_text(names)}))
            .collect();
        (
            serde_json::Value::Array(columns),
            serde_json::Value::Array(skipped),
        )
    }

    /// SI unit of a channel, for tables and plots.
    pub fn unit_of(name: &str) -> &'static str {
        match Channel::from_name(name).map(Channel::sensor) {
            Some(Sensor::Gyro) => "rad/s",
            Some(Sensor::Accel) => "m/s^2",
            None if name == "temp" => "degC",
            None => "1",
        }
    }
}

/// What the reader is told besides the file: the settings a log's names do not give.
#[derive(Clone, Debug, Default)]
pub struct ReadOptions {
    /// Sample rate, Hz ([`crate::valid_rate_hz`]): required when the log has no time column, checked
    /// against it otherwise.
    pub rate_hz: Option<f64>,
    /// Units of columns whose names do not state one (each applies to every column of its kind).
    pub units: UnitOptions,
    /// (canonical name, file column) pairs: columns mapped by hand.
    pub columns: Vec<(String, String)>,
    /// The sensor_msgs/Imu topic of a bag or MCAP file (default: the only one).
    pub topic: Option<String>,
}
