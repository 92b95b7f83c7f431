//! Raw TOML tables to the validated SI model: the temperature profile, and each axis' terms (each
//! read by its own type, `terms/<effect>.rs`).

use super::error::ConfigError;
use super::raw::*;
use super::read::{Ctx, ReadContext, Text};
use crate::effect::Sensor;
use crate::model::*;
use crate::temperature::TemperatureProfile;
use crate::terms::{Effect, RawAxis};
use crate::units::{Quantity, Signal};
use crate::AXIS_NAMES;

/// The `[temperature]` table: the profile and the reference temperature (25 degC when absent).
pub(super) fn convert_temperature(
    ctx: &Ctx,
    raw: Option<&RawTemperature>,
) -> Result<(TemperatureProfile, f64), ConfigError> {
    let Some(raw) = raw else {
        return Ok((TemperatureProfile::default(), 25.0));
    };
    let keys = ProfileKeys::of(ctx, raw)?;
    keys.check_no_extra(raw)?;
    let profile = keys.profile(raw)?;
    let reference = match &raw.reference {
        Some(r) => ctx.value("temperature.reference", r, Quantity::Temperature, false)?,
        None => 25.0,
    };
    Ok((profile, reference))
}

/// A temperature profile's name and the keys it uses (the rest of the table must not be set).
struct ProfileKeys<'a> {
    ctx: &'a Ctx<'a>,
    /// `constant`, `ramp`, `warmup`, `sinusoid` or `step`.
    name: &'a str,
    uses: &'static [&'static str],
    /// The keys as a message lists them.
    described: &'static str,
}

impl<'a> ProfileKeys<'a> {
    /// The keys of `raw`'s profile; an unknown profile is an error naming the ones there are.
    fn of(ctx: &'a Ctx<'a>, raw: &'a RawTemperature) -> Result<ProfileKeys<'a>, ConfigError> {
        let name = raw.profile.get_ref().as_str();
        let (uses, described): (&'static [&'static str], &'static str) = match name {
            "constant" => (&["value"], "value"),
            "ramp" => (&["start", "rate", "end"], "start, rate and optionally end"),
            "warmup" => (
                &["start", "end", "time_constant"],
                "start, end, time_constant",
            ),
            "sinusoid" => (&["mean", "amplitude", "period"], "mean, amplitude, period"),
            "step" => (&["start", "end", "at"], "start, end, at"),
            other => {
                return Err(ctx.invalid_at(
                    "temperature.profile",
                    Some(&raw.profile),
                    "one of \"constant\", \"ramp\", \"warmup\", \"sinusoid\", \"step\"",
                    format!("\"{other}\""),
                ))
            }
        };
        Ok(ProfileKeys {
            ctx,
            name,
            uses,
            described,
        })
    }

    /// A key the profile does not use is an error (`reference` belongs to every profile).
    fn check_no_extra(&self, raw: &RawTemperature) -> Result<(), ConfigError> {
        let fields: [(&str, &Option<Text>); 10] = [
            ("value", &raw.value),
            ("start", &raw.start),
            ("end", &raw.end),
            ("rate", &raw.rate),
            ("time_constant", &raw.time_constant),
            ("mean", &raw.mean),
            ("amplitude", &raw.amplitude),
            ("period", &raw.period),
            ("at", &raw.at),
            ("reference", &raw.reference),
        ];
        for (name, v) in fields {
            if v.is_some() && name != "reference" && !self.uses.contains(&name) {
                return Err(self.ctx.invalid_at(
                    &format!("temperature.{name}"),
                    v.as_ref(),
                    format!("only {} for profile \"{}\"", self.described, self.name),
                    "an extra key",
                ));
            }
        }
        Ok(())
    }

    /// A key the profile needs, with its dotted name; missing is an error listing the keys.
    fn need(&self, name: &str, v: &Option<Text>) -> Result<(String, Text), ConfigError> {
        let key = format!("temperature.{name}");
        let text = v.clone().ok_or_else(|| {
            self.ctx.invalid(
                &key,
                format!("{} for profile \"{}\"", self.described, self.name),
                "nothing",
            )
        })?;
        Ok((key, text))
    }

    /// A needed value of quantity `q`, any sign.
    fn get(&self, name: &str, v: &Option<Text>, q: Quantity) -> Result<f64, ConfigError> {
        let (key, text) = self.need(name, v)?;
        self.ctx.value(&key, &text, q, false)
    }

    /// A needed value of quantity `q`, > 0.
    fn get_positive(&self, name: &str, v: &Option<Text>, q: Quantity) -> Result<f64, ConfigError> {
        let (key, text) = self.need(name, v)?;
        self.ctx.positive(&key, &text, q)
    }

