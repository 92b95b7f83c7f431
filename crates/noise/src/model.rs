//! Validated sensor models in SI: one `AxisModel` per axis, three per triad, a gyro and an
//! accelerometer triad per sensor, and the temperature profile driving temperature-dependent bias.
//!
//! Signal units: rad/s (gyro) or m/s^2 (accel). Each term's coefficient is stated in the IEEE 952
//! convention (docs/model.md §2): Q (signal·s), N (signal·sqrt(s)), B (signal), K (signal/sqrt(s)),
//! R (signal/s).

use crate::closed_form as cf;
use crate::effect::{Effect, Sensor, TermFilter};
use crate::filter::{Outliers, OutputFilter, WarmupTransient};

/// Why a model value is invalid (programmatic construction; configs report through `ConfigError`).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{what}: expected {expected}, found {found}")]
pub struct ModelError {
    pub what: &'static str,
    pub expected: &'static str,
    pub found: f64,
}

pub(crate) fn check(what: &'static str, value: f64, positive: bool) -> Result<f64, ModelError> {
    let ok = value.is_finite() && if positive { value > 0.0 } else { value >= 0.0 };
    if ok {
        Ok(value)
    } else {
        Err(ModelError {
            what,
            expected: if positive {
                "a finite value > 0"
            } else {
                "a finite value >= 0"
            },
            found: value,
        })
    }
}

/// Flicker (1/f) bias instability of IEEE coefficient B, generated as a sum of log-spaced
/// Gauss-Markov processes with correlation times spanning `[tau_min_s, tau_max_s]`
/// (docs/model.md §3, kshana `Flicker`: equal variance sigma_0^2 = B^2 ln(rho) / pi each).
/// The Allan plateau 0.664 B holds for averaging times in [30 tau_min, tau_max / 30] (see `per_decade`).
#[derive(Clone, Debug, PartialEq)]
pub struct Flicker {
    /// IEEE coefficient B (signal units); the Allan plateau is 0.6643 B.
    pub b: f64,
    /// Shortest correlation time of the band, s.
    pub tau_min_s: f64,
    /// Longest correlation time of the band, s.
    pub tau_max_s: f64,
    /// Gauss-Markov components per decade of correlation time. Over averaging times
    /// [30 tau_min, tau_max / 30] the closed-form Allan deviation of the sum stays within
    /// 0.987 .. 1.010 of 0.664 B with 1 per decade and 0.987 .. 1.000 with 2 (checked numerically).
    pub per_decade: u32,
}

impl Flicker {
    /// Default band: 0.1 s to 1e5 s, a plateau over 3 s .. 3333 s, covering the averaging times where a
    /// 12 h log of a MEMS sensor shows its bias instability.
    pub const DEFAULT_TAU_MIN_S: f64 = 0.1;
    pub const DEFAULT_TAU_MAX_S: f64 = 1e5;
    /// One per decade: as flat as two within the plateau (see `per_decade`), at half the cost per sample.
    pub const DEFAULT_PER_DECADE: u32 = 1;

    pub fn new(
        b: f64,
        tau_min_s: f64,
        tau_max_s: f64,
        per_decade: u32,
    ) -> Result<Flicker, ModelError> {
        check("flicker B", b, false)?;
        check("flicker band start", tau_min_s, true)?;
        check("flicker band end", tau_max_s, true)?;
        if tau_max_s <= tau_min_s {
            return Err(ModelError {
                what: "flicker band end",
                expected: "a time longer than the band start",
                found: tau_max_s,
            });
        }
        if per_decade == 0 || per_decade > 20 {
            return Err(ModelError {
                what: "flicker per_decade",
                expected: "1 to 20 components per decade",
                found: f64::from(per_decade),
            });
        }
        Ok(Flicker {
            b,
            tau_min_s,
            tau_max_s,
            per_decade,
        })
    }

    /// With the default band.
    pub fn with_b(b: f64) -> Flicker {
        Flicker {
            b,
            tau_min_s: Self::DEFAULT_TAU_MIN_S,
            tau_max_s: Self::DEFAULT_TAU_MAX_S,
            per_decade: Self::DEFAULT_PER_DECADE,
        }
    }

