//! A constant bias (Woodman §3.2.1).

use super::term::{ErrorTerm, TermKind};
use crate::model_error::{check_finite, ModelError};

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
}
