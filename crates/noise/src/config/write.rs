//! The model written back as a sensor TOML (SI units, every axis explicit).

use super::signal_of;
use crate::effect::Sensor;
use crate::model::*;
use crate::temperature::TemperatureProfile;
use crate::terms::bias_instability::BiasInstability;
use crate::terms::constant_bias::ConstantBias;
use crate::terms::gauss_markov::GaussMarkov;
use crate::terms::misalignment::Misalignment;
use crate::terms::outliers::Outliers;
use crate::terms::output_filter::{FilterKind, OutputFilter};
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
use crate::units::{format_si, Quantity, Signal};
use crate::AXIS_NAMES;
use std::fmt::Write as _;

impl SensorModel {
    /// The `[temperature]` table, each value written by `fmt` (value SI, quantity).
    fn write_temperature(&self, s: &mut String, fmt: &dyn Fn(f64, Quantity) -> String) {
        let t = Quantity::Temperature;
        let _ = writeln!(s, "\n[temperature]");
        match &self.temperature {
            TemperatureProfile::Constant { temp_c } => {
                let _ = writeln!(s, "profile = \"constant\"\nvalue = \"{}\"", fmt(*temp_c, t));
            }
            TemperatureProfile::Ramp {
                start_c,
                rate_c_per_s,
                end_c,
            } => {
                let _ = writeln!(
                    s,
                    "profile = \"ramp\"\nstart = \"{}\"\nrate = \"{}\"",
                    fmt(*start_c, t),
                    fmt(*rate_c_per_s, Quantity::TemperatureRate)
                );
                if let Some(e) = end_c {
                    let _ = writeln!(s, "end = \"{}\"", fmt(*e, t));
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
                    fmt(*start_c, t),
                    fmt(*end_c, t),
                    fmt(*time_constant_s, Quantity::Time)
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
                    fmt(*mean_c, t),
                    fmt(*amplitude_c, t),
                    fmt(*period_s, Quantity::Time)
                );
            }
            TemperatureProfile::Step {
                before_c,
                after_c,
                at_s,
            } => {
                let _ = writeln!(
                    s,
                    "profile = \"step\"\nstart = \"{}\"\nend = \"{}\"\nat = \"{}\"",
                    fmt(*before_c, t),
                    fmt(*after_c, t),
                    fmt(*at_s, Quantity::Time)
                );
            }
        }
        let _ = writeln!(
            s,
            "reference = \"{}\"",
            fmt(self.temperature_reference_c, t)
        );
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
        self.write_temperature(&mut s, &format_si);
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
    // `{:?}`: the shortest text that parses back to the same bits.
    write_axis_with(s, a, sig, &format_si, &|v| format!("{v:?}"));
}

/// The keys of one axis, each value written by `format_si` (value, quantity) -> "value unit",
/// plain numbers (the outlier rate per hour) by `number`.
fn write_axis_with(
    s: &mut String,
    a: &AxisModel,
    sig: Signal,
    format_si: &dyn Fn(f64, Quantity) -> String,
    number: &dyn Fn(f64) -> String,
) {
    let mut line = |key: &str, v: f64, q: Quantity| {
        let _ = writeln!(s, "{key} = \"{}\"", format_si(v, q));
    };
    if let Some(v) = a.get::<Quantization>().map(Quantization::coefficient) {
        line("quantization", v, Quantity::Integrated(sig));
    }
    if let Some(v) = a.get::<WhiteNoise>().map(WhiteNoise::density) {
        line("white_noise", v, Quantity::NoiseDensity(sig));
    }
    if let Some(v) = a.get::<RateRandomWalk>().map(RateRandomWalk::density) {
        line("rate_random_walk", v, Quantity::RandomWalk(sig));
    }
    if let Some(v) = a.get::<RateRamp>().map(RateRamp::rate) {
        line("rate_ramp", v, Quantity::Ramp(sig));
    }
    if let Some(v) = a.get::<TemperatureBias>().map(TemperatureBias::per_degree) {
        line("temperature_bias", v, Quantity::PerDegree(sig));
    }
    if let Some(v) = a.get::<ConstantBias>().map(ConstantBias::bias) {
        line("constant_bias", v, Quantity::Signal(sig));
    }
    if let Some(v) = a.get::<TurnOnBias>().map(TurnOnBias::sigma) {
        line("turn_on_bias", v, Quantity::Signal(sig));
    }
    if let Some(v) = a.get::<ScaleFactor>().map(ScaleFactor::ratio) {
        line("scale_factor", v, Quantity::Ratio);
    }
    match a.get::<BiasInstability>() {
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
    if let Some(g) = a.get::<GaussMarkov>() {
        let _ = writeln!(
            s,
            "gauss_markov = {{ sigma = \"{}\", time_constant = \"{}\" }}",
            format_si(g.sigma, Quantity::Signal(sig)),
            format_si(g.tau_s, Quantity::Time)
        );
    }
    if let Some(w) = a.get::<Sinusoid>() {
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
    if let Some(f) = a.get::<OutputFilter>() {
        let parameter = match f.kind {
            FilterKind::MovingAverage { taps } | FilterKind::Bartlett { taps } => {
                format!("taps = {taps}")
            }
            FilterKind::LowPass1 { cutoff_hz } | FilterKind::LowPass2 { cutoff_hz } => {
                format!("cutoff = \"{}\"", format_si(cutoff_hz, Quantity::Frequency))
            }
        };
        let _ = writeln!(
            s,
            "output_filter = {{ kind = \"{}\", {parameter}, decimation = {} }}",
            f.kind.name(),
            f.decimation
        );
    }
    if let Some(o) = a.get::<Outliers>() {
        let _ = writeln!(
            s,
            "outliers = {{ rate = \"{} /h\", size = \"{}\" }}",
            number(o.rate_per_hour),
            format_si(o.size, Quantity::Signal(sig))
        );
    }
    if let Some(w) = a.get::<WarmupTransient>() {
        let _ = writeln!(
            s,
            "warmup_transient = {{ amplitude = \"{}\", time_constant = \"{}\", per_run = {} }}",
            format_si(w.amplitude, Quantity::Signal(sig)),
            format_si(w.tau_s, Quantity::Time),
            w.per_run
        );
    }
    if let Some(r) = a.get::<Resonance>() {
        let _ = writeln!(
            s,
            "resonance = {{ sigma = \"{}\", frequency = \"{}\", bandwidth = \"{}\" }}",
            format_si(r.sigma, Quantity::Signal(sig)),
            format_si(r.frequency_hz, Quantity::Frequency),
            format_si(r.bandwidth_hz, Quantity::Frequency)
        );
    }
    if let Some([m1, m2]) = a.get::<Misalignment>().map(Misalignment::angles_rad) {
        let _ = writeln!(
            s,
            "misalignment = [\"{}\", \"{}\"]",
            format_si(m1, Quantity::Angle),
            format_si(m2, Quantity::Angle)
        );
    }
}

/// The units a written config uses for each quantity: those of an existing config where it has
/// the quantity, else the units spec sheets use (deg/h, deg/sqrt(h), ug, m/s/sqrt(h), ...).
#[derive(Clone, Debug, Default)]
pub struct UnitStyle {
    /// (quantity, unit text) found in the config, first occurrence.
    units: Vec<(Quantity, String)>,
}

impl UnitStyle {
    /// The units of a config's text (a sensor TOML); unknown or unreadable parts are ignored.
    pub fn from_config_text(text: &str) -> UnitStyle {
        let mut units: Vec<(Quantity, String)> = Vec::new();
        let Ok(doc) = text.parse::<toml::Table>() else {
            return UnitStyle::default();
        };
        let mut note = |q: Quantity, v: &toml::Value| {
            if let Some(t) = v.as_str() {
                let unit = crate::units::unit_part(t).trim().to_string();
                if !unit.is_empty()
                    && !units.iter().any(|(k, _)| *k == q)
                    && crate::units::parse_quantity(&format!("1 {unit}"), q).is_ok()
                {
                    units.push((q, unit));
                }
            }
        };
        for sensor in Sensor::ALL {
            let sig = signal_of(sensor);
            let Some(tables) = doc.get(sensor.name()).and_then(|v| v.as_table()) else {
                continue;
            };
            for axis in tables.values().filter_map(|v| v.as_table()) {
                for (key, v) in axis {
                    let q = match key.as_str() {
                        "quantization" => Quantity::Integrated(sig),
                        "white_noise" => Quantity::NoiseDensity(sig),
                        "rate_random_walk" => Quantity::RandomWalk(sig),
                        "rate_ramp" => Quantity::Ramp(sig),
                        "temperature_bias" => Quantity::PerDegree(sig),
                        "constant_bias" | "turn_on_bias" | "bias_instability" | "outliers"
                        | "warmup_transient" | "output_filter" | "resonance" => {
                            Quantity::Signal(sig)
                        }
                        "scale_factor" => Quantity::Ratio,
                        "misalignment" => {
                            if let Some(first) = v.as_array().and_then(|a| a.first()) {
                                note(Quantity::Angle, first);
                            }
                            continue;
                        }
                        _ => continue,
                    };
                    match v.as_table() {
                        None => note(q, v),
                        Some(t) => {
                            for (k, inner) in t {
                                match k.as_str() {
                                    "value" | "sigma" | "amplitude" | "stability" | "size" => {
                                        note(Quantity::Signal(sig), inner)
                                    }
                                    "time_constant" | "period" => note(Quantity::Time, inner),
                                    "frequency" | "cutoff" | "bandwidth" => {
                                        note(Quantity::Frequency, inner)
                                    }
                                    _ => {}
                                }
                            }
                        }
                    }
                }
            }
        }
        UnitStyle { units }
    }

    /// The unit for a quantity.
    fn unit(&self, q: Quantity) -> &str {
        if let Some((_, u)) = self.units.iter().find(|(k, _)| *k == q) {
            return u;
        }
        match q {
            Quantity::Signal(Signal::AngularRate) => "deg/h",
            Quantity::Signal(Signal::Acceleration) => "ug",
            Quantity::NoiseDensity(Signal::AngularRate) => "deg/sqrt(h)",
            Quantity::NoiseDensity(Signal::Acceleration) => "m/s/sqrt(h)",
            Quantity::RandomWalk(Signal::AngularRate) => "deg/h/sqrt(h)",
            Quantity::RandomWalk(Signal::Acceleration) => "ug/sqrt(h)",
            Quantity::Ramp(Signal::AngularRate) => "deg/h/h",
            Quantity::Ramp(Signal::Acceleration) => "ug/h",
            Quantity::Integrated(Signal::AngularRate) => "deg",
            Quantity::Integrated(Signal::Acceleration) => "m/s",
            Quantity::PerDegree(Signal::AngularRate) => "deg/h/degC",
            Quantity::PerDegree(Signal::Acceleration) => "ug/degC",
            Quantity::Angle => "deg",
            Quantity::Ratio => "ppm",
            Quantity::Time => "s",
            Quantity::Frequency => "Hz",
            Quantity::Temperature => "degC",
            Quantity::TemperatureRate => "degC/s",
        }
    }

    /// `value` (SI) as "v unit" with five significant digits.
    pub fn format(&self, value: f64, q: Quantity) -> String {
        let unit = self.unit(q);
        match crate::units::parse_quantity(&format!("1 {unit}"), q) {
            Ok(factor) if factor > 0.0 && q != Quantity::Temperature => {
                format!("{} {unit}", sig5(value / factor))
            }
            _ => format!("{} {}", sig5(value), q.si_unit()),
        }
    }
}

/// Five significant digits, plain where that is short, else with an exponent.
fn sig5(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let e = v.abs().log10().floor() as i32;
    if (-3..6).contains(&e) {
        let decimals = (4 - e).max(0) as usize;
        let t = format!("{v:.decimals$}");
        if t.contains('.') {
            t.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            t
        }
    } else {
        format!("{v:.4e}")
    }
}

impl SensorModel {
    /// Write the model as a config in `style`'s units with about five significant digits: a
    /// triad whose three axes agree as one `[sensor.all]` table, no empty tables, the temperature
    /// table only when it is not the default (constant 25 degC). For people; `to_toml_string` is
    /// the exact SI form.
    pub fn to_toml_string_styled(&self, style: &UnitStyle) -> String {
        let f = |v: f64, q: Quantity| style.format(v, q);
        let mut s = String::new();
        let _ = writeln!(s, "name = {}", toml_str(&self.name));
        if let Some(d) = &self.description {
            let _ = writeln!(s, "description = {}", toml_str(d));
        }
        let default_temperature = self.temperature == TemperatureProfile::default()
            && self.temperature_reference_c == 25.0;
        if !default_temperature {
            self.write_temperature(&mut s, &f);
        }
        for sensor in Sensor::ALL {
            let sig = signal_of(sensor);
            let axes = &self.triad(sensor).axes;
            if axes[0] == axes[1] && axes[1] == axes[2] {
                if axes[0] != AxisModel::default() {
                    let _ = writeln!(s, "\n[{}.all]", sensor.name());
                    write_axis_with(&mut s, &axes[0], sig, &f, &sig5);
                }
                continue;
            }
            for (axis, name) in axes.iter().zip(AXIS_NAMES) {
                if *axis != AxisModel::default() {
                    let _ = writeln!(s, "\n[{}.{}]", sensor.name(), name);
                    write_axis_with(&mut s, axis, sig, &f, &sig5);
                }
            }
        }
        s
    }
}
