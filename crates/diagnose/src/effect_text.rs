//! A `diagnose` finding as a person reads it: each parameter in the unit a spec sheet writes it
//! in, to 4 significant digits, with its 95 % interval where it has one (a discrete choice, such
//! as a filter's taps or decimation or an outlier count, has none); the JSON keeps SI.

use crate::report::FoundEffect;
use noise::text::{allan_units, noise_density_alt, sig, trimmed};

/// How one parameter is shown: scale from SI and unit, or a discrete choice.
enum Shown {
    Scaled(f64, String),
    Discrete(&'static str),
}

/// The display of parameter `key` on a channel whose SI unit is `si_unit` (rad/s or m/s^2).
fn shown(key: &str, si_unit: &str) -> Shown {
    let units = allan_units(si_unit);
    let u = |i: usize| Shown::Scaled(units[i].0, units[i].1.clone());
    match key {
        "q" => u(1),
        "n" | "n_without" => u(2),
        "b" | "level" => u(3),
        "k" => u(4),
        "r" => u(5),
        "sigma" | "amplitude" | "size" => u(0),
        "coefficient" => Shown::Scaled(units[0].0, format!("{}/degC", units[0].1)),
        "tau_s" => Shown::Scaled(1.0, "s".into()),
        "frequency_hz" | "cutoff_hz" | "noise_bandwidth_hz" | "bandwidth_hz" => {
            Shown::Scaled(1.0, "Hz".into())
        }
        "rate_per_hour" => Shown::Scaled(1.0, "/h".into()),
        "threshold_sigma" => Shown::Discrete(" sigma"),
        "count" | "taps" | "decimation" => Shown::Discrete(""),
        _ => Shown::Scaled(1.0, String::new()),
    }
}

/// The SI unit of a channel's samples (`gx`.. rad/s, `ax`.. m/s^2).
fn si_unit_of(ch: noise::Channel) -> &'static str {
    if ch.is_gyro() {
        "rad/s"
    } else {
        "m/s^2"
    }
}

/// The name a parameter is shown under (the JSON key without its unit suffix).
fn label(key: &str) -> &str {
    key.trim_end_matches("_hz")
        .trim_end_matches("_s")
        .trim_end_matches("_sigma")
}

/// `b = 29.37 deg/h [26.32, 32.41]` for every parameter of `e` on channel `ch` (the filter's
/// kind first); the white-noise level also per sqrt(Hz), as datasheets give it.
pub fn params_text(e: &FoundEffect, ch: noise::Channel) -> String {
    // A model's own term refitted to level 0 is removed from the corrected model: the finding is
    // its absence, not an effect of size 0.
    if e.zero_level {
        return "removed from the model: the log shows none of it (fitted level 0)".into();
    }
    let si_unit = si_unit_of(ch);
    let values = e.parameters.iter().map(|(k, &v)| {
        let (lo, hi) = (e.parameters_lo.get(k), e.parameters_hi.get(k));
        match shown(k, si_unit) {
            Shown::Discrete(unit) => format!("{} = {}{unit}", label(k), trimmed(v, 6)),
            Shown::Scaled(scale, unit) => {
                let num = |x: f64| sig(x * scale, 4);
                let space = if unit.is_empty() || unit.starts_with('/') {
                    ""
                } else {
                    " "
                };
                let alt = if matches!(k.as_str(), "n" | "n_without") {
                    noise_density_alt(si_unit, v).map_or(String::new(), |a| format!(" (= {a})"))
                } else {
                    String::new()
                };
                let interval = match (lo, hi) {
                    (Some(&l), Some(&h)) if l.is_finite() && h.is_finite() && l < h => {
                        format!(" [{}, {}]", num(l), num(h))
                    }
                    _ => String::new(),
                };
                format!("{} = {}{space}{unit}{interval}{alt}", label(k), num(v))
            }
        }
    });
    e.parameters
        .kind
        .map(|k| format!("kind = {k}"))
        .into_iter()
        .chain(values)
        .collect::<Vec<_>>()
        .join(", ")
}

/// Values of parameter `key` on channel `ch` (SI) in the unit a spec sheet writes it in, 3
/// significant digits, the unit once after the last: `values_text("n", gz, &[a, b])` is
/// "2.30, 2.41 deg/sqrt(h)" (`drift`'s model levels; the JSON keeps SI).
pub fn values_text(key: &str, ch: noise::Channel, values: &[f64]) -> String {
    match shown(key, si_unit_of(ch)) {
        Shown::Discrete(unit) => values
            .iter()
            .map(|&v| format!("{}{unit}", trimmed(v, 6)))
            .collect::<Vec<_>>()
            .join(", "),
        Shown::Scaled(scale, unit) => {
            let nums: Vec<String> = values.iter().map(|&v| sig(v * scale, 3)).collect();
            let space = if unit.is_empty() || unit.starts_with('/') {
                ""
            } else {
                " "
            };
            format!("{}{space}{unit}", nums.join(", "))
        }
    }
}

/// "model had b = 37.63 deg/h" for a wrong level, "not in the model" for a missing term.
pub fn model_text(e: &FoundEffect, ch: noise::Channel) -> String {
    let si_unit = si_unit_of(ch);
    match &e.model_parameters {
        Some(p) => format!(
            "model had {}",
            p.iter()
                .map(|(k, &v)| match shown(k, si_unit) {
                    Shown::Discrete(unit) => {
                        format!("{} = {}{unit}", label(k), trimmed(v, 6))
                    }
                    Shown::Scaled(scale, unit) => {
                        format!("{} = {} {unit}", label(k), sig(v * scale, 4))
                    }
                })
                .collect::<Vec<_>>()
                .join(", ")
        ),
        None => "not in the model".into(),
    }
}

/// The evidence for a finding: the BIC improvement of an Allan-round finding, or, for one found
/// by a time-domain detector (round 0: outliers, a warm-up transient, a temperature
/// coefficient), that it was found in the time domain: its evidence is the detector's
/// threshold, not a BIC over the Allan curve (which a few spikes barely move; the channel's
/// gap can even grow a little when they are removed, as the model's band is compared with a
/// curve that lost their short-tau variance).
pub fn evidence_text(e: &FoundEffect) -> String {
    if e.round == 0 || !e.delta_bic.is_finite() {
        "found in the time domain (its detector's threshold is the evidence; no BIC over the Allan curve)".into()
    } else {
        format!("dBIC {:.0}", e.delta_bic)
    }
}
