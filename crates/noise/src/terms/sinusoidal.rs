//! A sinusoidal error (docs/model.md §2: Hou 4.64 for its Allan variance).

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

    /// Phase-averaged Allan variance, continuous (`dt_s` None, Hou 4.64) or of the sampled sequence.
    pub fn avar(&self, tau_s: f64, dt_s: Option<f64>) -> f64 {
        match dt_s {
            None => cf::sinusoid_avar(self.amplitude, self.frequency_hz, tau_s),
            Some(dt) => cf::sinusoid_avar_sampled(self.amplitude, self.frequency_hz, tau_s, dt),
        }
    }

    /// Exact Allan variance behind the output filter `fa`.
    pub fn avar_filtered(&self, tau_s: f64, fa: &FilteredAllan) -> f64 {
        fa.sinusoid(self.amplitude, self.frequency_hz, tau_s)
    }
}
