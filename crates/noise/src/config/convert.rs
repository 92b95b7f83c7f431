//! Raw TOML tables to the validated SI model: the temperature profile, and each axis' terms (each
//! read by its own type, `terms/<effect>.rs`).

use super::error::ConfigError;
use super::raw::*;
use super::read::{signal_of, Ctx, ReadContext, Text};
use crate::effect::Sensor;
use crate::model::*;
use crate::temperature::TemperatureProfile;
use crate::terms::{Effect, RawAxis};
use crate::units::Quantity;
use crate::AXIS_NAMES;

pub(super) fn convert_temperature(
    ctx: &Ctx,
    raw: Option<&RawTemperature>,
) -> Result<(TemperatureProfile, f64), ConfigError> {
    let Some(raw) = raw else {
        return Ok((TemperatureProfile::default(), 25.0));
    };
    let t = Quantity::Temperature;
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
    let profile = raw.profile.get_ref().as_str();
    let (uses, profile_keys): (&[&str], &str) = match profile {
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
        "step" => {
            let (key, at) = need("at", &raw.at)?;
            TemperatureProfile::Step {
                before_c: get("start", &raw.start, t)?,
                after_c: get("end", &raw.end, t)?,
                at_s: ctx.value(&key, &at, Quantity::Time, true)?,
            }
        }
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
            };
            if let Some(term) = table.read(effect, &cx) {
                let term = term?;
                m.set_term(term);
            }
        }
    }
    Ok(m)
}
