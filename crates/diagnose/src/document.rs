//! The documents of `diagnose` and `drift`, shared by every front end (the CLI's commands, the
//! Python package's `imudrift.diagnose` and `imudrift.drift`): the corrected model's TOML, the
//! JSON documents (docs/cli.md, `diagnose --json`, `drift --json`), the check of a protocol
//! against the logs' sampling and the choice of the data a model was fitted on. Front ends read
//! the files; errors name a setting through the front end's names for it ([`ProtocolNames`]).

use crate::drift_check::DriftCheck;
use crate::effect_text::params_text;
use crate::fitted_on::{FittedOn, FittedOnError};
use crate::protocol::{Calibration, Initialisation, Protocol};
use crate::report::{Diagnosis, HeldOutGap};
use noise::text::{sampling, sig, time};
use noise::{SensorModel, UnitStyle};
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// The corrected model as TOML, with a header saying where it came from (seed, bands, each
/// effect found with its parameters in spec-sheet units) and, at the end, the data its levels
/// were fitted on (for `drift`'s parametric bootstrap, docs/drift.md). Written in the units and
/// conventions `style` reads from the input model's text (spec-sheet units where it has none).
pub fn corrected_model_toml(
    result: &Diagnosis,
    model: &SensorModel,
    style: &UnitStyle,
    fitted_on: Option<&FittedOn>,
) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "# Written by `imudrift diagnose` (seed {}, {} simulated logs per band) from {:?}.",
        result.seed, result.seeds, model.name
    );
    for (name, report) in &result.channels {
        for e in &report.effects {
            let _ = writeln!(
                out,
                "# {name}: {} {} {}",
                e.kind,
                e.effect,
                params_text(e, *name)
            );
        }
    }
    let temperature_found = result.channels.values().any(|r| {
        r.effects
            .iter()
            .any(|e| e.effect == noise::Effect::TemperatureBias)
    });
    if temperature_found {
        let _ = writeln!(
            out,
            "# temperature_bias was fitted against the log's measured temperature column; simulations of this\n\
             # model apply it to the [temperature] profile below, so set that profile to the conditions of interest."
        );
    }
    let m = &result.model_final;
    if [&m.gyro, &m.accel]
        .iter()
        .any(|t| t.axes.iter().any(|a| a.has(noise::Effect::BiasInstability)))
    {
        let _ = writeln!(
            out,
            "# The b values above are IEEE 952 coefficients B (Allan plateau 0.664 B); the model below writes\n\
             # bias_instability in the input's convention{}.",
            if style.keeps_allan_minimum() {
                " (allan_minimum: the minimum of the axis' Allan deviation, as spec sheets quote it;\n\
                 # B is solved from the whole axis, so editing another term of an axis changes its B: to keep\n\
                 # it, write that axis' bias_instability as B with convention = \"ieee\" (B is the b above where\n\
                 # diagnose fitted it))"
            } else {
                " (ieee: the coefficient B)"
            }
        );
    }
    out.push_str(&result.model_final.to_toml_string_styled(style));
    if let Some(f) = fitted_on {
        out.push_str(&f.to_toml());
    }
    out.push_str(&crate::alternatives::to_toml(&result.alternatives, style));
    out
}

/// A held-out log's gaps with the original and the corrected model, per channel, with its name.
pub type HeldOutChecks = Vec<(String, BTreeMap<noise::Channel, HeldOutGap>)>;

/// Where a diagnosis came from, for its document.
pub struct DiagnoseSources<'a> {
    /// Each run's log name, in order (the first one's is `log`).
    pub logs: &'a [String],
    /// The first log's `columns[]` and `skipped_columns[]` (`logio::Log::columns_json`).
    pub columns: (serde_json::Value, serde_json::Value),
    /// The model's name as given (its file).
    pub model: &'a str,
}

/// The `diagnose --json` document (docs/cli.md): the diagnosis, the held-out `checks`, each
/// run's `log`, the first `log`, `columns`, `skipped_columns`, `model` and the corrected model.
pub fn diagnose_document(
    result: &Diagnosis,
    sources: DiagnoseSources<'_>,
    corrected: &str,
    checks: &HeldOutChecks,
) -> Result<serde_json::Value, serde_json::Error> {
    let mut v = serde_json::to_value(result)?;
    let Some(obj) = v.as_object_mut() else {
        return Ok(v);
    };
    let checks: Vec<serde_json::Value> = checks
        .iter()
        .map(|(log, gaps)| serde_json::json!({ "log": log, "channels": gaps }))
        .collect();
    obj.insert("checks".into(), checks.into());
    // Several runs: each run's entry names its log (`log` is the first run's, as for one log).
    if let Some(runs) = obj.get_mut("runs").and_then(|r| r.as_array_mut()) {
        for (run, log) in runs.iter_mut().zip(sources.logs) {
            if let Some(run) = run.as_object_mut() {
                run.insert("log".into(), log.clone().into());
            }
        }
    }
    let first = sources.logs.first().cloned().unwrap_or_default();
    obj.insert("log".into(), first.into());
    obj.insert("columns".into(), sources.columns.0);
    obj.insert("skipped_columns".into(), sources.columns.1);
    obj.insert("model".into(), sources.model.into());
    obj.insert("corrected_model_toml".into(), corrected.into());
    Ok(v)
}

