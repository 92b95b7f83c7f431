//! Sensor configs in TOML, with units as spec sheets write them, converted into validated SI models.
//!
//! ```toml
//! name = "Xsens MTx"
//! [temperature]                 # optional: constant 25 degC
//! profile = "warmup"            # constant (value) | ramp (start, rate, end?) | warmup (start, end, time_constant) | sinusoid (mean, amplitude, period)
//! start = "20 degC"
//! end = "35 degC"
//! time_constant = "600 s"
//! reference = "25 degC"         # temperature_bias is zero here
//! [gyro.all]                    # every axis, unless the axis table sets the same key
//! white_noise = "0.075 deg/sqrt(s)"
//! [gyro.x]
//! bias_instability = { value = "0.010 deg/s", convention = "allan_minimum" }
//! ```
//! Axis keys: `quantization`, `white_noise`, `bias_instability` (a table), `rate_random_walk`,
//! `rate_ramp`, `gauss_markov = { sigma, time_constant }`, `sinusoidal = { amplitude, frequency, phase? }`,
//! `temperature_bias`, `constant_bias`, `turn_on_bias`, `scale_factor`, `misalignment = [a, b]`.
//!
//! `bias_instability` states its convention (docs/architecture.md, Units):
//! - `{ value, convention = "ieee" }`: value is the IEEE coefficient B (Allan plateau 0.664 B);
//! - `{ value, convention = "allan_minimum" }`: value is the minimum of the axis' Allan deviation, as
//!   Woodman (TR-696 §5.1) and many spec sheets report it; B is solved so that the closed-form Allan
//!   deviation of the whole axis model (white noise, random walks ... included) has that minimum over
//!   the flicker band's plateau, averaging times [30 tau_min, tau_max / 30] (3 s .. 3333 s by default);
//! - `{ model = "random_walk", stability, period }`: Woodman's bias random walk (eq 9).
//!
//! Flicker options: `band = ["0.1 s", "1e5 s"]` (correlation times), `per_decade = 1`.

use crate::closed_form as cf;
use crate::effect::Sensor;
use crate::model::*;
use crate::units::{format_si, parse_quantity, Quantity, Signal};
use serde::Deserialize;
use std::fmt::Write as _;
use std::path::Path;

/// Most Gauss-Markov components a flicker bias instability may have (20 decades at 5 per decade).
const MAX_FLICKER_COMPONENTS: f64 = 100.0;

/// A config that cannot be used: names the file, the key and what was expected.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ConfigError {
    #[error("{file}: cannot read the file: {message}")]
    Io { file: String, message: String },
    /// TOML syntax, unknown keys, wrong types (the message carries line and column).
    #[error("{file}: {message}")]
    Parse { file: String, message: String },
    /// A value that parses but is not acceptable.
    #[error("{file}{at}: key `{key}`: expected {expected}, found {found}", at = line.map(|l| format!(":{l}")).unwrap_or_default())]
    Invalid {
        file: String,
        /// 1-based line of the value, when the value exists.
        line: Option<usize>,
        key: String,
        expected: String,
        found: String,
    },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSensor {
    name: String,
    description: Option<String>,
    temperature: Option<RawTemperature>,
    gyro: Option<RawTriad>,
    accel: Option<RawTriad>,
}

/// A config value with its place in the file.
type Text = toml::Spanned<String>;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTemperature {
    profile: Text,
    reference: Option<Text>,
    value: Option<Text>,
    start: Option<Text>,
    end: Option<Text>,
    rate: Option<Text>,
    time_constant: Option<Text>,
    mean: Option<Text>,
    amplitude: Option<Text>,
    period: Option<Text>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RawTriad {
    all: Option<RawAxis>,
    x: Option<RawAxis>,
    y: Option<RawAxis>,
    z: Option<RawAxis>,
}

#[derive(Deserialize, Default, Clone)]
#[serde(deny_unknown_fields)]
struct RawAxis {
    quantization: Option<Text>,
    white_noise: Option<Text>,
    bias_instability: Option<toml::Spanned<RawBiasField>>,
    rate_random_walk: Option<Text>,
    rate_ramp: Option<Text>,
    gauss_markov: Option<RawGaussMarkov>,
    sinusoidal: Option<RawSinusoid>,
    temperature_bias: Option<Text>,
    constant_bias: Option<Text>,
    turn_on_bias: Option<Text>,
    scale_factor: Option<Text>,
    misalignment: Option<Vec<Text>>,
}

/// What `bias_instability` may be: a value with a unit (the Allan-deviation minimum, as spec
/// sheets quote "in-run bias stability") or the table form with its convention stated.
#[derive(Clone)]
enum RawBiasField {
    Plain(String),
    Table(Box<RawBiasInstability>),
}

/// The accepted forms, for error messages.
const BIAS_INSTABILITY_FORMS: &str = "a value with a unit, e.g. bias_instability = \"10 deg/h\" (the Allan-deviation minimum, as spec sheets quote in-run bias stability), or a table: { value = \"10 deg/h\", convention = \"allan_minimum\" | \"ieee\" }, or { model = \"random_walk\", stability = \"36 ug\", period = \"800 s\" }";

impl<'de> Deserialize<'de> for RawBiasField {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = RawBiasField;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str(BIAS_INSTABILITY_FORMS)
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<RawBiasField, E> {
                Ok(RawBiasField::Plain(v.to_string()))
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                map: A,
            ) -> Result<RawBiasField, A::Error> {
                RawBiasInstability::deserialize(serde::de::value::MapAccessDeserializer::new(map))
                    .map(|t| RawBiasField::Table(Box::new(t)))
            }
        }
        d.deserialize_any(V)
    }
}

