//! White noise: angle random walk of a gyro, velocity random walk of an accelerometer (docs/model.md §2, §3).

use super::term::{
    note_value_units, ErrorTerm, GenContext, Generate, RawClock, Stage, TermKind, WriteContext,
};
use crate::closed_form as cf;
use crate::config::error::ConfigError;
use crate::config::read::{ReadContext, Text};
use crate::discrete::{draws, normal};
use crate::filter::FilteredAllan;
use crate::law_source::{LawSource, LawSourceContext};
use crate::model_error::{check, ModelError};
use crate::units::{Quantity, Signal};
use crate::ImuRng;
use crate::NormalStream;
use rand::Rng;

/// White-noise density N (ARW rad/sqrt(s), VRW m/s/sqrt(s)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WhiteNoise {
    density: f64,
}

impl WhiteNoise {
    /// A finite value >= 0.
    pub fn new(density: f64) -> Result<WhiteNoise, ModelError> {
        Ok(WhiteNoise {
            density: check("white noise density", density, false)?,
        })
    }

    /// N (rad/sqrt(s) or m/s/sqrt(s)).
    pub fn density(&self) -> f64 {
        self.density
    }
}

impl ErrorTerm for WhiteNoise {
    fn law_sources(&self, _cx: &LawSourceContext) -> Vec<LawSource> {
        vec![LawSource::White(self.density)]
    }

    /// N, named `n` (docs/cli.md).
    fn level(&self) -> Option<(&'static str, f64)> {
        Some(("n", self.density))
    }

    /// sigma^2 = N^2 / tau (Hou 4.36), exact for the sampled sequence too.
    fn allan_variance(&self, tau_s: f64) -> Option<f64> {
        Some(cf::white_noise_avar(self.density, tau_s))
    }

    fn allan_variance_filtered(&self, tau_s: f64, _dt_s: f64, fa: &FilteredAllan) -> Option<f64> {
        Some(fa.white_noise(self.density, tau_s))
    }

    fn config_value(&self, cx: &WriteContext) -> String {
        cx.quoted(self.density, Quantity::NoiseDensity(cx.sig))
    }
}

impl TermKind for WhiteNoise {
    const STOCHASTIC: bool = true;
    const LONG_TERM: bool = false;
    const FREE_PARAMETERS: usize = 1;
    const SHOWS_IN_STATIC_LOG: bool = true;
    type Raw = Text;
    const EXAMPLE: Option<&'static str> =
        Some("white_noise = \"0.05 deg/s/sqrt(Hz)\" (gyro) or \"40 ug/sqrt(Hz)\" (accelerometer)");

    fn with_level(&self, level: f64) -> Result<WhiteNoise, ModelError> {
        WhiteNoise::new(level)
    }

    fn from_raw(raw: &Text, cx: &ReadContext) -> Result<WhiteNoise, ConfigError> {
        let value = cx.value(raw, Quantity::NoiseDensity(cx.sig), true)?;
        WhiteNoise::new(value).map_err(|e| cx.refused(&cx.key, e))
    }

    fn note_units(value: &toml::Value, sig: Signal, note: &mut dyn FnMut(Quantity, &toml::Value)) {
        note_value_units(value, Quantity::NoiseDensity(sig), sig, note);
    }

    type Generator = WhiteNoiseGenerator;

    fn generator(&self, cx: &GenContext, rng: &dyn Fn() -> ImuRng) -> WhiteNoiseGenerator {
        WhiteNoiseGenerator {
            sampler: WhiteNoiseSampler::new(self.density, cx.dt_raw_s),
            rng: NormalStream::new(rng()),
        }
    }
}

/// White noise of density N sampled every dt: n_k = (N / sqrt(dt)) w_k (docs/model.md §3; Kalibr
/// sigma_d = sigma / sqrt(dt); Woodman sigma = N / sqrt(dt)).
#[derive(Clone, Copy, Debug)]
pub struct WhiteNoiseSampler {
    sd: f64,
}

impl WhiteNoiseSampler {
    pub fn new(n: f64, dt_s: f64) -> WhiteNoiseSampler {
        WhiteNoiseSampler {
            sd: n / dt_s.sqrt(),
        }
    }
    #[inline]
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        self.sd * normal(rng)
    }
    /// Add the next `out.len()` values to `out` (the values of as many `sample` calls).
    #[inline]
    pub(crate) fn add_block(
        &self,
        rng: &mut NormalStream,
        out: &mut [f64],
        scratch: &mut Vec<f64>,
    ) {
        let n = out.len();
        for (v, w) in out.iter_mut().zip(draws(rng, scratch, n)) {
            *v += self.sd * w;
        }
    }
}

/// White noise with its stream.
#[derive(Clone, Debug)]
pub struct WhiteNoiseGenerator {
    sampler: WhiteNoiseSampler,
    rng: NormalStream,
}

impl WhiteNoiseGenerator {
    /// The raw samples' standard deviation.
    pub(crate) fn sd(&self) -> f64 {
        self.sampler.sd
    }
}

impl Generate for WhiteNoiseGenerator {
    fn stage(&self) -> Stage {
        Stage::Raw
    }

    #[inline]
    fn add_raw(&mut self, _clock: RawClock, out: &mut [f64], scratch: &mut Vec<f64>) {
        self.sampler.add_block(&mut self.rng, out, scratch);
    }
}

/// A valid term of the effect, for the registry's tests (`terms::samples`).
#[cfg(test)]
pub(crate) fn sample() -> WhiteNoise {
    WhiteNoise::new(2e-3).unwrap()
}
