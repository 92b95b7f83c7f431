//! Scenario configuration (`configs/scenarios/*.toml`): which sensor, which trajectory, how long,
//! how fast, how many runs, which seed, where to look (checkpoints), initial alignment errors and
//! error-term switches. A raw serde struct (`deny_unknown_fields`) is converted into the validated
//! [`Scenario`]; every error names the source, the key and what was expected.

use noise::TermSelector;
use serde::Deserialize;
use std::path::PathBuf;
use strapdown::earth::Place;
use strapdown::{EarthModel, EarthTrajectory, RoundEarth, Scheme, TrajectorySpec, Vertical};

/// A configuration error: `source` (file name), `key` (dotted TOML path) and what was expected.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{source_name}: key `{key}`: {message}")]
pub struct ScenarioError {
    pub source_name: String,
    pub key: String,
    pub message: String,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScenario {
    name: Option<String>,
    description: Option<String>,
    sensor: String,
    duration_s: Option<f64>,
    rate_hz: Option<f64>,
    runs: Option<u64>,
    seed: Option<u64>,
    scheme: Option<String>,
    gravity_mps2: Option<f64>,
    earth: Option<RawEarth>,
    trajectory: Option<TrajectorySpec>,
    checkpoints: Option<RawCheckpoints>,
    alignment: Option<RawAlignment>,
    terms: Option<RawTerms>,
    reference: Option<Reference>,
    ablation: Option<bool>,
}

/// A published measurement to print beside the simulation (e.g. Woodman's 152.67 m at 60 s).
#[derive(Debug, Clone, PartialEq, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct Reference {
    /// The navigation-error quantity's name (`pos_horizontal_m` ...; TOML / JSON key `channel`).
    #[serde(rename = "channel")]
    pub quantity: String,
    /// Statistic compared: `mean`, `rms`, `p50` or `p95`.
    pub statistic: String,
    pub t_s: f64,
    pub value: f64,
    /// Where the number comes from.
    pub source: String,
    /// What a reader should know when comparing (printed under the comparison, not in the JSON).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
}