impl RawBiasField {
    /// The table form; a plain value becomes `{ value, convention = "allan_minimum" }` with the
    /// value's place in the file.
    fn table(field: &toml::Spanned<RawBiasField>) -> RawBiasInstability {
        match field.get_ref() {
            RawBiasField::Table(t) => (**t).clone(),
            RawBiasField::Plain(v) => RawBiasInstability {
                model: None,
                value: Some(toml::Spanned::new(field.span(), v.clone())),
                convention: Some(toml::Spanned::new(field.span(), "allan_minimum".into())),
                band: None,
                per_decade: None,
                stability: None,
                period: None,
            },
        }
    }
}

#[derive(Deserialize, Clone)]
#[serde(deny_unknown_fields)]
struct RawBiasInstability {
    model: Option<Text>,
    value: Option<Text>,
    convention: Option<Text>,
    band: Option<Vec<Text>>,
    per_decade: Option<i64>,
    stability: Option<Text>,
    period: Option<Text>,
}

#[derive(Deserialize, Clone)]
#[serde(deny_unknown_fields)]
struct RawGaussMarkov {
    sigma: Text,
    time_constant: Text,
}

#[derive(Deserialize, Clone)]
#[serde(deny_unknown_fields)]
struct RawSinusoid {
    amplitude: Text,
    frequency: Text,
    phase: Option<Text>,
}

/// Conversion context: file name for errors.
struct Ctx<'a> {
    file: &'a str,
    source: &'a str,
}

impl Ctx<'_> {
    /// An error about `key`, at the line of `at` when the value exists.
    fn invalid_at(
        &self,
        key: &str,
        at: Option<&Text>,
        expected: impl Into<String>,
        found: impl Into<String>,
    ) -> ConfigError {
        let line = at.map(|t| {
            let start = t.span().start.min(self.source.len());
            1 + self.source.as_bytes()[..start]
                .iter()
                .filter(|&&b| b == b'\n')
                .count()
        });
        ConfigError::Invalid {
            file: self.file.to_string(),
            line,
            key: key.to_string(),
            expected: expected.into(),
            found: found.into(),
        }
    }

    fn invalid(
        &self,
        key: &str,
        expected: impl Into<String>,
        found: impl Into<String>,
    ) -> ConfigError {
        self.invalid_at(key, None, expected, found)
    }

    /// Parse a value with units; `nonneg` rejects negative values.
    fn value(&self, key: &str, text: &Text, q: Quantity, nonneg: bool) -> Result<f64, ConfigError> {
        let quoted = format!("\"{}\"", text.get_ref());
        let v = parse_quantity(text.get_ref(), q).map_err(|e| {
            self.invalid_at(
                key,
                Some(text),
                format!("a value in {} such as {} ({e})", q.si_unit(), q.example()),
                quoted.clone(),
            )
        })?;
        if nonneg && v < 0.0 {
            return Err(self.invalid_at(key, Some(text), "a value >= 0", quoted));
        }
        Ok(v)
    }

    fn positive(&self, key: &str, text: &Text, q: Quantity) -> Result<f64, ConfigError> {
        let v = self.value(key, text, q, true)?;
        if v == 0.0 {
            let quoted = format!("\"{}\"", text.get_ref());
            return Err(self.invalid_at(key, Some(text), "a value > 0", quoted));
        }
        Ok(v)
    }
}

impl SensorModel {
    /// Parse and validate a sensor config. `source_name` (usually the file path) appears in errors.
    pub fn from_toml_str(text: &str, source_name: &str) -> Result<SensorModel, ConfigError> {
        let raw: RawSensor = toml::from_str(text).map_err(|e| ConfigError::Parse {
            file: source_name.to_string(),
            message: with_shape_hint(e.to_string().trim_end()),
        })?;
        let ctx = Ctx {
            file: source_name,
            source: text,
        };
        let (temperature, reference) = convert_temperature(&ctx, raw.temperature.as_ref())?;
        let gyro = convert_triad(&ctx, Sensor::Gyro, raw.gyro.unwrap_or_default())?;
        let accel = convert_triad(&ctx, Sensor::Accel, raw.accel.unwrap_or_default())?;
        Ok(SensorModel {
            name: raw.name,
            description: raw.description,
            gyro,
            accel,
            temperature,
            temperature_reference_c: reference,
        })
    }

    /// Read a config file.
    pub fn load(path: &Path) -> Result<SensorModel, ConfigError> {
        let name = path.display().to_string();
        let bytes = std::fs::read(path).map_err(|e| ConfigError::Io {
            file: name.clone(),
            message: e.to_string(),
        })?;
        let text = utf8_text(bytes, &name)?;
        SensorModel::from_toml_str(&text, &name)
    }

