//! A first-order Gauss-Markov bias (docs/model.md §2, §3).

use super::term::{ErrorTerm, TermKind};
use crate::closed_form as cf;
use crate::filter::FilteredAllan;
use crate::model_error::{check, ModelError};

/// First-order Gauss-Markov bias: stationary std `sigma`, correlation time `tau_s`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaussMarkov {
    pub sigma: f64,
    pub tau_s: f64,
}

impl GaussMarkov {
    pub fn new(sigma: f64, tau_s: f64) -> Result<GaussMarkov, ModelError> {
        Ok(GaussMarkov {
            sigma: check("Gauss-Markov sigma", sigma, false)?,
            tau_s: check("Gauss-Markov correlation time", tau_s, true)?,
        })
    }
}

impl ErrorTerm for GaussMarkov {
    /// Hou 4.60 (docs/model.md §2).
    fn allan_variance(&self, tau_s: f64) -> Option<f64> {
        Some(cf::gauss_markov_avar(self.sigma, self.tau_s, tau_s))
    }

    fn allan_variance_sampled(&self, tau_s: f64, dt_s: f64) -> Option<f64> {
        Some(cf::gauss_markov_avar_sampled(
            self.sigma, self.tau_s, tau_s, dt_s,
        ))
    }

    fn allan_variance_filtered(&self, tau_s: f64, _dt_s: f64, fa: &FilteredAllan) -> Option<f64> {
        Some(fa.gauss_markov(self.sigma, self.tau_s, tau_s))
    }
}

impl TermKind for GaussMarkov {
    const STOCHASTIC: bool = true;
    const SHOWS_IN_STATIC_LOG: bool = true;
}
