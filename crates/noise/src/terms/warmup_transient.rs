//! The turn-on warm-up transient of the bias.

use super::term::{ErrorTerm, GenContext, Generate, RawClock, Stage, TermKind};
use crate::discrete::normal;
use crate::model_error::{check, ModelError};
use crate::ImuRng;

/// Bias settling after turn-on: `amplitude` e^{-t / tau_s}, with `amplitude` fixed, or, when
/// `per_run` is set, drawn per run from N(0, amplitude^2) (turn-on to turn-on).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WarmupTransient {
    pub amplitude: f64,
    pub tau_s: f64,
    pub per_run: bool,
}

impl WarmupTransient {
    pub fn new(amplitude: f64, tau_s: f64, per_run: bool) -> Result<WarmupTransient, ModelError> {
        if !amplitude.is_finite() {
            return Err(ModelError {
                what: "warm-up transient amplitude",
                expected: "a finite value",
                found: amplitude,
            });
        }
        Ok(WarmupTransient {
            amplitude,
            tau_s: check("warm-up transient time constant", tau_s, true)?,
            per_run,
        })
    }
}

impl ErrorTerm for WarmupTransient {}

impl TermKind for WarmupTransient {
    const STOCHASTIC: bool = false;
    const SHOWS_IN_STATIC_LOG: bool = false;
    type Generator = TransientGenerator;

    /// A per-run amplitude is the term's one draw.
    fn generator(&self, _cx: &GenContext, rng: &dyn Fn() -> ImuRng) -> TransientGenerator {
        let amplitude = if self.per_run {
            self.amplitude * normal(&mut rng())
        } else {
            self.amplitude
        };
        TransientGenerator {
            amplitude,
            tau_s: self.tau_s,
        }
    }
}

/// This run's amplitude times e^{-t / tau}, held at its t = 0 value before (in the filter's pre-roll).
#[derive(Clone, Copy, Debug)]
pub struct TransientGenerator {
    amplitude: f64,
    tau_s: f64,
}

impl Generate for TransientGenerator {
    fn stage(&self) -> Stage {
        Stage::Raw
    }

    #[inline]
    fn add_raw(&mut self, clock: RawClock, out: &mut [f64], _scratch: &mut Vec<f64>) {
        let (a, tau) = (self.amplitude, self.tau_s);
        out.iter_mut()
            .enumerate()
            .for_each(|(i, v)| *v += a * (-clock.t(i).max(0.0) / tau).exp());
    }
}
