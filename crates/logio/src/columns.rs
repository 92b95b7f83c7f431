//! Which quantity and unit a log column holds, from its header name: the names robotics and
//! navigation logs use (`gyro_x`, `gyr_x`, `wx`, `omega_x`, `angular_velocity.x`, `acc_x`,
//! `accel_x`, `linear_acceleration.x`, `t`, `time`, `timestamp`, `temp`, ...) and the unit
//! suffixes they carry (`gyro_x_dps`, `gyro_x_rad_s`, `acc_x_g`, `acc_x_mps2`, `t_ms`, `time_ns`,
//! `gyro_x[deg/s]`, `acc_x (m/s^2)`). `rostopic echo -p` columns (`field.angular_velocity.x`,
//! `%time` in ns) are read too.
//!
//! No guessing: a column whose name says neither a known quantity nor axis is skipped (and listed);
//! a unit suffix that is not one of the known spellings makes the column skipped too.

use crate::error::{Problem, Setting, SettingNames};
use crate::units::{AccelUnit, GyroUnit, TimeUnit};
use noise::{Channel, Sensor};

/// What a column holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quantity {
    Time,
    /// A gyro or accelerometer channel.
    Imu(Channel),
    Temperature,
}

impl Quantity {
    /// The canonical channel name (docs/cli.md).
    pub fn channel(self) -> &'static str {
        match self {
            Quantity::Time => "t",
            Quantity::Imu(c) => c.name(),
            Quantity::Temperature => "temp",
        }
    }

    /// The sensor of a gyro or accelerometer channel.
    pub fn sensor(self) -> Option<Sensor> {
        match self {
            Quantity::Imu(c) => Some(c.sensor()),
            _ => None,
        }
    }

    /// The quantity of a canonical channel name.
    pub fn of_channel(name: &str) -> Option<Quantity> {
        match name {
            "t" => Some(Quantity::Time),
            "temp" => Some(Quantity::Temperature),
            _ => Channel::from_name(name).map(Quantity::Imu),
        }
    }
}

/// A unit a column name states.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NamedUnit {
    Gyro(GyroUnit),
    Accel(AccelUnit),
    Time(TimeUnit),
    Celsius,
}

/// What a header name says: the quantity and, when the name carries one, the unit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Recognised {
    pub quantity: Quantity,
    pub unit: Option<NamedUnit>,
}

/// Why a column is not used.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum NotRecognised {
    /// The name is not a quantity the reader knows.
    Unknown,
    /// A known quantity with a unit suffix that is not one of the known spellings.
    Unit(String),
}

const GYRO_WORDS: [&str; 11] = [
    "gyro",
    "gyr",
    "gyroscope",
    "w",
    "omega",
    "angular",
    "ang",
    "g",
    "angularvelocity",
    "angvel",
    "angularrate",
];
const ACCEL_WORDS: [&str; 10] = [
    "acc",
    "accel",
    "accelerometer",
    "a",
    "linear",
    "lin",
    "acceleration",
    "linearacceleration",
    "linacc",
    "specificforce",
];
/// Words that make a gyro- or accelerometer-like name something else (an estimate's bias, a
/// covariance, a standard deviation): such columns are not samples.
const NOT_SAMPLES: [&str; 9] = [
    "bias",
    "cov",
    "covariance",
    "std",
    "stddev",
    "var",
    "variance",
    "offset",
    "scale",
];
const TIME_WORDS: [&str; 6] = ["t", "time", "timestamp", "stamp", "%time", "times"];
const TEMP_WORDS: [&str; 3] = ["temp", "temperature", "tmp"];

fn axis_of(token: &str) -> Option<usize> {
    match token {
        "x" => Some(0),
        "y" => Some(1),
        "z" => Some(2),
        _ => None,
    }
}

