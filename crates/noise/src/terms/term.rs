//! What every error effect provides, implemented by each effect's parameter type in its own file
//! under `terms/`: [`ErrorTerm`], what a value of it does (callable through a `Term`), and
//! [`TermKind`], what the type is. The registry (`terms/mod.rs`) ties each type to its effect.

use crate::config::error::ConfigError;
use crate::config::read::ReadContext;
use crate::filter::FilteredAllan;
use crate::law_source::{LawSource, LawSourceContext};
use crate::model_error::ModelError;
use crate::temperature::TemperatureProfile;
use crate::units::{Quantity, Signal};
use crate::ImuRng;
use std::fmt;

/// What one error effect's validated parameters (SI) do. Every method has a default for an
/// effect it does not apply to, so a file states only what its effect does.
pub trait ErrorTerm: fmt::Debug {
    /// Allan variance of a continuous record at averaging time `tau_s` (docs/model.md §2), `None`
    /// when the term adds nothing (or, like outliers, needs the sample interval).
    fn allan_variance(&self, _tau_s: f64) -> Option<f64> {
        None
    }

    /// Exact Allan variance of the generated series at sample interval `dt_s` (`tau_s` a multiple
    /// of it); by default the continuous form, where sampling does not change it.
    fn allan_variance_sampled(&self, tau_s: f64, _dt_s: f64) -> Option<f64> {
        self.allan_variance(tau_s)
    }

    /// Exact Allan variance at output interval `dt_s` behind the output filter `fa`; by default
    /// the sampled form, for terms the filter does not touch (quantisation and outliers act on the
    /// output register, and unit DC gain keeps a ramp a ramp).
    fn allan_variance_filtered(&self, tau_s: f64, dt_s: f64, _fa: &FilteredAllan) -> Option<f64> {
        self.allan_variance_sampled(tau_s, dt_s)
    }

    /// Its growth-law sources (docs/model.md §4) under the laws' conditions `cx`, in the order
    /// the laws add them: usually one; none for a term that adds no error of its own (the output
    /// filter); [`LawSource::NoLaw`] for one without a closed form.
    fn law_sources(&self, cx: &LawSourceContext) -> Vec<LawSource>;

    /// The level its Allan variance is quadratic in, with its docs/cli.md JSON name (`q`, `n`, `b`,
    /// `k`, `r`, `coefficient`, `sigma`, `amplitude`): what a fit of the term's size estimates.
    /// Signed where the term is (a rate ramp, a temperature coefficient). None for a term without
    /// one.
    fn level(&self) -> Option<(&'static str, f64)> {
        None
    }

    /// The parameters that set the shape of its Allan signature, with their docs/cli.md JSON names
    /// (a Gauss-Markov correlation time, a frequency, a filter's taps): what a fit searches or
    /// keeps beside the level. Conventions fixed in the config (flicker's band) are not among them.
    fn shape(&self) -> Vec<(&'static str, f64)> {
        Vec::new()
    }

    /// The value of the term's config key as the sensor TOML writes it (the text after
    /// `key = `): a quoted value with its unit, an array or an inline table.
    fn config_value(&self, cx: &WriteContext) -> String;
}

/// How a sensor TOML is written: the axis' signal and how values are formatted (exact SI, or in a
/// config's own units).
pub struct WriteContext<'a> {
    pub sig: Signal,
    /// A value (SI) of a quantity as "value unit".
    pub format: &'a dyn Fn(f64, Quantity) -> String,
    /// A plain number (the outlier rate per hour).
    pub number: &'a dyn Fn(f64) -> String,
}

impl WriteContext<'_> {
    /// `"value unit"`, quoted.
    pub fn quoted(&self, value: f64, q: Quantity) -> String {
        format!("\"{}\"", (self.format)(value, q))
    }
}

/// The units a written config learns from a key's value (`UnitStyle`): a plain string is a value
/// of `plain`; in an inline table, the values of the usual inner keys (`value`, `sigma`, ... of the
/// signal, `time_constant`, `period` of time, `frequency`, `cutoff`, `bandwidth` of frequency).
pub fn note_value_units(
    value: &toml::Value,
    plain: Quantity,
    sig: Signal,
    note: &mut dyn FnMut(Quantity, &toml::Value),
) {
    match value.as_table() {
        None => note(plain, value),
        Some(t) => {
            for (k, inner) in t {
                match k.as_str() {
                    "value" | "sigma" | "amplitude" | "stability" | "size" => {
                        note(Quantity::Signal(sig), inner)
                    }
                    "time_constant" | "period" => note(Quantity::Time, inner),
                    "frequency" | "cutoff" | "bandwidth" => note(Quantity::Frequency, inner),
                    _ => {}
                }
            }
        }
    }
}

/// What an error effect is, beside what its values do.
pub trait TermKind: ErrorTerm + Sized {
    /// A stochastic term with an Allan signature; the others are deterministic or drawn once per
    /// run.
    const STOCHASTIC: bool;
    /// Does a static log's Allan deviation show it (the terms `AxisModel::stochastic_only`
    /// keeps: the stochastic ones, the rate ramp, the sinusoid and the output filter)?
    const SHOWS_IN_STATIC_LOG: bool;
    /// Does it shape drift at long horizons, where white noise alone understates a real sensor's
    /// drift (`model_notes`: a triad without any such term is noted as optimistic)?
    const LONG_TERM: bool;
    /// The parameters a fit of the term to an Allan curve adjusts (its level and shape
    /// parameters, with the white-noise density an output filter is fitted with), as an
    /// information criterion counts them.
    const FREE_PARAMETERS: usize;