    /// The Gauss-Markov components as (correlation time s, stationary std), shortest first.
    pub fn components(&self) -> Vec<(f64, f64)> {
        let decades = (self.tau_max_s / self.tau_min_s).log10();
        let intervals = ((decades * f64::from(self.per_decade)).round() as usize).max(1);
        let ln_rho = (self.tau_max_s / self.tau_min_s).ln() / intervals as f64;
        // docs/model.md §3: for IEEE B, sigma_0^2 = B^2 ln(rho) / pi per component.
        let sigma0 = self.b * (ln_rho / std::f64::consts::PI).sqrt();
        (0..=intervals)
            .map(|i| (self.tau_min_s * (ln_rho * i as f64).exp(), sigma0))
            .collect()
    }

    /// Allan variance of the component sum (docs/model.md §2 Gauss-Markov closed form, summed).
    pub fn avar(&self, tau_s: f64) -> f64 {
        self.avar_at(tau_s, None)
    }

    /// Exact Allan variance of the sampled component sum.
    pub fn avar_sampled(&self, tau_s: f64, dt_s: f64) -> f64 {
        self.avar_at(tau_s, Some(dt_s))
    }

    fn avar_at(&self, tau_s: f64, dt_s: Option<f64>) -> f64 {
        self.components()
            .iter()
            .map(|&(tc, s)| gauss_markov_avar(s, tc, tau_s, dt_s))
            .sum()
    }

    /// Variance of the k-fold integral (k = 1..=3) of the component sum at time `t_s`: the sum of the
    /// components' exact Gauss-Markov forms (`closed_form::gauss_markov_kfold_variance`).
    pub fn integrated_variance(&self, t_s: f64, k: i32) -> Option<f64> {
        self.components()
            .iter()
            .map(|&(tc, s)| cf::gauss_markov_kfold_variance(s, tc, t_s, k))
            .sum()
    }
}

/// Bias instability in one of its two models.
#[derive(Clone, Debug, PartialEq)]
pub enum BiasInstability {
    /// Flicker noise, IEEE 952 (Allan plateau 0.664 B).
    Flicker(Flicker),
    /// Woodman's bias random walk (TR-696 §3.2.3, eq 9): the bias changes by `stability` (1 sigma)
    /// over `period_s`, i.e. a random walk of density K = stability / sqrt(period).
    RandomWalk { stability: f64, period_s: f64 },
}

impl BiasInstability {
    /// Allan variance (docs/model.md §2: flicker as GM sum; random walk K^2 tau/3).
    pub fn avar(&self, tau_s: f64) -> f64 {
        self.avar_at(tau_s, None)
    }

    /// Exact Allan variance of the sampled process.
    pub fn avar_sampled(&self, tau_s: f64, dt_s: f64) -> f64 {
        self.avar_at(tau_s, Some(dt_s))
    }

    fn avar_at(&self, tau_s: f64, dt_s: Option<f64>) -> f64 {
        match self {
            BiasInstability::Flicker(f) => f.avar_at(tau_s, dt_s),
            BiasInstability::RandomWalk {
                stability,
                period_s,
            } => random_walk_avar(
                cf::woodman_bias_random_walk(*stability, *period_s),
                tau_s,
                dt_s,
            ),
        }
    }
}

/// Random walk K: continuous (Hou 4.53) or sampled form.
fn random_walk_avar(k: f64, tau_s: f64, dt_s: Option<f64>) -> f64 {
    match dt_s {
        None => cf::rate_random_walk_avar(k, tau_s),
        Some(dt) => cf::rate_random_walk_avar_sampled(k, tau_s, dt),
    }
}

/// Gauss-Markov: continuous (Hou 4.60) or sampled form.
fn gauss_markov_avar(sigma: f64, tc_s: f64, tau_s: f64, dt_s: Option<f64>) -> f64 {
    match dt_s {
        None => cf::gauss_markov_avar(sigma, tc_s, tau_s),
        Some(dt) => cf::gauss_markov_avar_sampled(sigma, tc_s, tau_s, dt),
    }
}

/// First-order Gauss-Markov bias: stationary std `sigma`, correlation time `tau_s`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaussMarkov {
    pub sigma: f64,
    pub tau_s: f64,
}

impl GaussMarkov {
    pub fn new(sigma: f64, tau_s: f64) -> Result<GaussMarkov, ModelError> {
        Ok(GaussMarkov {
            sigma: check("Gauss-Markov sigma", sigma, false)?,
            tau_s: check("Gauss-Markov correlation time", tau_s, true)?,
        })
    }
}

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
}