    /// Write the model back as a config in SI units (every axis explicit, bias instability as IEEE B).
    /// `from_toml_str` of the result gives this model back bit for bit.
    pub fn to_toml_string(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "# written by imudrift; units SI");
        let _ = writeln!(s, "name = {}", toml_str(&self.name));
        if let Some(d) = &self.description {
            let _ = writeln!(s, "description = {}", toml_str(d));
        }
        let t = Quantity::Temperature;
        let _ = writeln!(s, "\n[temperature]");
        match &self.temperature {
            TemperatureProfile::Constant { temp_c } => {
                let _ = writeln!(
                    s,
                    "profile = \"constant\"\nvalue = \"{}\"",
                    format_si(*temp_c, t)
                );
            }
            TemperatureProfile::Ramp {
                start_c,
                rate_c_per_s,
                end_c,
            } => {
                let _ = writeln!(
                    s,
                    "profile = \"ramp\"\nstart = \"{}\"\nrate = \"{}\"",
                    format_si(*start_c, t),
                    format_si(*rate_c_per_s, Quantity::TemperatureRate)
                );
                if let Some(e) = end_c {
                    let _ = writeln!(s, "end = \"{}\"", format_si(*e, t));
                }
            }
            TemperatureProfile::Warmup {
                start_c,
                end_c,
                time_constant_s,
            } => {
                let _ = writeln!(
                    s,
                    "profile = \"warmup\"\nstart = \"{}\"\nend = \"{}\"\ntime_constant = \"{}\"",
                    format_si(*start_c, t),
                    format_si(*end_c, t),
                    format_si(*time_constant_s, Quantity::Time)
                );
            }
            TemperatureProfile::Sinusoid {
                mean_c,
                amplitude_c,
                period_s,
            } => {
                let _ = writeln!(
                    s,
                    "profile = \"sinusoid\"\nmean = \"{}\"\namplitude = \"{}\"\nperiod = \"{}\"",
                    format_si(*mean_c, t),
                    format_si(*amplitude_c, t),
                    format_si(*period_s, Quantity::Time)
                );
            }
        }
        let _ = writeln!(
            s,
            "reference = \"{}\"",
            format_si(self.temperature_reference_c, t)
        );
        for sensor in Sensor::ALL {
            let sig = signal_of(sensor);
            for (axis, name) in self.triad(sensor).axes.iter().zip(AXIS_NAMES) {
                let _ = writeln!(s, "\n[{}.{}]", sensor.name(), name);
                write_axis(&mut s, axis, sig);
            }
        }
        s
    }
}

fn toml_str(text: &str) -> String {
    toml::Value::String(text.to_string()).to_string()
}

fn write_axis(s: &mut String, a: &AxisModel, sig: Signal) {
    let mut line = |key: &str, v: f64, q: Quantity| {
        let _ = writeln!(s, "{key} = \"{}\"", format_si(v, q));
    };
    if let Some(v) = a.quantization {
        line("quantization", v, Quantity::Integrated(sig));
    }
    if let Some(v) = a.white_noise {
        line("white_noise", v, Quantity::NoiseDensity(sig));
    }
    if let Some(v) = a.rate_random_walk {
        line("rate_random_walk", v, Quantity::RandomWalk(sig));
    }
    if let Some(v) = a.rate_ramp {
        line("rate_ramp", v, Quantity::Ramp(sig));
    }
    if let Some(v) = a.temperature_bias {
        line("temperature_bias", v, Quantity::PerDegree(sig));
    }
    if let Some(v) = a.constant_bias {
        line("constant_bias", v, Quantity::Signal(sig));
    }
    if let Some(v) = a.turn_on_bias {
        line("turn_on_bias", v, Quantity::Signal(sig));
    }
    if let Some(v) = a.scale_factor {
        line("scale_factor", v, Quantity::Ratio);
    }
    match &a.bias_instability {
        Some(BiasInstability::Flicker(f)) => {
            let _ = writeln!(
                s,
                "bias_instability = {{ value = \"{}\", convention = \"ieee\", band = [\"{}\", \"{}\"], per_decade = {} }}",
                format_si(f.b, Quantity::Signal(sig)),
                format_si(f.tau_min_s, Quantity::Time),
                format_si(f.tau_max_s, Quantity::Time),
                f.per_decade
            );
        }
        Some(BiasInstability::RandomWalk {
            stability,
            period_s,
        }) => {
            let _ = writeln!(
                s,
                "bias_instability = {{ model = \"random_walk\", stability = \"{}\", period = \"{}\" }}",
                format_si(*stability, Quantity::Signal(sig)),
                format_si(*period_s, Quantity::Time)
            );
        }
        None => {}
    }
    if let Some(g) = a.gauss_markov {
        let _ = writeln!(
            s,
            "gauss_markov = {{ sigma = \"{}\", time_constant = \"{}\" }}",
            format_si(g.sigma, Quantity::Signal(sig)),
            format_si(g.tau_s, Quantity::Time)
        );
    }
    if let Some(w) = a.sinusoidal {
        let phase = w
            .phase_rad
            .map(|p| format!(", phase = \"{}\"", format_si(p, Quantity::Angle)))
            .unwrap_or_default();
        let _ = writeln!(
            s,
            "sinusoidal = {{ amplitude = \"{}\", frequency = \"{}\"{phase} }}",
            format_si(w.amplitude, Quantity::Signal(sig)),
            format_si(w.frequency_hz, Quantity::Frequency)
        );
    }
    if let Some([m1, m2]) = a.misalignment {
        let _ = writeln!(
            s,
            "misalignment = [\"{}\", \"{}\"]",
            format_si(m1, Quantity::Angle),
            format_si(m2, Quantity::Angle)
        );
    }
}

pub(crate) fn signal_of(sensor: Sensor) -> Signal {
    match sensor {
        Sensor::Gyro => Signal::AngularRate,
        Sensor::Accel => Signal::Acceleration,
    }
}

