//! The model written back as a sensor TOML (SI units, every axis explicit).

use super::signal_of;
use crate::effect::Sensor;
use crate::model::*;
use crate::units::{format_si, Quantity, Signal};
use std::fmt::Write as _;

impl SensorModel {
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
