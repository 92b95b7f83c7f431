//! The turn-on warm-up transient of the bias.

use super::term::{
    note_value_units, ErrorTerm, GenContext, Generate, RawClock, Stage, TermKind, WriteContext,
};
use crate::config::error::ConfigError;
use crate::config::read::{ReadContext, Text};
use crate::discrete::normal;
use crate::law_source::{LawSource, LawSourceContext};
use crate::model_error::{check, ModelError};
use crate::units::{Quantity, Signal};
use crate::ImuRng;

/// Bias settling after turn-on: `amplitude` e^{-t / tau_s}, with `amplitude` fixed, or, when
/// `per_run` is set, drawn per run from N(0, amplitude^2) (turn-on to turn-on).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WarmupTransient {
    amplitude: f64,
    tau_s: f64,
    per_run: bool,
}

impl WarmupTransient {
    /// Checks the amplitude (finite, any sign) and the time constant (finite, > 0).
    pub fn new(amplitude: f64, tau_s: f64, per_run: bool) -> Result<WarmupTransient, ModelError> {
        if !amplitude.is_finite() {
            return Err(ModelError {
                what: "warm-up transient amplitude",
                expected: "a finite value",
                found: amplitude,
            });
        }
        Ok(WarmupTransient {
            amplitude,
            tau_s: check("warm-up transient time constant", tau_s, true)?,
            per_run,
        })
    }

    /// Amplitude at t = 0 (signal units, signed), or the standard deviation of the per-run draw.
    pub fn amplitude(&self) -> f64 {
        self.amplitude
    }

    /// Time constant, s.
    pub fn tau_s(&self) -> f64 {
        self.tau_s
    }

    /// Is the amplitude drawn per run from N(0, amplitude^2)?
    pub fn per_run(&self) -> bool {
        self.per_run
    }
}

/// `warmup_transient = { amplitude, time_constant, per_run? }` as written.
#[derive(serde::Deserialize, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawWarmupTransient {
    amplitude: Text,
    time_constant: Text,
    per_run: Option<bool>,
}

impl ErrorTerm for WarmupTransient {
    fn law_sources(&self, _cx: &LawSourceContext) -> Vec<LawSource> {
        vec![LawSource::Transient {
            amplitude: self.amplitude,
            tau_s: self.tau_s,
            per_run: self.per_run,
        }]
    }

    fn config_value(&self, cx: &WriteContext) -> String {
        format!(
            "{{ amplitude = {}, time_constant = {}, per_run = {} }}",
            cx.quoted(self.amplitude, Quantity::Signal(cx.sig)),
            cx.quoted(self.tau_s, Quantity::Time),
            self.per_run
        )
    }
}

impl TermKind for WarmupTransient {
    const STOCHASTIC: bool = false;
    const LONG_TERM: bool = false;
    const FREE_PARAMETERS: usize = 2;
    const SHOWS_IN_STATIC_LOG: bool = false;
    type Raw = RawWarmupTransient;
    const EXAMPLE: Option<&'static str> = Some("warmup_transient = { amplitude = \"0.03 deg/s\", time_constant = \"600 s\", per_run = false }");

    /// `per_run`: the amplitude drawn per run from N(0, amplitude^2); default false.
    fn from_raw(
        raw: &RawWarmupTransient,
        cx: &ReadContext,
    ) -> Result<WarmupTransient, ConfigError> {
        let amplitude =
            cx.sub_value("amplitude", &raw.amplitude, Quantity::Signal(cx.sig), false)?;
        let tau_s = cx.sub_positive("time_constant", &raw.time_constant, Quantity::Time)?;
        WarmupTransient::new(amplitude, tau_s, raw.per_run.unwrap_or(false))
            .map_err(|e| cx.refused(&cx.key, e))
    }

    fn note_units(value: &toml::Value, sig: Signal, note: &mut dyn FnMut(Quantity, &toml::Value)) {
        note_value_units(value, Quantity::Signal(sig), sig, note);
    }

    type Generator = TransientGenerator;

    /// A per-run amplitude is the term's one draw.
    fn generator(&self, _cx: &GenContext, rng: &dyn Fn() -> ImuRng) -> TransientGenerator {
        let amplitude = if self.per_run {
            self.amplitude * normal(&mut rng())
        } else {
            self.amplitude
        };
        TransientGenerator {
            amplitude,
            tau_s: self.tau_s,
        }
    }
}

/// This run's amplitude times e^{-t / tau}, held at its t = 0 value before (in the filter's pre-roll).
#[derive(Clone, Copy, Debug)]
pub struct TransientGenerator {
    amplitude: f64,
    tau_s: f64,
}

impl Generate for TransientGenerator {
    fn stage(&self) -> Stage {
        Stage::Raw
    }

    #[inline]
    fn add_raw(&mut self, clock: RawClock, out: &mut [f64], _scratch: &mut Vec<f64>) {
        let (a, tau) = (self.amplitude, self.tau_s);
        out.iter_mut()
            .enumerate()
            .for_each(|(i, v)| *v += a * (-clock.t(i).max(0.0) / tau).exp());
    }
}

/// A valid term of the effect, for the registry's tests (`terms::samples`).
#[cfg(test)]
pub(crate) fn sample() -> WarmupTransient {
    WarmupTransient::new(5e-4, 600.0, false).unwrap()
}