/// Recognise a header name.
pub fn recognise(name: &str) -> Result<Recognised, NotRecognised> {
    let lower = name.trim().to_ascii_lowercase();
    // A unit in brackets: `gyro_x[deg/s]`, `acc_x (m/s^2)`.
    let (stem, bracket_unit) = match lower.find(['[', '(']) {
        Some(i) => {
            let unit = lower[i + 1..]
                .trim_end_matches([']', ')'])
                .trim()
                .to_string();
            (lower[..i].trim().to_string(), Some(unit))
        }
        None => (lower.clone(), None),
    };
    let stem = stem.strip_prefix("field.").unwrap_or(&stem);
    let all: Vec<&str> = stem
        .split(['_', '.', '-', ' ', '/'])
        .filter(|t| !t.is_empty())
        .collect();
    if all.iter().any(|t| NOT_SAMPLES.contains(t)) {
        return Err(NotRecognised::Unknown);
    }
    // Words before the quantity are a prefix (`imu_gyro_x`, `imu0.angular_velocity.x`).
    let is_word = |t: &str| {
        // A word glued to its axis letter (`gyrx`); split at the last character, not byte.
        let glued = match t.char_indices().last() {
            Some((i, _)) if i > 0 => {
                axis_of(&t[i..]).is_some()
                    && (GYRO_WORDS.contains(&&t[..i]) || ACCEL_WORDS.contains(&&t[..i]))
            }
            _ => false,
        };
        GYRO_WORDS.contains(&t)
            || ACCEL_WORDS.contains(&t)
            || TIME_WORDS.contains(&t)
            || TEMP_WORDS.contains(&t)
            || glued
    };
    let start = all.iter().position(|t| is_word(t)).unwrap_or(0);
    let tokens = &all[start..];
    let first = *tokens.first().ok_or(NotRecognised::Unknown)?;
    // The unit tokens: what follows the quantity (and axis), or the bracket.
    let unit_text = |rest: &[&str]| -> Option<String> {
        match (&bracket_unit, rest.is_empty()) {
            (Some(u), _) => Some(u.clone()),
            (None, false) => Some(rest.join("_")),
            (None, true) => None,
        }
    };
    // Time and temperature: a word, then an optional unit.
    if TIME_WORDS.contains(&first) {
        let unit = match unit_text(&tokens[1..]) {
            // `rostopic echo -p` writes `%time` in nanoseconds.
            None if first == "%time" => Some(TimeUnit::Ns),
            None => None,
            Some(u) => Some(time_unit(&u).ok_or(NotRecognised::Unit(u))?),
        };
        return Ok(Recognised {
            quantity: Quantity::Time,
            unit: unit.map(NamedUnit::Time),
        });
    }
    if TEMP_WORDS.contains(&first) {
        return match unit_text(&tokens[1..]) {
            None => Ok(Recognised {
                quantity: Quantity::Temperature,
                unit: None,
            }),
            Some(u) if ["c", "degc", "deg_c", "celsius", "°c"].contains(&u.as_str()) => {
                Ok(Recognised {
                    quantity: Quantity::Temperature,
                    unit: Some(NamedUnit::Celsius),
                })
            }
            Some(u) => Err(NotRecognised::Unit(u)),
        };
    }
    // Gyro or accelerometer: a quantity word (the axis may be glued to it: `wx`, `gyrox`), words
    // that qualify it (`velocity`, `out`, `meas`, `raw`), the axis, then an optional unit.
    let (is_gyro, axis_at, glued) = {
        let split_glued = |t: &str| -> Option<(String, usize)> {
            // Split before the last character (a name may hold any UTF-8).
            let (i, _) = t.char_indices().last()?;
            let (head, last) = t.split_at(i);
            Some((head.to_string(), axis_of(last)?))
        };
        if let Some((head, axis)) = split_glued(first) {
            if GYRO_WORDS.contains(&head.as_str()) {
                (true, 0, Some(axis))
            } else if ACCEL_WORDS.contains(&head.as_str()) {
                (false, 0, Some(axis))
            } else {
                (GYRO_WORDS.contains(&first), usize::MAX, None)
            }
        } else {
            (GYRO_WORDS.contains(&first), usize::MAX, None)
        }
    };
    let is_accel = ACCEL_WORDS.contains(&first) || (glued.is_some() && !is_gyro);
    if !(is_gyro || is_accel) {
        return Err(NotRecognised::Unknown);
    }
    let (axis, rest) = match glued {
        Some(axis) => (axis, &tokens[axis_at + 1..]),
        None => {
            let k = tokens[1..]
                .iter()
                .position(|t| axis_of(t).is_some())
                .ok_or(NotRecognised::Unknown)?
                + 1;
            // Between the quantity word and the axis only qualifiers, never another quantity.
            if tokens[1..k]
                .iter()
                .any(|t| TIME_WORDS.contains(t) || TEMP_WORDS.contains(t))
            {
                return Err(NotRecognised::Unknown);
            }
            (axis_of(tokens[k]).expect("found above"), &tokens[k + 1..])
        }
    };
    let unit = match unit_text(rest) {
        None => None,
        Some(u) if is_gyro => Some(NamedUnit::Gyro(
            gyro_unit(&u).ok_or(NotRecognised::Unit(u))?,
        )),
        Some(u) => Some(NamedUnit::Accel(
            accel_unit(&u).ok_or(NotRecognised::Unit(u))?,
        )),
    };
    Ok(Recognised {
        quantity: Quantity::Imu(Channel::new(
            if is_gyro { Sensor::Gyro } else { Sensor::Accel },
            axis,
        )),
        unit,
    })
}

