//! A constant bias (Woodman §3.2.1).

use super::term::{ErrorTerm, GenContext, Generate, Stage, TermKind};
use crate::model_error::{check_finite, ModelError};
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

impl ErrorTerm for ConstantBias {}

impl TermKind for ConstantBias {
    const STOCHASTIC: bool = false;
    const SHOWS_IN_STATIC_LOG: bool = false;
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
