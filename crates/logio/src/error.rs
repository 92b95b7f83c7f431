//! The reader's errors: where (file, line or message, column) and what, in words that name the
//! reader's settings ([`Setting`], the fields of `ReadOptions`) and never a front end's flags; a
//! front end renders them with its own names through [`LogError::render`].

use crate::limits::{MAX_LOG_RATE_HZ, MIN_LOG_RATE_HZ};
use crate::units::{AccelUnit, GyroUnit, TimeUnit};
use noise::Sensor;

/// A setting of the reader (a field of `ReadOptions`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Setting {
    /// `rate_hz`: the sample rate.
    Rate,
    /// `columns`: channel = file column pairs given by hand.
    Columns,
    /// `units.gyro`: the unit of gyro columns whose names do not state one.
    GyroUnit,
    /// `units.accel`: the same for accelerometer columns.
    AccelUnit,
    /// `units.time`: the same for the time column.
    TimeUnit,
    /// `topic`: the sensor_msgs/Imu topic of a bag or MCAP file.
    Topic,
}

impl Setting {
    /// The setting's name in `ReadOptions`, as the reader's own messages write it.
    pub fn name(self) -> &'static str {
        match self {
            Setting::Rate => "rate_hz",
            Setting::Columns => "columns",
            Setting::GyroUnit => "units.gyro",
            Setting::AccelUnit => "units.accel",
            Setting::TimeUnit => "units.time",
            Setting::Topic => "topic",
        }
    }
}

/// How a message names a setting: [`Setting::name`], or a front end's own words (its flags).
pub type SettingNames<'a> = &'a dyn Fn(Setting) -> &'static str;

/// Where in a log.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum At {
    /// A 1-based line of a text log.
    Line(usize),
    /// The 1-based message of a bag's or MCAP file's topic.
    Message { topic: String, index: usize },
}

/// What is wrong. The variants that involve a setting are typed so that a front end can name
/// it; everything else is said in words ([`Problem::Content`]).
#[derive(Clone, Debug, PartialEq)]
pub enum Problem {
    /// The file cannot be opened or read (the cause says why).
    Unreadable,
    /// The directory cannot be listed.
    UnreadableDirectory,
    /// The file cannot be mapped into memory.
    Unmappable,
    /// Anything about the file's content or size that no setting changes.
    Content(String),
    /// The sample rate setting is not a rate a log can have.
    BadRate { rate_hz: f64 },
    /// A column mapping was given for a bag, whose fields are fixed.
    ColumnsInBag,
    /// A unit other than the SI one was given for a bag (REP 103 fixes them).
    UnitsInBag,
    /// A topic was given for a CSV log.
    TopicInCsv,
    /// A column mapping names a column the header does not have.
    MappedColumnMissing {
        channel: String,
        column: String,
        header: Vec<String>,
    },
    /// A column's name states one unit and the setting another.
    UnitConflict {
        column: String,
        from_name: &'static str,
        setting: Setting,
        given: &'static str,
    },
    /// Gyro or accelerometer columns whose unit nothing states.
    UnitMissing { columns: Vec<(String, Sensor)> },
    /// No gyro or accelerometer column among these.
    NoImuColumn { header: Vec<String> },
    /// The rate setting and the time column disagree.
    RateDisagrees { rate_hz: f64, from_t_hz: f64 },
    /// Neither a time column nor a rate.
    NoRate,
    /// The time column's steps are too small for seconds.
    TimeStepTooSmall { median_s: f64 },
    /// The topic asked for is not an IMU topic of the file.
    NoSuchTopic {
        topic: String,
        imu_type: &'static str,
        topics: String,
    },
    /// Several IMU topics and none chosen.
    SeveralTopics {
        imu_type: &'static str,
        topics: Vec<String>,
    },
}

