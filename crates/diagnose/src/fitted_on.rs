//! What a fitted model's levels were estimated from: the `[fitted_on]` table `imudrift diagnose`
//! writes at the end of the model it corrects (docs/drift.md, "Parameter uncertainty").
//!
//! A model fitted from finite logs is uncertain, and by how much depends on the data it was fitted
//! on: the logs' sample interval and lengths, the channels they had and the shortest averaging
//! time used. With those, `drift` re-creates logs like them from the model, refits the levels and
//! so draws each simulated experiment's levels from their sampling distribution (`bootstrap`).
//! A model without the table (a datasheet) is taken as exact.
//!
//! ```toml
//! [fitted_on]
//! sample_interval_s = 0.01
//! samples = [1000000]
//! channels = ["gx", "gy", "gz", "ax", "ay", "az"]
//! tau_min_s = 0.0
//! run_to_run = [
//!     { channel = "gy", effects = ["rate_random_walk"], runs = 6, variance = 0.106, null_variance = 0.123 },
//! ]
//! ```
//!
//! `run_to_run` (written when the logs are several runs) is how the run-to-run spreads the model
//! states were estimated (`run_spread`): per channel and group, the runs, the variance V of their
//! log-multipliers and the null's mean variance sigma_e^2. `drift` draws each experiment's spread
//! from it (`run_spread::draw_spreads`).
//!
//! The table is read here, not in the noise crate (which only skips it): it describes data, not
//! the error model.

use crate::input::LogInput;
use noise::{Channel, Effect, ImuChannels};
use serde::{Deserialize, Serialize, Serializer};
use std::fmt::Write as _;

/// The data a model's levels were fitted on (validated).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FittedOn {
    /// Sample interval of the logs, s.
    pub sample_interval_s: f64,
    /// Samples of each log.
    pub samples: Vec<usize>,
    /// Which of gx gy gz ax ay az every log had.
    #[serde(serialize_with = "channel_names")]
    pub channels: ImuChannels<bool>,
    /// Shortest averaging time the fit used, s.
    pub tau_min_s: f64,
    /// How each run-to-run spread was estimated from the runs (none for one run).
    pub run_to_run: Vec<SpreadFit>,
}

/// The estimate of one channel's group spread from the fitted runs (`run_spread::RunSpread`'s
/// statistic and its null): what the spread's sampling distribution needs.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SpreadFit {
    pub channel: Channel,
    /// The group's terms (their levels move together between runs).
    pub effects: Vec<Effect>,
    /// Runs the spread was estimated from (2 or more).
    pub runs: usize,
    /// V: the sample variance of the runs' ln multipliers.
    pub variance: f64,
    /// sigma_e^2: the null's mean V (the runs' sampling part).
    pub null_variance: f64,
}

fn channel_names<S: Serializer>(channels: &ImuChannels<bool>, s: S) -> Result<S::Ok, S::Error> {
    s.collect_seq(channels.iter().filter(|(_, &on)| on).map(|(c, _)| c.name()))
}

/// The table as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFittedOn {
    sample_interval_s: f64,
    samples: Vec<i64>,
    channels: Vec<String>,
    tau_min_s: f64,
    #[serde(default)]
    run_to_run: Vec<RawSpreadFit>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSpreadFit {
    channel: String,
    effects: Vec<String>,
    runs: i64,
    variance: f64,
    null_variance: f64,
}

/// A `[fitted_on]` table that cannot be used; the message names the key and what was expected.
#[derive(Debug, thiserror::Error)]
pub enum FittedOnError {
    #[error("[fitted_on]: {0}")]
    Syntax(String),
    #[error("[fitted_on] {key} = {value}: expected {expected}")]
    Value {
        key: &'static str,
        value: String,
        expected: &'static str,
    },
}

/// Shortest log an Allan analysis accepts (as `LogInput::validate`).
const MIN_SAMPLES: i64 = 64;
/// Most runs a spread's estimate may record (each of `drift`'s experiments draws a chi-square of
/// runs - 1 degrees of freedom as that many squared normals).
const MAX_RUNS: i64 = 10_000;