fn convert_temperature(
    ctx: &Ctx,
    raw: Option<&RawTemperature>,
) -> Result<(TemperatureProfile, f64), ConfigError> {
    let Some(raw) = raw else {
        return Ok((TemperatureProfile::default(), 25.0));
    };
    let t = Quantity::Temperature;
    let fields: [(&str, &Option<Text>); 9] = [
        ("value", &raw.value),
        ("start", &raw.start),
        ("end", &raw.end),
        ("rate", &raw.rate),
        ("time_constant", &raw.time_constant),
        ("mean", &raw.mean),
        ("amplitude", &raw.amplitude),
        ("period", &raw.period),
        ("reference", &raw.reference),
    ];
    let profile = raw.profile.get_ref().as_str();
    let (uses, profile_keys): (&[&str], &str) = match profile {
        "constant" => (&["value"], "value"),
        "ramp" => (&["start", "rate", "end"], "start, rate and optionally end"),
        "warmup" => (
            &["start", "end", "time_constant"],
            "start, end, time_constant",
        ),
        "sinusoid" => (&["mean", "amplitude", "period"], "mean, amplitude, period"),
        other => {
            return Err(ctx.invalid_at(
                "temperature.profile",
                Some(&raw.profile),
                "one of \"constant\", \"ramp\", \"warmup\", \"sinusoid\"",
                format!("\"{other}\""),
            ))
        }
    };
    for (name, v) in fields {
        if v.is_some() && name != "reference" && !uses.contains(&name) {
            return Err(ctx.invalid_at(
                &format!("temperature.{name}"),
                v.as_ref(),
                format!("only {profile_keys} for profile \"{profile}\""),
                "an extra key",
            ));
        }
    }
    let need = |name: &str, v: &'_ Option<Text>| -> Result<(String, Text), ConfigError> {
        let key = format!("temperature.{name}");
        let text = v.clone().ok_or_else(|| {
            ctx.invalid(
                &key,
                format!("{profile_keys} for profile \"{profile}\""),
                "nothing",
            )
        })?;
        Ok((key, text))
    };
    let get = |name: &str, v: &Option<Text>, q: Quantity| -> Result<f64, ConfigError> {
        let (key, text) = need(name, v)?;
        ctx.value(&key, &text, q, false)
    };
    let get_positive = |name: &str, v: &Option<Text>, q: Quantity| -> Result<f64, ConfigError> {
        let (key, text) = need(name, v)?;
        ctx.positive(&key, &text, q)
    };
    let profile = match profile {
        "constant" => TemperatureProfile::Constant {
            temp_c: get("value", &raw.value, t)?,
        },
        "ramp" => {
            let start_c = get("start", &raw.start, t)?;
            let rate_c_per_s = get("rate", &raw.rate, Quantity::TemperatureRate)?;
            let end_c = match &raw.end {
                None => None,
                Some(text) => {
                    let end = ctx.value("temperature.end", text, t, false)?;
                    // The ramp must be able to reach its end.
                    if (end - start_c) * rate_c_per_s < 0.0 {
                        return Err(ctx.invalid_at(
                            "temperature.end",
                            Some(text),
                            "an end temperature the ramp reaches (above start for a rising ramp, below for a falling one)",
                            format!("\"{}\"", text.get_ref()),
                        ));
                    }
                    Some(end)
                }
            };
            TemperatureProfile::Ramp {
                start_c,
                rate_c_per_s,
                end_c,
            }
        }
        "warmup" => TemperatureProfile::Warmup {
            start_c: get("start", &raw.start, t)?,
            end_c: get("end", &raw.end, t)?,
            time_constant_s: get_positive("time_constant", &raw.time_constant, Quantity::Time)?,
        },
        _ => TemperatureProfile::Sinusoid {
            mean_c: get("mean", &raw.mean, t)?,
            amplitude_c: get("amplitude", &raw.amplitude, t)?,
            period_s: get_positive("period", &raw.period, Quantity::Time)?,
        },
    };
    let reference = match &raw.reference {
        Some(r) => ctx.value("temperature.reference", r, t, false)?,
        None => 25.0,
    };
    Ok((profile, reference))
}

fn convert_triad(ctx: &Ctx, sensor: Sensor, raw: RawTriad) -> Result<TriadModel, ConfigError> {
    let all = raw.all.unwrap_or_default();
    let mut triad = TriadModel::default();
    for (i, (axis, name)) in [raw.x, raw.y, raw.z]
        .into_iter()
        .zip(AXIS_NAMES)
        .enumerate()
    {
        triad.axes[i] = convert_axis(ctx, sensor, name, &axis.unwrap_or_default(), &all)?;
    }
    Ok(triad)
}

