//! A bias drawn once per run, turn-on to turn-on.

use super::term::{ErrorTerm, TermKind};
use crate::model_error::{check, ModelError};

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

impl ErrorTerm for TurnOnBias {}

impl TermKind for TurnOnBias {
    const STOCHASTIC: bool = false;
    const SHOWS_IN_STATIC_LOG: bool = false;
}