    /// The config key's value as serde reads it from an axis table (units still in strings).
    type Raw: serde::de::DeserializeOwned + Clone;

    /// Read after the other terms of the axis, which [`TermKind::from_raw`] then sees in
    /// [`ReadContext::others`] (bias instability's `allan_minimum` convention).
    const READS_OTHER_TERMS: bool = false;

    /// An example of the key for messages about a value of the wrong shape.
    const EXAMPLE: Option<&'static str> = None;

    /// The same term at another [`ErrorTerm::level`], its shape kept, through the validating
    /// constructor; an error for a term without a level.
    fn with_level(&self, level: f64) -> Result<Self, ModelError> {
        Err(ModelError {
            what: "level",
            expected: "a term with a level",
            found: level,
        })
    }

    /// The validated term from its key's value: units converted to SI, ranges checked, errors
    /// naming the file, line and key.
    fn from_raw(raw: &Self::Raw, cx: &ReadContext) -> Result<Self, ConfigError>;

    /// Tell `note` the units this key's value is written in ([`note_value_units`] for most).
    fn note_units(value: &toml::Value, sig: Signal, note: &mut dyn FnMut(Quantity, &toml::Value));

    /// The per-run state that generates the term's samples.
    type Generator: Generate;

    /// This run's generator: per-run draws (a turn-on bias, an initial state, a phase) come first
    /// from the term's own stream, made by `rng` (called at most once, only by terms that draw).
    fn generator(&self, cx: &GenContext, rng: &dyn Fn() -> ImuRng) -> Self::Generator;
}

/// What a term's generator knows of its channel.
#[derive(Clone, Copy, Debug)]
pub struct GenContext<'a> {
    /// The axis within its triad (0 = x): where the ideal input's own component is.
    pub axis: usize,
    /// The output sample interval, s.
    pub dt_out_s: f64,
    /// The interval of the raw processes: the output interval, or the output filter's internal
    /// one, s.
    pub dt_raw_s: f64,
    /// The impulse response of the axis' output filter at the raw interval (unit DC gain), if it
    /// has one.
    pub filter_response: Option<&'a [f64]>,
    /// The sensor's temperature profile and the temperature where `temperature_bias` is zero, degC.
    pub temperature: &'a TemperatureProfile,
    pub temperature_reference_c: f64,
}

/// Where in a channel's sample a generator acts (`ChannelErrors` runs them in the registry's
/// generation order within each stage).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// On the ideal input, once per run: the row of (I + scale factor + misalignment) applied to
    /// the ideal triad input, and the bias added to it.
    Input,
    /// Added to the raw samples (at the output filter's internal rate, before the filter).
    Raw,
    /// On the output register, after the filter.
    Output,
    /// Nothing per sample (the output filter, which the channel runs itself).
    None,
}

/// The times of a block of raw samples: sample `i` is at `(k0 + i) dt_s - offset_s` (the offset
/// is the output filter's pre-roll; 0 without a filter).
#[derive(Clone, Copy, Debug)]
pub struct RawClock {
    pub k0: u64,
    pub dt_s: f64,
    pub offset_s: f64,
}

impl RawClock {
    /// The time of sample `i` of the block, s.
    #[inline]
    pub fn t(&self, i: usize) -> f64 {
        // x - 0.0 == x bit for bit: without a filter the times are k dt.
        (self.k0 + i as u64) as f64 * self.dt_s - self.offset_s
    }
}

/// A term's per-run state. Each method has a no-op default; a generator implements those of its
/// [`Stage`]. Values are the same, bit for bit, for any split of the samples into blocks.
pub trait Generate {
    /// Where it acts.
    fn stage(&self) -> Stage;

    /// [`Stage::Input`]: change the row applied to the ideal triad input (starts as the unit row
    /// of the axis) or the bias added to it (starts at 0).
    fn input(&self, _row: &mut [f64; 3], _bias: &mut f64) {}

    /// [`Stage::Raw`]: add the values of the raw samples of `clock` to `out`; `scratch` is for
    /// the block's normal draws.
    fn add_raw(&mut self, _clock: RawClock, _out: &mut [f64], _scratch: &mut Vec<f64>) {}

    /// [`Stage::Output`]: act on output samples `k0 ..` (interval `dt_s`) in `out`.
    fn output(&mut self, _k0: u64, _dt_s: f64, _out: &mut [f64]) {}

    /// Reference a slowly varying bias to its value at t = 0 (a perfect turn-on calibration).
    fn calibrate_start(&mut self) {}

    /// Reference a slowly varying bias to its mean over `window_s` before t = 0, drawn from the
    /// stream `rng` makes (called only by generators that calibrate).
    fn calibrate_window(&mut self, _window_s: f64, _rng: &dyn Fn() -> ImuRng) {}
}

/// The generator of a term that does nothing per sample.
#[derive(Clone, Copy, Debug)]
pub struct NoGenerator;

impl Generate for NoGenerator {
    fn stage(&self) -> Stage {
        Stage::None
    }
}