impl TryFrom<RawFittedOn> for FittedOn {
    type Error = FittedOnError;

    fn try_from(raw: RawFittedOn) -> Result<FittedOn, FittedOnError> {
        let bad = |key, value: String, expected| FittedOnError::Value {
            key,
            value,
            expected,
        };
        let dt = raw.sample_interval_s;
        if !(dt > 0.0 && dt.is_finite()) {
            return Err(bad(
                "sample_interval_s",
                dt.to_string(),
                "a positive time in seconds",
            ));
        }
        if raw.samples.is_empty() || raw.samples.iter().any(|&n| n < MIN_SAMPLES) {
            return Err(bad(
                "samples",
                format!("{:?}", raw.samples),
                "one sample count of at least 64 per log",
            ));
        }
        let mut channels = ImuChannels::<bool>::default();
        for name in &raw.channels {
            let c = Channel::from_name(name).ok_or_else(|| {
                bad(
                    "channels",
                    format!("{:?}", raw.channels),
                    "channel names among gx gy gz ax ay az",
                )
            })?;
            channels[c] = true;
        }
        if !channels.values().contains(&true) {
            return Err(bad(
                "channels",
                "[]".into(),
                "at least one of gx gy gz ax ay az",
            ));
        }
        if !(raw.tau_min_s >= 0.0 && raw.tau_min_s.is_finite()) {
            return Err(bad(
                "tau_min_s",
                raw.tau_min_s.to_string(),
                "a time in seconds, 0 or more",
            ));
        }
        let run_to_run = raw
            .run_to_run
            .iter()
            .map(|r| {
                let text = || {
                    format!(
                        "{{ channel = {:?}, effects = {:?}, runs = {}, variance = {}, null_variance = {} }}",
                        r.channel, r.effects, r.runs, r.variance, r.null_variance
                    )
                };
                let expected = "{ channel = one of gx gy gz ax ay az, effects = [term names], \
                                runs from 2 to 10000, variance >= 0, null_variance > 0 }";
                let channel = Channel::from_name(&r.channel);
                let effects: Option<Vec<Effect>> =
                    r.effects.iter().map(|e| Effect::from_name(e)).collect();
                match (channel, effects) {
                    (Some(channel), Some(effects))
                        if !effects.is_empty()
                            && (2..=MAX_RUNS).contains(&r.runs)
                            && r.variance >= 0.0
                            && r.variance.is_finite()
                            && r.null_variance > 0.0
                            && r.null_variance.is_finite() =>
                    {
                        Ok(SpreadFit {
                            channel,
                            effects,
                            runs: r.runs as usize,
                            variance: r.variance,
                            null_variance: r.null_variance,
                        })
                    }
                    _ => Err(bad("run_to_run", text(), expected)),
                }
            })
            .collect::<Result<Vec<SpreadFit>, FittedOnError>>()?;
        Ok(FittedOn {
            sample_interval_s: dt,
            samples: raw.samples.iter().map(|&n| n as usize).collect(),
            channels,
            tau_min_s: raw.tau_min_s,
            run_to_run,
        })
    }
}

/// The whole model document, of which only `[fitted_on]` is read here.
#[derive(Deserialize)]
struct Document {
    fitted_on: Option<RawFittedOn>,
}

impl FittedOn {
    /// The data of `logs` (one sample interval: the first log's), the channels every log has.
    pub fn from_logs(logs: &[LogInput], tau_min_s: f64) -> Option<FittedOn> {
        let first = logs.first()?;
        let samples = logs
            .iter()
            .map(|l| l.channels.values().iter().flatten().map(|c| c.len()).min())
            .collect::<Option<Vec<usize>>>()?;
        Some(FittedOn {
            sample_interval_s: first.dt_s,
            samples,
            channels: ImuChannels::from_fn(|c| logs.iter().all(|l| l.channels[c].is_some())),
            tau_min_s,
            run_to_run: Vec::new(),
        })
    }

