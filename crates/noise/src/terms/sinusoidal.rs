//! A sinusoidal error (docs/model.md §2: Hou 4.64 for its Allan variance).

use super::term::{ErrorTerm, GenContext, Generate, RawClock, Stage, TermKind};
use crate::closed_form as cf;
use crate::filter::FilteredAllan;
use crate::model_error::{check, ModelError};
use crate::ImuRng;
use rand::Rng;

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
    type Generator = SinusoidGenerator;

    /// Without a phase, this run's is the term's one draw (uniform on [0, 2 pi)). Behind an output
    /// filter the sinusoid is added after it, at the output rate: a linear filter turns
    /// A sin(w t + p) into A |H| sin(w t + p + arg H), H = sum_j h_j e^{-i w j dt_i} (exact once the
    /// pre-roll has filled the filter), so it is not generated at the internal rate.
    fn generator(&self, cx: &GenContext, rng: &dyn Fn() -> ImuRng) -> SinusoidGenerator {
        let phase = self
            .phase_rad
            .unwrap_or_else(|| rng().gen_range(0.0..std::f64::consts::TAU));
        let (amplitude, omega) = (self.amplitude, std::f64::consts::TAU * self.frequency_hz);
        match cx.filter_response {
            None => SinusoidGenerator {
                amplitude,
                omega,
                phase,
                after_filter: false,
            },
            Some(response) => {
                let (mut re, mut im) = (0.0f64, 0.0f64);
                for (j, h) in response.iter().enumerate() {
                    let arg = omega * j as f64 * cx.dt_raw_s;
                    re += h * arg.cos();
                    im -= h * arg.sin();
                }
                SinusoidGenerator {
                    amplitude: amplitude * re.hypot(im),
                    omega,
                    phase: phase + im.atan2(re),
                    after_filter: true,
                }
            }
        }
    }
}

/// amplitude sin(omega t + phase), in the raw samples or (behind a filter, with the filter's gain
/// and phase) in the output samples.
#[derive(Clone, Copy, Debug)]
pub struct SinusoidGenerator {
    amplitude: f64,
    /// rad/s.
    omega: f64,
    phase: f64,
    after_filter: bool,
}

impl Generate for SinusoidGenerator {
    fn stage(&self) -> Stage {
        if self.after_filter {
            Stage::Output
        } else {
            Stage::Raw
        }
    }

    #[inline]
    fn add_raw(&mut self, clock: RawClock, out: &mut [f64], _scratch: &mut Vec<f64>) {
        let (a, omega, phase) = (self.amplitude, self.omega, self.phase);
        out.iter_mut()
            .enumerate()
            .for_each(|(i, v)| *v += a * (omega * clock.t(i) + phase).sin());
    }

    fn output(&mut self, k0: u64, dt_s: f64, out: &mut [f64]) {
        let (a, omega, phase) = (self.amplitude, self.omega, self.phase);
        out.iter_mut()
            .enumerate()
            .for_each(|(i, v)| *v += a * (omega * (k0 + i as u64) as f64 * dt_s + phase).sin());
    }
}