/// Unit spellings, separators normalised to `_` (`rad/s`, `rad_s`, `rads`, `radps` are one).
fn norm(u: &str) -> String {
    u.replace('²', "2")
        .replace(['°', 'º'], "deg")
        .replace(['/', ' ', '-', '.'], "_")
        .replace("^", "")
}

fn gyro_unit(u: &str) -> Option<GyroUnit> {
    match norm(u).as_str() {
        "rad_s" | "rads" | "radps" | "rad_sec" | "rad_per_s" | "r_s" | "rad_s_1" | "rads_1" => {
            Some(GyroUnit::RadPerS)
        }
        "deg_s" | "degs" | "dps" | "degps" | "deg_sec" | "deg_per_s" | "d_s" | "deg_s_1" => {
            Some(GyroUnit::DegPerS)
        }
        "deg_h" | "dph" | "degph" | "deg_hr" | "deg_per_h" => Some(GyroUnit::DegPerH),
        _ => None,
    }
}

fn accel_unit(u: &str) -> Option<AccelUnit> {
    match norm(u).as_str() {
        "m_s2" | "ms2" | "mps2" | "m_s_2" | "m_ss" | "mpss" | "m_s_s" | "m_per_s2" | "ms_2" => {
            Some(AccelUnit::MPerS2)
        }
        "g" => Some(AccelUnit::G),
        "mg" => Some(AccelUnit::MilliG),
        _ => None,
    }
}

fn time_unit(u: &str) -> Option<TimeUnit> {
    match norm(u).as_str() {
        "s" | "sec" | "secs" | "seconds" => Some(TimeUnit::S),
        "ms" | "msec" => Some(TimeUnit::Ms),
        "us" | "usec" | "µs" => Some(TimeUnit::Us),
        "ns" | "nsec" => Some(TimeUnit::Ns),
        _ => None,
    }
}

/// Where a column's channel or unit came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    /// The column's name.
    Name,
    /// A setting (the column mapping, a unit setting).
    Setting(Setting),
    /// The SI unit the canonical names and hand-mapped columns default to.
    Default,
    /// The fields of a sensor_msgs/Imu message.
    ImuMessage,
    /// ROS REP 103 (sensor_msgs/Imu is in SI units).
    Rep103,
}

impl Source {
    /// In words, a setting named by `names`.
    pub fn render(self, names: SettingNames) -> &'static str {
        match self {
            Source::Name => "name",
            Source::Setting(s) => names(s),
            Source::Default => "default",
            Source::ImuMessage => "sensor_msgs/Imu",
            Source::Rep103 => "REP 103",
        }
    }
}

