//! White noise added on the output register, after the output filter (docs/model.md §2, §3).
//!
//! A sensor's `white_noise` is the noise of the sensing element: it goes through the output filter
//! like the rest of the raw signal, so behind a low-pass its Allan deviation falls below N/sqrt(tau)
//! at averaging times near and under the filter's time constant. Noise that enters after the filter
//! (the converter and read-out chain, or a rate change after the filter that the filter does not
//! band-limit) keeps the plain white-noise slope down to the shortest tau: this term. Without an
//! output filter on the axis it is the same process as `white_noise` (the two densities add in
//! quadrature).

use super::term::{
    note_value_units, ErrorTerm, GenContext, Generate, Stage, TermKind, WriteContext,
};
use super::white_noise::WhiteNoiseSampler;
use crate::closed_form as cf;
use crate::config::error::ConfigError;
use crate::config::read::{ReadContext, Text};
use crate::law_source::{LawSource, LawSourceContext};
use crate::model_error::{check, ModelError};
use crate::units::{Quantity, Signal};
use crate::ImuRng;
use crate::NormalStream;

/// Density N of the white noise on the output register (rad/sqrt(s) or m/s/sqrt(s)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OutputWhiteNoise {
    density: f64,
}

impl OutputWhiteNoise {
    /// A finite value >= 0.
    pub fn new(density: f64) -> Result<OutputWhiteNoise, ModelError> {
        Ok(OutputWhiteNoise {
            density: check("output white noise density", density, false)?,
        })
    }

    /// N (rad/sqrt(s) or m/s/sqrt(s)).
    pub fn density(&self) -> f64 {
        self.density
    }
}

impl ErrorTerm for OutputWhiteNoise {
    /// An angle (velocity) random walk like `white_noise`'s: the growth laws integrate the output,
    /// where the filter's position in the chain does not matter beyond its time constant.
    fn law_sources(&self, _cx: &LawSourceContext) -> Vec<LawSource> {
        vec![LawSource::White(self.density)]
    }

    /// N, named `n` (docs/cli.md).
    fn level(&self) -> Option<(&'static str, f64)> {
        Some(("n", self.density))
    }

    /// sigma^2 = N^2 / tau (Hou 4.36), exact for the sampled sequence; the output filter does not
    /// act on it (the default `allan_variance_filtered`: it is added after the filter).
    fn allan_variance(&self, tau_s: f64) -> Option<f64> {
        Some(cf::white_noise_avar(self.density, tau_s))
    }

    fn config_value(&self, cx: &WriteContext) -> String {
        cx.quoted(self.density, Quantity::NoiseDensity(cx.sig))
    }
}

impl TermKind for OutputWhiteNoise {
    const STOCHASTIC: bool = true;
    const LONG_TERM: bool = false;
    const FREE_PARAMETERS: usize = 1;
    const SHOWS_IN_STATIC_LOG: bool = true;
    type Raw = Text;
    const EXAMPLE: Option<&'static str> = Some(
        "output_white_noise = \"0.004 deg/s/sqrt(Hz)\" (gyro) or \"40 ug/sqrt(Hz)\" (accelerometer)",
    );

    fn with_level(&self, level: f64) -> Result<OutputWhiteNoise, ModelError> {
        OutputWhiteNoise::new(level)
    }

    fn from_raw(raw: &Text, cx: &ReadContext) -> Result<OutputWhiteNoise, ConfigError> {
        let value = cx.value(raw, Quantity::NoiseDensity(cx.sig), true)?;
        OutputWhiteNoise::new(value).map_err(|e| cx.refused(&cx.key, e))
    }

    fn note_units(value: &toml::Value, sig: Signal, note: &mut dyn FnMut(Quantity, &toml::Value)) {
        note_value_units(value, Quantity::NoiseDensity(sig), sig, note);
    }

    type Generator = OutputWhiteNoiseGenerator;

    /// `white_noise`'s sampler at the output interval: n_k = (N / sqrt(dt)) w_k (docs/model.md §3),
    /// on the term's own stream.
    fn generator(&self, cx: &GenContext, rng: &dyn Fn() -> ImuRng) -> OutputWhiteNoiseGenerator {
        OutputWhiteNoiseGenerator {
            sampler: WhiteNoiseSampler::new(self.density, cx.dt_out_s),
            rng: NormalStream::new(rng()),
            scratch: Vec::new(),
        }
    }
}

/// White noise on the output register with its stream.
#[derive(Clone, Debug)]
pub struct OutputWhiteNoiseGenerator {
    /// `white_noise`'s sampler at the output interval.
    sampler: WhiteNoiseSampler,
    rng: NormalStream,
    scratch: Vec<f64>,
}

impl Generate for OutputWhiteNoiseGenerator {
    fn stage(&self) -> Stage {
        Stage::Output
    }

    /// Adds the next `out.len()` draws (the stream's values do not depend on the block split).
    fn output(&mut self, _k0: u64, _dt_s: f64, out: &mut [f64]) {
        self.sampler
            .add_block(&mut self.rng, out, &mut self.scratch);
    }
}

/// A valid term of the effect, for the registry's tests (`terms::samples`).
#[cfg(test)]
pub(crate) fn sample() -> OutputWhiteNoise {
    OutputWhiteNoise::new(1e-3).unwrap()
}