    /// The profile from its keys (checked by [`ProfileKeys::of`] and `check_no_extra`).
    fn profile(&self, raw: &RawTemperature) -> Result<TemperatureProfile, ConfigError> {
        let t = Quantity::Temperature;
        Ok(match self.name {
            "constant" => TemperatureProfile::Constant {
                temp_c: self.get("value", &raw.value, t)?,
            },
            "ramp" => self.ramp(raw)?,
            "warmup" => TemperatureProfile::Warmup {
                start_c: self.get("start", &raw.start, t)?,
                end_c: self.get("end", &raw.end, t)?,
                time_constant_s: self.get_positive(
                    "time_constant",
                    &raw.time_constant,
                    Quantity::Time,
                )?,
            },
            "step" => {
                let (key, at) = self.need("at", &raw.at)?;
                TemperatureProfile::Step {
                    before_c: self.get("start", &raw.start, t)?,
                    after_c: self.get("end", &raw.end, t)?,
                    at_s: self.ctx.value(&key, &at, Quantity::Time, true)?,
                }
            }
            _ => TemperatureProfile::Sinusoid {
                mean_c: self.get("mean", &raw.mean, t)?,
                amplitude_c: self.get("amplitude", &raw.amplitude, t)?,
                period_s: self.get_positive("period", &raw.period, Quantity::Time)?,
            },
        })
    }

    /// A ramp: start and rate, and an end it must be able to reach.
    fn ramp(&self, raw: &RawTemperature) -> Result<TemperatureProfile, ConfigError> {
        let t = Quantity::Temperature;
        let start_c = self.get("start", &raw.start, t)?;
        let rate_c_per_s = self.get("rate", &raw.rate, Quantity::TemperatureRate)?;
        let end_c = match &raw.end {
            None => None,
            Some(text) => {
                let end = self.ctx.value("temperature.end", text, t, false)?;
                if (end - start_c) * rate_c_per_s < 0.0 {
                    return Err(self.ctx.invalid_at(
                        "temperature.end",
                        Some(text),
                        "an end temperature the ramp reaches (above start for a rising ramp, below for a falling one)",
                        format!("\"{}\"", text.get_ref()),
                    ));
                }
                Some(end)
            }
        };
        Ok(TemperatureProfile::Ramp {
            start_c,
            rate_c_per_s,
            end_c,
        })
    }
}

pub(super) fn convert_triad(
    ctx: &Ctx,
    sensor: Sensor,
    raw: RawTriad,
) -> Result<TriadModel, ConfigError> {
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

/// One axis: each effect's key from the axis table, or else from `all` (errors name the table the
/// value came from), read by its term in `Effect` order, the terms that read the others last.
fn convert_axis(
    ctx: &Ctx,
    sensor: Sensor,
    axis_name: &str,
    raw: &RawAxis,
    all: &RawAxis,
) -> Result<AxisModel, ConfigError> {
    let mut m = AxisModel::default();
    for late in [false, true] {
        for effect in Effect::ALL {
            if effect.reads_other_terms() != late {
                continue;
            }
            let (table, from) = if raw.has(effect) {
                (raw, axis_name)
            } else {
                (all, "all")
            };
            let cx = ReadContext {
                ctx,
                key: format!("{}.{from}.{}", sensor.name(), effect.name()),
                sig: signal_of(sensor),
                others: &m,
                position: effect as usize,
            };
            if let Some(term) = table.read(effect, &cx) {
                let term = term?;
                m.set_term(term);
            }
        }
    }
    let (spreads, from) = match (&raw.run_to_run, &all.run_to_run) {
        (Some(s), _) => (s, axis_name),
        (None, Some(s)) => (s, "all"),
        (None, None) => return Ok(m),
    };
    for (name, value) in spreads {
        let key = format!("{}.{from}.run_to_run.{name}", sensor.name());
        let span = Some(value.span());
        let err = |expected: String, found: String| {
            ctx.invalid_in_span(&key, span.clone(), expected, found)
        };
        let Some(effect) = Effect::from_name(name) else {
            return Err(err(
                "the name of a term of the axis with a level (such as rate_random_walk)".into(),
                format!("`{name}`, not an effect"),
            ));
        };
        let spread = read_spread(value.get_ref()).map_err(|found| {
            err(
                format!(
                    "a spread from 0 to {} (the sd of the level's natural log between power-ons): a number, or a string such as \"30 %\"",
                    crate::run_to_run::MAX_SPREAD
                ),
                found,
            )
        })?;
        m.set_run_to_run(effect, spread).map_err(|e| {
            let expected = match e.expected {
                "a term the axis has" => format!(
                    "a term the axis has (`{}.{axis_name}` has no `{name}`)",
                    sensor.name()
                ),
                other => other.to_string(),
            };
            err(expected, value.get_ref().to_string())
        })?;
    }
    Ok(m)
}

/// A run-to-run spread as written: a number (0.3), or a string with a per-cent sign ("30 %") or
/// without ("0.3"); the text found when it is neither or outside 0 ..= `MAX_SPREAD`.
fn read_spread(value: &toml::Value) -> Result<f64, String> {
    let v = match value {
        toml::Value::Float(f) => *f,
        toml::Value::Integer(i) => *i as f64,
        toml::Value::String(t) => {
            let t = t.trim();
            let (number, scale) = match t.strip_suffix('%') {
                Some(n) => (n.trim(), 0.01),
                None => (t, 1.0),
            };
            number
                .parse::<f64>()
                .map(|v| v * scale)
                .map_err(|_| value.to_string())?
        }
        _ => return Err(value.to_string()),
    };
    if !(0.0..=crate::run_to_run::MAX_SPREAD).contains(&v) {
        return Err(value.to_string());
    }
    Ok(v)
}

pub(crate) fn signal_of(sensor: Sensor) -> Signal {
    match sensor {
        Sensor::Gyro => Signal::AngularRate,
        Sensor::Accel => Signal::Acceleration,
    }
}