/// The `[earth]` table (names relied on by users' scripts: `model`, `latitude_deg`,
/// `longitude_deg`, `height_m`; and `vertical`).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawEarth {
    model: Option<String>,
    latitude_deg: Option<f64>,
    longitude_deg: Option<f64>,
    height_m: Option<f64>,
    vertical: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCheckpoints {
    times_s: Option<Vec<f64>>,
    log_count: Option<usize>,
    first_s: Option<f64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawAlignment {
    roll_deg: Option<f64>,
    pitch_deg: Option<f64>,
    yaw_deg: Option<f64>,
    roll_std_deg: Option<f64>,
    pitch_std_deg: Option<f64>,
    yaw_std_deg: Option<f64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTerms {
    only: Option<Vec<String>>,
    without: Option<Vec<String>>,
    bias_calibrated_at_start: Option<bool>,
    bias_calibration_window_s: Option<f64>,
}

/// Initial alignment error per Euler angle (rad): a fixed offset plus a per-run Gaussian draw.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Alignment {
    pub fixed_rad: [f64; 3],
    pub std_rad: [f64; 3],
}

impl Alignment {
    pub fn is_zero(&self) -> bool {
        self.fixed_rad
            .iter()
            .chain(&self.std_rad)
            .all(|&v| v == 0.0)
    }
}

/// A validated scenario.
#[derive(Debug, Clone, PartialEq)]
pub struct Scenario {
    pub name: String,
    pub description: String,
    /// Sensor TOML path as written (relative paths are relative to the scenario file).
    pub sensor: PathBuf,
    pub duration_s: f64,
    pub rate_hz: f64,
    pub runs: u64,
    pub seed: u64,
    /// Strapdown mechanisation scheme (`woodman` or `accurate`, strapdown's names).
    pub scheme: Scheme,
    /// Gravity at the start place, m/s^2 (the flat Earth's `gravity_mps2`, or normal gravity at
    /// the round Earth's latitude and height).
    pub gravity_mps2: f64,
    /// The Earth the scenario runs on (`[earth]`; the round, rotating WGS-84 Earth by default).
    pub earth: EarthModel,
    /// The trajectory as written (strapdown's spec) and built on the scenario's Earth.
    pub trajectory_spec: TrajectorySpec,
    pub trajectory: EarthTrajectory,
    /// Step indices k (t = k dt) at which errors are recorded, ascending, unique, 1 <= k <= steps.
    pub checkpoint_steps: Vec<u64>,
    pub alignment: Alignment,
    /// Term switches `terms.only` / `terms.without` (`gyro.white_noise` ...).
    pub only: Option<Vec<TermSelector>>,
    pub without: Vec<TermSelector>,
    /// `terms.bias_calibrated_at_start`: the slowly varying bias processes (flicker bias
    /// instability, Gauss-Markov) are referenced to their value at t = 0, b(t) - b(0), as for a
    /// user who estimates the bias at turn-on and subtracts it (Woodman TR-696 §3.2.1).
    pub bias_calibrated_at_start: bool,
    /// `terms.bias_calibration_window_s` = W: the bias estimate is the mean of each slowly varying
    /// bias process over [-W, 0] (the static output averaged for W seconds before the run), so
    /// the error is b(t) - m (`noise::ImuErrors::with_calibration_window`). Implies
    /// `bias_calibrated_at_start` (which is then true); None: the instantaneous b(0).
    pub bias_calibration_window_s: Option<f64>,
    pub reference: Option<Reference>,
    /// Print the ablation table (each term alone and the model without it) by default.
    pub ablation: bool,
}

/// Standard gravity (m/s^2) for a static level IMU.
/// (One definition for the workspace: the noise crate's, used by its unit conversions.)
pub use noise::units::STANDARD_GRAVITY_MPS2;
/// Default duration when a scenario leaves `duration_s` out (s): Woodman's 60 s runs.
pub const DEFAULT_DURATION_S: f64 = 60.0;
/// Default sample rate when a scenario leaves `rate_hz` out (Hz).
pub const DEFAULT_RATE_HZ: f64 = 100.0;
/// Default latitude of the round Earth when a scenario leaves `earth.latitude_deg` out, deg
/// (mid-latitude: Earth rate splits evenly between the north and down axes).
pub const DEFAULT_LATITUDE_DEG: f64 = 45.0;
/// Default number of Monte Carlo runs when a scenario leaves `runs` out (Woodman measured 500).
pub const DEFAULT_RUNS: u64 = 500;
/// Default master seed when a scenario leaves `seed` out.
pub const DEFAULT_SEED: u64 = 1;
/// Most checkpoints a scenario may ask for: each costs 8 bytes per run per navigation-error quantity.
pub const MAX_CHECKPOINTS: usize = 100_000;
/// Default number of log-spaced checkpoints.
pub const DEFAULT_LOG_COUNT: usize = 25;
/// Default first checkpoint, in samples: early enough to see the accelerometer-dominated start
/// (Woodman: the first ~0.3 s at 100 Hz), late enough that the law's discretisation error is small.
pub const DEFAULT_FIRST_STEPS: u64 = 10;

impl Scenario {
    pub fn dt_s(&self) -> f64 {
        1.0 / self.rate_hz
    }

    /// Number of mechanisation steps.
    pub fn steps(&self) -> u64 {
        (self.duration_s * self.rate_hz).round() as u64
    }

    pub fn checkpoint_times_s(&self) -> Vec<f64> {
        self.checkpoint_steps
            .iter()
            .map(|&k| k as f64 * self.dt_s())
            .collect()
    }

    /// Parse and validate scenario TOML text; `source_name` (the file name) prefixes every error.
    pub fn from_toml_str(text: &str, source_name: &str) -> Result<Scenario, ScenarioError> {
        let err = |key: &str, message: String| ScenarioError {
            source_name: source_name.to_string(),
            key: key.to_string(),
            message,
        };
        let raw = parse_raw(text, &err)?;
        let (duration_s, rate_hz, steps) = timing(&raw, &err)?;
        let runs = raw.runs.unwrap_or(DEFAULT_RUNS);
        if runs == 0 {
            return Err(err("runs", "expected an integer >= 1".into()));
        }
        let scheme = scheme(raw.scheme.as_deref(), &err)?;
        let earth = earth(raw.earth.unwrap_or_default(), raw.gravity_mps2, &err)?;
        let gravity_mps2 = earth.gravity_mps2();
        let trajectory_spec = raw.trajectory.unwrap_or(TrajectorySpec::Static {
            roll_deg: 0.0,
            pitch_deg: 0.0,
            yaw_deg: 0.0,
        });
        let trajectory = EarthTrajectory::new(
            build_trajectory(&trajectory_spec, gravity_mps2, &err)?,
            earth,
        );
        let mut checkpoint_steps = checkpoint_steps(raw.checkpoints, rate_hz, steps, &err)?;
        if let Some(r) = &raw.reference {
            // The reference time is always a checkpoint.
            let k = ((r.t_s * rate_hz).round() as u64).clamp(1, steps);
            checkpoint_steps.push(k);
            checkpoint_steps.sort_unstable();
            checkpoint_steps.dedup();
        }
        let alignment = alignment(raw.alignment.unwrap_or_default(), &err)?;
        let terms = raw.terms.unwrap_or_default();
        let (only, without) = term_switches(&terms, &err)?;
        if let Some(r) = &raw.reference {
            check_reference(r, duration_s, &err)?;
        }
        check_calibration(&terms, &err)?;
        if raw.sensor.trim().is_empty() {
            return Err(err("sensor", "expected a path to a sensor TOML".into()));
        }
        Ok(Scenario {
            name: raw.name.unwrap_or_else(|| {
                source_name
                    .rsplit('/')
                    .next()
                    .unwrap_or(source_name)
                    .trim_end_matches(".toml")
                    .to_string()
            }),
            description: raw.description.unwrap_or_default(),
            sensor: PathBuf::from(raw.sensor),
            duration_s,
            rate_hz,
            runs,
            seed: raw.seed.unwrap_or(DEFAULT_SEED),
            scheme,
            gravity_mps2,
            earth,
            trajectory_spec,
            trajectory,
            checkpoint_steps,
            alignment,
            only,
            without,
            bias_calibrated_at_start: terms.bias_calibrated_at_start.unwrap_or(false)
                || terms.bias_calibration_window_s.is_some(),
            bias_calibration_window_s: terms.bias_calibration_window_s,
            reference: raw.reference,
            ablation: raw.ablation.unwrap_or(false),
        })
    }
}

/// The TOML document; a missing `sensor` says how to give one.
fn parse_raw(text: &str, err: &ErrFn) -> Result<RawScenario, ScenarioError> {
    toml::from_str(text).map_err(|e| {
        let message = e.message();
        if message.contains("missing field `sensor`") {
            return err(
                "sensor",
                "missing: a scenario names its sensor, e.g. `sensor = \"../sensors/mtx.toml\"` \
                 (relative to the scenario file); every other key has a default \
                 (a sensor TOML can also be simulated directly: `imudrift simulate SENSOR.toml`)"
                    .into(),
            );
        }
        // toml's message names the line, column and offending key.
        err("(document)", e.to_string().trim_end().replace('\n', " "))
    })
}

/// The `[earth]` table and the flat Earth's `gravity_mps2`: `model = "wgs84"` (default) at
/// `latitude_deg` (default [`DEFAULT_LATITUDE_DEG`]), `longitude_deg`, `height_m` (default 0) with
/// the vertical channel `held` (default: a known height) or `free`; or `model = "flat"`,
/// Woodman's Earth, with `gravity_mps2` (default standard gravity).
fn earth(raw: RawEarth, gravity: Option<f64>, err: &ErrFn) -> Result<EarthModel, ScenarioError> {
    let model = raw.model.as_deref().unwrap_or("wgs84");
    match model {
        "flat" => {
            for (key, given) in [
                ("earth.latitude_deg", raw.latitude_deg.is_some()),
                ("earth.longitude_deg", raw.longitude_deg.is_some()),
                ("earth.height_m", raw.height_m.is_some()),
                ("earth.vertical", raw.vertical.is_some()),
            ] {
                if given {
                    return Err(err(
                        key,
                        "applies to `model = \"wgs84\"` only: the flat Earth has no place".into(),
                    ));
                }
            }
            Ok(EarthModel::Flat {
                gravity_mps2: match gravity {
                    Some(g) => positive("gravity_mps2", g, err)?,
                    None => STANDARD_GRAVITY_MPS2,
                },
            })
        }
        "wgs84" => {
            if gravity.is_some() {
                return Err(err(
                    "gravity_mps2",
                    "applies to `[earth] model = \"flat\"` only: on the WGS-84 Earth gravity \
                     follows from earth.latitude_deg and earth.height_m"
                        .into(),
                ));
            }
            let lat = finite(
                "earth.latitude_deg",
                raw.latitude_deg.unwrap_or(DEFAULT_LATITUDE_DEG),
                err,
            )?;
            if lat.abs() > 89.0 {
                return Err(err(
                    "earth.latitude_deg",
                    format!("expected a latitude in [-89, 89] deg (the north-east-down frame is singular at the poles), got {lat}"),
                ));
            }
            let lon = finite("earth.longitude_deg", raw.longitude_deg.unwrap_or(0.0), err)?;
            if lon.abs() > 180.0 {
                return Err(err(
                    "earth.longitude_deg",
                    format!("expected a longitude in [-180, 180] deg, got {lon}"),
                ));
            }
            let h = finite("earth.height_m", raw.height_m.unwrap_or(0.0), err)?;
            if !(-1000.0..=20_000.0).contains(&h) {
                return Err(err(
                    "earth.height_m",
                    format!("expected a height in [-1000, 20000] m above the ellipsoid (the normal-gravity height series holds there), got {h}"),
                ));
            }
            let vertical = match raw.vertical.as_deref().unwrap_or("held") {
                "held" => Vertical::Held,
                "free" => Vertical::Free,
                other => {
                    return Err(err(
                        "earth.vertical",
                        format!("expected `held` (a known height) or `free` (the unaided, diverging vertical channel), got `{other}`"),
                    ))
                }
            };
            Ok(EarthModel::Round(RoundEarth {
                vertical,
                ..RoundEarth::at(Place::from_deg(lat, lon, h))
            }))
        }
        other => Err(err(
            "earth.model",
            format!(
                "expected `wgs84` (the round, rotating Earth) or `flat` (Woodman's), got `{other}`"
            ),
        )),
    }
}

/// A finite value > 0.
fn positive(key: &str, v: f64, err: &ErrFn) -> Result<f64, ScenarioError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(err(key, format!("expected a finite number > 0, got {v}")))
    }
}

