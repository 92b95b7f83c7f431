//! Rate ramp: a bias growing linearly with time (docs/model.md §2).

use super::term::{ErrorTerm, GenContext, Generate, RawClock, Stage, TermKind};
use crate::closed_form as cf;
use crate::model_error::{check_finite, ModelError};
use crate::ImuRng;

/// Rate ramp R (rad/s^2, m/s^3), signed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RateRamp {
    rate: f64,
}

impl RateRamp {
    /// Any finite value.
    pub fn new(rate: f64) -> Result<RateRamp, ModelError> {
        Ok(RateRamp {
            rate: check_finite("rate ramp", rate)?,
        })
    }

    /// R (rad/s^2 or m/s^3).
    pub fn rate(&self) -> f64 {
        self.rate
    }
}

impl ErrorTerm for RateRamp {
    /// sigma^2 = R^2 tau^2 / 2 (Hou 4.56), exact for samples too; unit DC gain keeps it through
    /// the output filter.
    fn allan_variance(&self, tau_s: f64) -> Option<f64> {
        Some(cf::rate_ramp_avar(self.rate, tau_s))
    }
}

impl TermKind for RateRamp {
    const STOCHASTIC: bool = false;
    const SHOWS_IN_STATIC_LOG: bool = true;
    type Generator = RampGenerator;

    fn generator(&self, _cx: &GenContext, _rng: &dyn Fn() -> ImuRng) -> RampGenerator {
        RampGenerator { rate: self.rate }
    }
}

/// The ramp R t.
#[derive(Clone, Copy, Debug)]
pub struct RampGenerator {
    rate: f64,
}

impl Generate for RampGenerator {
    fn stage(&self) -> Stage {
        Stage::Raw
    }

    #[inline]
    fn add_raw(&mut self, clock: RawClock, out: &mut [f64], _scratch: &mut Vec<f64>) {
        // A zero ramp adds nothing (not even a signed zero).
        if self.rate != 0.0 {
            let ramp = self.rate;
            out.iter_mut()
                .enumerate()
                .for_each(|(i, v)| *v += ramp * clock.t(i));
        }
    }
}