impl Problem {
    /// The problem in words, settings named by `names`.
    pub fn render(&self, names: SettingNames) -> String {
        let n = names;
        match self {
            Problem::Unreadable | Problem::UnreadableDirectory | Problem::Unmappable => {
                String::new()
            }
            Problem::Content(text) => text.clone(),
            Problem::BadRate { rate_hz } => format!(
                "{} {}: expected the log's sample rate in Hz, at least {MIN_LOG_RATE_HZ:e} and at most {MAX_LOG_RATE_HZ:e}",
                n(Setting::Rate),
                sig(*rate_hz, 6)
            ),
            Problem::ColumnsInBag => format!(
                "{} maps CSV columns; a bag's sensor_msgs/Imu fields are always angular_velocity and linear_acceleration",
                n(Setting::Columns)
            ),
            Problem::UnitsInBag => format!(
                "sensor_msgs/Imu is in rad/s and m/s^2 (ROS REP 103); leave {} and {} out",
                n(Setting::GyroUnit),
                n(Setting::AccelUnit)
            ),
            Problem::TopicInCsv => format!(
                "{} applies to ROS bags and MCAP files; this is a CSV log",
                n(Setting::Topic)
            ),
            Problem::MappedColumnMissing {
                channel,
                column,
                header,
            } => format!(
                "{} {channel}={column}: no column {column:?} in the header (columns: {})",
                n(Setting::Columns),
                header.join(", ")
            ),
            Problem::UnitConflict {
                column,
                from_name,
                setting,
                given,
            } => format!(
                "column `{column}` says {from_name} in its name but {} is {given}; leave the option out or correct it",
                n(*setting)
            ),
            Problem::UnitMissing { columns } => {
                let listed: Vec<String> = columns
                    .iter()
                    .map(|(name, sensor)| format!("`{name}` ({})", sensor_word(*sensor)))
                    .collect();
                let mut settings = Vec::new();
                if columns.iter().any(|(_, s)| *s == Sensor::Gyro) {
                    let units: Vec<&str> = GyroUnit::ALL.iter().map(|u| u.name()).collect();
                    settings.push(format!("{} {}", n(Setting::GyroUnit), units.join("|")));
                }
                if columns.iter().any(|(_, s)| *s == Sensor::Accel) {
                    let units: Vec<&str> = AccelUnit::ALL.iter().map(|u| u.name()).collect();
                    settings.push(format!("{} {}", n(Setting::AccelUnit), units.join("|")));
                }
                format!(
                    "no unit in the name of {}: give {} (each applies to every such column)",
                    listed.join(", "),
                    settings.join(" and ")
                )
            }
            Problem::NoImuColumn { header } => format!(
                "no gyro or accelerometer column recognised among {}; name them like gyro_x_dps, gyr_x, wx, angular_velocity.x, acc_x_g, accel_x, linear_acceleration.x (unit suffixes dps, rad_s, g, mps2), or map them with {} gx=NAME",
                header.join(", "),
                n(Setting::Columns)
            ),
            Problem::RateDisagrees { rate_hz, from_t_hz } => format!(
                "{} {} Hz disagrees with the `t` column ({} Hz); give the rate the log was sampled at, or leave {} out to use `t`",
                n(Setting::Rate),
                sig(*rate_hz, 6),
                sig(*from_t_hz, 6),
                n(Setting::Rate)
            ),
            Problem::NoRate => format!(
                "no `t` column: give the sample rate with {} HZ (or map a time column with {} t=NAME)",
                n(Setting::Rate),
                n(Setting::Columns)
            ),
            Problem::TimeStepTooSmall { median_s } => {
                let units: Vec<&str> = TimeUnit::ALL[1..].iter().map(|u| u.name()).collect();
                format!(
                    "the `t` column's median step is {median_s:e} s; expected a sample rate of at most {MAX_LOG_RATE_HZ:e} Hz (is `t` in seconds? {} {} says otherwise)",
                    n(Setting::TimeUnit),
                    units.join("|")
                )
            }
            Problem::NoSuchTopic {
                topic,
                imu_type,
                topics,
            } => format!(
                "{} {topic}: no {imu_type} topic of that name (topics: {topics})",
                n(Setting::Topic)
            ),
            Problem::SeveralTopics { imu_type, topics } => format!(
                "{} {imu_type} topics ({}): choose one with {}",
                topics.len(),
                topics.join(", "),
                n(Setting::Topic)
            ),
        }
    }
}

