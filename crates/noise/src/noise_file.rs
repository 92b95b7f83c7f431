//! IMU noise files of visual-inertial tools, written and read: Kalibr's `imu.yaml`, OpenVINS's
//! `kalibr_imu_chain.yaml` (the same keys under `imu0:`) and VINS-Fusion's config keys.
//!
//! The four values are continuous-time densities of the two terms these estimators model
//! (docs/noise-files.md, after the Kalibr wiki "IMU Noise Model"):
//! - noise density sigma_g (rad/s/sqrt(Hz)), sigma_a (m/s^2/sqrt(Hz)): the white-noise density N of
//!   IEEE 952, the Allan deviation of the -1/2 slope line read at tau = 1 s;
//! - random walk sigma_bg (rad/s^2/sqrt(Hz)), sigma_ba (m/s^3/sqrt(Hz)): the rate random walk K of
//!   IEEE 952, the +1/2 slope line read at tau = 3 s.
//!
//! Their discrete-time forms at sample interval dt are sigma_d = sigma / sqrt(dt) for the noise and
//! sigma_bd = sigma_b * sqrt(dt) for the random walk (Kalibr wiki); the files hold the continuous
//! values. One value per sensor: these tools take no per-axis values, so the largest of the three
//! axes is written (the worst axis, stated in the file) and each axis is given in a comment.

pub use crate::config::error::NoiseFileError;
use crate::model::{AxisModel, SensorModel, TriadModel};
use crate::temperature::TemperatureProfile;
use crate::terms::rate_random_walk::RateRandomWalk;
use crate::terms::white_noise::WhiteNoise;
use std::fmt::Write as _;

/// Which tool's keys.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Flavor {
    /// Kalibr `imu.yaml`: `gyroscope_noise_density`, `gyroscope_random_walk`,
    /// `accelerometer_noise_density`, `accelerometer_random_walk`, `rostopic`, `update_rate`.
    Kalibr,
    /// OpenVINS `kalibr_imu_chain.yaml`: Kalibr's keys under `imu0:`, with `T_i_b`, `time_offset`
    /// and `model: "kalibr"`.
    OpenVins,
    /// VINS-Fusion config keys `gyr_n`, `gyr_w`, `acc_n`, `acc_w` (same continuous-time meaning).
    VinsFusion,
}

impl Flavor {
    pub fn name(self) -> &'static str {
        match self {
            Flavor::Kalibr => "kalibr",
            Flavor::OpenVins => "openvins",
            Flavor::VinsFusion => "vins-fusion",
        }
    }
}

/// One per-axis value and how it was obtained (written as a comment).
#[derive(Clone, Debug, PartialEq)]
pub struct AxisValue {
    pub value: f64,
    /// e.g. "IEEE 952 fit" or "bound: random-walk line through the Allan deviation at 1000 s".
    pub how: String,
}

/// The values of a noise file, SI continuous-time, per axis (x, y, z).
#[derive(Clone, Debug, PartialEq)]
pub struct NoiseValues {
    pub gyro_noise_density: [AxisValue; 3],
    pub gyro_random_walk: [AxisValue; 3],
    pub accel_noise_density: [AxisValue; 3],
    pub accel_random_walk: [AxisValue; 3],
    pub rostopic: String,
    pub update_rate_hz: f64,
    /// Where the values come from, for the header comment (e.g. "allan on imu1.csv").
    pub origin: String,
}

impl NoiseValues {
    /// The values of every channel, `per(c)` = (noise density, random walk) of channel `c`.
    pub fn from_channels(
        per: impl Fn(crate::Channel) -> (AxisValue, AxisValue),
        rostopic: String,
        update_rate_hz: f64,
        origin: String,
    ) -> NoiseValues {
        use crate::{Channel, Sensor};
        let density = |s| Channel::of(s).map(|c| per(c).0);
        let walk = |s| Channel::of(s).map(|c| per(c).1);
        NoiseValues {
            gyro_noise_density: density(Sensor::Gyro),
            gyro_random_walk: walk(Sensor::Gyro),
            accel_noise_density: density(Sensor::Accel),
            accel_random_walk: walk(Sensor::Accel),
            rostopic,
            update_rate_hz,
            origin,
        }
    }
}

/// The margin multiplied into the four written values, and the name of the setting that gave it
/// (written into the header comment: a front end passes its own name for it, e.g. its option).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Inflation<'a> {
    /// The factor (1 = the values as measured).
    pub factor: f64,
    /// The setting's name as the reader of the file knows it.
    pub setting: &'a str,
}