    /// The table with how the run-to-run spreads were estimated from these logs
    /// (`run_spread::RunSpread::fit`).
    pub fn with_run_spreads(mut self, fits: impl IntoIterator<Item = SpreadFit>) -> FittedOn {
        self.run_to_run = fits.into_iter().collect();
        self
    }

    /// The `[fitted_on]` table of a model's TOML text, if it has one.
    pub fn from_model_text(text: &str) -> Result<Option<FittedOn>, FittedOnError> {
        // Read in place (not through a `toml::Value`) so that an error keeps its span: the
        // message names the line.
        let doc: Document = toml::from_str(text).map_err(|e| {
            let line = e
                .span()
                .map(|r| text[..r.start.min(text.len())].lines().count().max(1));
            FittedOnError::Syntax(match line {
                Some(l) => format!("line {l}: {}", e.message()),
                None => e.message().to_string(),
            })
        })?;
        doc.fitted_on.map(FittedOn::try_from).transpose()
    }

    /// The table as TOML, to append to a model's text: it starts with an empty line and the
    /// `[fitted_on]` header (what a reader that wants the model alone cuts at), numbers in their
    /// shortest exact form.
    pub fn to_toml(&self) -> String {
        let mut s = String::from("\n[fitted_on]\n");
        s.push_str(
            "# The data the levels above were fitted on: `imudrift drift` draws each simulated\n\
             # experiment's levels from their sampling distribution on data like this (a parametric\n\
             # bootstrap, docs/drift.md). Delete this table to take the levels as exact.\n",
        );
        let _ = writeln!(s, "sample_interval_s = {:?}", self.sample_interval_s);
        let samples: Vec<String> = self.samples.iter().map(|n| n.to_string()).collect();
        let _ = writeln!(s, "samples = [{}]", samples.join(", "));
        let names: Vec<String> = self
            .channels
            .iter()
            .filter(|(_, &on)| on)
            .map(|(c, _)| format!("\"{}\"", c.name()))
            .collect();
        let _ = writeln!(s, "channels = [{}]", names.join(", "));
        let _ = writeln!(s, "tau_min_s = {:?}", self.tau_min_s);
        if !self.run_to_run.is_empty() {
            s.push_str(
                "# How the run_to_run spreads were estimated from these runs (per channel and group: the\n\
                 # variance of the runs' ln levels and its part from sampling alone): `drift` draws each\n\
                 # experiment's spread from it.\n\
                 run_to_run = [\n",
            );
            for f in &self.run_to_run {
                let effects: Vec<String> = f
                    .effects
                    .iter()
                    .map(|e| format!("\"{}\"", e.name()))
                    .collect();
                let _ = writeln!(
                    s,
                    "    {{ channel = \"{}\", effects = [{}], runs = {}, variance = {:?}, null_variance = {:?} }},",
                    f.channel.name(),
                    effects.join(", "),
                    f.runs,
                    f.variance,
                    f.null_variance
                );
            }
            s.push_str("]\n");
        }
        s
    }

    /// Every `run_to_run` entry names terms `model`'s axis has with a level (the terms whose
    /// spread `drift` draws); the error names the entry and the term.
    pub fn check_spreads(&self, model: &noise::SensorModel) -> Result<(), FittedOnError> {
        for f in &self.run_to_run {
            let axis = model.axis(f.channel.sensor(), f.channel.axis());
            if let Some(e) = f
                .effects
                .iter()
                .find(|&&e| axis.term(e).and_then(|t| t.level()).is_none())
            {
                return Err(FittedOnError::Value {
                    key: "run_to_run",
                    value: format!(
                        "{{ channel = \"{}\", effects = [.. \"{}\" ..] }}",
                        f.channel.name(),
                        e.name()
                    ),
                    expected:
                        "terms the model's axis has, with a level (as `diagnose` writes them)",
                });
            }
        }
        Ok(())
    }

