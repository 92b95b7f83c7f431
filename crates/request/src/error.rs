//! Why a request cannot be carried out: one error type for every command, each setting named
//! through the front end's [`Names`] ([`RequestError::render`]).

use crate::setting::{Names, Setting};
use montecarlo::experiment::ExperimentError;
use montecarlo::job::{JobError, MAX_VALUE_BYTES, MAX_WORK_SAMPLES};
use noise::text::error_chain;

pub type Result<T> = std::result::Result<T, RequestError>;

/// What a piece of work is cut down by, when it is more than [`MAX_WORK_SAMPLES`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Remedy {
    /// A Monte Carlo run: fewer runs, shorter, a lower rate, or shards.
    Simulate,
    /// A generated log: shorter or at a lower rate.
    Generate,
}

/// How a constant channel is left out with a front end's settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LeaveOut {
    /// Leave its column out of the log, or map another one (`diagnose`, `drift`).
    Column,
    /// Leave it out of the channels analysed (`allan`).
    Channel,
}

/// A file named by a request that cannot be read, or whose text is not usable.
#[derive(Debug)]
pub struct FileError {
    /// The file as given.
    pub name: String,
    /// What it was read as ("a sensor model, scenario or noise file").
    pub what: &'static str,
    /// Where it was named ("scenarios/x.toml: key `sensor`: the sensor file"), if not directly.
    pub within: Option<String>,
    pub problem: FileProblem,
}

#[derive(Debug)]
pub enum FileProblem {
    /// The operating system's error (missing, a directory, too large, ...).
    Io(std::io::Error),
    /// The bytes are not text (UTF-8), or the text is not a sensor model.
    Text(Box<noise::ConfigError>),
}

impl std::error::Error for FileError {}

impl std::fmt::Display for FileError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if let Some(w) = &self.within {
            write!(f, "{w}: ")?;
        }
        match &self.problem {
            FileProblem::Io(e) => write!(f, "cannot read {} as {}: {e}", self.name, self.what),
            FileProblem::Text(e) => write!(f, "{}", error_chain(e)),
        }
    }
}