/// Duration (s), rate (Hz) and the number of steps: a whole number of samples, at most 1e12.
fn timing(raw: &RawScenario, err: &ErrFn) -> Result<(f64, f64, u64), ScenarioError> {
    let duration_s = positive(
        "duration_s",
        raw.duration_s.unwrap_or(DEFAULT_DURATION_S),
        err,
    )?;
    let rate_hz = positive("rate_hz", raw.rate_hz.unwrap_or(DEFAULT_RATE_HZ), err)?;
    let steps_f = duration_s * rate_hz;
    let steps = steps_f.round();
    if steps > 1e12 {
        return Err(err(
            "duration_s",
            format!("{steps_f:.3e} samples at rate_hz = {rate_hz:e} is more than 1e12"),
        ));
    }
    if steps < 1.0 || (steps_f - steps).abs() > 1e-9 * steps.max(1.0) {
        return Err(err(
            "duration_s",
            format!(
                "expected a whole number of samples at rate_hz = {rate_hz}, got {steps_f} samples"
            ),
        ));
    }
    Ok((duration_s, rate_hz, steps as u64))
}

/// The mechanisation scheme by strapdown's name (default: accurate).
fn scheme(name: Option<&str>, err: &ErrFn) -> Result<Scheme, ScenarioError> {
    let name = name.unwrap_or(Scheme::Accurate.name());
    Scheme::from_name(name).ok_or_else(|| {
        err(
            "scheme",
            format!(
                "expected one of {}, got `{name}`",
                Scheme::ALL.map(|s| format!("`{}`", s.name())).join(", ")
            ),
        )
    })
}

