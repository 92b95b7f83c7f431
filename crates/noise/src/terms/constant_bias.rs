//! A constant bias (Woodman §3.2.1).

use super::term::{
    note_value_units, ErrorTerm, GenContext, Generate, Stage, TermKind, WriteContext,
};
use crate::config::error::ConfigError;
use crate::config::read::{ReadContext, Text};
use crate::law_source::{LawSource, LawSourceContext};
use crate::model_error::{check_finite, ModelError};
use crate::units::{Quantity, Signal};
use crate::ImuRng;

/// Constant bias (rad/s, m/s^2), signed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConstantBias {
    bias: f64,
}

impl ConstantBias {
    /// Any finite value.
    pub fn new(bias: f64) -> Result<ConstantBias, ModelError> {
        Ok(ConstantBias {
            bias: check_finite("constant bias", bias)?,
        })
    }

    /// The bias (rad/s or m/s^2).
    pub fn bias(&self) -> f64 {
        self.bias
    }
}

impl ErrorTerm for ConstantBias {
    fn law_sources(&self, _cx: &LawSourceContext) -> Vec<LawSource> {
        vec![LawSource::Bias(self.bias)]
    }

    fn config_value(&self, cx: &WriteContext) -> String {
        cx.quoted(self.bias, Quantity::Signal(cx.sig))
    }
}

impl TermKind for ConstantBias {
    const STOCHASTIC: bool = false;
    const LONG_TERM: bool = false;
    const FREE_PARAMETERS: usize = 1;
    const SHOWS_IN_STATIC_LOG: bool = false;
    type Raw = Text;
    const EXAMPLE: Option<&'static str> =
        Some("constant_bias = \"0.1 deg/s\" (gyro) or \"2 mg\" (accelerometer)");

    fn from_raw(raw: &Text, cx: &ReadContext) -> Result<ConstantBias, ConfigError> {
        let value = cx.value(raw, Quantity::Signal(cx.sig), false)?;
        ConstantBias::new(value).map_err(|e| cx.refused(&cx.key, e))
    }

    fn note_units(value: &toml::Value, sig: Signal, note: &mut dyn FnMut(Quantity, &toml::Value)) {
        note_value_units(value, Quantity::Signal(sig), sig, note);
    }

    type Generator = ConstantBiasGenerator;

    fn generator(&self, _cx: &GenContext, _rng: &dyn Fn() -> ImuRng) -> ConstantBiasGenerator {
        ConstantBiasGenerator { bias: self.bias }
    }
}

/// The bias, added to the ideal input.
#[derive(Clone, Copy, Debug)]
pub struct ConstantBiasGenerator {
    bias: f64,
}

impl Generate for ConstantBiasGenerator {
    fn stage(&self) -> Stage {
        Stage::Input
    }

    fn input(&self, _row: &mut [f64; 3], bias: &mut f64) {
        *bias += self.bias;
    }
}

/// A valid term of the effect, for the registry's tests (`terms::samples`).
#[cfg(test)]
pub(crate) fn sample() -> ConstantBias {
    ConstantBias::new(2e-2).unwrap()
}