/// A number as a message shows it: exactly, in scientific notation outside 1e-4 to 1e16 (a rate
/// of 1e300 is "1e300", not its 301 digits).
pub fn number(v: f64) -> String {
    if v.is_finite() && v != 0.0 && !(1e-4..1e16).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// Why a request cannot be carried out.
#[derive(Debug)]
pub enum RequestError {
    File(FileError),
    /// A scenario text (after the front end's edits) that is not TOML.
    ScenarioNotToml {
        source_name: String,
        message: String,
    },
    /// The scenario, sensor model or experiment refused by its library.
    Job(Box<JobError>),
    /// A term switch that does not parse (`setting`: `Only` or `Without`).
    Terms {
        setting: Setting,
        message: String,
    },
    Rate(f64),
    RateTooHigh {
        rate_hz: f64,
        max_hz: f64,
    },
    /// A duration and rate giving no sample or too many.
    Samples {
        duration_s: f64,
        rate_hz: f64,
        samples: f64,
    },
    /// A model whose output filter does not fit the sample rate.
    FilterRate {
        source_name: String,
        message: String,
    },
    Threads {
        n: usize,
        max: usize,
        cores: usize,
    },
    PoolStart(String),
    /// Per-run values beyond the memory limit.
    Memory {
        runs: u64,
        checkpoints: usize,
        bytes: u64,
        limit: u64,
    },
    /// Work beyond [`MAX_WORK_SAMPLES`]; `what` names the job.
    Work {
        what: String,
        runs: f64,
        samples: f64,
        decimation: f64,
        work: f64,
        remedy: Remedy,
    },
    /// A shard that is not `i/k` with 0 <= i < k.
    Shard(String),
    /// A merge of no shard.
    NoShards,
    /// A shard's bytes that are not a shard file.
    NotShard {
        name: String,
        message: String,
    },
    ShardFormat {
        name: String,
        found: String,
    },
    /// A shard's stored scenario or sensor that no longer builds.
    StoredScenario {
        name: String,
        source: Box<JobError>,
    },
    /// Shards that do not belong together.
    Merge(Box<montecarlo::job::MergeError>),
    /// A log with no gyro or accelerometer channel (`columns`: its quantities in file order).
    NoImuChannel {
        source_name: String,
        columns: String,
    },
    /// A constant channel: no noise to analyse.
    Constant {
        source_name: String,
        channel: &'static str,
        /// Its first value.
        value: f64,
        /// Its largest minus its smallest value (0, or below `logio::MIN_SPREAD`).
        spread: f64,
        leave_out: LeaveOut,
    },
    /// Series given as arrays that are not a log.
    Series(logio::SeriesError),
    TooFewSeeds(usize),
    TooManySeeds(usize),
    Rounds(usize),
    MinDeltaBic(f64),
    TauMin(f64),
    Horizon(f64),
    Latitude(f64),
    /// Simulated experiments outside `min..=max`.
    Replicates {
        value: usize,
        min: usize,
        max: usize,
    },
    /// A log's sample rate outside what a log can have.
    LogRate(f64),
    Confidence(f64),
    ConfidenceText(String),
    TooFewSamples(usize),
    Sample {
        index: usize,
        value: f64,
    },
    /// Samples all one value (`spread` 0) or within `logio::MIN_SPREAD` of `value`.
    ConstantSamples {
        value: f64,
        spread: f64,
    },
    /// An averaging time (s) that is not finite and > 0, at `index` of the list.
    Tau {
        index: usize,
        value: f64,
    },
    /// A curve with fewer than `needed` averaging times of at least 9 intervals (Woodman's rule);
    /// `channel` is the log's channel, when the samples are one.
    UnusableCurve {
        source_name: String,
        channel: Option<String>,
        samples: usize,
        usable: usize,
        needed: usize,
        /// No averaging time at all: the grid or tau list has none the samples can hold.
        empty: bool,
    },
    /// A curve with a deviation whose square is not a normal double (0, underflowing, or not
    /// finite): no fit or interval can use it.
    DegenerateDeviation {
        source_name: String,
        channel: Option<String>,
        tau_s: f64,
        dev: f64,
    },
    /// A deviation function (allantools' conventions) whose tau list leaves no point.
    NoPoint {
        function: String,
        samples: usize,
    },
    /// A sensor model named by a one-line text that is neither an existing path nor a model's
    /// text.
    NoSuchModel(String),
    /// A diagnosed model's own tables (`[fitted_on]`, `[[alternatives]]`) that do not read.
    ModelTables {
        name: String,
        message: String,
    },
    /// Simulated logs that would not fit in memory.
    SimulationMemory {
        source_name: String,
        samples: usize,
        threads: usize,
        need: u64,
        available: u64,
    },
    /// Two logs with the same samples: one run given twice.
    RepeatedLog {
        first: String,
        second: String,
    },
    /// Generated values that overflow or exceed `noise::limits::MAX_ABS_VALUE` (`channel` at
    /// sample `k`).
    Overflow {
        channel: &'static str,
        value: f64,
        k: usize,
    },
}

impl RequestError {
    /// Whether the error is a file the system could not read (an `OSError` in Python), rather
    /// than an input that is not usable.
    pub fn is_unreadable(&self) -> bool {
        matches!(
            self,
            RequestError::File(FileError {
                problem: FileProblem::Io(_),
                ..
            }) | RequestError::NoSuchModel(_)
        )
    }

    /// The message, each setting named by `names`.
    pub fn render(&self, names: Names) -> String {
        let n = |s| names(s);
        match self {
            RequestError::File(e) => e.to_string(),
            RequestError::ScenarioNotToml {
                source_name,
                message,
            } => format!("cannot read scenario {source_name} as TOML: {message}"),
            RequestError::Job(e) if matches!(**e, JobError::Experiment(ExperimentError::NoRuns)) => {
                format!("{}: expected an integer >= 1", n(Setting::Runs))
            }
            RequestError::Job(e) => error_chain(&**e),
            RequestError::Terms { setting, message } => format!("{}: {message}", n(*setting)),
            RequestError::Rate(r) => format!(
                "{}: expected a sample rate in Hz > 0, found {}",
                n(Setting::Rate),
                number(*r)
            ),
            RequestError::RateTooHigh { rate_hz, max_hz } => {
                format!("{} {rate_hz}: expected at most {max_hz:e} Hz", n(Setting::Rate))
            }
            RequestError::Samples {
                duration_s,
                rate_hz,
                samples,
            } => format!(
                "{} {duration_s} s at {} {rate_hz} gives {samples} samples; expected 1 to 1e12",
                n(Setting::Duration),
                n(Setting::Rate)
            ),
            RequestError::FilterRate {
                source_name,
                message,
            } => format!(
                "{source_name}: {message}; lower the cutoff or raise {}",
                n(Setting::Rate)
            ),
            RequestError::Threads { n: t, max, cores } => format!(
                "{} {t}: expected at most {max} (this machine has {cores} cores; 0 or none uses them all)",
                n(Setting::Threads)
            ),
            RequestError::PoolStart(e) => format!("cannot start the worker threads: {e}"),
            RequestError::Memory {
                runs,
                checkpoints,
                bytes,
                limit,
            } => format!(
                "{}: {runs} runs x {checkpoints} checkpoints keep {} of per-run values (limit {}); split them with {} and {}, or use fewer checkpoints",
                n(Setting::Runs),
                logio::byte_size(*bytes as f64),
                if *limit == MAX_VALUE_BYTES {
                    "8 GiB".to_string()
                } else {
                    format!("{}, the memory available", logio::byte_size(*limit as f64))
                },
                n(Setting::Shard),
                n(Setting::Merge)
            ),
            RequestError::Work {
                what,
                runs,
                samples,
                decimation,
                work,
                remedy,
            } => {
                let filter = if *decimation > 1.0 {
                    format!(" x decimation {decimation}")
                } else {
                    String::new()
                };
                let remedy = match remedy {
                    Remedy::Simulate => format!(
                        "use fewer {}, a shorter {} or a lower {} (or split the runs with {})",
                        n(Setting::Runs),
                        n(Setting::Duration),
                        n(Setting::Rate),
                        n(Setting::Shard)
                    ),
                    Remedy::Generate => {
                        format!("generate a shorter log or at a lower {}", n(Setting::Rate))
                    }
                };
                format!(
                    "{what}: {runs:.3e} run(s) x {samples:.3e} samples{filter} are {work:.2e} samples of work (limit {MAX_WORK_SAMPLES:.0e}, about 3 h on 2 cores): {remedy}"
                )
            }
            RequestError::Shard(text) => format!(
                "{}: shard `{text}`: expected `i/k` with integers 0 <= i < k (e.g. `0/4`, as Slurm's SLURM_ARRAY_TASK_ID/array size)",
                n(Setting::Shard)
            ),
            RequestError::NoShards => format!(
                "{}: expected the shards of a job, got none",
                n(Setting::Merge)
            ),
            RequestError::NotShard { name, message } => {
                format!("{name}: not an imudrift shard file: {message}")
            }
            RequestError::ShardFormat { name, found } => format!(
                "{name}: key `format`: expected `{}`, got `{found}`",
                montecarlo::shard::SHARD_FORMAT
            ),
            RequestError::StoredScenario { name, source } => {
                format!("{name}: the stored scenario: {}", error_chain(&**source))
            }
            RequestError::Merge(e) => error_chain(&**e),
            RequestError::NoImuChannel {
                source_name,
                columns,
            } => format!(
                "{source_name}: no gyro or accelerometer channel (expected columns gx gy gz ax ay az, or map them with {} gx=NAME; columns: {columns})",
                n(Setting::Columns)
            ),
            RequestError::Constant {
                source_name,
                channel,
                value,
                spread,
                leave_out,
            } => format!(
                "{source_name}: channel {channel} is {}: it has no noise to analyse (a stuck or disconnected sensor, or a column of zeros?); {}",
                constant_text(*value, *spread),
                match leave_out {
                    LeaveOut::Column => format!(
                        "leave the column out or map another one with {}",
                        n(Setting::Columns)
                    ),
                    LeaveOut::Channel => format!("leave it out with {}", n(Setting::Channels)),
                }
            ),
            RequestError::Series(e) => e.to_string(),
            RequestError::ModelTables { name, message } => format!("{name}: {message}"),
            RequestError::LogRate(r) => format!(
                "{} {}: expected a sample rate in Hz from {:e} to {:e}",
                n(Setting::Rate),
                number(*r),
                logio::MIN_LOG_RATE_HZ,
                logio::MAX_LOG_RATE_HZ
            ),
            RequestError::Confidence(c) => format!(
                "{} {}: expected a level between 0 and 1 (0 % and 100 %)",
                n(Setting::Confidence),
                number(*c)
            ),
            RequestError::ConfidenceText(t) => format!(
                "{}: expected 1sigma, a fraction such as 0.95 or a percentage such as 95%, got `{t}`",
                n(Setting::Confidence)
            ),
            RequestError::TooFewSamples(k) => format!(
                "{}: {k} samples: at least 2 are needed",
                n(Setting::Data)
            ),
            RequestError::Sample { index, value } => format!(
                "{}[{index}] is {}: every sample must be finite and of magnitude below {:e} (a NaN gap is not bridged)",
                n(Setting::Data),
                number(*value),
                logio::MAX_ABS_VALUE
            ),
            RequestError::ConstantSamples { value, spread } => format!(
                "{}: {}: a constant channel has no noise to analyse (a stuck or disconnected sensor, or a column of zeros?)",
                n(Setting::Data),
                if *spread == 0.0 {
                    format!("every sample is {value}")
                } else {
                    format!("the samples are {}", constant_text(*value, *spread))
                }
            ),
            RequestError::Tau { index, value } => format!(
                "{}[{index}] is {}: expected an averaging time in seconds, finite and > 0",
                n(Setting::Taus),
                number(*value)
            ),
            RequestError::UnusableCurve {
                source_name,
                channel,
                samples,
                usable,
                needed,
                empty,
            } => format!(
                "{source_name}: {samples} samples give {usable} averaging time(s) with at least 9 intervals (Woodman's rule){}; an Allan analysis needs at least {needed}: use a longer log{}",
                channel
                    .as_deref()
                    .map(|c| format!(" for channel {c}"))
                    .unwrap_or_default(),
                if *empty {
                    format!(
                        " (the {} has no averaging factor this log can hold)",
                        n(Setting::Taus)
                    )
                } else {
                    String::new()
                }
            ),
            RequestError::DegenerateDeviation {
                source_name,
                channel,
                tau_s,
                dev,
            } => format!(
                "{source_name}: the deviation{} at tau {} s is {}: its square is not a normal number (the samples' variations cancel there, or are too small to square: below about 1e-154), so no interval or fit can use it; {}",
                channel
                    .as_deref()
                    .map(|c| format!(" of channel {c}"))
                    .unwrap_or_default(),
                number(*tau_s),
                number(*dev),
                if *dev == 0.0 || !dev.is_finite() {
                    "check the samples"
                } else {
                    "scale the samples (another unit)"
                }
            ),
            RequestError::NoPoint { function, samples } => format!(
                "{function}: {samples} samples leave no averaging time of the {} with 2 or more terms",
                n(Setting::Taus)
            ),
            RequestError::NoSuchModel(text) => format!(
                "cannot read {text} as a sensor model: no such file (and not a model's text: a sensor TOML has `key = value` lines, nor a shipped sensor's name: {})",
                crate::shipped::SHIPPED_SENSORS.map(|(n, _)| n).join(", ")
            ),
            RequestError::SimulationMemory {
                source_name,
                samples,
                threads,
                need,
                available,
            } => format!(
                "{source_name}: simulating logs of {samples} samples on {threads} threads needs about {:.1} GiB and {:.1} GiB is available: use fewer {} or a shorter log",
                *need as f64 / (1u64 << 30) as f64,
                *available as f64 / (1u64 << 30) as f64,
                n(Setting::Threads)
            ),
            RequestError::Replicates { value, min, max } => format!(
                "{} {value}: expected {min} to {max} simulated experiments",
                n(Setting::Replicates)
            ),
            RequestError::TooFewSeeds(v) => format!(
                "{} {v}: at least 2 simulated logs are needed for a band",
                n(Setting::Seeds)
            ),
            RequestError::TooManySeeds(v) => format!(
                "{} {v}: expected at most {} simulated logs per band",
                n(Setting::Seeds),
                diagnose::settings::MAX_SEEDS
            ),
            RequestError::Rounds(v) => format!(
                "{} {v}: expected at most {}",
                n(Setting::Rounds),
                diagnose::settings::MAX_ROUNDS
            ),
            RequestError::MinDeltaBic(v) => {
                format!("{} {v}: expected a number >= 0", n(Setting::MinDeltaBic))
            }
            RequestError::TauMin(v) => format!(
                "{} {}: expected a time >= 0",
                n(Setting::TauMin),
                number(*v)
            ),
            RequestError::Horizon(v) => format!(
                "{}: expected times > 0, found {}",
                n(Setting::Horizons),
                number(*v)
            ),
            RequestError::Latitude(v) => format!(
                "{} {v}: expected a latitude in [-89, 89] deg (the north-east-down frame is singular at the poles)",
                n(Setting::Latitude)
            ),
            RequestError::RepeatedLog { first, second } => format!(
                "{}: one run given twice would count as two runs and make every interval about sqrt(2) too narrow; give each run once",
                if first == second {
                    format!("{first} is given twice")
                } else {
                    format!("{second} has the same samples as {first}")
                }
            ),
            RequestError::Overflow { channel, value, k } => format!(
                "channel {channel} is {value:.4e} at sample {k}: beyond the magnitude a log can hold ({:e}, the bound every reader of logs holds); the model's values are far too large: check their units",
                noise::limits::MAX_ABS_VALUE
            ),
        }
    }
}

impl std::fmt::Display for RequestError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.render(&Setting::name))
    }
}

impl std::error::Error for RequestError {}

impl From<JobError> for RequestError {
    fn from(e: JobError) -> Self {
        RequestError::Job(Box::new(e))
    }
}

impl From<FileError> for RequestError {
    fn from(e: FileError) -> Self {
        RequestError::File(e)
    }
}

/// A constant series in words: "constant (V)", or for values that differ by less than
/// `logio::MIN_SPREAD`, by how much and why that is constant to an analysis.
fn constant_text(value: f64, spread: f64) -> String {
    if spread == 0.0 {
        format!("constant ({})", number(value))
    } else {
        format!(
            "constant to within {} (from {}): values closer than {:e} differ by amounts whose squares underflow",
            number(spread),
            number(value),
            logio::MIN_SPREAD
        )
    }
}
