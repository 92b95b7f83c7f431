//! A `spec` comparison from its settings, shared by every front end (the CLI's `spec`, the
//! Python package's `imudrift.spec`): the settings checked before any work, each sensor's spec
//! values (or their readback, [`crate::spec`]), drift runs and requirements, and the JSON
//! document (docs/cli.md, `spec --json`). Front ends read the model files and run the drift runs
//! (with their own pool, progress or interrupt, [`RunRange`]); errors name a setting through the
//! front end's names for them ([`SpecNames`]), never an option of one front end.

use crate::experiment::{Experiment, ExperimentError};
use crate::job::{check_finite, NotFinite, RunRange};
use crate::nav_quantity::NavQuantity;
use crate::requirement::{evaluate, Requirement, RequirementError, RequirementResult};
use crate::runner::RunFailure;
use crate::spec::{
    drift_experiment, drift_rows, gyro_readback, gyro_spec_values, SensorSpec, READBACK_CONFIDENCE,
    READBACK_DURATION_S, READBACK_RATE_HZ,
};
use noise::text::{error_chain as chain, time};
use noise::{Effect, Sensor, SensorModel};
use serde::Serialize;

/// Drift times when neither times nor requirements give any, s.
pub const DEFAULT_TIMES_S: [f64; 3] = [60.0, 600.0, 3600.0];
/// Monte Carlo runs per sensor: enough for the table (200), more when a requirement's p95 must be
/// placed against a threshold (500 runs: the p95's 95 % interval spans about ranks 465-485).
pub const DEFAULT_RUNS: u64 = 200;
pub const DEFAULT_RUNS_REQUIRE: u64 = 500;
/// Sample rate of the drift runs unless set, Hz.
pub const DEFAULT_RATE_HZ: f64 = 100.0;
/// Highest drift sample rate accepted, Hz.
pub const MAX_RATE_HZ: f64 = 1e6;
/// Most mechanisation steps (runs x samples) per sensor a spec run may ask for (about 3 h on
/// 2 cores at 1e7 steps/s per core).
pub const MAX_STEPS_PER_SENSOR: f64 = 1e11;

/// A setting of the comparison, as a front end names it in messages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpecSetting {
    Require,
    Times,
    Rate,
    Runs,
    ReadbackDuration,
}

/// A front end's names of the settings (the CLI's flags, the Python arguments).
pub type SpecNames<'a> = &'a dyn Fn(SpecSetting) -> &'static str;

/// What a front end asks for, before it is checked.
#[derive(Clone, Debug, Default)]
pub struct SpecRequest {
    /// Requirement texts ("pos_horizontal_m < 10 m @ 300 s").
    pub require: Vec<String>,
    /// Drift times, s (`None`: [`DEFAULT_TIMES_S`], or only the requirements' times).
    pub times_s: Option<Vec<f64>>,
    pub rate_hz: f64,
    /// `None`: [`DEFAULT_RUNS`], or [`DEFAULT_RUNS_REQUIRE`] with requirements.
    pub runs: Option<u64>,
    /// Read the spec values back from a simulated static log of [`READBACK_DURATION_S`].
    pub readback: bool,
    /// The readback log's length, s (implies `readback`).
    pub readback_duration_s: Option<f64>,
    /// Memory available for the readback log, bytes (`None`: not known, not checked).
    pub available_memory_bytes: Option<u64>,
}

/// Why a comparison cannot be made; [`SpecError::render`] tells it with a front end's names.
#[derive(Debug)]
pub enum SpecError {
    Requirement(RequirementError),
    Rate(f64),
    RateTooHigh(f64),
    TimeNotFinite(f64),
    ShorterThanASample {
        t_s: f64,
        rate_hz: f64,
    },
    NoTimes,
    NoRuns,
    TooMuchWork {
        runs: u64,
        last_s: f64,
        rate_hz: f64,
        steps: f64,
    },
    ReadbackTooShort,
    ReadbackTooLong(f64),
    ReadbackMemory {
        duration_s: f64,
        need: f64,
        available: f64,
    },
    /// A sensor's drift experiment cannot be built (`name`: the sensor file as given).
    Experiment {
        name: String,
        source: ExperimentError,
    },
    /// Every drift run of a sensor failed.
    AllRunsFailed {
        name: String,
        runs: u64,
        first: String,
    },
    /// A sensor's drift statistics overflow.
    NotFinite {
        name: String,
        model: String,
        source: NotFinite,
    },
}