/// How a file column is used: its channel, the unit its values are in, and where that came from.
#[derive(Clone, Debug, PartialEq)]
pub struct ColumnUse {
    /// The file's column name.
    pub column: String,
    /// What the column holds.
    pub quantity: Quantity,
    /// Its canonical name (`t`, `gx` .. `az`, `temp`).
    pub channel: &'static str,
    /// The unit of the file's values (converted to SI on reading).
    pub unit: &'static str,
    /// How the channel was chosen: by name or by the column mapping.
    pub channel_from: Source,
    /// How the unit was: by name, a unit setting or the SI default.
    pub unit_from: Source,
    /// Factor from the file's unit to SI.
    pub to_si: f64,
}

/// A column not used, and why.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Skipped {
    pub column: String,
    pub reason: SkipReason,
}

/// Why a column is not used.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SkipReason {
    /// Its name is none of the quantities the reader knows.
    NotAQuantity,
    /// A known quantity with a unit suffix the reader does not know.
    UnknownUnit(String),
    /// A second column for `channel`, which is read from `first`.
    Duplicate {
        channel: &'static str,
        first: String,
    },
}

impl Skipped {
    /// The reason in words, settings named by `names`.
    pub fn reason_text(&self, names: SettingNames) -> String {
        let columns = names(Setting::Columns);
        match &self.reason {
            SkipReason::NotAQuantity => {
                "not a quantity imudrift reads (time, gyro, accelerometer, temperature)".into()
            }
            SkipReason::UnknownUnit(u) => format!(
                "unit `{u}` in the name is not one imudrift knows (map the column with {columns} and give the unit option)"
            ),
            SkipReason::Duplicate { channel, first } => format!(
                "also {channel}, read from `{first}`; choose with {columns} {channel}={}",
                self.column
            ),
        }
    }
}

/// The units the reader is given for columns whose names do not state one.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct UnitOptions {
    pub gyro: Option<GyroUnit>,
    pub accel: Option<AccelUnit>,
    pub time: Option<TimeUnit>,
}

