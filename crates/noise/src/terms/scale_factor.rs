//! Scale-factor error (Woodman §3.2.5: drift proportional to the rate and duration of motion).

use super::term::{ErrorTerm, GenContext, Generate, Stage, TermKind};
use crate::model_error::{check_finite, ModelError};
use crate::ImuRng;

/// Scale-factor error (dimensionless: 300 ppm = 3e-4), signed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScaleFactor {
    ratio: f64,
}

impl ScaleFactor {
    /// Any finite value.
    pub fn new(ratio: f64) -> Result<ScaleFactor, ModelError> {
        Ok(ScaleFactor {
            ratio: check_finite("scale factor", ratio)?,
        })
    }

    /// The error as a ratio.
    pub fn ratio(&self) -> f64 {
        self.ratio
    }
}

impl ErrorTerm for ScaleFactor {}

impl TermKind for ScaleFactor {
    const STOCHASTIC: bool = false;
    const SHOWS_IN_STATIC_LOG: bool = false;
    type Generator = ScaleFactorGenerator;

    fn generator(&self, cx: &GenContext, _rng: &dyn Fn() -> ImuRng) -> ScaleFactorGenerator {
        ScaleFactorGenerator {
            ratio: self.ratio,
            axis: cx.axis,
        }
    }
}

/// The axis' own sensitivity, 1 + ratio.
#[derive(Clone, Copy, Debug)]
pub struct ScaleFactorGenerator {
    ratio: f64,
    axis: usize,
}

impl Generate for ScaleFactorGenerator {
    fn stage(&self) -> Stage {
        Stage::Input
    }

    fn input(&self, row: &mut [f64; 3], _bias: &mut f64) {
        row[self.axis] += self.ratio;
    }
}
