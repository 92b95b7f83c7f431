//! Scale-factor error (Woodman §3.2.5: drift proportional to the rate and duration of motion).

use super::term::{ErrorTerm, TermKind};
use crate::model_error::{check_finite, ModelError};

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
}
