//! A first-order Gauss-Markov bias (docs/model.md §2, §3).

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

    /// Allan variance, continuous (`dt_s` None, Hou 4.60) or of the sampled sequence.
    pub fn avar(&self, tau_s: f64, dt_s: Option<f64>) -> f64 {
        cf::gauss_markov_avar_at(self.sigma, self.tau_s, tau_s, dt_s)
    }

    /// Exact Allan variance behind the output filter `fa`.
    pub fn avar_filtered(&self, tau_s: f64, fa: &FilteredAllan) -> f64 {
        fa.gauss_markov(self.sigma, self.tau_s, tau_s)
    }
}