/// One term of an axis with its parameters (SI, as in [`AxisModel`]'s fields): the closed form of
/// "an effect and its values", used from the config to the growth laws to diagnose.
#[derive(Clone, Debug, PartialEq)]
pub enum Term {
    Quantization(f64),
    WhiteNoise(f64),
    BiasInstability(BiasInstability),
    RateRandomWalk(f64),
    RateRamp(f64),
    GaussMarkov(GaussMarkov),
    Sinusoidal(Sinusoid),
    TemperatureBias(f64),
    ConstantBias(f64),
    TurnOnBias(f64),
    ScaleFactor(f64),
    Misalignment([f64; 2]),
    Outliers(Outliers),
    WarmupTransient(WarmupTransient),
    OutputFilter(OutputFilter),
    Resonance(Resonance),
}

impl Term {
    /// Which effect this is.
    pub fn effect(&self) -> Effect {
        match self {
            Term::Quantization(_) => Effect::Quantization,
            Term::WhiteNoise(_) => Effect::WhiteNoise,
            Term::BiasInstability(_) => Effect::BiasInstability,
            Term::RateRandomWalk(_) => Effect::RateRandomWalk,
            Term::RateRamp(_) => Effect::RateRamp,
            Term::GaussMarkov(_) => Effect::GaussMarkov,
            Term::Sinusoidal(_) => Effect::Sinusoidal,
            Term::TemperatureBias(_) => Effect::TemperatureBias,
            Term::ConstantBias(_) => Effect::ConstantBias,
            Term::TurnOnBias(_) => Effect::TurnOnBias,
            Term::ScaleFactor(_) => Effect::ScaleFactor,
            Term::Misalignment(_) => Effect::Misalignment,
            Term::Outliers(_) => Effect::Outliers,
            Term::WarmupTransient(_) => Effect::WarmupTransient,
            Term::OutputFilter(_) => Effect::OutputFilter,
            Term::Resonance(_) => Effect::Resonance,
        }
    }
}

/// The error model of one axis, SI. `None` means the term is absent.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AxisModel {
    /// Quantisation coefficient Q of the integrated output (rad or m/s); the LSB of the integrated
    /// output is Q·sqrt(12) (Hou §4.3.1: Q = LSB/sqrt(12)).
    pub quantization: Option<f64>,
    /// White-noise density N (ARW rad/sqrt(s), VRW m/s/sqrt(s)).
    pub white_noise: Option<f64>,
    pub bias_instability: Option<BiasInstability>,
    /// Rate random walk K (rad/s/sqrt(s), m/s^2/sqrt(s)).
    pub rate_random_walk: Option<f64>,
    /// Rate ramp R (rad/s^2, m/s^3).
    pub rate_ramp: Option<f64>,
    pub gauss_markov: Option<GaussMarkov>,
    pub sinusoidal: Option<Sinusoid>,
    /// Bias per degC away from the reference temperature (rad/s/degC, m/s^2/degC).
    pub temperature_bias: Option<f64>,
    /// Constant bias (rad/s, m/s^2).
    pub constant_bias: Option<f64>,
    /// Standard deviation of the bias drawn once per run (turn-on to turn-on), rad/s or m/s^2.
    pub turn_on_bias: Option<f64>,
    /// Scale-factor error (dimensionless: 300 ppm = 3e-4).
    pub scale_factor: Option<f64>,
    /// Misalignment (rad): sensitivity of this axis to the two other axes, in axis order
    /// (x: [y, z]; y: [x, z]; z: [x, y]).
    pub misalignment: Option<[f64; 2]>,
    /// Isolated spikes on the output register.
    pub outliers: Option<Outliers>,
    /// Bias settling after turn-on.
    pub warmup_transient: Option<WarmupTransient>,
    /// The sensor's digital output filter (and decimation), applied to every term but quantisation
    /// and outliers.
    pub output_filter: Option<OutputFilter>,
    /// A narrow-band random vibration (second-order Gauss-Markov).
    pub resonance: Option<Resonance>,
}

impl AxisModel {
    /// Closed-form Allan variance of the stochastic terms at averaging time `tau_s`
    /// (docs/model.md §2: sum of independent terms). Deterministic and per-run terms add nothing,
    /// except the rate ramp (R^2 tau^2/2) and the sinusoid (phase-averaged, Hou 4.64).
    pub fn allan_variance(&self, tau_s: f64) -> f64 {
        self.avar_at(tau_s, None)
    }