/// The trajectory with the scenario's gravity in its ideal accelerometer outputs, so a static
/// IMU stays still; an invalid value names its `trajectory.` key.
fn build_trajectory(
    spec: &TrajectorySpec,
    gravity_mps2: f64,
    err: &ErrFn,
) -> Result<strapdown::AnyTrajectory, ScenarioError> {
    spec.build_with_gravity(gravity_mps2).map_err(|e| match e {
        strapdown::TrajectoryError::Invalid { key, expected, got } => err(
            &if key == "gravity_mps2" {
                key
            } else {
                format!("trajectory.{key}")
            },
            format!("expected {expected}, got {got}"),
        ),
        other => err("trajectory", other.to_string()),
    })
}

/// The `[reference]` table: a known statistic of a known quantity inside the run.
fn check_reference(r: &Reference, duration_s: f64, err: &ErrFn) -> Result<(), ScenarioError> {
    if !["mean", "rms", "p50", "p95"].contains(&r.statistic.as_str()) {
        return Err(err(
            "reference.statistic",
            format!("expected mean, rms, p50 or p95, got `{}`", r.statistic),
        ));
    }
    if crate::nav_quantity::NavQuantity::from_name(&r.quantity).is_none() {
        return Err(err(
            "reference.channel",
            format!(
                "expected a channel name such as pos_horizontal_m, got `{}`",
                r.quantity
            ),
        ));
    }
    if !(r.t_s > 0.0 && r.t_s <= duration_s) {
        return Err(err(
            "reference.t_s",
            format!("expected a time in (0, duration_s], got {}", r.t_s),
        ));
    }
    Ok(())
}