impl SpecError {
    /// The message, each setting named by `names`.
    pub fn render(&self, names: SpecNames) -> String {
        let n = |s| names(s);
        match self {
            SpecError::Requirement(e) => format!("{}: {e}", n(SpecSetting::Require)),
            SpecError::Rate(r) => format!(
                "{}: expected a sample rate in Hz > 0, found {r}",
                n(SpecSetting::Rate)
            ),
            SpecError::RateTooHigh(r) => format!(
                "{}: expected at most {MAX_RATE_HZ} Hz, found {r}",
                n(SpecSetting::Rate)
            ),
            SpecError::TimeNotFinite(t) => format!(
                "{}: expected times in seconds > 0, found {t}",
                n(SpecSetting::Times)
            ),
            SpecError::ShorterThanASample { t_s, rate_hz } => format!(
                "{} / {}: {t_s} s is shorter than one sample at {} {rate_hz} Hz",
                n(SpecSetting::Times),
                n(SpecSetting::Require),
                n(SpecSetting::Rate)
            ),
            SpecError::NoTimes => format!(
                "{}: expected positive times in seconds, e.g. 60,600,3600",
                n(SpecSetting::Times)
            ),
            SpecError::NoRuns => format!("{}: expected an integer >= 1", n(SpecSetting::Runs)),
            SpecError::TooMuchWork { runs, last_s, rate_hz, steps } => format!(
                "{runs} runs of {} at {rate_hz} Hz are {steps:.2e} mechanisation steps per sensor (limit {MAX_STEPS_PER_SENSOR:.0e}, about 3 h on 2 cores): use fewer {}, a lower {} or an earlier time",
                time(*last_s),
                n(SpecSetting::Runs),
                n(SpecSetting::Rate)
            ),
            SpecError::ReadbackTooShort => format!(
                "{}: expected at least 10 s",
                n(SpecSetting::ReadbackDuration)
            ),
            SpecError::ReadbackTooLong(d) => format!(
                "{}: {d:e} s at {READBACK_RATE_HZ} Hz is more than 2e9 samples (16 GB per axis); use at most 5.5e6 s (64 days)",
                n(SpecSetting::ReadbackDuration)
            ),
            SpecError::ReadbackMemory { duration_s, need, available } => format!(
                "{}: a {} readback log needs about {:.1} GiB and {:.1} GiB is available: use a shorter {}",
                n(SpecSetting::ReadbackDuration),
                time(*duration_s),
                need / (1u64 << 30) as f64,
                available / (1u64 << 30) as f64,
                n(SpecSetting::ReadbackDuration)
            ),
            SpecError::Experiment { name, source } => format!("{name}: {}", chain(source)),
            SpecError::AllRunsFailed { name, runs, first } => format!(
                "{name}: every one of the {runs} drift runs failed ({first}); the model's values are probably far too large (check their units)"
            ),
            SpecError::NotFinite { name, model, source } => {
                format!("{name}: drift of {model}: {source}")
            }
        }
    }
}

/// The comparison's settings, checked: requirements parsed, drift times rounded to whole
/// samples, sorted, with the requirements' own.
#[derive(Clone, Debug)]
pub struct SpecSettings {
    requirements: Vec<Requirement>,
    times_s: Vec<f64>,
    rate_hz: f64,
    runs: u64,
    readback_duration_s: Option<f64>,
}