    /// Allan variance of the series the generator produces at sample interval `dt_s`
    /// (`tau_s` a multiple of `dt_s`), exact where sampling matters.
    pub fn allan_variance_sampled(&self, tau_s: f64, dt_s: f64) -> f64 {
        self.avar_at(tau_s, Some(dt_s))
    }

    /// Continuous forms (`dt_s` None) or exact sampled ones. The sampled forms include the output
    /// filter ([`crate::filter::FilteredAllan`]) and the outliers; the continuous forms leave both
    /// out (the filter's effect vanishes for tau much longer than its span; outliers need the
    /// sample interval).
    fn avar_at(&self, tau_s: f64, dt_s: Option<f64>) -> f64 {
        if let (Some(dt), Some(f)) = (dt_s, &self.output_filter) {
            return self.avar_filtered(tau_s, dt, &crate::filter::FilteredAllan::new(f, dt));
        }
        let terms = [
            self.quantization.map(|q| cf::quantization_avar(q, tau_s)),
            self.white_noise.map(|n| cf::white_noise_avar(n, tau_s)),
            self.bias_instability
                .as_ref()
                .map(|b| b.avar_at(tau_s, dt_s)),
            self.rate_random_walk
                .map(|k| random_walk_avar(k, tau_s, dt_s)),
            self.rate_ramp.map(|r| cf::rate_ramp_avar(r, tau_s)),
            self.gauss_markov
                .map(|g| gauss_markov_avar(g.sigma, g.tau_s, tau_s, dt_s)),
            self.sinusoidal.map(|w| match dt_s {
                None => cf::sinusoid_avar(w.amplitude, w.frequency_hz, tau_s),
                Some(dt) => cf::sinusoid_avar_sampled(w.amplitude, w.frequency_hz, tau_s, dt),
            }),
            self.outliers
                .zip(dt_s)
                .map(|(o, dt)| o.avar_sampled(tau_s, dt)),
            self.resonance.map(|r| r.avar(tau_s, dt_s)),
        ];
        terms.into_iter().flatten().sum()
    }

    /// Exact Allan variance at output interval `dt_s` with the output filter `fa`: every term through
    /// the filter but quantisation, the ramp (unit DC gain keeps a ramp a ramp) and the outliers.
    fn avar_filtered(&self, tau_s: f64, dt_s: f64, fa: &crate::filter::FilteredAllan) -> f64 {
        let terms = [
            self.quantization.map(|q| cf::quantization_avar(q, tau_s)),
            self.white_noise.map(|n| fa.white_noise(n, tau_s)),
            self.bias_instability.as_ref().map(|b| match b {
                BiasInstability::Flicker(f) => f
                    .components()
                    .iter()
                    .map(|&(tc, s)| fa.gauss_markov(s, tc, tau_s))
                    .sum(),
                BiasInstability::RandomWalk {
                    stability,
                    period_s,
                } => fa.random_walk(cf::woodman_bias_random_walk(*stability, *period_s), tau_s),
            }),
            self.rate_random_walk.map(|k| fa.random_walk(k, tau_s)),
            self.rate_ramp.map(|r| cf::rate_ramp_avar(r, tau_s)),
            self.gauss_markov
                .map(|g| fa.gauss_markov(g.sigma, g.tau_s, tau_s)),
            self.sinusoidal
                .map(|w| fa.sinusoid(w.amplitude, w.frequency_hz, tau_s)),
            self.outliers.map(|o| o.avar_sampled(tau_s, dt_s)),
            self.resonance
                .map(|r| fa.resonance(r.sigma, r.frequency_hz, r.bandwidth_hz, tau_s)),
        ];
        terms.into_iter().flatten().sum()
    }

    /// [`AxisModel::allan_variance_sampled`] at several taus (the filter's response computed once).
    pub fn allan_variance_sampled_many(&self, taus_s: &[f64], dt_s: f64) -> Vec<f64> {
        match &self.output_filter {
            Some(f) => {
                let fa = crate::filter::FilteredAllan::new(f, dt_s);
                taus_s
                    .iter()
                    .map(|&t| self.avar_filtered(t, dt_s, &fa))
                    .collect()
            }
            None => taus_s
                .iter()
                .map(|&t| self.avar_at(t, Some(dt_s)))
                .collect(),
        }
    }