/// `terms.bias_calibration_window_s`: > 0 s, and not with the bias calibration switched off.
fn check_calibration(terms: &RawTerms, err: &ErrFn) -> Result<(), ScenarioError> {
    if let Some(w) = terms.bias_calibration_window_s {
        if !(w.is_finite() && w > 0.0) {
            return Err(err(
                "terms.bias_calibration_window_s",
                format!("expected a calibration window > 0 s, got {w}"),
            ));
        }
        if terms.bias_calibrated_at_start == Some(false) {
            return Err(err(
                "terms.bias_calibration_window_s",
                "a calibration window needs the bias calibrated at start: set \
                 terms.bias_calibrated_at_start = true or leave it out"
                    .into(),
            ));
        }
    }
    Ok(())
}

type ErrFn<'a> = dyn Fn(&str, String) -> ScenarioError + 'a;

/// `terms.only` and `terms.without`, each item read as a term (the error names the key).
#[allow(clippy::type_complexity)]
fn term_switches(
    terms: &RawTerms,
    err: &ErrFn,
) -> Result<(Option<Vec<TermSelector>>, Vec<TermSelector>), ScenarioError> {
    let read = |key: &str, items: &[String]| -> Result<Vec<TermSelector>, ScenarioError> {
        items
            .iter()
            .map(|item| TermSelector::parse(item).map_err(|e| err(key, e.to_string())))
            .collect()
    };
    let only = terms
        .only
        .as_deref()
        .map(|items| read("terms.only", items))
        .transpose()?;
    let without = read(
        "terms.without",
        terms.without.as_deref().unwrap_or_default(),
    )?;
    Ok((only, without))
}

fn finite(key: &str, v: f64, err: &ErrFn) -> Result<f64, ScenarioError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(err(key, format!("expected a finite number, got {v}")))
    }
}

