//! A first-order Gauss-Markov bias (docs/model.md §2, §3).

use super::term::{ErrorTerm, GenContext, Generate, RawClock, Stage, TermKind, WriteContext};
use crate::closed_form as cf;
use crate::config::error::ConfigError;
use crate::config::read::{ReadContext, Text};
use crate::discrete::GaussMarkovBank;
use crate::filter::FilteredAllan;
use crate::law_source::{LawSource, LawSourceContext};
use crate::model_error::{check, ModelError};
use crate::units::{Quantity, Signal};
use crate::ImuRng;
use crate::NormalStream;

/// First-order Gauss-Markov bias: stationary std `sigma`, correlation time `tau_s`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaussMarkov {
    sigma: f64,
    tau_s: f64,
}

impl GaussMarkov {
    /// Checks sigma (finite, >= 0) and the correlation time (finite, > 0).
    pub fn new(sigma: f64, tau_s: f64) -> Result<GaussMarkov, ModelError> {
        Ok(GaussMarkov {
            sigma: check("Gauss-Markov sigma", sigma, false)?,
            tau_s: check("Gauss-Markov correlation time", tau_s, true)?,
        })
    }

    /// Stationary standard deviation (signal units).
    pub fn sigma(&self) -> f64 {
        self.sigma
    }

    /// Correlation time, s.
    pub fn tau_s(&self) -> f64 {
        self.tau_s
    }
}

/// `gauss_markov = { sigma, time_constant }` as written.
#[derive(serde::Deserialize, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawGaussMarkov {
    sigma: Text,
    time_constant: Text,
}

impl ErrorTerm for GaussMarkov {
    fn law_sources(&self, _cx: &LawSourceContext) -> Vec<LawSource> {
        vec![LawSource::GaussMarkov {
            sigma: self.sigma,
            tc_s: self.tau_s,
        }]
    }

    /// Sigma, named `sigma` (docs/cli.md).
    fn level(&self) -> Option<(&'static str, f64)> {
        Some(("sigma", self.sigma))
    }

    /// The correlation time, named `tau_s`.
    fn shape(&self) -> Vec<(&'static str, f64)> {
        vec![("tau_s", self.tau_s)]
    }

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

    fn config_value(&self, cx: &WriteContext) -> String {
        format!(
            "{{ sigma = {}, time_constant = {} }}",
            cx.quoted(self.sigma, Quantity::Signal(cx.sig)),
            cx.quoted(self.tau_s, Quantity::Time)
        )
    }
}

impl TermKind for GaussMarkov {
    const STOCHASTIC: bool = true;
    const LONG_TERM: bool = true;
    const FREE_PARAMETERS: usize = 2;
    const SHOWS_IN_STATIC_LOG: bool = true;
    type Raw = RawGaussMarkov;

    /// The correlation time kept.
    fn with_level(&self, level: f64) -> Result<GaussMarkov, ModelError> {
        GaussMarkov::new(level, self.tau_s)
    }

    fn from_raw(raw: &RawGaussMarkov, cx: &ReadContext) -> Result<GaussMarkov, ConfigError> {
        let sigma = cx.sub_value("sigma", &raw.sigma, Quantity::Signal(cx.sig), true)?;
        let tau_s = cx.sub_positive("time_constant", &raw.time_constant, Quantity::Time)?;
        GaussMarkov::new(sigma, tau_s).map_err(|e| cx.refused(&cx.key, e))
    }

    /// None: a written config has never taken its units from this table.
    fn note_units(
        _value: &toml::Value,
        _sig: Signal,
        _note: &mut dyn FnMut(Quantity, &toml::Value),
    ) {
    }

    type Generator = BankGenerator;

    /// A bank of one, its initial state drawn from the term's stream.
    fn generator(&self, cx: &GenContext, rng: &dyn Fn() -> ImuRng) -> BankGenerator {
        BankGenerator::new(&[(self.tau_s, self.sigma)], cx.dt_raw_s, rng())
    }
}

/// A bank of Gauss-Markov processes with its stream (also flicker's band, `bias_instability`):
/// the slowly varying biases a calibration references.
#[derive(Clone, Debug)]
pub struct BankGenerator {
    bank: GaussMarkovBank,
    rng: NormalStream,
}

impl BankGenerator {
    /// `components`: (correlation time s, stationary std), run multi-rate
    /// ([`GaussMarkovBank::multirate`]); the initial states are the first draws of `rng`.
    pub(crate) fn new(components: &[(f64, f64)], dt_s: f64, mut rng: ImuRng) -> BankGenerator {
        BankGenerator {
            bank: GaussMarkovBank::multirate(components, dt_s, &mut rng),
            rng: NormalStream::new(rng),
        }
    }
}

impl BankGenerator {
    /// The bank's next `out.len()` values and then `follower`'s, in one pass
    /// ([`GaussMarkovBank::add_block_then`]): the values of `add_raw` on each term in turn.
    #[inline]
    pub(crate) fn add_raw_then(
        &mut self,
        out: &mut [f64],
        scratch: &mut Vec<f64>,
        follower: &mut impl crate::discrete::Follower,
    ) {
        self.bank
            .add_block_then(&mut self.rng, out, scratch, follower);
    }

    /// The bank and its stream.
    pub(crate) fn parts(&mut self) -> (&mut GaussMarkovBank, &mut NormalStream) {
        (&mut self.bank, &mut self.rng)
    }
}

impl Generate for BankGenerator {
    fn stage(&self) -> Stage {
        Stage::Raw
    }

    #[inline]
    fn add_raw(&mut self, _clock: RawClock, out: &mut [f64], scratch: &mut Vec<f64>) {
        self.bank.add_block(&mut self.rng, out, scratch);
    }

    fn calibrate_start(&mut self) {
        self.bank.reference_to_start();
    }

    fn calibrate_window(&mut self, window_s: f64, rng: &dyn Fn() -> ImuRng) {
        self.bank.reference_to_window_mean(window_s, &mut rng());
    }
}

/// A valid term of the effect, for the registry's tests (`terms::samples`).
#[cfg(test)]
pub(crate) fn sample() -> GaussMarkov {
    GaussMarkov::new(6e-4, 70.0).unwrap()
}