/// A column's unit (name, factor to SI, where it came from) as its name or the unit `setting`
/// states it; `None` when neither does. A name and a setting that disagree are an error.
fn stated_unit(
    column: &str,
    from_name: Option<(&'static str, f64)>,
    option: Option<(&'static str, f64)>,
    setting: Setting,
) -> Result<Option<(&'static str, f64, Source)>, Problem> {
    match (from_name, option) {
        (Some(a), Some(b)) if a.0 != b.0 => Err(Problem::UnitConflict {
            column: column.to_string(),
            from_name: a.0,
            setting,
            given: b.0,
        }),
        (Some(a), _) => Ok(Some((a.0, a.1, Source::Name))),
        (None, Some(b)) => Ok(Some((b.0, b.1, Source::Setting(setting)))),
        (None, None) => Ok(None),
    }
}

/// The channel and unit of every column of a header (`None` for a skipped one), and the skipped
/// columns with their reasons. `explicit` are the (channel, column) pairs of the column mapping
/// (checked by the caller to name columns of the header). Errors: a unit the name and the
/// setting disagree on, a gyro or accelerometer column whose unit nothing states.
pub fn map_header(
    names: &[String],
    explicit: &[(String, String)],
    units: UnitOptions,
) -> Result<(Vec<Option<ColumnUse>>, Vec<Skipped>), Problem> {
    let mut uses: Vec<Option<ColumnUse>> = vec![None; names.len()];
    let mut skipped = Vec::new();
    let mut taken: Vec<(&'static str, usize)> = Vec::new();
    // Explicit mappings first: they win over a recognised name for the same channel.
    let mut order: Vec<(usize, Option<Quantity>)> = Vec::new();
    for (canon, col) in explicit {
        if let Some(i) = names.iter().position(|n| n == col) {
            order.push((i, Quantity::of_channel(canon)));
        }
    }
    for i in 0..names.len() {
        if !order.iter().any(|&(j, _)| j == i) {
            order.push((i, None));
        }
    }
    let mut missing_unit: Vec<(String, Sensor)> = Vec::new();
    for (i, forced) in order {
        let name = &names[i];
        let recognised = recognise(name);
        let (quantity, channel_from) = match (forced, &recognised) {
            (Some(q), _) => (q, Source::Setting(Setting::Columns)),
            (None, Ok(r)) => (r.quantity, Source::Name),
            (None, Err(NotRecognised::Unknown)) => {
                skipped.push(Skipped {
                    column: name.clone(),
                    reason: SkipReason::NotAQuantity,
                });
                continue;
            }
            (None, Err(NotRecognised::Unit(u))) => {
                skipped.push(Skipped {
                    column: name.clone(),
                    reason: SkipReason::UnknownUnit(u.clone()),
                });
                continue;
            }
        };
        let channel = quantity.channel();
        if let Some(&(_, j)) = taken.iter().find(|(c, _)| *c == channel) {
            skipped.push(Skipped {
                column: name.clone(),
                reason: SkipReason::Duplicate {
                    channel,
                    first: names[j].clone(),
                },
            });
            continue;
        }
        // The unit the name states, if it is one of this quantity's.
        let named = match (&recognised, quantity) {
            (Ok(r), _) if r.quantity == quantity => r.unit,
            (Ok(r), Quantity::Imu(c)) if r.quantity.sensor() == Some(c.sensor()) => r.unit,
            _ => None,
        };
        // Canonical names and explicit mappings default to SI (docs/cli.md); other recognised
        // names need their unit stated.
        let may_default =
            channel_from == Source::Setting(Setting::Columns) || name.trim() == channel;
        let (unit, to_si, unit_from) = match quantity {
            Quantity::Imu(c) => {
                let (sensor, from_name, option, setting, si_unit) = match c.sensor() {
                    Sensor::Gyro => (
                        Sensor::Gyro,
                        match named {
                            Some(NamedUnit::Gyro(u)) => Some((u.name(), u.to_si())),
                            _ => None,
                        },
                        units.gyro.map(|u| (u.name(), u.to_si())),
                        Setting::GyroUnit,
                        "rad/s",
                    ),
                    _ => (
                        Sensor::Accel,
                        match named {
                            Some(NamedUnit::Accel(u)) => Some((u.name(), u.to_si())),
                            _ => None,
                        },
                        units.accel.map(|u| (u.name(), u.to_si())),
                        Setting::AccelUnit,
                        "m/s^2",
                    ),
                };
                match stated_unit(name, from_name, option, setting)? {
                    Some(u) => u,
                    None if may_default => (si_unit, 1.0, Source::Default),
                    None => {
                        missing_unit.push((name.clone(), sensor));
                        ("", f64::NAN, Source::Default)
                    }
                }
            }
            Quantity::Time => {
                let from_name = match named {
                    Some(NamedUnit::Time(u)) => Some((u.name(), u.to_si())),
                    _ => None,
                };
                let option = units.time.map(|u| (u.name(), u.to_si()));
                stated_unit(name, from_name, option, Setting::TimeUnit)?.unwrap_or((
                    "s",
                    1.0,
                    Source::Default,
                ))
            }
            Quantity::Temperature => (
                "degC",
                1.0,
                if named.is_some() {
                    Source::Name
                } else {
                    Source::Default
                },
            ),
        };
        taken.push((channel, i));
        uses[i] = Some(ColumnUse {
            column: name.clone(),
            quantity,
            channel,
            unit,
            channel_from,
            unit_from,
            to_si,
        });
    }
    if !missing_unit.is_empty() {
        return Err(Problem::UnitMissing {
            columns: missing_unit,
        });
    }
    skipped.sort_by_key(|s| names.iter().position(|n| *n == s.column));
    Ok((uses, skipped))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn q(name: &str) -> (Quantity, Option<NamedUnit>) {
        let r = recognise(name).unwrap_or_else(|e| panic!("{name}: {e:?}"));
        (r.quantity, r.unit)
    }

    #[test]
    fn the_usual_names_and_suffixes() {
        use AccelUnit as A;
        use GyroUnit as G;
        use NamedUnit as U;
        use Quantity::*;
        let cases: &[(&str, Quantity, Option<NamedUnit>)] = &[
            ("gx", Imu(Channel::Gx), None),
            ("az", Imu(Channel::Az), None),
            ("gyro_x", Imu(Channel::Gx), None),
            ("gyr_y", Imu(Channel::Gy), None),
            ("wx", Imu(Channel::Gx), None),
            ("omega_z", Imu(Channel::Gz), None),
            ("angular_velocity.x", Imu(Channel::Gx), None),
            ("field.angular_velocity.y", Imu(Channel::Gy), None),
            ("gyro_x_dps", Imu(Channel::Gx), Some(U::Gyro(G::DegPerS))),
            ("gyro_x_rad_s", Imu(Channel::Gx), Some(U::Gyro(G::RadPerS))),
            (
                "Gyro_X [deg/s]",
                Imu(Channel::Gx),
                Some(U::Gyro(G::DegPerS)),
            ),
            ("gyro_out_x", Imu(Channel::Gx), None),
            ("gyro_meas_z", Imu(Channel::Gz), None),
            ("acc_x", Imu(Channel::Ax), None),
            ("accel_y", Imu(Channel::Ay), None),
            ("linear_acceleration.z", Imu(Channel::Az), None),
            ("acc_x_g", Imu(Channel::Ax), Some(U::Accel(A::G))),
            ("acc_x_mps2", Imu(Channel::Ax), Some(U::Accel(A::MPerS2))),
            (
                "accel_z (m/s^2)",
                Imu(Channel::Az),
                Some(U::Accel(A::MPerS2)),
            ),
            ("accx_mg", Imu(Channel::Ax), Some(U::Accel(A::MilliG))),
            ("t", Time, None),
            ("t_s", Time, Some(U::Time(TimeUnit::S))),
            ("time", Time, None),
            ("timestamp", Time, None),
            ("timestamp_ns", Time, Some(U::Time(TimeUnit::Ns))),
            ("time_ms", Time, Some(U::Time(TimeUnit::Ms))),
            ("t_us", Time, Some(U::Time(TimeUnit::Us))),
            ("%time", Time, Some(U::Time(TimeUnit::Ns))),
            ("temp", Temperature, None),
            ("temperature_c", Temperature, Some(U::Celsius)),
            (
                "w_RS_S_x [rad s^-1]",
                Imu(Channel::Gx),
                Some(U::Gyro(G::RadPerS)),
            ),
            (
                "a_RS_S_z [m s^-2]",
                Imu(Channel::Az),
                Some(U::Accel(A::MPerS2)),
            ),
            (
                "imu_gyro_y_dps",
                Imu(Channel::Gy),
                Some(U::Gyro(G::DegPerS)),
            ),
            ("imu0/angular_velocity/z", Imu(Channel::Gz), None),
            ("AngularVelocity.X", Imu(Channel::Gx), None),
            ("gyroX", Imu(Channel::Gx), None),
            ("LinearAcceleration_Y", Imu(Channel::Ay), None),
            ("acc_x [m/s²]", Imu(Channel::Ax), Some(U::Accel(A::MPerS2))),
            ("Gyr_Z (°/s)", Imu(Channel::Gz), Some(U::Gyro(G::DegPerS))),
            (
                "Gyroscope x (rad/s)",
                Imu(Channel::Gx),
                Some(U::Gyro(G::RadPerS)),
            ),
            (
                "Acceleration z (m/s^2)",
                Imu(Channel::Az),
                Some(U::Accel(A::MPerS2)),
            ),
            ("Time (s)", Time, Some(U::Time(TimeUnit::S))),
            ("AccX", Imu(Channel::Ax), None),
            ("Gyro_X(dps)", Imu(Channel::Gx), Some(U::Gyro(G::DegPerS))),
        ];
        for &(name, quantity, unit) in cases {
            assert_eq!(q(name), (quantity, unit), "{name}");
        }
    }

    fn text(p: Problem) -> String {
        p.render(&Setting::name)
    }

    fn header(names: &[&str]) -> Vec<String> {
        names.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn a_header_maps_with_units_from_names_options_or_the_si_default() {
        let h = header(&[
            "t_s",
            "gyro_x_dps",
            "gyro_y_dps",
            "gz",
            "acc_x_g",
            "mag_x",
            "temp",
        ]);
        let (uses, skipped) = map_header(&h, &[], UnitOptions::default()).unwrap();
        let got: Vec<_> = uses
            .iter()
            .map(|u| {
                u.as_ref()
                    .map(|u| (u.channel, u.unit, u.unit_from.render(&Setting::name)))
            })
            .collect();
        assert_eq!(
            got,
            [
                Some(("t", "s", "name")),
                Some(("gx", "deg/s", "name")),
                Some(("gy", "deg/s", "name")),
                Some(("gz", "rad/s", "default")),
                Some(("ax", "g", "name")),
                None,
                Some(("temp", "degC", "default")),
            ]
        );
        assert_eq!(skipped.len(), 1);
        assert_eq!(skipped[0].column, "mag_x");
        assert!((uses[1].as_ref().unwrap().to_si - std::f64::consts::PI / 180.0).abs() < 1e-18);
    }

    #[test]
    fn units_must_be_stated_and_must_agree() {
        let h = header(&["gyro_x", "acc_x"]);
        let e = text(map_header(&h, &[], UnitOptions::default()).unwrap_err());
        assert!(
            e.contains("`gyro_x` (gyro)")
                && e.contains("`acc_x` (accelerometer)")
                && e.contains("units.gyro rad/s|deg/s|deg/h"),
            "{e}"
        );
        let units = UnitOptions {
            gyro: Some(GyroUnit::RadPerS),
            accel: Some(AccelUnit::G),
            time: None,
        };
        let (uses, _) = map_header(&h, &[], units).unwrap();
        assert_eq!(
            uses[0].as_ref().unwrap().unit_from,
            Source::Setting(Setting::GyroUnit)
        );
        assert_eq!(uses[1].as_ref().unwrap().unit, "g");
        let h = header(&["gyro_x_dps"]);
        let e = text(map_header(&h, &[], units).unwrap_err());
        assert!(
            e.contains("deg/s") && e.contains("units.gyro is rad/s"),
            "{e}"
        );
        let t = UnitOptions {
            time: Some(TimeUnit::S),
            ..UnitOptions::default()
        };
        let e = text(map_header(&header(&["t_ms", "gx"]), &[], t).unwrap_err());
        assert!(
            e.contains("`t_ms` says ms") && e.contains("units.time is s"),
            "{e}"
        );
        let a = UnitOptions {
            accel: Some(AccelUnit::MPerS2),
            ..UnitOptions::default()
        };
        let e = text(map_header(&header(&["acc_x_g"]), &[], a).unwrap_err());
        assert!(e.contains("units.accel is m/s^2"), "{e}");
    }

    #[test]
    fn a_second_column_for_one_channel_is_skipped_unless_chosen() {
        let h = header(&["gyro_out_x", "gyro_meas_x"]);
        let units = UnitOptions {
            gyro: Some(GyroUnit::RadPerS),
            ..UnitOptions::default()
        };
        let (uses, skipped) = map_header(&h, &[], units).unwrap();
        assert_eq!(uses[0].as_ref().unwrap().channel, "gx");
        assert!(uses[1].is_none());
        assert!(
            skipped[0]
                .reason_text(&Setting::name)
                .contains("columns gx=gyro_meas_x"),
            "{skipped:?}"
        );
        let explicit = [("gx".to_string(), "gyro_meas_x".to_string())];
        let (uses, skipped) = map_header(&h, &explicit, units).unwrap();
        assert!(uses[0].is_none());
        assert_eq!(
            uses[1].as_ref().unwrap().channel_from,
            Source::Setting(Setting::Columns)
        );
        assert_eq!(skipped[0].column, "gyro_out_x");
    }

    #[test]
    fn unknown_names_and_units_are_not_guessed() {
        for name in [
            "mag_x",
            "pressure",
            "gyro",
            "frame_id",
            "orientation.x",
            "seq",
            "",
        ] {
            assert_eq!(recognise(name), Err(NotRecognised::Unknown), "{name}");
        }
        assert_eq!(
            recognise("gyro_x_furlongs"),
            Err(NotRecognised::Unit("furlongs".into()))
        );
        assert_eq!(recognise("t_days"), Err(NotRecognised::Unit("days".into())));
    }
}
