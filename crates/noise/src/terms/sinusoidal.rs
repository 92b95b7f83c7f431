//! A sinusoidal error (docs/model.md §2: Hou 4.64 for its Allan variance).

use super::term::{ErrorTerm, TermKind};
use crate::closed_form as cf;
use crate::filter::FilteredAllan;
use crate::model_error::{check, ModelError};

/// Sinusoidal error `amplitude · sin(2 pi frequency_hz t + phase)`. Without a phase, one is drawn
/// uniformly per run (the phase average is what the Allan closed form describes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sinusoid {
    pub amplitude: f64,
    pub frequency_hz: f64,
    pub phase_rad: Option<f64>,
}

impl Sinusoid {
    pub fn new(
        amplitude: f64,
        frequency_hz: f64,
        phase_rad: Option<f64>,
    ) -> Result<Sinusoid, ModelError> {
        check("sinusoid amplitude", amplitude, false)?;
        check("sinusoid frequency", frequency_hz, true)?;
        if let Some(p) = phase_rad {
            if !p.is_finite() {
                return Err(ModelError {
                    what: "sinusoid phase",
                    expected: "a finite angle",
                    found: p,
                });
            }
        }
        Ok(Sinusoid {
            amplitude,
            frequency_hz,
            phase_rad,
        })
    }
}

impl ErrorTerm for Sinusoid {
    /// Phase averaged (Hou 4.64).
    fn allan_variance(&self, tau_s: f64) -> Option<f64> {
        Some(cf::sinusoid_avar(self.amplitude, self.frequency_hz, tau_s))
    }

    fn allan_variance_sampled(&self, tau_s: f64, dt_s: f64) -> Option<f64> {
        Some(cf::sinusoid_avar_sampled(
            self.amplitude,
            self.frequency_hz,
            tau_s,
            dt_s,
        ))
    }

    fn allan_variance_filtered(&self, tau_s: f64, _dt_s: f64, fa: &FilteredAllan) -> Option<f64> {
        Some(fa.sinusoid(self.amplitude, self.frequency_hz, tau_s))
    }
}

impl TermKind for Sinusoid {
    const STOCHASTIC: bool = false;
    const SHOWS_IN_STATIC_LOG: bool = true;
}