impl SpecSettings {
    /// Check `req` before any work.
    pub fn new(req: &SpecRequest) -> Result<SpecSettings, SpecError> {
        let requirements = req
            .require
            .iter()
            .map(|r| r.parse::<Requirement>())
            .collect::<Result<Vec<_>, _>>()
            .map_err(SpecError::Requirement)?;
        let mut times: Vec<f64> = match &req.times_s {
            Some(t) => t.clone(),
            None if !requirements.is_empty() => Vec::new(),
            None => DEFAULT_TIMES_S.to_vec(),
        };
        let rate = req.rate_hz;
        if !(rate.is_finite() && rate > 0.0) {
            return Err(SpecError::Rate(rate));
        }
        if rate > MAX_RATE_HZ {
            return Err(SpecError::RateTooHigh(rate));
        }
        if let Some(&t) = times.iter().find(|t| !t.is_finite()) {
            return Err(SpecError::TimeNotFinite(t));
        }
        times.extend(requirements.iter().map(|r| r.t_s));
        // Drift is recorded at whole samples: each time is rounded to the nearest sample.
        for t in &mut times {
            let k = (*t * rate).round();
            if k < 1.0 {
                return Err(SpecError::ShorterThanASample {
                    t_s: *t,
                    rate_hz: rate,
                });
            }
            *t = k / rate;
        }
        times.sort_by(f64::total_cmp);
        times.dedup();
        if times.is_empty() {
            return Err(SpecError::NoTimes);
        }
        let runs = req.runs.unwrap_or(if requirements.is_empty() {
            DEFAULT_RUNS
        } else {
            DEFAULT_RUNS_REQUIRE
        });
        if runs == 0 {
            return Err(SpecError::NoRuns);
        }
        // Refuse work that would run for hours before starting it (about 1e7 steps/s per core).
        let last_s = times.last().copied().unwrap_or(0.0);
        let steps = runs as f64 * last_s * rate;
        if steps > MAX_STEPS_PER_SENSOR {
            return Err(SpecError::TooMuchWork {
                runs,
                last_s,
                rate_hz: rate,
                steps,
            });
        }
        let readback_duration_s = match req.readback_duration_s {
            Some(d) => Some(d),
            None => req.readback.then_some(READBACK_DURATION_S),
        };
        if let Some(d) = readback_duration_s {
            check_readback_duration(d, req.available_memory_bytes)?;
        }
        Ok(SpecSettings {
            requirements,
            times_s: times,
            rate_hz: rate,
            runs,
            readback_duration_s,
        })
    }

    pub fn requirements(&self) -> &[Requirement] {
        &self.requirements
    }

    /// Drift times (the requirements' included), rounded to whole samples, sorted, s.
    pub fn times_s(&self) -> &[f64] {
        &self.times_s
    }

    pub fn rate_hz(&self) -> f64 {
        self.rate_hz
    }

    pub fn runs(&self) -> u64 {
        self.runs
    }

    /// Length of the readback log, s (`None`: spec values only).
    pub fn readback_duration_s(&self) -> Option<f64> {
        self.readback_duration_s
    }
}

/// A readback log of `d` s must be long enough to read, and fit in memory.
fn check_readback_duration(d: f64, available: Option<u64>) -> Result<(), SpecError> {
    if !(d.is_finite() && d * READBACK_RATE_HZ >= 1000.0) {
        return Err(SpecError::ReadbackTooShort);
    }
    // 8 bytes per sample per axis; refuse before allocating what the machine cannot hold.
    if d * READBACK_RATE_HZ > 2e9 {
        return Err(SpecError::ReadbackTooLong(d));
    }
    // The three axes are generated and analysed at once: each holds its samples and their
    // integral (16 bytes a sample).
    let need = 3.0 * 16.0 * d * READBACK_RATE_HZ;
    if let Some(available) = available {
        if need > available as f64 {
            return Err(SpecError::ReadbackMemory {
                duration_s: d,
                need,
                available: available as f64,
            });
        }
    }
    Ok(())
}

/// The `spec` JSON document (docs/cli.md, `spec --json`).
#[derive(Serialize, Debug, Clone)]
pub struct SpecDoc {
    pub seed: u64,
    /// `null` when no readback was asked for.
    pub readback_duration_s: Option<f64>,
    pub readback_rate_hz: f64,
    pub readback_confidence: f64,
    pub drift_rate_hz: f64,
    pub sensors: Vec<SensorOut>,
}

