//! What a term contributes to the drift growth laws (docs/model.md §4): its statistical description
//! as a [`LawSource`], which each term states itself (`ErrorTerm::law_sources`, in its file under
//! `terms/`) and the growth laws (montecarlo's `laws`) integrate through the strapdown couplings.

use crate::temperature::TemperatureProfile;
use serde::{Deserialize, Serialize};

/// The statistical description of one error term on one axis, SI.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum LawSource {
    /// Known constant (signed).
    Bias(f64),
    /// Constant drawn once per run from N(0, sigma^2) (turn-on bias, random alignment).
    RandomConstant(f64),
    /// White noise of density N.
    White(f64),
    /// Random walk of density K (rate random walk, Woodman's bias random walk), zero start.
    RandomWalk(f64),
    /// Stationary first-order Gauss-Markov (sigma, correlation time s).
    GaussMarkov { sigma: f64, tc_s: f64 },
    /// A sum of independent stationary Gauss-Markov processes, (correlation time s, sigma) each:
    /// the flicker bias instability as the noise crate realises it (`Flicker::components`).
    GaussMarkovSum(Vec<(f64, f64)>),
    /// The same sum with each component referenced to its value at t = 0, x(t) = b(t) - b(0): the
    /// bias as seen after a perfect turn-on calibration (scenario `terms.bias_calibrated_at_start`;
    /// `closed_form::gauss_markov_kfold_from_start_variance`). A single Gauss-Markov term is a
    /// sum of one.
    GaussMarkovSumFromStart(Vec<(f64, f64)>),
    /// The same sum with each component referenced to its mean over a calibration window of
    /// `window_s` seconds before t = 0, x(t) = b(t) - m (scenario `terms.bias_calibration_window_s`;
    /// `closed_form::gauss_markov_kfold_from_window_variance`).
    GaussMarkovSumFromWindow {
        parts: Vec<(f64, f64)>,
        window_s: f64,
    },
    /// Rate ramp R (signed), error R t.
    Ramp(f64),
    /// Sinusoid `amplitude · sin(2 pi freq_hz t + phase)`, point-sampled at t_k = k dt
    /// (`sample_interval_s` = dt; each sample held over its interval, a delay of dt/2); the phase
    /// uniform on [0, 2 pi) per run when `None` (`closed_form::sinusoid_growth`: mean 0 and
    /// variance A^2 (a_k^2 + b_k^2)/2; fixed phase: the deterministic k-fold integral;
    /// `sinusoid_growth_sampled` for the sampling). With a random phase the integrals are not
    /// Gaussian (arcsine distributed), so horizontal magnitudes they feed get an rms law but no
    /// mean.
    Sinusoid {
        amplitude: f64,
        freq_hz: f64,
        phase: Option<f64>,
        sample_interval_s: f64,
    },
    /// Stationary resonance (second-order Gauss-Markov) of std sigma, natural frequency and
    /// half-power bandwidth (`closed_form::resonance_kfold_variance`). A calibration leaves it
    /// alone: it averages out over any window much longer than 1 / bandwidth.
    Resonance {
        sigma: f64,
        frequency_hz: f64,
        bandwidth_hz: f64,
    },
    /// Warm-up transient `amplitude e^{-t/tau_s}` after turn-on; with `per_run` the amplitude is
    /// drawn per run from N(0, amplitude^2) (`closed_form::transient_growth`).
    Transient {
        amplitude: f64,
        tau_s: f64,
        per_run: bool,
    },
    /// Active, but no closed-form growth law exists in docs/model.md §4 (e.g. quantisation): the
    /// report says so.
    NoLaw(String),
}

/// What a term's law source may depend on besides its parameters: the conditions of the laws
/// (docs/model.md §4: a static, level, north-facing IMU, or a constant rate about body z).
#[derive(Clone, Copy, Debug)]
pub struct LawSourceContext<'a> {
    /// The ideal reading of the term's own axis (rad/s or m/s^2).
    pub ideal: f64,
    /// The ideal readings of the triad's two other axes, in misalignment order (x: y, z; y: x, z;
    /// z: x, y).
    pub others: [f64; 2],
    /// The sample interval, s (the sampled sinusoid's law and the outliers' rate depend on it).
    pub dt_s: f64,
    /// The sensor's temperature profile and the temperature where `temperature_bias` is zero, degC.
    pub temperature: &'a TemperatureProfile,
    pub temperature_reference_c: f64,
}
