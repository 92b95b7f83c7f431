//! Raw TOML values to the validated SI model: units parsed, ranges checked, errors naming the
//! file, line, key and what was expected.

use super::allan_minimum::solve_b_for_minimum;
use super::error::ConfigError;
use super::raw::*;
use crate::effect::Sensor;
use crate::model::*;
use crate::model_error::ModelError;
use crate::temperature::TemperatureProfile;
use crate::terms::bias_instability::{BiasInstability, Flicker};
use crate::terms::constant_bias::ConstantBias;
use crate::terms::gauss_markov::GaussMarkov;
use crate::terms::misalignment::Misalignment;
use crate::terms::outliers::Outliers;
use crate::terms::output_filter::{FilterKind, OutputFilter, MAX_RESPONSE};
use crate::terms::quantization::Quantization;
use crate::terms::rate_ramp::RateRamp;
use crate::terms::rate_random_walk::RateRandomWalk;
use crate::terms::resonance::Resonance;
use crate::terms::scale_factor::ScaleFactor;
use crate::terms::sinusoidal::Sinusoid;
use crate::terms::temperature_bias::TemperatureBias;
use crate::terms::turn_on_bias::TurnOnBias;
use crate::terms::warmup_transient::WarmupTransient;
use crate::terms::white_noise::WhiteNoise;
use crate::units::{parse_quantity, unit_part, Quantity, Signal};
use crate::AXIS_NAMES;

/// Most Gauss-Markov components a flicker bias instability may have (20 decades at 5 per decade).
const MAX_FLICKER_COMPONENTS: f64 = 100.0;