impl SpecDoc {
    /// The document of `sensors` compared under `settings` with `seed`.
    pub fn new(seed: u64, settings: &SpecSettings, sensors: Vec<SensorOut>) -> SpecDoc {
        SpecDoc {
            seed,
            readback_duration_s: settings.readback_duration_s,
            readback_rate_hz: READBACK_RATE_HZ,
            readback_confidence: READBACK_CONFIDENCE,
            drift_rate_hz: settings.rate_hz,
            sensors,
        }
    }

    /// The document's text as `spec --json` prints it (pretty, a final newline).
    pub fn to_json(&self) -> String {
        // Plain data (strings, numbers, maps) always serialises.
        serde_json::to_string_pretty(self).unwrap_or_default() + "\n"
    }
}

/// One sensor's comparison with the notes on what the model lacks and its requirements.
#[derive(Serialize, Debug, Clone)]
pub struct SensorOut {
    #[serde(flatten)]
    pub spec: SensorSpec,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub model_notes: Vec<String>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub requirements: Vec<RequirementResult>,
}

/// Whether any axis of `sensor` has any error term.
fn has_any(model: &SensorModel, sensor: Sensor) -> bool {
    Effect::ALL.iter().any(|&e| model.has(sensor, e))
}

/// Whether the model has a term that drives `quantity`.
fn informs(model: &SensorModel, quantity: NavQuantity) -> bool {
    let gyro = has_any(model, Sensor::Gyro);
    let accel = has_any(model, Sensor::Accel);
    if quantity.name().ends_with("_rad") {
        gyro
    } else {
        gyro || accel
    }
}

/// The static drift experiment of `model` (the sensor file `name`) under `settings`: a front end
/// checks its size before [`compare`] runs it.
pub fn experiment(
    model: &SensorModel,
    settings: &SpecSettings,
    seed: u64,
    name: &str,
) -> Result<Experiment, SpecError> {
    drift_experiment(
        model,
        &settings.times_s,
        settings.rate_hz,
        settings.runs,
        seed,
    )
    .map_err(|source| SpecError::Experiment {
        name: name.to_string(),
        source,
    })
}

/// One sensor (the file `name`, with its [`experiment`] `exp`): its spec values (or read back
/// from a simulated log, in the current thread pool), the drift runs (`run`, labelled by the
/// model's name) and the requirements. The failed runs come beside the result; `Ok(None)` when
/// `run` was stopped.
pub fn compare(
    model: &SensorModel,
    exp: &Experiment,
    settings: &SpecSettings,
    seed: u64,
    name: &str,
    run: &RunRange<'_>,
) -> Result<Option<(SensorOut, Vec<RunFailure>)>, SpecError> {
    let gyro = match settings.readback_duration_s {
        Some(d) => gyro_readback(model, seed, d, READBACK_RATE_HZ),
        None => gyro_spec_values(model, READBACK_RATE_HZ),
    };
    let Some(batch) = run(exp, 0..exp.runs, &model.name) else {
        return Ok(None);
    };
    if batch.matrix.runs() == 0 {
        return Err(SpecError::AllRunsFailed {
            name: name.to_string(),
            runs: settings.runs,
            first: batch
                .failures
                .first()
                .map_or("no run finished".to_string(), |f| f.message.clone()),
        });
    }
    let report = exp.report(&batch.matrix, &batch.failures);
    check_finite(&report).map_err(|source| SpecError::NotFinite {
        name: name.to_string(),
        model: model.name.clone(),
        source,
    })?;
    let checkpoint_times = exp.scenario.checkpoint_times_s();
    let rate = settings.rate_hz;
    let requirements = settings
        .requirements
        .iter()
        .filter_map(|req| {
            // Every requirement's time is a drift time (SpecSettings::new), so a checkpoint.
            let cp = checkpoint_times
                .iter()
                .position(|&t| (t - req.t_s).abs() <= 0.5 / rate)?;
            let values = batch.matrix.series(cp, req.quantity as usize);
            Some(evaluate(req, values, informs(model, req.quantity)))
        })
        .collect();
    let out = SensorOut {
        spec: SensorSpec {
            name: model.name.clone(),
            gyro,
            drift: drift_rows(&report),
            drift_runs: report.runs_ok,
        },
        model_notes: noise::model_notes::notes(model, checkpoint_times.last().copied()),
        requirements,
    };
    Ok(Some((out, batch.failures)))
}
