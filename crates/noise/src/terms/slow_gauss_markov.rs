//! A second first-order Gauss-Markov bias, for the slow wander (docs/model.md §2): the same
//! process as `gauss_markov` (exact discretisation, Maybeck 4-114; Allan variance Hou 4.60), kept
//! in a slot of its own so that one channel can hold both a fast Gauss-Markov term (for example
//! the stand-in `diagnose` fits at the shortest averaging times) and a slow one (a bias wandering
//! over minutes to hours, which is what a dead-reckoned drift integrates).

use super::gauss_markov::{BankGenerator, GaussMarkov, RawGaussMarkov};
use super::term::{ErrorTerm, GenContext, TermKind, WriteContext};
use crate::config::error::ConfigError;
use crate::config::read::ReadContext;
use crate::filter::FilteredAllan;
use crate::law_source::{LawSource, LawSourceContext};
use crate::model_error::ModelError;
use crate::units::{Quantity, Signal};
use crate::ImuRng;

/// A slow first-order Gauss-Markov bias: the [`GaussMarkov`] process in a slot of its own.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlowGaussMarkov(GaussMarkov);

impl SlowGaussMarkov {
    /// Checks sigma (finite, >= 0) and the correlation time (finite, > 0).
    pub fn new(sigma: f64, tau_s: f64) -> Result<SlowGaussMarkov, ModelError> {
        GaussMarkov::new(sigma, tau_s).map(SlowGaussMarkov)
    }

    /// Stationary standard deviation (signal units).
    pub fn sigma(&self) -> f64 {
        self.0.sigma()
    }

    /// Correlation time, s.
    pub fn tau_s(&self) -> f64 {
        self.0.tau_s()
    }

    /// The same process as a [`GaussMarkov`] term.
    pub fn process(&self) -> GaussMarkov {
        self.0
    }
}

impl ErrorTerm for SlowGaussMarkov {
    fn law_sources(&self, cx: &LawSourceContext) -> Vec<LawSource> {
        self.0.law_sources(cx)
    }

    /// Sigma, named `sigma` (docs/cli.md).
    fn level(&self) -> Option<(&'static str, f64)> {
        self.0.level()
    }

    /// The correlation time, named `tau_s`.
    fn shape(&self) -> Vec<(&'static str, f64)> {
        self.0.shape()
    }

    /// Hou 4.60, as `gauss_markov`.
    fn allan_variance(&self, tau_s: f64) -> Option<f64> {
        self.0.allan_variance(tau_s)
    }

    fn allan_variance_sampled(&self, tau_s: f64, dt_s: f64) -> Option<f64> {
        self.0.allan_variance_sampled(tau_s, dt_s)
    }

    fn allan_variance_filtered(&self, tau_s: f64, dt_s: f64, fa: &FilteredAllan) -> Option<f64> {
        self.0.allan_variance_filtered(tau_s, dt_s, fa)
    }

    fn config_value(&self, cx: &WriteContext) -> String {
        self.0.config_value(cx)
    }
}

impl TermKind for SlowGaussMarkov {
    const STOCHASTIC: bool = true;
    const LONG_TERM: bool = true;
    const FREE_PARAMETERS: usize = 2;
    const SHOWS_IN_STATIC_LOG: bool = true;
    type Raw = RawGaussMarkov;
    const EXAMPLE: Option<&'static str> =
        Some("slow_gauss_markov = { sigma = \"0.02 deg/s\", time_constant = \"1300 s\" }");

    /// The correlation time kept.
    fn with_level(&self, level: f64) -> Result<SlowGaussMarkov, ModelError> {
        SlowGaussMarkov::new(level, self.tau_s())
    }

    fn from_raw(raw: &RawGaussMarkov, cx: &ReadContext) -> Result<SlowGaussMarkov, ConfigError> {
        GaussMarkov::from_raw(raw, cx).map(SlowGaussMarkov)
    }

    /// As `gauss_markov`'s.
    fn note_units(value: &toml::Value, sig: Signal, note: &mut dyn FnMut(Quantity, &toml::Value)) {
        GaussMarkov::note_units(value, sig, note)
    }

    type Generator = BankGenerator;

    /// A bank of one, its initial state drawn from the term's own stream.
    fn generator(&self, cx: &GenContext, rng: &dyn Fn() -> ImuRng) -> BankGenerator {
        self.0.generator(cx, rng)
    }
}

/// A valid term of the effect, for the registry's tests (`terms::samples`).
#[cfg(test)]
pub(crate) fn sample() -> SlowGaussMarkov {
    SlowGaussMarkov::new(3e-4, 2000.0).unwrap()
}