impl Inflation<'static> {
    /// The values as measured (factor 1: the header says nothing about a margin).
    pub const NONE: Inflation<'static> = Inflation {
        factor: 1.0,
        setting: "inflate",
    };
}

/// One written value: the Kalibr / OpenVINS key, the VINS-Fusion key, the unit and meaning (a
/// comment), and the per-axis values.
struct Row<'a> {
    key: &'static str,
    short: &'static str,
    unit: &'static str,
    axes: &'a [AxisValue; 3],
}

/// The four values in the order the files list them.
fn rows(v: &NoiseValues) -> [Row<'_>; 4] {
    [
        Row {
            key: "accelerometer_noise_density",
            short: "acc_n",
            unit: "m/s^2/sqrt(Hz), accelerometer white noise",
            axes: &v.accel_noise_density,
        },
        Row {
            key: "accelerometer_random_walk",
            short: "acc_w",
            unit: "m/s^3/sqrt(Hz), accelerometer bias random walk",
            axes: &v.accel_random_walk,
        },
        Row {
            key: "gyroscope_noise_density",
            short: "gyr_n",
            unit: "rad/s/sqrt(Hz), gyro white noise",
            axes: &v.gyro_noise_density,
        },
        Row {
            key: "gyroscope_random_walk",
            short: "gyr_w",
            unit: "rad/s^2/sqrt(Hz), gyro bias random walk",
            axes: &v.gyro_random_walk,
        },
    ]
}

/// The largest of the three axes (the one value per sensor these tools take).
fn worst(axes: &[AxisValue; 3]) -> f64 {
    axes.iter().map(|x| x.value).fold(f64::NAN, f64::max)
}

/// A model axis's noise density and random walk for a noise file: its white noise N (before and
/// after the output filter in quadrature, `AxisModel::white_noise_density`), and its rate
/// random walk K or, where it has none, the largest random walk its Allan curve allows over the
/// averaging times `taus_s` (the +1/2 line sigma^2 = K^2 tau / 3, IEEE 952 Table C.1, touching
/// the model's curve, which covers its bias instability there; `how_tau(tau)` names the tau of
/// contact in the value's comment). `None` without white noise or averaging times. `how` says
/// where the values come from (e.g. "corrected model").
pub fn axis_noise_values(
    axis: &AxisModel,
    taus_s: &[f64],
    how: &str,
    how_tau: &dyn Fn(f64) -> String,
) -> Option<(AxisValue, AxisValue)> {
    let n = AxisValue {
        value: axis.white_noise_density()?,
        how: how.into(),
    };
    let k = match axis.get::<RateRandomWalk>().map(RateRandomWalk::density) {
        Some(k) => AxisValue {
            value: k,
            how: how.into(),
        },
        None => {
            let (k, tau) = taus_s
                .iter()
                .map(|&tau| ((axis.allan_variance(tau) * 3.0 / tau).sqrt(), tau))
                .min_by(|x, y| x.0.total_cmp(&y.0))?;
            AxisValue {
                value: k,
                how: format!(
                    "no rate random walk in the model; bound: +1/2 line touching its Allan curve at {}",
                    how_tau(tau)
                ),
            }
        }
    };
    Some((n, k))
}

/// Write a noise file. `inflation` multiplies the four written values (factor 1 = as measured);
/// the measured values stay in the comments.
pub fn write_noise_file(v: &NoiseValues, flavor: Flavor, inflation: Inflation<'_>) -> String {
    let rows = rows(v);
    let mut s = String::new();
    write_header(&mut s, v, flavor, inflation, &rows);
    let indent = if flavor == Flavor::OpenVins { "  " } else { "" };
    if flavor == Flavor::OpenVins {
        s.push_str("imu0:\n  T_i_b:\n    - [1.0, 0.0, 0.0, 0.0]\n    - [0.0, 1.0, 0.0, 0.0]\n    - [0.0, 0.0, 1.0, 0.0]\n    - [0.0, 0.0, 0.0, 1.0]\n");
    }
    if flavor == Flavor::VinsFusion {
        write_vins_fusion_note(&mut s, v, inflation.factor);
        let _ = writeln!(s, "imu_topic: \"{}\"", v.rostopic);
    }
    for row in &rows {
        let name = if flavor == Flavor::VinsFusion {
            row.short
        } else {
            row.key
        };
        let _ = writeln!(
            s,
            "{indent}{name}: {}  # [{}]",
            sci(worst(row.axes) * inflation.factor),
            row.unit
        );
    }
    if flavor != Flavor::VinsFusion {
        let _ = writeln!(s, "{indent}rostopic: {}", v.rostopic);
        let _ = writeln!(s, "{indent}update_rate: {}", rate_text(v.update_rate_hz));
    }
    if flavor == Flavor::OpenVins {
        write_openvins_intrinsics(&mut s);
    }
    s
}