/// Conversion context: file name for errors.
pub(super) struct Ctx<'a> {
    pub(super) file: &'a str,
    pub(super) source: &'a str,
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

    /// A rate of events per hour: `"60 /h"`, `"2 /min"`, `"0.01 /s"`, any frequency unit
    /// (`"1/h"`, `"0.01 Hz"`), or a plain number meaning per hour. A value per hour keeps its bits.
    fn per_hour(&self, key: &str, text: &Text) -> Result<f64, ConfigError> {
        let quoted = format!("\"{}\"", text.get_ref());
        let err = |why: String| {
            self.invalid_at(
                key,
                Some(text),
                format!("a number of events per time such as \"60 /h\", \"2 /min\", \"0.01 /s\", or a plain number per hour ({why})"),
                quoted.clone(),
            )
        };
        let all = text.get_ref().trim();
        let unit = unit_part(all);
        let value = parse_quantity(&all[..all.len() - unit.len()], Quantity::Ratio)
            .map_err(|e| err(e.to_string()))?;
        let unit = unit.trim();
        let factor = if unit.is_empty() {
            1.0
        } else {
            // "/h" reads as "1/h".
            let expr = if unit.starts_with('/') {
                format!("1 1{unit}")
            } else {
                format!("1 {unit}")
            };
            let per_hour = 3600.0
                * parse_quantity(&expr, Quantity::Frequency).map_err(|e| err(e.to_string()))?;
            if (per_hour - 1.0).abs() < 1e-12 {
                1.0
            } else {
                per_hour
            }
        };
        let v = value * factor;
        if !v.is_finite() || v < 0.0 {
            return Err(self.invalid_at(key, Some(text), "a rate >= 0", quoted));
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

pub(crate) fn signal_of(sensor: Sensor) -> Signal {
    match sensor {
        Sensor::Gyro => Signal::AngularRate,
        Sensor::Accel => Signal::Acceleration,
    }
}

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
    let mut m = AxisModel::default();
    // A value that parsed but that the term's constructor refuses (not finite).
    let refused = |key: String, e: ModelError| ctx.invalid(&key, e.expected, e.to_string());
    macro_rules! scalar {
        ($f:ident, $q:expr, $nonneg:expr, $ty:ident) => {
            if let Some((v, key)) = pick!($f) {
                let value = ctx.value(&key, v, $q, $nonneg)?;
                m.set_term($ty::new(value).map_err(|e| refused(key, e))?);
            }
        };
    }
    scalar!(quantization, Quantity::Integrated(sig), true, Quantization);
    scalar!(white_noise, Quantity::NoiseDensity(sig), true, WhiteNoise);
    scalar!(
        rate_random_walk,
        Quantity::RandomWalk(sig),
        true,
        RateRandomWalk
    );
    scalar!(rate_ramp, Quantity::Ramp(sig), false, RateRamp);
    scalar!(
        temperature_bias,
        Quantity::PerDegree(sig),
        false,
        TemperatureBias
    );
    scalar!(constant_bias, Quantity::Signal(sig), false, ConstantBias);
    scalar!(turn_on_bias, Quantity::Signal(sig), true, TurnOnBias);
    scalar!(scale_factor, Quantity::Ratio, false, ScaleFactor);
    if let Some((g, key)) = pick!(gauss_markov) {
        m.set_term(GaussMarkov {
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
        m.set_term(Sinusoid {
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
        let angles = [
            ctx.value(&format!("{key}[0]"), &list[0], Quantity::Angle, false)?,
            ctx.value(&format!("{key}[1]"), &list[1], Quantity::Angle, false)?,
        ];
        m.set_term(Misalignment::new(angles).map_err(|e| refused(key, e))?);
    }
    if let Some((f, key)) = pick!(output_filter) {
        m.set_term(convert_output_filter(ctx, &key, f)?);
    }
    if let Some((o, key)) = pick!(outliers) {
        let rate = ctx.per_hour(&format!("{key}.rate"), &o.rate)?;
        let size_key = format!("{key}.size");
        let size = ctx.value(&size_key, &o.size, Quantity::Signal(sig), true)?;
        m.set_term(
            Outliers::new(rate, size)
                .map_err(|e| ctx.invalid_at(&size_key, Some(&o.size), e.expected, e.to_string()))?,
        );
    }
    if let Some((w, key)) = pick!(warmup_transient) {
        m.set_term(
            WarmupTransient::new(
                ctx.value(
                    &format!("{key}.amplitude"),
                    &w.amplitude,
                    Quantity::Signal(sig),
                    false,
                )?,
                ctx.positive(
                    &format!("{key}.time_constant"),
                    &w.time_constant,
                    Quantity::Time,
                )?,
                w.per_run.unwrap_or(false),
            )
            .map_err(|e| ctx.invalid(&key, e.expected, e.to_string()))?,
        );
    }
    if let Some((r, key)) = pick!(resonance) {
        let bw_key = format!("{key}.bandwidth");
        m.set_term(
            Resonance::new(
                ctx.value(
                    &format!("{key}.sigma"),
                    &r.sigma,
                    Quantity::Signal(sig),
                    true,
                )?,
                ctx.positive(
                    &format!("{key}.frequency"),
                    &r.frequency,
                    Quantity::Frequency,
                )?,
                ctx.positive(&bw_key, &r.bandwidth, Quantity::Frequency)?,
            )
            .map_err(|e| {
                ctx.invalid_at(
                    &bw_key,
                    Some(&r.bandwidth),
                    e.expected,
                    format!(
                        "\"{}\" with frequency \"{}\"",
                        r.bandwidth.get_ref(),
                        r.frequency.get_ref()
                    ),
                )
            })?,
        );
    }
    // Bias instability last: the "allan_minimum" convention needs the other terms.
    if let Some((b, key)) = pick!(bias_instability) {
        let table = RawBiasField::table(b);
        let b = convert_bias_instability(ctx, &key, &table, sig, &m)?;
        m.set_term(b);
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

/// `output_filter = { kind, taps | cutoff, decimation? }`: the kind's own parameter and no other.
fn convert_output_filter(
    ctx: &Ctx,
    key: &str,
    raw: &RawOutputFilter,
) -> Result<OutputFilter, ConfigError> {
    let sub = |name: &str| format!("{key}.{name}");
    // An integer's place in the file, for `invalid_at`.
    let at = |i: &Integer| Text::new(i.span(), i.get_ref().to_string());
    let kind = raw.kind.get_ref().as_str();
    let fir = match kind {
        "moving_average" | "bartlett" => true,
        "lowpass1" | "lowpass2" => false,
        other => {
            return Err(ctx.invalid_at(
                &sub("kind"),
                Some(&raw.kind),
                "one of \"moving_average\", \"bartlett\" (with taps), \"lowpass1\", \"lowpass2\" (with cutoff)",
                format!("\"{other}\""),
            ))
        }
    };
    let (needs, extra) = if fir {
        ("taps", raw.cutoff.clone().map(|c| ("cutoff", c)))
    } else {
        ("cutoff", raw.taps.as_ref().map(|t| ("taps", at(t))))
    };
    if let Some((name, text)) = extra {
        return Err(ctx.invalid_at(
            &sub(name),
            Some(&text),
            format!("only `{needs}` and `decimation` for kind \"{kind}\""),
            "an extra key",
        ));
    }
    let kind = if fir {
        let t = raw.taps.as_ref().ok_or_else(|| {
            ctx.invalid(
                &sub("taps"),
                format!("the number of taps for kind \"{kind}\", an integer such as taps = 8"),
                "nothing",
            )
        })?;
        let taps = u32::try_from(*t.get_ref())
            .ok()
            .filter(|&n| n >= 1 && n as usize <= MAX_RESPONSE)
            .ok_or_else(|| {
                ctx.invalid_at(
                    &sub("taps"),
                    Some(&at(t)),
                    format!("an integer from 1 to {MAX_RESPONSE}"),
                    t.get_ref().to_string(),
                )
            })?;
        if kind == "moving_average" {
            FilterKind::MovingAverage { taps }
        } else {
            FilterKind::Bartlett { taps }
        }
    } else {
        let c = raw.cutoff.as_ref().ok_or_else(|| {
            ctx.invalid(
                &sub("cutoff"),
                format!("the cutoff frequency for kind \"{kind}\", e.g. cutoff = \"25 Hz\""),
                "nothing",
            )
        })?;
        let cutoff_hz = ctx.positive(&sub("cutoff"), c, Quantity::Frequency)?;
        if kind == "lowpass1" {
            FilterKind::LowPass1 { cutoff_hz }
        } else {
            FilterKind::LowPass2 { cutoff_hz }
        }
    };
    let decimation = match &raw.decimation {
        None => 1,
        Some(d) => u32::try_from(*d.get_ref())
            .ok()
            .filter(|&n| n >= 1)
            .ok_or_else(|| {
                ctx.invalid_at(
                    &sub("decimation"),
                    Some(&at(d)),
                    "a whole number >= 1 (internal samples per output sample; 1: no decimation)",
                    d.get_ref().to_string(),
                )
            })?,
    };
    OutputFilter::new(kind, decimation).map_err(|e| ctx.invalid(key, e.expected, e.to_string()))
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