fn convert_axis(
    ctx: &Ctx,
    sensor: Sensor,
    axis_name: &str,
    raw: &RawAxis,
    all: &RawAxis,
) -> Result<AxisModel, ConfigError> {
    let sig = signal_of(sensor);
    // Each value comes from the axis table or else from `all`; errors name the table it came from.
    macro_rules! pick {
        ($f:ident) => {
            match (&raw.$f, &all.$f) {
                (Some(v), _) => Some((
                    v,
                    format!("{}.{}.{}", sensor.name(), axis_name, stringify!($f)),
                )),
                (None, Some(v)) => Some((v, format!("{}.all.{}", sensor.name(), stringify!($f)))),
                (None, None) => None,
            }
        };
    }
    let scalar = |p: Option<(&Text, String)>, q: Quantity, nonneg: bool| {
        p.map(|(v, key)| ctx.value(&key, v, q, nonneg)).transpose()
    };
    let mut m = AxisModel {
        quantization: scalar(pick!(quantization), Quantity::Integrated(sig), true)?,
        white_noise: scalar(pick!(white_noise), Quantity::NoiseDensity(sig), true)?,
        bias_instability: None,
        rate_random_walk: scalar(pick!(rate_random_walk), Quantity::RandomWalk(sig), true)?,
        rate_ramp: scalar(pick!(rate_ramp), Quantity::Ramp(sig), false)?,
        gauss_markov: None,
        sinusoidal: None,
        temperature_bias: scalar(pick!(temperature_bias), Quantity::PerDegree(sig), false)?,
        constant_bias: scalar(pick!(constant_bias), Quantity::Signal(sig), false)?,
        turn_on_bias: scalar(pick!(turn_on_bias), Quantity::Signal(sig), true)?,
        scale_factor: scalar(pick!(scale_factor), Quantity::Ratio, false)?,
        misalignment: None,
    };
    if let Some((g, key)) = pick!(gauss_markov) {
        m.gauss_markov = Some(GaussMarkov {
            sigma: ctx.value(
                &format!("{key}.sigma"),
                &g.sigma,
                Quantity::Signal(sig),
                true,
            )?,
            tau_s: ctx.positive(
                &format!("{key}.time_constant"),
                &g.time_constant,
                Quantity::Time,
            )?,
        });
    }
    if let Some((w, key)) = pick!(sinusoidal) {
        m.sinusoidal = Some(Sinusoid {
            amplitude: ctx.value(
                &format!("{key}.amplitude"),
                &w.amplitude,
                Quantity::Signal(sig),
                true,
            )?,
            frequency_hz: ctx.positive(
                &format!("{key}.frequency"),
                &w.frequency,
                Quantity::Frequency,
            )?,
            phase_rad: w
                .phase
                .as_ref()
                .map(|p| ctx.value(&format!("{key}.phase"), p, Quantity::Angle, false))
                .transpose()?,
        });
    }
    if let Some((list, key)) = pick!(misalignment) {
        if list.len() != 2 {
            return Err(ctx.invalid_at(
                &key,
                list.first(),
                "two angles: the sensitivity to the other two axes in x, y, z order",
                format!("{} values", list.len()),
            ));
        }
        m.misalignment = Some([
            ctx.value(&format!("{key}[0]"), &list[0], Quantity::Angle, false)?,
            ctx.value(&format!("{key}[1]"), &list[1], Quantity::Angle, false)?,
        ]);
    }
    // Bias instability last: the "allan_minimum" convention needs the other terms.
    if let Some((b, key)) = pick!(bias_instability) {
        let table = RawBiasField::table(b);
        m.bias_instability = Some(convert_bias_instability(ctx, &key, &table, sig, &m)?);
    }
    Ok(m)
}

fn convert_bias_instability(
    ctx: &Ctx,
    key: &str,
    raw: &RawBiasInstability,
    sig: Signal,
    others: &AxisModel,
) -> Result<BiasInstability, ConfigError> {
    let sub = |name: &str| format!("{key}.{name}");
    let model = raw
        .model
        .as_ref()
        .map_or("flicker", |m| m.get_ref().as_str());
    match model {
        "random_walk" => {
            for (name, present, at) in [
                ("value", raw.value.is_some(), raw.value.as_ref()),
                (
                    "convention",
                    raw.convention.is_some(),
                    raw.convention.as_ref(),
                ),
                (
                    "band",
                    raw.band.is_some(),
                    raw.band.as_ref().and_then(|b| b.first()),
                ),
                ("per_decade", raw.per_decade.is_some(), None),
            ] {
                if present {
                    return Err(ctx.invalid_at(
                        &sub(name),
                        at,
                        "only `stability` and `period` for model \"random_walk\"",
                        "an extra key",
                    ));
                }
            }
            let need = |name: &str, v: &Option<Text>| {
                v.clone().ok_or_else(|| {
                    ctx.invalid(
                        &sub(name),
                        "a value (model \"random_walk\" needs stability and period)",
                        "nothing",
                    )
                })
            };
            let stability = ctx.value(
                &sub("stability"),
                &need("stability", &raw.stability)?,
                Quantity::Signal(sig),
                true,
            )?;
            let period_s = ctx.positive(
                &sub("period"),
                &need("period", &raw.period)?,
                Quantity::Time,
            )?;
            Ok(BiasInstability::RandomWalk {
                stability,
                period_s,
            })
        }
        "flicker" => {
            for (name, at) in [("stability", &raw.stability), ("period", &raw.period)] {
                if let Some(at) = at {
                    return Err(ctx.invalid_at(
                        &sub(name),
                        Some(at),
                        "no `stability`/`period` for a flicker bias instability (use model = \"random_walk\" for Woodman's bias random walk)",
                        "an extra key",
                    ));
                }
            }
            let value_text = raw.value.as_ref().ok_or_else(|| {
                ctx.invalid(
                    &sub("value"),
                    "the bias instability value, e.g. \"0.010 deg/s\"",
                    "nothing",
                )
            })?;
            let value = ctx.value(&sub("value"), value_text, Quantity::Signal(sig), true)?;
            let (tau_min_s, tau_max_s) =
                match &raw.band {
                    None => (Flicker::DEFAULT_TAU_MIN_S, Flicker::DEFAULT_TAU_MAX_S),
                    Some(b) if b.len() == 2 => (
                        ctx.positive(&format!("{}[0]", sub("band")), &b[0], Quantity::Time)?,
                        ctx.positive(&format!("{}[1]", sub("band")), &b[1], Quantity::Time)?,
                    ),
                    Some(b) => return Err(ctx.invalid_at(
                        &sub("band"),
                        b.first(),
                        "two correlation times [shortest, longest], e.g. [\"0.1 s\", \"1e5 s\"]",
                        format!("{} values", b.len()),
                    )),
                };
            if tau_max_s <= tau_min_s {
                return Err(ctx.invalid_at(
                    &sub("band"),
                    raw.band.as_ref().and_then(|b| b.first()),
                    "the longest time after the shortest",
                    format!("{tau_min_s} s .. {tau_max_s} s"),
                ));
            }
            let per_decade = match raw.per_decade {
                None => Flicker::DEFAULT_PER_DECADE,
                Some(n) if (1..=20).contains(&n) => n as u32,
                Some(n) => {
                    return Err(ctx.invalid(
                        &sub("per_decade"),
                        "an integer from 1 to 20",
                        n.to_string(),
                    ))
                }
            };
            // One Gauss-Markov component per 1/per_decade decade of the band: bound their number,
            // which sets the cost of every sample.
            let components = (tau_max_s / tau_min_s).log10() * f64::from(per_decade);
            if components.is_nan() || components > MAX_FLICKER_COMPONENTS {
                return Err(ctx.invalid_at(
                    &sub("band"),
                    raw.band.as_ref().and_then(|b| b.first()),
                    format!(
                        "a band and per_decade giving at most {MAX_FLICKER_COMPONENTS} components (decades x per_decade), e.g. [\"0.1 s\", \"1e5 s\"] with per_decade = 1"
                    ),
                    format!("{components:.3e} components"),
                ));
            }
            let flicker = |b: f64| Flicker {
                b,
                tau_min_s,
                tau_max_s,
                per_decade,
            };
            let b = match raw.convention.as_ref().map(|c| c.get_ref().as_str()) {
                Some("ieee") => value,
                Some("allan_minimum") => solve_b_for_minimum(value, others, &flicker).map_err(|floor| {
                    ctx.invalid_at(
                        &sub("value"),
                        Some(value_text),
                        format!(
                            "an Allan minimum above what the other terms of the axis already give ({} over the flicker band's plateau; widen `band`)",
                            in_units_of(floor, value_text.get_ref(), Quantity::Signal(sig))
                        ),
                        format!("\"{}\"", value_text.get_ref()),
                    )
                })?,
                Some(other) => {
                    return Err(ctx.invalid_at(
                        &sub("convention"),
                        raw.convention.as_ref(),
                        "\"ieee\" (value is B, Allan plateau 0.664 B) or \"allan_minimum\" (value is the Allan-deviation minimum, as Woodman reports it)",
                        format!("\"{other}\""),
                    ))
                }
                None => {
                    return Err(ctx.invalid(
                        &sub("convention"),
                        "a stated convention: \"ieee\" (value is B, plateau 0.664 B) or \"allan_minimum\" (value is the Allan-deviation minimum)",
                        "nothing",
                    ))
                }
            };
            Ok(BiasInstability::Flicker(flicker(b)))
        }
        other => Err(ctx.invalid(
            &sub("model"),
            "\"flicker\" (default) or \"random_walk\" (Woodman's bias random walk)",
            format!("\"{other}\""),
        )),
    }
}