    /// Total duration of the logs, s.
    pub fn duration_s(&self) -> f64 {
        self.samples.iter().sum::<usize>() as f64 * self.sample_interval_s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn example() -> FittedOn {
        FittedOn {
            sample_interval_s: 0.01,
            samples: vec![1_000_000, 999_999],
            channels: ImuChannels([true, true, true, false, false, true]),
            tau_min_s: 0.04,
            run_to_run: vec![SpreadFit {
                channel: Channel::Gz,
                effects: vec![Effect::RateRandomWalk, Effect::GaussMarkov],
                runs: 6,
                variance: 0.1058130509144893,
                null_variance: 0.12332084171925294,
            }],
        }
    }

    /// Written and read back exactly, after a model's text (which the table does not disturb).
    #[test]
    fn round_trip() {
        let f = example();
        let text = format!(
            "name = \"x\"\n[gyro.all]\nwhite_noise = \"0.1 deg/sqrt(h)\"\n{}",
            f.to_toml()
        );
        assert_eq!(FittedOn::from_model_text(&text).unwrap(), Some(f));
        let model = noise::SensorModel::from_toml_str(&text, "test").unwrap();
        assert!(model
            .axis(noise::Sensor::Gyro, 0)
            .has(noise::Effect::WhiteNoise));
        assert_eq!(FittedOn::from_model_text("name = \"x\"\n").unwrap(), None);
    }

    /// A spread entry whose terms the model's axis lacks is an error naming the term.
    #[test]
    fn spreads_must_name_the_models_terms() {
        let f = example();
        let has = noise::SensorModel::from_toml_str(
            "name = \"x\"\n[gyro.z]\nrate_random_walk = \"1 deg/h/sqrt(h)\"\ngauss_markov = { sigma = \"1 deg/h\", time_constant = \"10 s\" }\n",
            "m",
        )
        .unwrap();
        f.check_spreads(&has).unwrap();
        let lacks = noise::SensorModel::from_toml_str(
            "name = \"x\"\n[gyro.z]\nrate_random_walk = \"1 deg/h/sqrt(h)\"\n",
            "m",
        )
        .unwrap();
        let e = f.check_spreads(&lacks).unwrap_err().to_string();
        assert!(
            e.contains("run_to_run") && e.contains("gauss_markov"),
            "{e}"
        );
    }

    /// A bad value is an error naming its key.
    #[test]
    fn bad_values_name_their_key() {
        let base = example().to_toml();
        for (from, to, key) in [
            (
                "sample_interval_s = 0.01",
                "sample_interval_s = -1.0",
                "sample_interval_s",
            ),
            ("samples = [1000000, 999999]", "samples = [10]", "samples"),
            ("\"az\"", "\"bz\"", "channels"),
            ("tau_min_s = 0.04", "tau_min_s = -0.5", "tau_min_s"),
            ("\"gz\", effects", "\"bz\", effects", "run_to_run"),
            ("\"gauss_markov\"", "\"gauss_markof\"", "run_to_run"),
            ("variance = 0.1058", "variance = -0.1058", "run_to_run"),
            ("runs = 6", "runs = 1", "run_to_run"),
            ("runs = 6", "runs = 10001", "run_to_run"),
            (
                "null_variance = 0.12",
                "null_variance = 0.0e0",
                "run_to_run",
            ),
        ] {
            let text = base.replace(from, to);
            let e = FittedOn::from_model_text(&text).unwrap_err().to_string();
            assert!(e.contains(key), "{e}");
        }
        let e = FittedOn::from_model_text(&base.replace("tau_min_s", "tau_minimum_s"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("tau_minimum_s"), "{e}");
        // A wrong type is named with its line.
        let e = FittedOn::from_model_text(&base.replace("runs = 6", "runs = \"six\""))
            .unwrap_err()
            .to_string();
        let line = base.lines().position(|l| l.contains("runs = 6")).unwrap() + 1;
        assert!(e.contains(&format!("line {line}:")), "{e}");
    }
}