    /// The term of `effect` with its parameters, if the axis has it: the one place that maps an
    /// effect to its field.
    pub fn term(&self, effect: Effect) -> Option<Term> {
        match effect {
            Effect::Quantization => self.quantization.map(Term::Quantization),
            Effect::WhiteNoise => self.white_noise.map(Term::WhiteNoise),
            Effect::BiasInstability => self.bias_instability.clone().map(Term::BiasInstability),
            Effect::RateRandomWalk => self.rate_random_walk.map(Term::RateRandomWalk),
            Effect::RateRamp => self.rate_ramp.map(Term::RateRamp),
            Effect::GaussMarkov => self.gauss_markov.map(Term::GaussMarkov),
            Effect::Sinusoidal => self.sinusoidal.map(Term::Sinusoidal),
            Effect::TemperatureBias => self.temperature_bias.map(Term::TemperatureBias),
            Effect::ConstantBias => self.constant_bias.map(Term::ConstantBias),
            Effect::TurnOnBias => self.turn_on_bias.map(Term::TurnOnBias),
            Effect::ScaleFactor => self.scale_factor.map(Term::ScaleFactor),
            Effect::Misalignment => self.misalignment.map(Term::Misalignment),
            Effect::Outliers => self.outliers.map(Term::Outliers),
            Effect::WarmupTransient => self.warmup_transient.map(Term::WarmupTransient),
            Effect::OutputFilter => self.output_filter.map(Term::OutputFilter),
            Effect::Resonance => self.resonance.map(Term::Resonance),
        }
    }

    /// Set a term (adding it if absent, replacing it otherwise).
    pub fn set_term(&mut self, term: Term) {
        match term {
            Term::Quantization(v) => self.quantization = Some(v),
            Term::WhiteNoise(v) => self.white_noise = Some(v),
            Term::BiasInstability(b) => self.bias_instability = Some(b),
            Term::RateRandomWalk(v) => self.rate_random_walk = Some(v),
            Term::RateRamp(v) => self.rate_ramp = Some(v),
            Term::GaussMarkov(g) => self.gauss_markov = Some(g),
            Term::Sinusoidal(w) => self.sinusoidal = Some(w),
            Term::TemperatureBias(v) => self.temperature_bias = Some(v),
            Term::ConstantBias(v) => self.constant_bias = Some(v),
            Term::TurnOnBias(v) => self.turn_on_bias = Some(v),
            Term::ScaleFactor(v) => self.scale_factor = Some(v),
            Term::Misalignment(m) => self.misalignment = Some(m),
            Term::Outliers(o) => self.outliers = Some(o),
            Term::WarmupTransient(w) => self.warmup_transient = Some(w),
            Term::OutputFilter(f) => self.output_filter = Some(f),
            Term::Resonance(r) => self.resonance = Some(r),
        }
    }

    /// Is the term present?
    pub fn has(&self, effect: Effect) -> bool {
        self.term(effect).is_some()
    }

    /// Remove a term.
    pub fn remove(&mut self, effect: Effect) {
        match effect {
            Effect::Quantization => self.quantization = None,
            Effect::WhiteNoise => self.white_noise = None,
            Effect::BiasInstability => self.bias_instability = None,
            Effect::RateRandomWalk => self.rate_random_walk = None,
            Effect::RateRamp => self.rate_ramp = None,
            Effect::GaussMarkov => self.gauss_markov = None,
            Effect::Sinusoidal => self.sinusoidal = None,
            Effect::TemperatureBias => self.temperature_bias = None,
            Effect::ConstantBias => self.constant_bias = None,
            Effect::TurnOnBias => self.turn_on_bias = None,
            Effect::ScaleFactor => self.scale_factor = None,
            Effect::Misalignment => self.misalignment = None,
            Effect::Outliers => self.outliers = None,
            Effect::WarmupTransient => self.warmup_transient = None,
            Effect::OutputFilter => self.output_filter = None,
            Effect::Resonance => self.resonance = None,
        }
    }

    /// The terms present with their parameters, in `Effect` order.
    pub fn terms(&self) -> Vec<Term> {
        Effect::ALL
            .into_iter()
            .filter_map(|e| self.term(e))
            .collect()
    }

    /// The terms present, in `Effect` order.
    pub fn effects(&self) -> Vec<Effect> {
        Effect::ALL.into_iter().filter(|&e| self.has(e)).collect()
    }

