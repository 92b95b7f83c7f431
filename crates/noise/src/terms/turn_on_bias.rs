//! A bias drawn once per run, turn-on to turn-on.

use super::term::{ErrorTerm, GenContext, Generate, Stage, TermKind};
use crate::discrete::normal;
use crate::model_error::{check, ModelError};
use crate::ImuRng;

/// Standard deviation of the bias drawn once per run (turn-on to turn-on), rad/s or m/s^2.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TurnOnBias {
    sigma: f64,
}

impl TurnOnBias {
    /// A finite value >= 0.
    pub fn new(sigma: f64) -> Result<TurnOnBias, ModelError> {
        Ok(TurnOnBias {
            sigma: check("turn-on bias sigma", sigma, false)?,
        })
    }

    /// The standard deviation (rad/s or m/s^2).
    pub fn sigma(&self) -> f64 {
        self.sigma
    }
}

impl ErrorTerm for TurnOnBias {}

impl TermKind for TurnOnBias {
    const STOCHASTIC: bool = false;
    const SHOWS_IN_STATIC_LOG: bool = false;
    type Generator = TurnOnBiasGenerator;

    /// This run's bias is the term's one draw, N(0, sigma^2).
    fn generator(&self, _cx: &GenContext, rng: &dyn Fn() -> ImuRng) -> TurnOnBiasGenerator {
        TurnOnBiasGenerator {
            bias: self.sigma * normal(&mut rng()),
        }
    }
}

/// This run's draw, added to the ideal input.
#[derive(Clone, Copy, Debug)]
pub struct TurnOnBiasGenerator {
    bias: f64,
}

impl Generate for TurnOnBiasGenerator {
    fn stage(&self) -> Stage {
        Stage::Input
    }

    fn input(&self, _row: &mut [f64; 3], bias: &mut f64) {
        *bias += self.bias;
    }
}
