//! Validated sensor models in SI: one `AxisModel` per axis, three per triad, a gyro and an
//! accelerometer triad per sensor, and the temperature profile driving temperature-dependent bias.
//!
//! Signal units: rad/s (gyro) or m/s^2 (accel). Each term's coefficient is stated in the IEEE 952
//! convention (docs/model.md §2): Q (signal·s), N (signal·sqrt(s)), B (signal), K (signal/sqrt(s)),
//! R (signal/s).

use crate::closed_form as cf;
use crate::effect::{Effect, Sensor, TermFilter};
use crate::temperature::TemperatureProfile;
use crate::terms::bias_instability::BiasInstability;
use crate::terms::gauss_markov::GaussMarkov;
use crate::terms::outliers::Outliers;
use crate::terms::output_filter::OutputFilter;
use crate::terms::resonance::Resonance;
use crate::terms::sinusoidal::Sinusoid;
use crate::terms::warmup_transient::WarmupTransient;

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
                .map(|k| cf::rate_random_walk_avar_at(k, tau_s, dt_s)),
            self.rate_ramp.map(|r| cf::rate_ramp_avar(r, tau_s)),
            self.gauss_markov.map(|g| g.avar(tau_s, dt_s)),
            self.sinusoidal.map(|w| w.avar(tau_s, dt_s)),
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
            self.bias_instability
                .as_ref()
                .map(|b| b.avar_filtered(tau_s, fa)),
            self.rate_random_walk.map(|k| fa.random_walk(k, tau_s)),
            self.rate_ramp.map(|r| cf::rate_ramp_avar(r, tau_s)),
            self.gauss_markov.map(|g| g.avar_filtered(tau_s, fa)),
            self.sinusoidal.map(|w| w.avar_filtered(tau_s, fa)),
            self.outliers.map(|o| o.avar_sampled(tau_s, dt_s)),
            self.resonance.map(|r| r.avar_filtered(tau_s, fa)),
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
    use crate::terms::bias_instability::Flicker;
    use crate::terms::output_filter::FilterKind;

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
                kind: FilterKind::Bartlett { taps: 8 },
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
}
