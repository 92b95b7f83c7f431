//! A resonance: a narrow-band random vibration (second-order Gauss-Markov process).

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

    /// Allan variance, continuous (`dt_s` None) or of the sampled sequence.
    pub fn avar(&self, tau_s: f64, dt_s: Option<f64>) -> f64 {
        let (s, f, b) = (self.sigma, self.frequency_hz, self.bandwidth_hz);
        match dt_s {
            None => cf::resonance_avar(s, f, b, tau_s),
            Some(dt) => cf::resonance_avar_sampled(s, f, b, tau_s, dt),
        }
    }

    /// Exact Allan variance behind the output filter `fa`.
    pub fn avar_filtered(&self, tau_s: f64, fa: &FilteredAllan) -> f64 {
        fa.resonance(self.sigma, self.frequency_hz, self.bandwidth_hz, tau_s)
    }
}
