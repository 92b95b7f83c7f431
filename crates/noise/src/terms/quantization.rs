//! Quantisation of the integrated output (docs/model.md §2: the tau^-1 slope of the Allan deviation).

use super::term::{ErrorTerm, TermKind};
use crate::closed_form as cf;
use crate::model_error::{check, ModelError};

/// Quantisation coefficient Q of the integrated output (rad or m/s); the LSB of the integrated
/// output is Q·sqrt(12) (Hou §4.3.1: Q = LSB/sqrt(12)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quantization {
    q: f64,
}

impl Quantization {
    /// A finite value >= 0.
    pub fn new(q: f64) -> Result<Quantization, ModelError> {
        Ok(Quantization {
            q: check("quantization coefficient", q, false)?,
        })
    }

    /// Q (rad or m/s).
    pub fn coefficient(&self) -> f64 {
        self.q
    }
}

impl ErrorTerm for Quantization {
    /// sigma^2 = 3 Q^2 / tau^2 (Hou 4.29), sampled or not; the output filter does not act on it
    /// (quantisation is of the output register).
    fn allan_variance(&self, tau_s: f64) -> Option<f64> {
        Some(cf::quantization_avar(self.q, tau_s))
    }
}

impl TermKind for Quantization {
    const STOCHASTIC: bool = true;
    const SHOWS_IN_STATIC_LOG: bool = true;
}