    /// Only the stochastic terms with an Allan signature (drops biases, scale factor, misalignment,
    /// temperature bias): what a static log's Allan deviation can show.
    pub fn stochastic_only(&self) -> AxisModel {
        AxisModel {
            quantization: self.quantization,
            white_noise: self.white_noise,
            bias_instability: self.bias_instability.clone(),
            rate_random_walk: self.rate_random_walk,
            rate_ramp: self.rate_ramp,
            gauss_markov: self.gauss_markov,
            sinusoidal: self.sinusoidal,
            outliers: self.outliers,
            output_filter: self.output_filter,
            resonance: self.resonance,
            ..AxisModel::default()
        }
    }
}

#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriadModel {
    /// x, y, z.
    pub axes: [AxisModel; 3],
}

/// Temperature over time (degC), driving `temperature_bias` and written as the log's `temp` column.
#[derive(Clone, Debug, PartialEq)]
pub enum TemperatureProfile {
    Constant {
        temp_c: f64,
    },
    /// `start_c + rate_c_per_s · t`, held at `end_c` once reached (if given).
    Ramp {
        start_c: f64,
        rate_c_per_s: f64,
        end_c: Option<f64>,
    },
    /// Exponential warm-up `end_c + (start_c - end_c) e^{-t/time_constant_s}`.
    Warmup {
        start_c: f64,
        end_c: f64,
        time_constant_s: f64,
    },
    /// `mean_c + amplitude_c sin(2 pi t / period_s)` (temperature cycling).
    Sinusoid {
        mean_c: f64,
        amplitude_c: f64,
        period_s: f64,
    },
    /// `before_c` until `at_s`, `after_c` from then on.
    Step {
        before_c: f64,
        after_c: f64,
        at_s: f64,
    },
}

impl Default for TemperatureProfile {
    fn default() -> Self {
        TemperatureProfile::Constant { temp_c: 25.0 }
    }
}

impl TemperatureProfile {
    /// Temperature at time `t_s`, degC.
    pub fn at(&self, t_s: f64) -> f64 {
        match *self {
            TemperatureProfile::Constant { temp_c } => temp_c,
            TemperatureProfile::Ramp {
                start_c,
                rate_c_per_s,
                end_c,
            } => {
                let t = start_c + rate_c_per_s * t_s;
                match end_c {
                    Some(e) if rate_c_per_s >= 0.0 => t.min(e),
                    Some(e) => t.max(e),
                    None => t,
                }
            }
            TemperatureProfile::Warmup {
                start_c,
                end_c,
                time_constant_s,
            } => end_c + (start_c - end_c) * (-t_s / time_constant_s).exp(),
            TemperatureProfile::Sinusoid {
                mean_c,
                amplitude_c,
                period_s,
            } => mean_c + amplitude_c * (std::f64::consts::TAU * t_s / period_s).sin(),
            TemperatureProfile::Step {
                before_c,
                after_c,
                at_s,
            } => {
                if t_s < at_s {
                    before_c
                } else {
                    after_c
                }
            }
        }
    }

