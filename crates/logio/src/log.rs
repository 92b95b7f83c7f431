//! The log a reader returns (SI units, channels by name) and the settings a reader is told.

use crate::columns::{ColumnUse, Quantity, Skipped, Source, UnitOptions};
use crate::error::SettingNames;
use noise::{Channel, ImuChannels, Sensor};

/// A log in SI units.
#[derive(Clone, Debug)]
pub struct Log {
    /// Where it came from (file name), for messages.
    pub source: String,
    /// Sample rate, Hz.
    pub rate_hz: f64,
    /// Time column, s (if the file had one).
    pub t_s: Option<Vec<f64>>,
    /// The gyro and accelerometer channels the log has, SI units (rad/s, m/s^2).
    pub channels: ImuChannels<Option<Vec<f64>>>,
    /// The temperature column, degC, if the log has one.
    pub temperature_c: Option<Vec<f64>>,
    /// The quantities in file order (without the time).
    pub order: Vec<Quantity>,
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
        self.series().next().map_or(0, |(_, v)| v.len())
    }

    /// A channel's samples, if the log has it.
    pub fn channel(&self, c: Channel) -> Option<&[f64]> {
        self.channels[c].as_deref()
    }

    /// Take a series out of the log (its samples move to the caller).
    pub fn take(&mut self, q: Quantity) -> Option<Vec<f64>> {
        match q {
            Quantity::Imu(c) => self.channels[c].take(),
            Quantity::Temperature => self.temperature_c.take(),
            Quantity::Time => self.t_s.take(),
        }
    }

    /// Every series the log has (channels, then the temperature), with its quantity.
    pub fn series(&self) -> impl Iterator<Item = (Quantity, &[f64])> {
        self.channels
            .iter()
            .filter_map(|(c, v)| Some((Quantity::Imu(c), v.as_deref()?)))
            .chain(
                self.temperature_c
                    .as_deref()
                    .map(|v| (Quantity::Temperature, v)),
            )
    }

    /// The names of the log's quantities in file order (`gx`, `temp`, ...).
    pub fn order_names(&self) -> Vec<&'static str> {
        self.order.iter().map(|q| q.channel()).collect()
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

    /// SI unit of a quantity, for tables and plots.
    pub fn unit_of(q: Quantity) -> &'static str {
        match q {
            Quantity::Imu(c) => match c.sensor() {
                Sensor::Gyro => "rad/s",
                Sensor::Accel => "m/s^2",
            },
            Quantity::Temperature => "degC",
            Quantity::Time => "s",
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

/// Why series given as arrays (a front end's own log, not a file) are not a log.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SeriesError {
    #[error("{source_name}: rate_hz: expected a sample rate in Hz > 0, found {rate_hz}")]
    Rate { source_name: String, rate_hz: f64 },
    #[error("{source_name}: {name:?} is not one of gx, gy, gz, ax, ay, az, temp")]
    Name { source_name: String, name: String },
    #[error("{source_name}: {name} given twice")]
    Twice { source_name: String, name: String },
    #[error("{source_name}: {name}[{index}] is {value:e}: every sample must be finite and of magnitude below {max:e}")]
    Value {
        source_name: String,
        name: String,
        index: usize,
        value: f64,
        max: f64,
    },
    #[error("{source_name}: {name} has {got} samples and {first} has {expected}: every series must have one sample per time step")]
    Length {
        source_name: String,
        name: String,
        got: usize,
        first: String,
        expected: usize,
    },
    #[error("{source_name}: {count} samples: at least 2 are needed")]
    TooShort { source_name: String, count: usize },
}

impl Log {
    /// A log from series a front end holds (named `gx` .. `az`, `temp`, SI units), checked as the
    /// reader checks a file's: the rate, every value finite and below the reader's bound, one
    /// length, at least two samples. Its columns are "from the name" with the SI ("default") unit,
    /// as the reader says of a file with those names.
    pub fn from_series(
        source: &str,
        rate_hz: f64,
        series: Vec<(String, Vec<f64>)>,
    ) -> std::result::Result<Log, SeriesError> {
        let source_name = source.to_string();
        if !crate::valid_rate_hz(rate_hz) {
            return Err(SeriesError::Rate {
                source_name,
                rate_hz,
            });
        }
        let mut log = Log {
            source: source_name.clone(),
            rate_hz,
            t_s: None,
            channels: ImuChannels::default(),
            temperature_c: None,
            order: Vec::new(),
            columns: Vec::new(),
            skipped: Vec::new(),
            topic: None,
        };
        let mut first: Option<(String, usize)> = None;
        for (name, values) in series {
            let quantity = match Quantity::of_channel(&name) {
                Some(q @ (Quantity::Imu(_) | Quantity::Temperature)) => q,
                _ => return Err(SeriesError::Name { source_name, name }),
            };
            if log.order.contains(&quantity) {
                return Err(SeriesError::Twice { source_name, name });
            }
            if let Some(index) = values.iter().position(|&v| !crate::valid_value(v)) {
                return Err(SeriesError::Value {
                    source_name,
                    name,
                    index,
                    value: values[index],
                    max: crate::limits::MAX_ABS_VALUE,
                });
            }
            match &first {
                Some((f, n)) if *n != values.len() => {
                    return Err(SeriesError::Length {
                        source_name,
                        name,
                        got: values.len(),
                        first: f.clone(),
                        expected: *n,
                    })
                }
                Some(_) => {}
                None => first = Some((name.clone(), values.len())),
            }
            log.columns.push(ColumnUse {
                column: name.clone(),
                quantity,
                channel: quantity.channel(),
                unit: Log::unit_of(quantity),
                channel_from: Source::Name,
                unit_from: Source::Default,
                to_si: 1.0,
            });
            log.order.push(quantity);
            match quantity {
                Quantity::Imu(c) => log.channels[c] = Some(values),
                _ => log.temperature_c = Some(values),
            }
        }
        if let Some((_, n)) = first.filter(|(_, n)| *n < 2) {
            return Err(SeriesError::TooShort {
                source_name,
                count: n,
            });
        }
        Ok(log)
    }
}