/// A config file's text; a byte that is not UTF-8 is an error naming its line and column.
pub fn utf8_text(bytes: Vec<u8>, file: &str) -> Result<String, ConfigError> {
    String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let before = &e.as_bytes()[..at];
        let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
        let column = at - before.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1) + 1;
        ConfigError::Parse {
            file: file.to_string(),
            message: format!(
                "line {line}, column {column}: byte 0x{:02x} is not UTF-8; save the file as UTF-8 text",
                e.as_bytes()[at]
            ),
        }
    })
}

/// An example of each value-with-unit key, for errors about a value of the wrong shape.
const KEY_EXAMPLES: [(&str, &str); 10] = [
    ("quantization", "quantization = \"0.001 deg\""),
    (
        "white_noise",
        "white_noise = \"0.05 deg/s/sqrt(Hz)\" (gyro) or \"40 ug/sqrt(Hz)\" (accelerometer)",
    ),
    (
        "rate_random_walk",
        "rate_random_walk = \"0.5 deg/h/sqrt(h)\"",
    ),
    ("rate_ramp", "rate_ramp = \"0.01 deg/h/h\""),
    ("temperature_bias", "temperature_bias = \"0.01 deg/s/degC\""),
    (
        "constant_bias",
        "constant_bias = \"0.1 deg/s\" (gyro) or \"2 mg\" (accelerometer)",
    ),
    ("turn_on_bias", "turn_on_bias = \"3 deg/s\""),
    ("scale_factor", "scale_factor = \"0.1 %\""),
    ("misalignment", "misalignment = [\"0.1 deg\", \"0.1 deg\"]"),
    ("name", "name = \"My IMU\""),
];

/// A TOML error about a value of the wrong shape, with the accepted form and an example added:
/// numbers need their unit, so a bare number is the commonest mistake.
fn with_shape_hint(message: &str) -> String {
    if message.contains("missing field `name`") {
        return format!("{message}\n  a sensor file starts with its name, e.g. name = \"My IMU\"");
    }
    if !message.contains("expected a string") {
        return message.to_string();
    }
    // toml quotes the offending line as "N | key = value".
    let key = message
        .lines()
        .find_map(|l| l.split_once(" | ").map(|(_, rest)| rest))
        .and_then(|rest| rest.split('=').next())
        .map(|k| k.trim().trim_matches('"'))
        .unwrap_or("");
    let example = KEY_EXAMPLES
        .iter()
        .find(|(k, _)| *k == key)
        .map_or("e.g. \"0.05 deg/s\"".to_string(), |(_, e)| {
            format!("e.g. {e}")
        });
    format!(
        "{message}\n  values carry their unit in a string, as spec sheets write them: {example}"
    )
}

/// `value` (SI) written in the unit of `like` (a config value such as "0.01 deg/h"), for messages.
fn in_units_of(value: f64, like: &str, q: Quantity) -> String {
    let unit = like
        .trim()
        .trim_start_matches(|c: char| c.is_ascii_digit() || "+-.eE".contains(c))
        .trim();
    match parse_quantity(&format!("1 {unit}"), q) {
        Ok(factor) if !unit.is_empty() => format!("{:.4} {unit}", value / factor),
        _ => format!("{value:.4e} {}", q.si_unit()),
    }
}

