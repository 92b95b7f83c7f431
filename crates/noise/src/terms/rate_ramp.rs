//! Rate ramp: a bias growing linearly with time (docs/model.md §2).

use super::term::{
    note_value_units, ErrorTerm, GenContext, Generate, RawClock, Stage, TermKind, WriteContext,
};
use crate::closed_form as cf;
use crate::config::error::ConfigError;
use crate::config::read::{ReadContext, Text};
use crate::law_source::{LawSource, LawSourceContext};
use crate::model_error::{check_finite, ModelError};
use crate::units::{Quantity, Signal};
use crate::ImuRng;

/// Rate ramp R (rad/s^2, m/s^3), signed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RateRamp {
    rate: f64,
}

impl RateRamp {
    /// Any finite value.
    pub fn new(rate: f64) -> Result<RateRamp, ModelError> {
        Ok(RateRamp {
            rate: check_finite("rate ramp", rate)?,
        })
    }

    /// R (rad/s^2 or m/s^3).
    pub fn rate(&self) -> f64 {
        self.rate
    }
}

impl ErrorTerm for RateRamp {
    fn law_sources(&self, _cx: &LawSourceContext) -> Vec<LawSource> {
        vec![LawSource::Ramp(self.rate)]
    }

    /// R (signed), named `r` (docs/cli.md).
    fn level(&self) -> Option<(&'static str, f64)> {
        Some(("r", self.rate))
    }

    /// sigma^2 = R^2 tau^2 / 2 (Hou 4.56), exact for samples too; unit DC gain keeps it through
    /// the output filter.
    fn allan_variance(&self, tau_s: f64) -> Option<f64> {
        Some(cf::rate_ramp_avar(self.rate, tau_s))
    }

    fn config_value(&self, cx: &WriteContext) -> String {
        cx.quoted(self.rate, Quantity::Ramp(cx.sig))
    }
}

impl TermKind for RateRamp {
    const STOCHASTIC: bool = false;
    const LONG_TERM: bool = true;
    const FREE_PARAMETERS: usize = 1;
    const SHOWS_IN_STATIC_LOG: bool = true;
    type Raw = Text;
    const EXAMPLE: Option<&'static str> = Some("rate_ramp = \"0.01 deg/h/h\"");

    fn with_level(&self, level: f64) -> Result<RateRamp, ModelError> {
        RateRamp::new(level)
    }

    fn from_raw(raw: &Text, cx: &ReadContext) -> Result<RateRamp, ConfigError> {
        let value = cx.value(raw, Quantity::Ramp(cx.sig), false)?;
        RateRamp::new(value).map_err(|e| cx.refused(&cx.key, e))
    }

    fn note_units(value: &toml::Value, sig: Signal, note: &mut dyn FnMut(Quantity, &toml::Value)) {
        note_value_units(value, Quantity::Ramp(sig), sig, note);
    }

    type Generator = RampGenerator;

    fn generator(&self, _cx: &GenContext, _rng: &dyn Fn() -> ImuRng) -> RampGenerator {
        RampGenerator { rate: self.rate }
    }
}

/// The ramp R t.
#[derive(Clone, Copy, Debug)]
pub struct RampGenerator {
    rate: f64,
}

impl Generate for RampGenerator {
    fn stage(&self) -> Stage {
        Stage::Raw
    }

    #[inline]
    fn add_raw(&mut self, clock: RawClock, out: &mut [f64], _scratch: &mut Vec<f64>) {
        // A zero ramp adds nothing (not even a signed zero).
        if self.rate != 0.0 {
            let ramp = self.rate;
            out.iter_mut()
                .enumerate()
                .for_each(|(i, v)| *v += ramp * clock.t(i));
        }
    }
}

/// A valid term of the effect, for the registry's tests (`terms::samples`).
#[cfg(test)]
pub(crate) fn sample() -> RateRamp {
    RateRamp::new(5e-7).unwrap()
}
