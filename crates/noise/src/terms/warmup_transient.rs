//! The turn-on warm-up transient of the bias.

use super::term::{ErrorTerm, TermKind};
use crate::model_error::{check, ModelError};

/// Bias settling after turn-on: `amplitude` e^{-t / tau_s}, with `amplitude` fixed, or, when
/// `per_run` is set, drawn per run from N(0, amplitude^2) (turn-on to turn-on).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WarmupTransient {
    pub amplitude: f64,
    pub tau_s: f64,
    pub per_run: bool,
}

impl WarmupTransient {
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
}

impl ErrorTerm for WarmupTransient {}

impl TermKind for WarmupTransient {
    const STOCHASTIC: bool = false;
    const SHOWS_IN_STATIC_LOG: bool = false;
}
