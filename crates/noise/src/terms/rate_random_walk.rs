//! Rate random walk (docs/model.md §2, §3).

use super::term::{
    note_value_units, ErrorTerm, GenContext, Generate, RawClock, Stage, TermKind, WriteContext,
};
use crate::closed_form as cf;
use crate::config::error::ConfigError;
use crate::config::read::{ReadContext, Text};
use crate::discrete::RandomWalk;
use crate::filter::FilteredAllan;
use crate::law_source::{LawSource, LawSourceContext};
use crate::model_error::{check, ModelError};
use crate::units::{Quantity, Signal};
use crate::ImuRng;
use crate::NormalStream;

/// Rate random walk K (rad/s/sqrt(s), m/s^2/sqrt(s)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RateRandomWalk {
    density: f64,
}

impl RateRandomWalk {
    /// A finite value >= 0.
    pub fn new(density: f64) -> Result<RateRandomWalk, ModelError> {
        Ok(RateRandomWalk {
            density: check("rate random walk density", density, false)?,
        })
    }

    /// K (rad/s/sqrt(s) or m/s^2/sqrt(s)).
    pub fn density(&self) -> f64 {
        self.density
    }
}

impl ErrorTerm for RateRandomWalk {
    fn law_sources(&self, _cx: &LawSourceContext) -> Vec<LawSource> {
        vec![LawSource::RandomWalk(self.density)]
    }

    /// K, named `k` (docs/cli.md).
    fn level(&self) -> Option<(&'static str, f64)> {
        Some(("k", self.density))
    }

    /// sigma^2 = K^2 tau / 3 (Hou 4.53).
    fn allan_variance(&self, tau_s: f64) -> Option<f64> {
        Some(cf::rate_random_walk_avar(self.density, tau_s))
    }

    fn allan_variance_sampled(&self, tau_s: f64, dt_s: f64) -> Option<f64> {
        Some(cf::rate_random_walk_avar_sampled(self.density, tau_s, dt_s))
    }

    fn allan_variance_filtered(&self, tau_s: f64, _dt_s: f64, fa: &FilteredAllan) -> Option<f64> {
        Some(fa.random_walk(self.density, tau_s))
    }

    fn config_value(&self, cx: &WriteContext) -> String {
        cx.quoted(self.density, Quantity::RandomWalk(cx.sig))
    }
}

impl TermKind for RateRandomWalk {
    const STOCHASTIC: bool = true;
    const LONG_TERM: bool = true;
    const FREE_PARAMETERS: usize = 1;
    const SHOWS_IN_STATIC_LOG: bool = true;
    type Raw = Text;
    const EXAMPLE: Option<&'static str> = Some("rate_random_walk = \"0.5 deg/h/sqrt(h)\"");

    fn with_level(&self, level: f64) -> Result<RateRandomWalk, ModelError> {
        RateRandomWalk::new(level)
    }

    fn from_raw(raw: &Text, cx: &ReadContext) -> Result<RateRandomWalk, ConfigError> {
        let value = cx.value(raw, Quantity::RandomWalk(cx.sig), true)?;
        RateRandomWalk::new(value).map_err(|e| cx.refused(&cx.key, e))
    }

    fn note_units(value: &toml::Value, sig: Signal, note: &mut dyn FnMut(Quantity, &toml::Value)) {
        note_value_units(value, Quantity::RandomWalk(sig), sig, note);
    }

    type Generator = RandomWalkGenerator;

    fn generator(&self, cx: &GenContext, rng: &dyn Fn() -> ImuRng) -> RandomWalkGenerator {
        RandomWalkGenerator {
            walk: RandomWalk::new(self.density, cx.dt_raw_s),
            rng: NormalStream::new(rng()),
        }
    }
}

/// A random walk with its stream (also Woodman's bias random walk, `bias_instability`).
#[derive(Clone, Debug)]
pub struct RandomWalkGenerator {
    pub(crate) walk: RandomWalk,
    pub(crate) rng: NormalStream,
}

impl RandomWalkGenerator {
    /// The walk over the next `n` samples as a follower of the flicker bank
    /// ([`crate::discrete::GaussMarkovBank::add_block_then`]), its draws in `scratch`.
    pub(crate) fn follower<'a>(
        &'a mut self,
        scratch: &'a mut Vec<f64>,
        n: usize,
    ) -> crate::discrete::WalkFollower<'a> {
        let w = crate::discrete::draws(&mut self.rng, scratch, n);
        crate::discrete::WalkFollower::new(&mut self.walk, w)
    }
}

impl Generate for RandomWalkGenerator {
    fn stage(&self) -> Stage {
        Stage::Raw
    }

    #[inline]
    fn add_raw(&mut self, _clock: RawClock, out: &mut [f64], scratch: &mut Vec<f64>) {
        self.walk.add_block(&mut self.rng, out, scratch);
    }
}

/// A valid term of the effect, for the registry's tests (`terms::samples`).
#[cfg(test)]
pub(crate) fn sample() -> RateRandomWalk {
    RateRandomWalk::new(4e-6).unwrap()
}