fn sensor_word(sensor: Sensor) -> &'static str {
    match sensor {
        Sensor::Gyro => "gyro",
        Sensor::Accel => "accelerometer",
    }
}

/// An error of the reader: the file, where in it, and what is wrong.
#[derive(Debug, thiserror::Error)]
#[error("{}", self.render(&Setting::name))]
pub struct LogError {
    /// The file (its path as given).
    pub file: String,
    /// The line or message, when the problem is at one.
    pub at: Option<At>,
    /// The column's name, when the problem is in one.
    pub column: Option<String>,
    /// What is wrong (boxed: errors stay small on the success path).
    pub problem: Box<Problem>,
    /// The underlying error (an I/O error, a decoder's), if any.
    #[source]
    pub cause: Option<Box<dyn std::error::Error + Send + Sync>>,
}

impl LogError {
    /// A problem of the file as a whole.
    pub(crate) fn new(file: &str, problem: Problem) -> LogError {
        LogError {
            file: file.to_string(),
            at: None,
            column: None,
            problem: Box::new(problem),
            cause: None,
        }
    }

    /// A problem of the content, said in words.
    pub(crate) fn content(file: &str, text: impl Into<String>) -> LogError {
        LogError::new(file, Problem::Content(text.into()))
    }

    pub(crate) fn at(mut self, at: At) -> LogError {
        self.at = Some(at);
        self
    }

    pub(crate) fn at_line(self, line: usize) -> LogError {
        self.at(At::Line(line))
    }

    pub(crate) fn in_column(mut self, column: &str) -> LogError {
        self.column = Some(column.to_string());
        self
    }

    pub(crate) fn caused_by(
        mut self,
        cause: impl Into<Box<dyn std::error::Error + Send + Sync>>,
    ) -> LogError {
        self.cause = Some(cause.into());
        self
    }

    /// Where: `file`, `file:line` or `file: topic T message k`.
    pub fn place(&self) -> String {
        match &self.at {
            None => self.file.clone(),
            Some(At::Line(line)) => format!("{}:{line}", self.file),
            Some(At::Message { topic, index }) => {
                format!("{}: topic {topic} message {index}", self.file)
            }
        }
    }

    /// The message with the settings named by `names` (the cause is not included: it is the
    /// error's `source`).
    pub fn render(&self, names: SettingNames) -> String {
        match *self.problem {
            Problem::Unreadable => return format!("cannot read {}", self.file),
            Problem::UnreadableDirectory => {
                return format!("cannot read the directory {}", self.file)
            }
            Problem::Unmappable => return format!("cannot map {}", self.file),
            _ => {}
        }
        let column = match &self.column {
            Some(c) => format!("column {c:?}: "),
            None => String::new(),
        };
        format!("{}: {column}{}", self.place(), self.problem.render(names))
    }
}

pub use noise::text::sig;

/// A size in bytes for people, binary units (IEC 80000-13 prefixes): "512 bytes", "3.5 KiB",
/// "1.2 GiB" (never "0.0 GB").
pub fn byte_size(b: f64) -> String {
    const UNITS: [&str; 6] = ["KiB", "MiB", "GiB", "TiB", "PiB", "EiB"];
    if b.is_nan() || b < 1024.0 {
        return format!("{b} bytes");
    }
    let mut v = b;
    let mut unit = "bytes";
    for u in UNITS {
        if v < 1024.0 {
            break;
        }
        v /= 1024.0;
        unit = u;
    }
    format!("{} {unit}", sig(v, 3))
}

/// The reader's results.
pub type Result<T> = std::result::Result<T, LogError>;