/// The `drift --json` document (docs/cli.md): the check with the `logs`' names and the `model`'s.
pub fn drift_document(
    result: &DriftCheck,
    logs: &[String],
    model: &str,
) -> Result<serde_json::Value, serde_json::Error> {
    let mut doc = serde_json::to_value(result)?;
    if let Some(o) = doc.as_object_mut() {
        o.insert("logs".into(), logs.to_vec().into());
        o.insert("model".into(), model.into());
    }
    Ok(doc)
}

/// The data a model's levels were fitted on, from its `[fitted_on]` table (`None` for a noise
/// file, a model without the table, or when its levels are to be taken as exact).
pub fn fitted_on_of(
    text: &str,
    name: &str,
    exact_parameters: bool,
) -> Result<Option<FittedOn>, FittedOnError> {
    if exact_parameters || noise::is_noise_file_text(text, name) {
        return Ok(None);
    }
    FittedOn::from_model_text(text)
}

/// The structures a model lists beside its own (its `[[alternatives]]`, written by `diagnose`;
/// none for a noise file, a model without them, or when its structure is to be taken as certain).
pub fn alternatives_of(
    text: &str,
    name: &str,
    one_structure: bool,
) -> Result<Vec<crate::alternatives::Alternative>, crate::alternatives::AlternativesError> {
    if one_structure || noise::is_noise_file_text(text, name) {
        return Ok(Vec::new());
    }
    crate::alternatives::from_model_text(text, name)
}

/// A setting of a drift protocol, as a front end names it in messages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProtocolSetting {
    Horizons,
    /// The calibration window, named with what precedes its time (`--calibration window:`).
    CalibrationWindow,
    /// The levelling window (`--init level:`).
    LevelWindow,
}

/// A front end's names of the protocol's settings.
pub type ProtocolNames<'a> = &'a dyn Fn(ProtocolSetting) -> &'static str;

/// A protocol the logs' sampling cannot carry ([`check_sampling`]); `rate` describes the logs'.
#[derive(Clone, Debug, PartialEq)]
pub enum SamplingError {
    HorizonTooShort {
        horizon_s: f64,
        rate: String,
    },
    HorizonNotWhole {
        horizon_s: f64,
        samples: f64,
        whole_s: f64,
        rate: String,
    },
    WindowTooShort {
        setting: ProtocolSetting,
        window_s: f64,
        rate: String,
    },
    WindowTooLong {
        setting: ProtocolSetting,
        window_s: f64,
        longest_s: f64,
    },
}

impl SamplingError {
    /// The message, the setting named by `names`.
    pub fn render(&self, names: ProtocolNames) -> String {
        match self {
            SamplingError::HorizonTooShort { horizon_s, rate } => format!(
                "{} {horizon_s}: shorter than one sample of the logs ({rate})",
                names(ProtocolSetting::Horizons)
            ),
            SamplingError::HorizonNotWhole { horizon_s, samples, whole_s, rate } => format!(
                "{} {horizon_s}: {} samples of the logs ({rate}); a horizon is a whole number of samples, e.g. {}",
                names(ProtocolSetting::Horizons),
                sig(*samples, 4).trim_end_matches('0'),
                time(*whole_s)
            ),
            SamplingError::WindowTooShort { setting, window_s, rate } => format!(
                "{}{window_s}: the window is shorter than one sample of the logs ({rate})",
                names(*setting)
            ),
            SamplingError::WindowTooLong { setting, window_s, longest_s } => format!(
                "{}{window_s}: the window is longer than the longest log ({})",
                names(*setting),
                time(*longest_s)
            ),
        }
    }
}

/// Refuse horizons and windows the logs' sampling (`dt_s`, the longest log `samples` long)
/// cannot carry: a horizon must be a whole number of samples (0.014 s at 100 Hz is not: it was
/// computed as one sample and reported as 0.014 s), a window at least one sample and at most the
/// longest log (a shorter one panicked, a longer one overflowed).
pub fn check_sampling(protocol: &Protocol, dt_s: f64, samples: usize) -> Result<(), SamplingError> {
    let rate = sampling(dt_s);
    for &h in &protocol.horizons_s {
        let n = h / dt_s;
        let whole = n.round();
        if whole < 1.0 {
            return Err(SamplingError::HorizonTooShort { horizon_s: h, rate });
        }
        if (n - whole).abs() > 1e-6 * whole {
            return Err(SamplingError::HorizonNotWhole {
                horizon_s: h,
                samples: n,
                whole_s: whole * dt_s,
                rate,
            });
        }
    }
    let longest_s = samples as f64 * dt_s;
    let windows = [
        match protocol.calibration {
            Calibration::Window { window_s } => {
                Some((ProtocolSetting::CalibrationWindow, window_s))
            }
            _ => None,
        },
        match protocol.initialisation {
            Initialisation::Levelled { window_s } => Some((ProtocolSetting::LevelWindow, window_s)),
            Initialisation::Perfect => None,
        },
    ];
    for (setting, w) in windows.into_iter().flatten() {
        if (w / dt_s).round() < 1.0 {
            return Err(SamplingError::WindowTooShort {
                setting,
                window_s: w,
                rate,
            });
        }
        if w > longest_s {
            return Err(SamplingError::WindowTooLong {
                setting,
                window_s: w,
                longest_s,
            });
        }
    }
    Ok(())
}