fn checkpoint_steps(
    raw: Option<RawCheckpoints>,
    rate_hz: f64,
    steps: u64,
    err: &ErrFn,
) -> Result<Vec<u64>, ScenarioError> {
    let raw = raw.unwrap_or(RawCheckpoints {
        times_s: None,
        log_count: None,
        first_s: None,
    });
    let mut ks: Vec<u64> = match raw.times_s {
        Some(times) => {
            if raw.log_count.is_some() || raw.first_s.is_some() {
                return Err(err(
                    "checkpoints.times_s",
                    "give either times_s or log_count/first_s, not both".into(),
                ));
            }
            if times.is_empty() {
                return Err(err(
                    "checkpoints.times_s",
                    "expected at least one time".into(),
                ));
            }
            let mut ks = Vec::with_capacity(times.len());
            for t in times {
                let k = (t * rate_hz).round();
                if !t.is_finite() || k < 1.0 || k > steps as f64 {
                    return Err(err(
                        "checkpoints.times_s",
                        format!("expected times in [1/rate_hz, duration_s], got {t}"),
                    ));
                }
                ks.push(k as u64);
            }
            ks
        }
        None => {
            let count = raw.log_count.unwrap_or(DEFAULT_LOG_COUNT);
            if count == 0 || count > MAX_CHECKPOINTS {
                return Err(err(
                    "checkpoints.log_count",
                    format!("expected an integer from 1 to {MAX_CHECKPOINTS}, got {count}"),
                ));
            }
            let first = match raw.first_s {
                Some(t) => {
                    let k = (t * rate_hz).round();
                    if !t.is_finite() || k < 1.0 || k > steps as f64 {
                        return Err(err(
                            "checkpoints.first_s",
                            format!("expected a time in [1/rate_hz, duration_s], got {t}"),
                        ));
                    }
                    k as u64
                }
                None => DEFAULT_FIRST_STEPS.min(steps),
            };
            log_spaced_steps(first, steps, count)
        }
    };
    ks.sort_unstable();
    ks.dedup();
    Ok(ks)
}

/// `count` step indices log-spaced from `first` to `last` inclusive (rounded, de-duplicated).
pub fn log_spaced_steps(first: u64, last: u64, count: usize) -> Vec<u64> {
    if count <= 1 || first >= last {
        return vec![last];
    }
    let (a, b) = ((first as f64).ln(), (last as f64).ln());
    let mut ks: Vec<u64> = (0..count)
        .map(|i| (a + (b - a) * i as f64 / (count - 1) as f64).exp().round() as u64)
        .collect();
    ks[count - 1] = last;
    ks.dedup();
    ks
}

fn alignment(raw: RawAlignment, err: &ErrFn) -> Result<Alignment, ScenarioError> {
    let fixed = [
        ("roll_deg", raw.roll_deg),
        ("pitch_deg", raw.pitch_deg),
        ("yaw_deg", raw.yaw_deg),
    ];
    let std = [
        ("roll_std_deg", raw.roll_std_deg),
        ("pitch_std_deg", raw.pitch_std_deg),
        ("yaw_std_deg", raw.yaw_std_deg),
    ];
    let mut a = Alignment::default();
    for i in 0..3 {
        a.fixed_rad[i] = finite(
            &format!("alignment.{}", fixed[i].0),
            fixed[i].1.unwrap_or(0.0),
            err,
        )?
        .to_radians();
        let s = std[i].1.unwrap_or(0.0);
        if !(s.is_finite() && s >= 0.0) {
            return Err(err(
                &format!("alignment.{}", std[i].0),
                format!("expected a standard deviation >= 0 in degrees, got {s}"),
            ));
        }
        a.std_rad[i] = s.to_radians();
    }
    Ok(a)
}

#[cfg(test)]
mod tests {
    use super::*;

    const MIN: &str = "sensor = \"../sensors/mtx.toml\"\nduration_s = 60.0\nrate_hz = 100.0\nruns = 500\nseed = 1\n";

    #[test]
    fn minimal_scenario_has_defaults() {
        let s = Scenario::from_toml_str(MIN, "x/mtx-static-60s.toml").unwrap();
        assert_eq!(s.name, "mtx-static-60s");
        assert_eq!(s.steps(), 6000);
        assert_eq!(*s.checkpoint_steps.first().unwrap(), 10);
        assert_eq!(*s.checkpoint_steps.last().unwrap(), 6000);
        assert!(s.checkpoint_steps.windows(2).all(|w| w[0] < w[1]));
        assert!(strapdown::Trajectory::is_static(&s.trajectory));
        assert_eq!(s.scheme, Scheme::Accurate);
    }