    /// The k-fold integral (k = 1..=3) from 0 to `t_s` of the excursion T(s) - `reference_c`, in
    /// degC s^k: what a temperature-bias coefficient turns into angle or velocity (k = 1), position
    /// (k = 2) or, through tilt, position (k = 3, times g). Exact, by Cauchy's formula
    /// I_k = int_0^t (t-s)^{k-1}/(k-1)! f(s) ds applied to each profile:
    /// a constant c gives c t^k/k!; a ramp r s held from t_e on gives r (t^{k+1} - (t - t_e)_+^{k+1})/(k+1)!;
    /// e^{-s/tau} gives tau^k sum_{n>=k} (-1)^{n-k} x^n/n! (x = t/tau); sin(w s) gives
    /// (1 - cos wt)/w, t/w - sin(wt)/w^2, t^2/(2w) - (1 - cos wt)/w^3. (Derived; not in docs/model.md.)
    /// `None` for k outside 1..=3.
    pub fn excursion_integral(&self, reference_c: f64, t_s: f64, k: i32) -> Option<f64> {
        if !(1..=3).contains(&k) {
            return None;
        }
        let fact = |n: i32| (1..=n).map(f64::from).product::<f64>();
        let constant = |c: f64| c * t_s.powi(k) / fact(k);
        Some(match *self {
            TemperatureProfile::Constant { temp_c } => constant(temp_c - reference_c),
            TemperatureProfile::Ramp {
                start_c,
                rate_c_per_s,
                end_c,
            } => {
                let held_after = match end_c {
                    Some(e) if rate_c_per_s != 0.0 => ((e - start_c) / rate_c_per_s).max(0.0),
                    _ => f64::INFINITY,
                };
                let past = (t_s - held_after).max(0.0);
                constant(start_c - reference_c)
                    + rate_c_per_s * (t_s.powi(k + 1) - past.powi(k + 1)) / fact(k + 1)
            }
            TemperatureProfile::Warmup {
                start_c,
                end_c,
                time_constant_s,
            } => {
                let x = t_s / time_constant_s;
                // tau^k [sum_{j<k} (-1)^{k-1-j} x^j/j! + (-1)^k e^{-x}], summed as its series for small x.
                let e = if x < 1.0 {
                    (k..k + 30)
                        .map(|n| {
                            let sign = if (n - k) % 2 == 0 { 1.0 } else { -1.0 };
                            sign * x.powi(n) / fact(n)
                        })
                        .sum::<f64>()
                } else {
                    let sign = |p: i32| if p % 2 == 0 { 1.0 } else { -1.0 };
                    (0..k)
                        .map(|j| sign(k - 1 - j) * x.powi(j) / fact(j))
                        .sum::<f64>()
                        + sign(k) * (-x).exp()
                };
                constant(end_c - reference_c) + (start_c - end_c) * time_constant_s.powi(k) * e
            }
            TemperatureProfile::Sinusoid {
                mean_c,
                amplitude_c,
                period_s,
            } => {
                let w = std::f64::consts::TAU / period_s;
                let one_minus_cos = 2.0 * (0.5 * w * t_s).sin().powi(2);
                let sine = match k {
                    1 => one_minus_cos / w,
                    2 => t_s / w - (w * t_s).sin() / (w * w),
                    _ => t_s * t_s / (2.0 * w) - one_minus_cos / w.powi(3),
                };
                constant(mean_c - reference_c) + amplitude_c * sine
            }
            // (after - before) times the k-fold integral of the unit step at t_e: (t - t_e)_+^k / k!.
            TemperatureProfile::Step {
                before_c,
                after_c,
                at_s,
            } => {
                constant(before_c - reference_c)
                    + (after_c - before_c) * (t_s - at_s.max(0.0)).max(0.0).powi(k) / fact(k)
            }
        })
    }
}

/// A whole sensor: gyro and accelerometer triads plus temperature.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SensorModel {
    pub name: String,
    pub description: Option<String>,
    pub gyro: TriadModel,
    pub accel: TriadModel,
    pub temperature: TemperatureProfile,
    /// Temperature at which `temperature_bias` is zero, degC.
    pub temperature_reference_c: f64,
}

impl SensorModel {
    pub fn triad(&self, sensor: Sensor) -> &TriadModel {
        match sensor {
            Sensor::Gyro => &self.gyro,
            Sensor::Accel => &self.accel,
        }
    }
    pub fn triad_mut(&mut self, sensor: Sensor) -> &mut TriadModel {
        match sensor {
            Sensor::Gyro => &mut self.gyro,
            Sensor::Accel => &mut self.accel,
        }
    }

    /// Axis `axis` (0 = x) of `sensor`.
    pub fn axis(&self, sensor: Sensor, axis: usize) -> &AxisModel {
        &self.triad(sensor).axes[axis]
    }
    pub fn axis_mut(&mut self, sensor: Sensor, axis: usize) -> &mut AxisModel {
        &mut self.triad_mut(sensor).axes[axis]
    }

    /// Does any axis of `sensor` have `effect`?
    pub fn has(&self, sensor: Sensor, effect: Effect) -> bool {
        self.triad(sensor).axes.iter().any(|a| a.has(effect))
    }

