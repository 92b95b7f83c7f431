//! Isolated outliers (spikes) on the output register.

use super::term::{ErrorTerm, TermKind};
use crate::model_error::{check, ModelError};

/// Isolated outliers: single output samples displaced by `size` (rad/s or m/s^2) with a random sign,
/// each output sample independently with probability p = `rate_per_hour` dt / 3600 (a Bernoulli
/// process: Poisson arrivals at the given rate on the sample grid). Applied to the output register,
/// after the filter and before quantisation. Their Allan variance is that of white noise of variance
/// p size^2 per sample (independent, zero mean): p size^2 / m at tau = m dt.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outliers {
    pub rate_per_hour: f64,
    pub size: f64,
}

impl Outliers {
    pub fn new(rate_per_hour: f64, size: f64) -> Result<Outliers, ModelError> {
        Ok(Outliers {
            rate_per_hour: check("outlier rate", rate_per_hour, false)?,
            size: check("outlier size", size, false)?,
        })
    }
    /// Probability that one output sample of interval `dt_s` is an outlier.
    pub fn probability(&self, dt_s: f64) -> f64 {
        (self.rate_per_hour * dt_s / 3600.0).min(1.0)
    }
    /// Exact Allan variance at tau = m dt of the outlier train alone.
    pub fn avar_sampled(&self, tau_s: f64, dt_s: f64) -> f64 {
        let m = (tau_s / dt_s).round().max(1.0);
        self.probability(dt_s) * self.size * self.size / m
    }
}

impl ErrorTerm for Outliers {
    /// White noise of variance p size^2 per output sample (no continuous form: p needs dt).
    fn allan_variance_sampled(&self, tau_s: f64, dt_s: f64) -> Option<f64> {
        Some(self.avar_sampled(tau_s, dt_s))
    }
}

impl TermKind for Outliers {
    const STOCHASTIC: bool = true;
    const SHOWS_IN_STATIC_LOG: bool = true;
}
