//! The model written back as a sensor TOML (SI units, every axis explicit).

use super::convert::signal_of;
use crate::effect::Sensor;
use crate::model::*;
use crate::temperature::TemperatureProfile;
use crate::terms::bias_instability::{model_adev_minimum, BiasInstability, Flicker};
use crate::terms::{Effect, WriteContext, WRITE_ORDER};
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
    write_axis_with(s, a, sig, &format_si, &|v| format!("{v:?}"), false);
}

/// The keys of one axis in [`WRITE_ORDER`], each value written by its term with `format_si`
/// (value, quantity) -> "value unit", plain numbers (the outlier rate per hour) by `number`.
fn write_axis_with(
    s: &mut String,
    a: &AxisModel,
    sig: Signal,
    format_si: &dyn Fn(f64, Quantity) -> String,
    number: &dyn Fn(f64) -> String,
    bi_as_minimum: bool,
) {
    let cx = WriteContext {
        sig,
        format: format_si,
        number,
    };
    for effect in WRITE_ORDER {
        if let Some(term) = a.term(effect) {
            let minimum = match a.get::<BiasInstability>() {
                Some(BiasInstability::Flicker(f))
                    if bias_instability_minimum_wanted(bi_as_minimum, effect) =>
                {
                    allan_minimum_value(a, f, &cx)
                }
                _ => None,
            };
            let value = minimum.unwrap_or_else(|| term.as_error_term().config_value(&cx));
            let _ = writeln!(s, "{} = {value}", effect.name());
        }
    }
    // The run-to-run spreads (docs/model.md §2.3), plain numbers, in `Effect` order.
    if !a.run_to_run().is_empty() {
        let items: Vec<String> = a
            .run_to_run()
            .iter()
            .map(|(e, &v)| format!("{} = {}", e.name(), number(v)))
            .collect();
        let _ = writeln!(s, "run_to_run = {{ {} }}", items.join(", "));
    }
}

/// Whether the bias instability is written in the `allan_minimum` convention.
fn bias_instability_minimum_wanted(bi_as_minimum: bool, effect: Effect) -> bool {
    bi_as_minimum && effect == Effect::BiasInstability
}

/// A flicker bias instability in the `allan_minimum` convention: the minimum of the axis' closed-
/// form Allan deviation over the plateau, as the reader takes it (`solve_b_for_minimum` against
/// the terms read before it: every term but those that read the others), so the value reads back
/// to the same B up to the printed digits. `None` when B adds less than 0.1 % to the minimum of the
/// other terms (a minimum that could not be read back to B): the `ieee` form is written then.
fn allan_minimum_value(a: &AxisModel, f: &Flicker, cx: &WriteContext) -> Option<String> {
    let mut others = a.clone();
    for e in Effect::ALL {
        if e.reads_other_terms() {
            others.remove(e);
        }
    }
    let floor = model_adev_minimum(&|tau| others.allan_variance(tau), f).0;
    others.set_term(BiasInstability::Flicker(f.clone()));
    let minimum = model_adev_minimum(&|tau| others.allan_variance(tau), f).0;
    if !(minimum.is_finite() && minimum - floor > 1e-3 * minimum) {
        return None;
    }
    Some(format!(
        "{{ value = {}, convention = \"allan_minimum\", band = [{}, {}], per_decade = {} }}",
        cx.quoted(minimum, Quantity::Signal(cx.sig)),
        cx.quoted(f.tau_min_s(), Quantity::Time),
        cx.quoted(f.tau_max_s(), Quantity::Time),
        f.per_decade()
    ))
}

/// The units a written config uses for each quantity: those of an existing config where it has
/// the quantity, else the units spec sheets use (deg/h, deg/sqrt(h), ug, m/s/sqrt(h), ...).
#[derive(Clone, Debug, Default)]
pub struct UnitStyle {
    /// (quantity, unit text) found in the config, first occurrence.
    units: Vec<(Quantity, String)>,
    /// The config gives a bias instability in the `allan_minimum` convention (stated, or a plain
    /// value, which means it): the written model keeps that convention.
    bi_allan_minimum: bool,
}

impl UnitStyle {
    /// The units of a config's text (a sensor TOML); unknown or unreadable parts are ignored.
    pub fn from_config_text(text: &str) -> UnitStyle {
        let mut units: Vec<(Quantity, String)> = Vec::new();
        let mut bi_allan_minimum = false;
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
                    if key == Effect::BiasInstability.name() {
                        bi_allan_minimum |= v.is_str()
                            || v.get("convention").and_then(|c| c.as_str())
                                == Some("allan_minimum");
                    }
                    if let Some(effect) = Effect::from_name(key) {
                        effect.note_units(v, sig, &mut note);
                    }
                }
            }
        }
        UnitStyle {
            units,
            bi_allan_minimum,
        }
    }

    /// Whether a model written in this style gives its bias instability as the Allan minimum
    /// (the config it was read from did).
    pub fn keeps_allan_minimum(&self) -> bool {
        self.bi_allan_minimum
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
    /// The keys of one axis (`sensor`, axis 0-2) as [`SensorModel::to_toml_string_styled`] writes
    /// them under its `[sensor.axis]` header, without the header.
    pub fn axis_toml_styled(&self, sensor: Sensor, axis: usize, style: &UnitStyle) -> String {
        let f = |v: f64, q: Quantity| style.format(v, q);
        let mut s = String::new();
        let a = &self.triad(sensor).axes[axis];
        write_axis_with(
            &mut s,
            a,
            signal_of(sensor),
            &f,
            &sig5,
            style.bi_allan_minimum,
        );
        s
    }

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
                    write_axis_with(&mut s, &axes[0], sig, &f, &sig5, style.bi_allan_minimum);
                }
                continue;
            }
            for (axis, name) in axes.iter().zip(AXIS_NAMES) {
                if *axis != AxisModel::default() {
                    let _ = writeln!(s, "\n[{}.{}]", sensor.name(), name);
                    write_axis_with(&mut s, axis, sig, &f, &sig5, style.bi_allan_minimum);
                }
            }
        }
        s
    }
}