/// The header comments: where the values come from, what they mean, the margin if any, and each
/// axis's value with how it was obtained.
fn write_header(
    s: &mut String,
    v: &NoiseValues,
    flavor: Flavor,
    inflation: Inflation<'_>,
    rows: &[Row<'_>; 4],
) {
    if flavor != Flavor::Kalibr {
        s.push_str("%YAML:1.0\n");
    }
    let _ = writeln!(
        s,
        "# IMU noise ({} keys) written by imudrift from {}.",
        flavor.name(),
        v.origin
    );
    s.push_str(
        "# Continuous-time densities: noise density = white noise N, the value at tau = 1 s of the\n\
         # Allan deviation's -1/2 line; random walk = rate random walk K, the +1/2 line's value at\n\
         # tau = 3 s (IEEE 952 Annex C); each axis below says where its value comes from.\n\
         # Discrete at dt: noise sigma/sqrt(dt), random walk sigma*sqrt(dt).\n\
         # One value per sensor: the largest of the three axes (worst axis); each axis below.\n",
    );
    if inflation.factor != 1.0 {
        let _ = writeln!(
            s,
            "# The written values are the measured ones multiplied by {} ({}), a margin for what the\n# two-term model leaves out (bias instability, temperature, vibration); the measured values are below.",
            inflation.factor, inflation.setting
        );
    }
    for row in rows {
        let per_axis: Vec<String> = row
            .axes
            .iter()
            .zip(["x", "y", "z"])
            .map(|(a, n)| format!("{n} {} ({})", sci(a.value), a.how))
            .collect();
        let _ = writeln!(s, "# {} [{}]: {}", row.key, row.unit, per_axis.join(", "));
    }
}

/// A rate for a noise file: 7 significant digits at most, no trailing zeros (`200` for a rate
/// of 199.99999995867375 Hz measured from timestamps, whose rounding lies far below).
fn rate_text(hz: f64) -> String {
    if !(hz.is_finite() && hz > 0.0) {
        return format!("{hz}");
    }
    let decimals = (6 - hz.log10().floor() as i32).max(0) as usize;
    let text = format!("{hz:.decimals$}");
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text
    }
}

/// VINS-Fusion's preintegration adds (value * dt)^2 per sample (mid-point rule: half of it for
/// the white noise), so a continuous density acts smaller there; the comment gives the values that
/// make it carry the continuous model, for users who want that (docs/noise-files.md).
fn write_vins_fusion_note(s: &mut String, v: &NoiseValues, inflate: f64) {
    let dt = 1.0 / v.update_rate_hz;
    if dt.is_finite() && dt > 0.0 {
        let _ = writeln!(
            s,
            "# VINS-Fusion applies these per sample; to make its propagation carry the continuous model at {} Hz use\n# gyr_n {}, acc_n {}, gyr_w {}, acc_w {} (sqrt(2/dt) N and K/sqrt(dt), worst axis).",
            rate_text(v.update_rate_hz),
            sci(worst(&v.gyro_noise_density) * inflate * (2.0 / dt).sqrt()),
            sci(worst(&v.accel_noise_density) * inflate * (2.0 / dt).sqrt()),
            sci(worst(&v.gyro_random_walk) * inflate / dt.sqrt()),
            sci(worst(&v.accel_random_walk) * inflate / dt.sqrt()),
        );
    }
}

/// OpenVINS's parser requires the intrinsics too; "calibrated" with identity matrices and a zero
/// g-sensitivity says the IMU is taken as already corrected.
fn write_openvins_intrinsics(s: &mut String) {
    s.push_str("  time_offset: 0.0\n  model: \"calibrated\"\n");
    for (key, rows) in [
        ("Tw", EYE3),
        ("R_IMUtoGYRO", EYE3),
        ("Ta", EYE3),
        ("R_IMUtoACC", EYE3),
        ("Tg", ["0.0, 0.0, 0.0"; 3]),
    ] {
        let _ = writeln!(s, "  {key}:");
        for r in rows {
            let _ = writeln!(s, "    - [{r}]");
        }
    }
}

const EYE3: [&str; 3] = ["1.0, 0.0, 0.0", "0.0, 1.0, 0.0", "0.0, 0.0, 1.0"];