/// Log-spaced averaging times inside the flicker band's plateau, [30 tau_min, tau_max / 30], where the
/// component sum is within 1.3 % of 0.664 B (`Flicker::per_decade`); nearer the band edges it falls off
/// (0.55 B at 2 tau_min), which would make a curve without a rising term take its minimum there.
fn plateau_taus(f: &Flicker) -> Vec<f64> {
    let lo = 30.0 * f.tau_min_s;
    let hi = (f.tau_max_s / 30.0).max(lo);
    let n = ((hi / lo).log10() * 40.0).ceil().max(1.0) as usize;
    (0..=n)
        .map(|i| lo * (hi / lo).powf(i as f64 / n as f64))
        .collect()
}

/// Minimum over the plateau taus of the total closed-form Allan deviation.
pub(crate) fn model_adev_minimum(axis: &AxisModel, band: &Flicker) -> (f64, f64) {
    plateau_taus(band)
        .into_iter()
        .map(|tau| (axis.allan_variance(tau).sqrt(), tau))
        .fold((f64::INFINITY, 0.0), |a, b| if b.0 < a.0 { b } else { a })
}

/// B such that the axis' total Allan-deviation minimum equals `target`. Err(floor) when the other
/// terms alone already exceed it. The minimum grows monotonically with B, so bisection converges.
fn solve_b_for_minimum(
    target: f64,
    others: &AxisModel,
    flicker: &dyn Fn(f64) -> Flicker,
) -> Result<f64, f64> {
    let min_with = |b: f64| {
        let mut axis = others.clone();
        axis.bias_instability = Some(BiasInstability::Flicker(flicker(b)));
        model_adev_minimum(&axis, &flicker(b)).0
    };
    let floor = min_with(0.0);
    if floor >= target {
        return Err(floor);
    }
    let (mut lo, mut hi) = (0.0, 2.0 * target / cf::FLICKER_PLATEAU_PER_B);
    while min_with(hi) < target {
        hi *= 2.0;
    }
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if min_with(mid) < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(0.5 * (lo + hi))
}

#[cfg(test)]
mod tests {
    use super::*;

    const BASIC: &str = r#"
name = "test"
[gyro.all]
white_noise = "0.075 deg/sqrt(s)"
[gyro.x]
bias_instability = { value = "0.010 deg/s", convention = "allan_minimum" }
rate_random_walk = "2e-4 deg/s/sqrt(s)"
[gyro.y]
white_noise = "0.1 deg/sqrt(s)"
"#;

    #[test]
    fn all_table_applies_unless_axis_overrides() {
        let m = SensorModel::from_toml_str(BASIC, "basic.toml").unwrap();
        let n = 0.075f64.to_radians();
        assert!((m.gyro.axes[0].white_noise.unwrap() - n).abs() < 1e-15);
        assert!((m.gyro.axes[1].white_noise.unwrap() - 0.1f64.to_radians()).abs() < 1e-15);
        assert!((m.gyro.axes[2].white_noise.unwrap() - n).abs() < 1e-15);
        assert!(m.accel.axes.iter().all(|a| a.effects().is_empty()));
    }

    #[test]
    fn allan_minimum_convention_reproduces_the_minimum() {
        let m = SensorModel::from_toml_str(BASIC, "basic.toml").unwrap();
        let axis = &m.gyro.axes[0];
        let Some(BiasInstability::Flicker(f)) = &axis.bias_instability else {
            panic!("flicker expected")
        };
        let (min, _) = model_adev_minimum(axis, f);
        assert!((min / 0.010f64.to_radians() - 1.0).abs() < 1e-9);
        // B is smaller than min/0.664: white noise and RRW contribute to the minimum too.
        let min_only = 0.010f64.to_radians() / cf::FLICKER_PLATEAU_PER_B;
        assert!(f.b < min_only, "B {} vs min/0.664 {}", f.b, min_only);
    }

    #[test]
    fn round_trip_through_toml_is_exact() {
        let text = r#"
name = "full \"quoted\""
description = "every term"
[temperature]
profile = "ramp"
start = "10 degC"
rate = "0.01 degC/s"
end = "40 degC"
reference = "20 degC"
[gyro.all]
quantization = "0.001 deg"
white_noise = "0.2 deg/sqrt(h)"
bias_instability = { value = "70 deg/h", convention = "ieee", band = ["0.5 s", "1e4 s"], per_decade = 3 }
rate_random_walk = "1 deg/h/sqrt(h)"
rate_ramp = "1 deg/h/h"
gauss_markov = { sigma = "0.01 deg/s", time_constant = "30 s" }
sinusoidal = { amplitude = "0.01 deg/s", frequency = "0.2 Hz", phase = "10 deg" }
temperature_bias = "0.01 deg/s/degC"
constant_bias = "-0.3 deg/s"
turn_on_bias = "3 deg/s"
scale_factor = "300 ppm"
misalignment = ["0.5 mrad", "-1 mrad"]
[accel.z]
white_noise = "40 ug/sqrt(Hz)"
bias_instability = { model = "random_walk", stability = "36 ug", period = "800 s" }
sinusoidal = { amplitude = "1 mg", frequency = "2 Hz" }
"#;
        let m = SensorModel::from_toml_str(text, "full.toml").unwrap();
        let back = SensorModel::from_toml_str(&m.to_toml_string(), "written.toml").unwrap();
        assert_eq!(m, back);
        for profile in [
            "profile = \"constant\"\nvalue = \"21 degC\"",
            "profile = \"warmup\"\nstart = \"20 degC\"\nend = \"35 degC\"\ntime_constant = \"10 min\"",
            "profile = \"sinusoid\"\nmean = \"25 degC\"\namplitude = \"2 degC\"\nperiod = \"1 h\"",
        ] {
            let text = format!("name = \"t\"\n[temperature]\n{profile}\n");
            let m = SensorModel::from_toml_str(&text, "t.toml").unwrap();
            assert_eq!(SensorModel::from_toml_str(&m.to_toml_string(), "w").unwrap(), m);
        }
    }

