//! White noise: angle random walk of a gyro, velocity random walk of an accelerometer (docs/model.md §2, §3).

use super::term::{ErrorTerm, TermKind};
use crate::closed_form as cf;
use crate::filter::FilteredAllan;
use crate::model_error::{check, ModelError};

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
    /// sigma^2 = N^2 / tau (Hou 4.36), exact for the sampled sequence too.
    fn allan_variance(&self, tau_s: f64) -> Option<f64> {
        Some(cf::white_noise_avar(self.density, tau_s))
    }

    fn allan_variance_filtered(&self, tau_s: f64, _dt_s: f64, fa: &FilteredAllan) -> Option<f64> {
        Some(fa.white_noise(self.density, tau_s))
    }
}

impl TermKind for WhiteNoise {
    const STOCHASTIC: bool = true;
    const SHOWS_IN_STATIC_LOG: bool = true;
}
