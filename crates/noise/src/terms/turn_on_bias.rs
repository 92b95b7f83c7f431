//! A bias drawn once per run, turn-on to turn-on.

use super::term::{
    note_value_units, ErrorTerm, GenContext, Generate, Stage, TermKind, WriteContext,
};
use crate::config::error::ConfigError;
use crate::config::read::{ReadContext, Text};
use crate::discrete::normal;
use crate::law_source::{LawSource, LawSourceContext};
use crate::model_error::{check, ModelError};
use crate::units::{Quantity, Signal};
use crate::ImuRng;

/// Standard deviation of the bias drawn once per run (turn-on to turn-on), rad/s or m/s^2.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TurnOnBias {
    sigma: f64,
}

impl TurnOnBias {
    /// A finite value >= 0.
    pub fn new(sigma: f64) -> Result<TurnOnBias, ModelError> {
        Ok(TurnOnBias {
            sigma: check("turn-on bias sigma", sigma, false)?,
        })
    }

    /// The standard deviation (rad/s or m/s^2).
    pub fn sigma(&self) -> f64 {
        self.sigma
    }
}

impl ErrorTerm for TurnOnBias {
    fn law_sources(&self, _cx: &LawSourceContext) -> Vec<LawSource> {
        vec![LawSource::RandomConstant(self.sigma)]
    }

    fn config_value(&self, cx: &WriteContext) -> String {
        cx.quoted(self.sigma, Quantity::Signal(cx.sig))
    }
}

impl TermKind for TurnOnBias {
    const STOCHASTIC: bool = false;
    const LONG_TERM: bool = false;
    const FREE_PARAMETERS: usize = 1;
    const SHOWS_IN_STATIC_LOG: bool = false;
    type Raw = Text;
    const EXAMPLE: Option<&'static str> = Some("turn_on_bias = \"3 deg/s\"");

    fn from_raw(raw: &Text, cx: &ReadContext) -> Result<TurnOnBias, ConfigError> {
        let value = cx.value(raw, Quantity::Signal(cx.sig), true)?;
        TurnOnBias::new(value).map_err(|e| cx.refused(&cx.key, e))
    }

    fn note_units(value: &toml::Value, sig: Signal, note: &mut dyn FnMut(Quantity, &toml::Value)) {
        note_value_units(value, Quantity::Signal(sig), sig, note);
    }

    type Generator = TurnOnBiasGenerator;

    /// This run's bias is the term's one draw, N(0, sigma^2).
    fn generator(&self, _cx: &GenContext, rng: &dyn Fn() -> ImuRng) -> TurnOnBiasGenerator {
        TurnOnBiasGenerator {
            bias: self.sigma * normal(&mut rng()),
        }
    }
}

/// This run's draw, added to the ideal input.
#[derive(Clone, Copy, Debug)]
pub struct TurnOnBiasGenerator {
    bias: f64,
}

impl Generate for TurnOnBiasGenerator {
    fn stage(&self) -> Stage {
        Stage::Input
    }

    fn input(&self, _row: &mut [f64; 3], bias: &mut f64) {
        *bias += self.bias;
    }
}

/// A valid term of the effect, for the registry's tests (`terms::samples`).
#[cfg(test)]
pub(crate) fn sample() -> TurnOnBias {
    TurnOnBias::new(3e-2).unwrap()
}