/// Five significant digits in scientific notation with a signed exponent (`1.6968e-04`):
/// Kalibr reads with PyYAML, whose YAML 1.1 floats need the dot and the exponent's sign
/// (`1e-3` would be read as text).
fn sci(v: f64) -> String {
    let t = format!("{v:.4e}");
    match t.split_once('e') {
        Some((m, e)) => {
            let (sign, digits) = match e.strip_prefix('-') {
                Some(d) => ('-', d),
                None => ('+', e),
            };
            format!("{m}e{sign}{digits:0>2}")
        }
        None => t,
    }
}

/// The key spellings of each value: Kalibr / OpenVINS, then VINS-Fusion.
const KEYS: [(&str, &str); 4] = [
    ("gyroscope_noise_density", "gyr_n"),
    ("gyroscope_random_walk", "gyr_w"),
    ("accelerometer_noise_density", "acc_n"),
    ("accelerometer_random_walk", "acc_w"),
];

/// One scalar of a noise file: its key path (`["imu0", "gyroscope_noise_density"]`), its text
/// and its 1-based line.
struct Entry {
    path: Vec<String>,
    value: String,
    line: usize,
}

/// A container being read: a mapping (waiting for a key, or holding the key of the value being
/// read) or a sequence; `as_key` when the container is itself a (complex) mapping key.
enum Frame {
    Map { key: Option<String>, as_key: bool },
    Seq { as_key: bool },
}

/// Collects every scalar reachable through mapping keys (the parser's events, YAML 1.2 as
/// `yaml-rust2` reads it: flow maps, quoting, anchors and aliases, block scalars), in file
/// order: a later duplicate key comes later, so the last one wins as YAML says.
#[derive(Default)]
struct Collector {
    stack: Vec<Frame>,
    path: Vec<String>,
    anchors: std::collections::HashMap<usize, String>,
    entries: Vec<Entry>,
}

impl Collector {
    /// A container starts: under the current key (or as a key, or in a sequence).
    fn open(&mut self, map: bool) {
        let as_key = matches!(self.stack.last(), Some(Frame::Map { key: None, .. }));
        let segment = match self.stack.last() {
            Some(Frame::Map { key: Some(k), .. }) => k.clone(),
            _ => "-".to_string(),
        };
        self.path.push(segment);
        self.stack.push(if map {
            Frame::Map { key: None, as_key }
        } else {
            Frame::Seq { as_key }
        });
    }

    /// A container ends: it was the value of its parent's key (or a key itself).
    fn close(&mut self) {
        self.path.pop();
        let as_key = match self.stack.pop() {
            Some(Frame::Map { as_key, .. } | Frame::Seq { as_key }) => as_key,
            None => false,
        };
        if let Some(Frame::Map { key, .. }) = self.stack.last_mut() {
            *key = as_key.then(|| "?".to_string());
        }
    }

    fn scalar(&mut self, value: String, line: usize) {
        match self.stack.last_mut() {
            Some(Frame::Map {
                key: key @ None, ..
            }) => *key = Some(value),
            Some(Frame::Map { key, .. }) => {
                let key = key.take();
                // Only a key at the top level or one level down can be the IMU's (`find`): a
                // deeper one is not kept, so deep nesting copies no long paths (linear time).
                if self.path.len() <= 2 {
                    let mut path = self.path[1..].to_vec();
                    path.extend(key);
                    self.entries.push(Entry { path, value, line });
                }
            }
            _ => {}
        }
    }
}

impl yaml_rust2::parser::MarkedEventReceiver for Collector {
    fn on_event(&mut self, ev: yaml_rust2::Event, mark: yaml_rust2::scanner::Marker) {
        use yaml_rust2::Event;
        match ev {
            Event::Scalar(value, _, anchor, _) => {
                if anchor > 0 {
                    self.anchors.insert(anchor, value.clone());
                }
                self.scalar(value, mark.line());
            }
            Event::Alias(id) => {
                let value = self.anchors.get(&id).cloned().unwrap_or_default();
                self.scalar(value, mark.line());
            }
            Event::MappingStart(..) => self.open(true),
            Event::SequenceStart(..) => self.open(false),
            Event::MappingEnd | Event::SequenceEnd => self.close(),
            _ => {}
        }
    }
}

/// The scalars of a noise file read as YAML (a leading byte-order mark and OpenCV's `%YAML:1.0`
/// first line, which is not a YAML directive, are skipped), or the parser's error and its line.
fn yaml_entries(text: &str) -> Result<Vec<Entry>, (usize, String)> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let text = match text.strip_prefix("%YAML:") {
        Some(rest) => rest.find('\n').map_or("", |i| &rest[i..]),
        None => text,
    };
    let mut collector = Collector::default();
    yaml_rust2::parser::Parser::new_from_str(text)
        .load(&mut collector, false)
        .map_err(|e| (e.marker().line(), e.info().to_string()))?;
    Ok(collector.entries)
}