    fn err(text: &str) -> String {
        SensorModel::from_toml_str(text, "bad.toml")
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn bad_configs_name_file_key_and_expectation() {
        let e = err("name = \"b\"\n[gyro.x]\nwhite_noize = \"1 deg/sqrt(h)\"\n");
        assert!(
            e.contains("bad.toml") && e.contains("white_noize") && e.contains("line 3"),
            "{e}"
        );
        let e = err("name = \"b\"\n[gyro.x]\nwhite_noise = \"1 deg/h\"\n");
        assert!(e.starts_with("bad.toml:3: key `gyro.x.white_noise`"), "{e}");
        assert!(
            e.contains("bad.toml")
                && e.contains("gyro.x.white_noise")
                && e.contains("rad/s/sqrt(Hz)"),
            "{e}"
        );
        let e = err("name = \"b\"\n[accel.all]\nwhite_noise = \"-1 ug/sqrt(Hz)\"\n");
        assert!(
            e.contains("accel.all.white_noise") && e.contains(">= 0"),
            "{e}"
        );
        let e = err("name = \"b\"\n[gyro.z]\nconstant_bias = \"NaN deg/s\"\n");
        assert!(e.contains("gyro.z.constant_bias"), "{e}");
        let e = err("name = \"b\"\n[gyro.z]\nconstant_bias = \"nan deg/s\"\n");
        assert!(e.contains("gyro.z.constant_bias"), "{e}");
        let e = err("name = \"b\"\n[gyro.z]\nbias_instability = { value = \"1 deg/h\" }\n");
        assert!(
            e.contains("gyro.z.bias_instability.convention") && e.contains("allan_minimum"),
            "{e}"
        );
        let e = err("name = \"b\"\n[gyro.z]\nwhite_noise = \"1 deg/sqrt(s)\"\nbias_instability = { value = \"1 deg/h\", convention = \"allan_minimum\" }\n");
        assert!(
            e.contains("gyro.z.bias_instability.value") && e.contains("above what the other terms"),
            "{e}"
        );
        let e = err("name = \"b\"\n[gyro.z]\ngauss_markov = { sigma = \"1 deg/s\", time_constant = \"0 s\" }\n");
        assert!(
            e.contains("gyro.z.gauss_markov.time_constant") && e.contains("> 0"),
            "{e}"
        );
        let e = err("name = \"b\"\n[temperature]\nprofile = \"warmup\"\nstart = \"20 degC\"\n");
        assert!(e.contains("temperature.end"), "{e}");
        let e = err("name = \"b\"\n[temperature]\nprofile = \"constant\"\nvalue = \"20 degC\"\nrate = \"1 degC/s\"\n");
        assert!(e.contains("temperature.rate"), "{e}");
        let e = err("name = \"b\"\n[temperature]\nprofile = \"ramp\"\nstart = \"30 degC\"\nrate = \"0.1 degC/s\"\nend = \"20 degC\"\n");
        assert!(e.starts_with("bad.toml:6: key `temperature.end`"), "{e}");
        let e = err("name = \"b\"\n[gyro.x]\nmisalignment = [\"1 mrad\"]\n");
        assert!(e.contains("gyro.x.misalignment"), "{e}");
        let e = err("name = \"b\"\n[gyro.x]\nwhite_noise = 0.1\n");
        assert!(e.contains("bad.toml") && e.contains("string"), "{e}");
        let e = err("[gyro.x]\n");
        assert!(e.contains("name"), "{e}");
    }

    #[test]
    fn a_plain_bias_instability_is_the_allan_minimum_as_spec_sheets_quote_it() {
        let plain = "name = \"p\"\n[gyro.all]\nwhite_noise = \"0.05 deg/s/rtHz\"\nbias_instability = \"20 deg/h\"\n";
        let table = "name = \"p\"\n[gyro.all]\nwhite_noise = \"0.05 deg/s/sqrt(Hz)\"\nbias_instability = { value = \"20 deg/h\", convention = \"allan_minimum\" }\n";
        let a = SensorModel::from_toml_str(plain, "plain.toml").unwrap();
        let b = SensorModel::from_toml_str(table, "table.toml").unwrap();
        assert_eq!(a.gyro, b.gyro);
        // The error of a plain value too low for the axis names its line and key.
        let e = err("name = \"p\"\n[gyro.all]\nwhite_noise = \"0.05 deg/s/rtHz\"\nbias_instability = \"2 deg/h\"\n");
        assert!(
            e.contains("bad.toml:4: key `gyro.all.bias_instability.value`"),
            "{e}"
        );
    }

    #[test]
    fn wrong_shapes_show_the_accepted_forms_with_an_example() {
        let e = err("name = \"b\"\n[gyro.all]\nwhite_noise = 0.05\n");
        assert!(
            e.contains("line 3") && e.contains("white_noise = \"0.05 deg/s/sqrt(Hz)\""),
            "{e}"
        );
        let e = err("name = \"b\"\n[gyro.all]\nbias_instability = 2\n");
        assert!(
            e.contains("line 3")
                && e.contains("bias_instability = \"10 deg/h\"")
                && e.contains("convention"),
            "{e}"
        );
        let e = err("[gyro.all]\nwhite_noise = \"1 deg/sqrt(h)\"\n");
        assert!(e.contains("name = \"My IMU\""), "{e}");
    }
}
