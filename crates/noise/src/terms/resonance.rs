//! A resonance: a narrow-band random vibration (second-order Gauss-Markov process).

use super::term::{ErrorTerm, TermKind};
use crate::closed_form as cf;
use crate::filter::FilteredAllan;
use crate::model_error::{check, ModelError};

/// A resonance: a narrow-band random vibration, white noise through a damped oscillator (a
/// second-order Gauss-Markov process). Stationary std `sigma`, natural frequency `frequency_hz`,
/// half-power (-3 dB) bandwidth `bandwidth_hz` = 2 zeta f0 of its spectral peak; underdamped
/// (bandwidth below twice the frequency). Closed forms in [`cf::resonance_exponent`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Resonance {
    pub sigma: f64,
    pub frequency_hz: f64,
    pub bandwidth_hz: f64,
}

impl Resonance {
    pub fn new(sigma: f64, frequency_hz: f64, bandwidth_hz: f64) -> Result<Resonance, ModelError> {
        check("resonance sigma", sigma, false)?;
        check("resonance frequency", frequency_hz, true)?;
        check("resonance bandwidth", bandwidth_hz, true)?;
        if bandwidth_hz >= 2.0 * frequency_hz {
            return Err(ModelError {
                what: "resonance bandwidth",
                expected: "a bandwidth below twice the frequency (an underdamped resonance)",
                found: bandwidth_hz,
            });
        }
        Ok(Resonance {
            sigma,
            frequency_hz,
            bandwidth_hz,
        })
    }

    /// Damping ratio zeta = bandwidth / (2 frequency).
    pub fn damping(&self) -> f64 {
        self.bandwidth_hz / (2.0 * self.frequency_hz)
    }
}

impl ErrorTerm for Resonance {
    /// [`cf::resonance_avar`].
    fn allan_variance(&self, tau_s: f64) -> Option<f64> {
        let (s, f, b) = (self.sigma, self.frequency_hz, self.bandwidth_hz);
        Some(cf::resonance_avar(s, f, b, tau_s))
    }

    fn allan_variance_sampled(&self, tau_s: f64, dt_s: f64) -> Option<f64> {
        let (s, f, b) = (self.sigma, self.frequency_hz, self.bandwidth_hz);
        Some(cf::resonance_avar_sampled(s, f, b, tau_s, dt_s))
    }

    fn allan_variance_filtered(&self, tau_s: f64, _dt_s: f64, fa: &FilteredAllan) -> Option<f64> {
        Some(fa.resonance(self.sigma, self.frequency_hz, self.bandwidth_hz, tau_s))
    }
}

impl TermKind for Resonance {
    const STOCHASTIC: bool = true;
    const SHOWS_IN_STATIC_LOG: bool = true;
}