/// The entry of `key` where the tools put it: at the top level (Kalibr, VINS-Fusion) or under
/// `imu0:` (OpenVINS); the top level first. The last occurrence wins (YAML: a later duplicate
/// replaces the earlier value).
fn find<'a>(entries: &'a [Entry], key: &str) -> Option<&'a Entry> {
    let at = |prefix: &[&str]| {
        entries.iter().rev().find(|e| {
            e.path.len() == prefix.len() + 1
                && e.path.iter().zip(prefix).all(|(a, b)| a == b)
                && e.path.last().is_some_and(|k| k == key)
        })
    };
    at(&[]).or_else(|| at(&["imu0"]))
}

/// At most the first 40 characters of `text` (and "..." when cut), for messages.
fn prefix(text: &str) -> String {
    match text.char_indices().nth(40) {
        None => text.to_string(),
        Some((at, _)) => format!("{}... ({} bytes)", &text[..at], text.len()),
    }
}

/// Does this text look like a Kalibr / OpenVINS / VINS-Fusion IMU noise file?
pub fn is_noise_file(text: &str) -> bool {
    yaml_entries(text).is_ok_and(|e| {
        KEYS.iter()
            .any(|(a, b)| find(&e, a).is_some() || find(&e, b).is_some())
    })
}

/// Read a noise file as a sensor model: white noise and rate random walk on every axis (the same
/// value on the three axes of a sensor), nothing else. `source` names the file in errors and
/// gives the model its name.
pub fn read_noise_file(text: &str, source: &str) -> Result<SensorModel, NoiseFileError> {
    let err = |line: Option<usize>, message: String| NoiseFileError {
        file: source.to_string(),
        line,
        message,
    };
    let entries = yaml_entries(text)
        .map_err(|(line, info)| err(Some(line), format!("not a YAML file: {info}")))?;
    let mut values = [0.0f64; 4];
    for (slot, (long, short)) in KEYS.iter().enumerate() {
        let found = find(&entries, long).or_else(|| find(&entries, short)).ok_or_else(|| {
            err(
                None,
                format!(
                    "no `{long}` (or `{short}`) at the top level or under `imu0:`: an IMU noise file gives gyroscope_noise_density, gyroscope_random_walk, accelerometer_noise_density and accelerometer_random_walk"
                ),
            )
        })?;
        let key = found.path.last().map_or("", String::as_str);
        let (text_value, line) = (found.value.trim(), found.line);
        let v: f64 = text_value.parse().map_err(|_| {
            err(
                Some(line),
                format!(
                    "key `{key}`: expected a number (continuous-time density, SI), found `{}`",
                    prefix(text_value)
                ),
            )
        })?;
        if !v.is_finite() {
            return Err(err(
                Some(line),
                format!("key `{key}`: {} is beyond the range of numbers (a finite value >= 0 is expected)", prefix(text_value)),
            ));
        }
        if v < 0.0 {
            return Err(err(
                Some(line),
                format!(
                    "key `{key}`: expected a value >= 0, found {}",
                    prefix(text_value)
                ),
            ));
        }
        values[slot] = v;
    }
    // Both values are finite and >= 0 (checked above), so the constructors accept them.
    let axis = |n: f64, k: f64| {
        let mut axis = AxisModel::default();
        if n > 0.0 {
            axis.set_term(WhiteNoise::new(n).expect("checked above"));
        }
        if k > 0.0 {
            axis.set_term(RateRandomWalk::new(k).expect("checked above"));
        }
        axis
    };
    let triad = |n: f64, k: f64| TriadModel {
        axes: [axis(n, k), axis(n, k), axis(n, k)],
    };
    let name = std::path::Path::new(source)
        .file_stem()
        .map_or("noise file".to_string(), |s| {
            s.to_string_lossy().to_string()
        });
    let rate = find(&entries, "update_rate").map(|e| prefix(e.value.trim()));
    Ok(SensorModel {
        name,
        description: Some(format!(
            "from the IMU noise file {source}{}: white noise and bias random walk only",
            rate.map(|r| format!(" (update_rate {r} Hz)"))
                .unwrap_or_default()
        )),
        gyro: triad(values[0], values[1]),
        accel: triad(values[2], values[3]),
        temperature: TemperatureProfile::default(),
        temperature_reference_c: 25.0,
    })
}