    #[test]
    fn errors_name_file_and_key() {
        let cases = [
            (MIN.replace("rate_hz = 100.0", "rate_hz = -1.0"), "rate_hz"),
            (MIN.replace("runs = 500", "runs = 0"), "runs"),
            (
                MIN.replace("duration_s = 60.0", "duration_s = 60.005"),
                "duration_s",
            ),
            (format!("{MIN}scheme = \"rk4\"\n"), "scheme"),
            (
                format!("{MIN}[trajectory]\nkind = \"coning\"\nhalf_angle_deg = 1.0\nfrequency_hz = -1.0\n"),
                "trajectory.frequency_hz",
            ),
            (
                format!("{MIN}[checkpoints]\ntimes_s = [61.0]\n"),
                "checkpoints.times_s",
            ),
            (
                format!("{MIN}[alignment]\nroll_std_deg = -1.0\n"),
                "alignment.roll_std_deg",
            ),
            (
                format!("{MIN}[terms]\nbias_calibration_window_s = 0.0\n"),
                "terms.bias_calibration_window_s",
            ),
            (
                format!("{MIN}[terms]\nbias_calibrated_at_start = false\nbias_calibration_window_s = 10.0\n"),
                "terms.bias_calibration_window_s",
            ),
            (
                format!("{MIN}[terms]\nonly = [\"gyro.whte_noise\"]\n"),
                "terms.only",
            ),
            (
                format!("{MIN}[terms]\nwithout = [\"gyro\", \"magneto\"]\n"),
                "terms.without",
            ),
            (format!("{MIN}[earth]\nmodel = \"sphere\"\n"), "earth.model"),
            (format!("{MIN}[earth]\nlatitude_deg = 95.0\n"), "earth.latitude_deg"),
            (format!("{MIN}[earth]\nlatitude_deg = nan\n"), "earth.latitude_deg"),
            (format!("{MIN}[earth]\nlongitude_deg = -181.0\n"), "earth.longitude_deg"),
            (format!("{MIN}[earth]\nheight_m = 1e6\n"), "earth.height_m"),
            (format!("{MIN}[earth]\nvertical = \"baro\"\n"), "earth.vertical"),
            (format!("{MIN}gravity_mps2 = 9.8\n"), "gravity_mps2"),
            (
                format!("{MIN}[earth]\nmodel = \"flat\"\nlatitude_deg = 10.0\n"),
                "earth.latitude_deg",
            ),
        ];
        let s = Scenario::from_toml_str(
            &format!("{MIN}[terms]\nbias_calibration_window_s = 10.0\n"),
            "s.toml",
        )
        .unwrap();
        assert!(s.bias_calibrated_at_start && s.bias_calibration_window_s == Some(10.0));
        let s = Scenario::from_toml_str(
            &format!("{MIN}[terms]\nonly = [\"white_noise\"]\nwithout = [\"accel\"]\n"),
            "s.toml",
        )
        .unwrap();
        assert_eq!(s.only.as_ref().map(|o| o[0].text()), Some("white_noise"));
        assert_eq!(s.without[0].terms().count(), noise::Effect::ALL.len());
        for (text, key) in cases {
            let e = Scenario::from_toml_str(&text, "s.toml").unwrap_err();
            assert_eq!(e.key, key, "{e}");
            assert!(e.to_string().starts_with("s.toml: key"), "{e}");
        }
        let e =
            Scenario::from_toml_str(&format!("{MIN}[trajectory]\nkind = \"spiral\"\n"), "s.toml")
                .unwrap_err();
        assert!(e.to_string().contains("spiral"), "{e}");
        let e = Scenario::from_toml_str(&format!("{MIN}colour = 3\n"), "s.toml").unwrap_err();
        assert!(e.to_string().contains("colour"), "{e}");
        let e = Scenario::from_toml_str("runs = 3\n", "s.toml").unwrap_err();
        assert!(e.to_string().contains("sensor"), "{e}");
    }

    #[test]
    fn log_spacing_is_inclusive_and_unique() {
        assert_eq!(log_spaced_steps(10, 1000, 3), vec![10, 100, 1000]);
        let ks = log_spaced_steps(1, 20, 50);
        assert_eq!(ks.len(), 20);
        assert_eq!(log_spaced_steps(5, 5, 10), vec![5]);
    }
}
