//! Temperature-dependent bias: a coefficient times the excursion of the temperature profile from
//! its reference (Woodman §3.2.4).

use super::term::{ErrorTerm, TermKind};
use crate::model_error::{check_finite, ModelError};

/// Bias per degC away from the reference temperature (rad/s/degC, m/s^2/degC), signed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TemperatureBias {
    per_degree: f64,
}

impl TemperatureBias {
    /// Any finite value.
    pub fn new(per_degree: f64) -> Result<TemperatureBias, ModelError> {
        Ok(TemperatureBias {
            per_degree: check_finite("temperature bias coefficient", per_degree)?,
        })
    }

    /// The coefficient, per degC.
    pub fn per_degree(&self) -> f64 {
        self.per_degree
    }
}

impl ErrorTerm for TemperatureBias {}

impl TermKind for TemperatureBias {
    const STOCHASTIC: bool = false;
    const SHOWS_IN_STATIC_LOG: bool = false;
}
