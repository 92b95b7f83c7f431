//! Quantisation of the integrated output (docs/model.md §2: the tau^-1 slope of the Allan deviation).

use super::term::{ErrorTerm, GenContext, Generate, Stage, TermKind};
use crate::closed_form as cf;
use crate::model_error::{check, ModelError};
use crate::ImuRng;
use rand::Rng;

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
    type Generator = Quantizer;

    /// The quantiser's phase is the term's one draw.
    fn generator(&self, _cx: &GenContext, rng: &dyn Fn() -> ImuRng) -> Quantizer {
        Quantizer::new(self.q, &mut rng())
    }
}

/// Quantisation of the integrated output (docs/cli.md: so its Allan signature is the tau^-1 slope):
/// the output released in a sample is a whole number of LSBs of the integral, LSB = Q sqrt(12)
/// (Hou §4.3.1, Q = LSB/sqrt(12)). `residual` is the integral not yet released.
#[derive(Clone, Copy, Debug)]
pub struct Quantizer {
    lsb: f64,
    residual: f64,
}

impl Quantizer {
    /// The quantiser's phase on the LSB grid is drawn from `rng`, so no run starts on a step.
    pub fn new<R: Rng + ?Sized>(q: f64, rng: &mut R) -> Quantizer {
        let lsb = q * 12f64.sqrt();
        Quantizer {
            lsb,
            residual: lsb * (rng.gen::<f64>() - 0.5),
        }
    }
    #[inline]
    pub fn apply(&mut self, value: f64, dt_s: f64) -> f64 {
        self.residual += value * dt_s;
        let n = (self.residual / self.lsb).round();
        self.residual -= n * self.lsb;
        n * self.lsb / dt_s
    }
}

impl Generate for Quantizer {
    fn stage(&self) -> Stage {
        Stage::Output
    }

    fn output(&mut self, _k0: u64, dt_s: f64, out: &mut [f64]) {
        out.iter_mut().for_each(|v| *v = self.apply(*v, dt_s));
    }
}