    /// The model with the terms the filter switches off removed (ablation).
    pub fn filtered(&self, filter: &TermFilter) -> SensorModel {
        let mut out = self.clone();
        for sensor in Sensor::ALL {
            for axis in out.triad_mut(sensor).axes.iter_mut() {
                for effect in Effect::ALL {
                    if !filter.allows(sensor, effect) {
                        axis.remove(effect);
                    }
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_effect_has_one_term_that_round_trips() {
        let terms = [
            Term::Quantization(1e-3),
            Term::WhiteNoise(2e-3),
            Term::BiasInstability(BiasInstability::Flicker(Flicker::with_b(3e-5))),
            Term::RateRandomWalk(4e-6),
            Term::RateRamp(5e-7),
            Term::GaussMarkov(GaussMarkov {
                sigma: 6e-4,
                tau_s: 70.0,
            }),
            Term::Sinusoidal(Sinusoid {
                amplitude: 8e-3,
                frequency_hz: 9.0,
                phase_rad: Some(0.1),
            }),
            Term::TemperatureBias(1e-5),
            Term::ConstantBias(2e-2),
            Term::TurnOnBias(3e-2),
            Term::ScaleFactor(4e-4),
            Term::Misalignment([5e-4, 6e-4]),
            Term::Outliers(Outliers {
                rate_per_hour: 60.0,
                size: 0.1,
            }),
            Term::WarmupTransient(WarmupTransient {
                amplitude: 5e-4,
                tau_s: 600.0,
                per_run: false,
            }),
            Term::OutputFilter(OutputFilter {
                kind: crate::filter::FilterKind::Bartlett { taps: 8 },
                decimation: 2,
            }),
            Term::Resonance(Resonance {
                sigma: 7e-4,
                frequency_hz: 20.0,
                bandwidth_hz: 0.7,
            }),
        ];
        // One term per effect, in Effect order.
        assert_eq!(terms.clone().map(|t| t.effect()), Effect::ALL);
        let mut axis = AxisModel::default();
        for t in &terms {
            assert!(!axis.has(t.effect()));
            axis.set_term(t.clone());
            assert_eq!(axis.term(t.effect()).as_ref(), Some(t));
        }
        assert_eq!(axis.terms(), terms.to_vec());
        assert_eq!(axis.effects(), Effect::ALL.to_vec());
        for e in Effect::ALL {
            axis.remove(e);
            assert!(!axis.has(e));
        }
        assert_eq!(axis, AxisModel::default());
    }

    #[test]
    fn temperature_excursion_integrals_match_numerical_integration() {
        // Rectangle-rule integrals of the profile on a 1e-4 s grid: agreement to 1e-3 relative (the
        // rule's O(dt/t) error) for each profile, k = 1..3, before, at and after the ramp's hold.
        let profiles = [
            TemperatureProfile::Constant { temp_c: 31.0 },
            TemperatureProfile::Ramp {
                start_c: 20.0,
                rate_c_per_s: 2.0,
                end_c: Some(30.0),
            },
            TemperatureProfile::Ramp {
                start_c: 30.0,
                rate_c_per_s: -0.5,
                end_c: None,
            },
            TemperatureProfile::Warmup {
                start_c: 10.0,
                end_c: 40.0,
                time_constant_s: 3.0,
            },
            TemperatureProfile::Sinusoid {
                mean_c: 26.0,
                amplitude_c: 4.0,
                period_s: 2.5,
            },
            TemperatureProfile::Step {
                before_c: 22.0,
                after_c: 30.0,
                at_s: 5.0,
            },
        ];
        let dt = 1e-4;
        for profile in &profiles {
            let (mut i1, mut i2, mut i3) = (0.0, 0.0, 0.0);
            let n = 120_000; // 12 s
            for j in 0..n {
                let t = (j as f64 + 0.5) * dt;
                i1 += (profile.at(t) - 25.0) * dt;
                i2 += i1 * dt;
                i3 += i2 * dt;
                if (j + 1) % 20_000 == 0 {
                    let t_end = (j + 1) as f64 * dt;
                    for (k, num) in [(1, i1), (2, i2), (3, i3)] {
                        let exact = profile.excursion_integral(25.0, t_end, k).unwrap();
                        assert!(
                            (exact - num).abs() <= 1e-3 * exact.abs().max(1e-3 * t_end.powi(k)),
                            "{profile:?} t {t_end} k {k}: exact {exact} vs numerical {num}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn flicker_plateau_ripple_is_as_documented() {
        // `Flicker::per_decade` documents 0.987 .. 1.010 (1 per decade) and 0.987 .. 1.000 (2) of
        // 0.664 B over [30 tau_min, tau_max / 30]; checked on 400 taus of the default band.
        for (per_decade, lo, hi) in [(1, 0.987, 1.010), (2, 0.987, 1.000)] {
            let f = Flicker::new(1.0, 0.1, 1e5, per_decade).unwrap();
            let (a, b) = (30.0 * f.tau_min_s, f.tau_max_s / 30.0);
            for i in 0..=400 {
                let tau = a * (b / a).powf(i as f64 / 400.0);
                let r = f.avar(tau).sqrt() / cf::FLICKER_PLATEAU_PER_B;
                assert!(
                    r > lo - 1e-3 && r < hi + 1e-3,
                    "{per_decade}/decade, tau {tau}: {r}"
                );
            }
        }
    }
}
