//! Validated sensor models in SI: one `AxisModel` per axis, three per triad, a gyro and an
//! accelerometer triad per sensor, and the temperature profile driving temperature-dependent bias.
//!
//! Signal units: rad/s (gyro) or m/s^2 (accel). Each term's coefficient is stated in the IEEE 952
//! convention (docs/model.md §2): Q (signal·s), N (signal·sqrt(s)), B (signal), K (signal/sqrt(s)),
//! R (signal/s).

use crate::config::read::OtherTerms;
use crate::effect::{Effect, Sensor, TermFilter};
use crate::filter::FilteredAllan;
use crate::model_error::ModelError;
use crate::temperature::TemperatureProfile;
use crate::terms::output_filter::OutputFilter;
use crate::terms::{Registered, Term};
use std::collections::BTreeMap;

/// The error model of one axis, SI: at most one term per effect, absent terms add nothing.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AxisModel {
    /// The term of each effect, at the effect's position in `Effect::ALL`.
    terms: [Option<Term>; Effect::COUNT],
    /// The run-to-run spread (sd of the natural log of the level between power-ons) of terms of
    /// this axis that have a level (docs/model.md §2.3); absent terms have none.
    run_to_run: BTreeMap<Effect, f64>,
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

    /// Continuous forms (`dt_s` None) or exact sampled ones, summed in `Effect` order. The sampled
    /// forms include the output filter ([`FilteredAllan`]) and the outliers; the continuous forms
    /// leave both out (the filter's effect vanishes for tau much longer than its span; outliers
    /// need the sample interval).
    fn avar_at(&self, tau_s: f64, dt_s: Option<f64>) -> f64 {
        if let (Some(dt), Some(f)) = (dt_s, self.get::<OutputFilter>()) {
            return self.avar_filtered(tau_s, dt, &FilteredAllan::new(f, dt));
        }
        self.terms()
            .filter_map(|t| match dt_s {
                None => t.as_error_term().allan_variance(tau_s),
                Some(dt) => t.as_error_term().allan_variance_sampled(tau_s, dt),
            })
            .sum()
    }

    /// Exact Allan variance at output interval `dt_s` with the output filter `fa`.
    fn avar_filtered(&self, tau_s: f64, dt_s: f64, fa: &FilteredAllan) -> f64 {
        self.terms()
            .filter_map(|t| t.as_error_term().allan_variance_filtered(tau_s, dt_s, fa))
            .sum()
    }

    /// [`AxisModel::allan_variance_sampled`] at several taus (the filter's response computed once).
    pub fn allan_variance_sampled_many(&self, taus_s: &[f64], dt_s: f64) -> Vec<f64> {
        match self.get::<OutputFilter>() {
            Some(f) => {
                let fa = FilteredAllan::new(f, dt_s);
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

    /// The parameters of the effect `T` is the type of, if the axis has it, e.g.
    /// `axis.get::<WhiteNoise>()`.
    pub fn get<T: Registered>(&self) -> Option<&T> {
        self.terms[T::EFFECT as usize]
            .as_ref()
            .and_then(T::from_term)
    }

    /// The white-noise density the Allan curve's tau^-1/2 line shows, which a spec sheet's ARW /
    /// VRW is: `white_noise` and `output_white_noise` (after the output filter) in quadrature
    /// (independent terms: their Allan variances N^2 / tau add); None without either.
    pub fn white_noise_density(&self) -> Option<f64> {
        use crate::terms::{output_white_noise::OutputWhiteNoise, white_noise::WhiteNoise};
        let n = self.get::<WhiteNoise>().map(WhiteNoise::density);
        let out = self
            .get::<OutputWhiteNoise>()
            .map(OutputWhiteNoise::density);
        match (n, out) {
            (None, None) => None,
            // hypot(n, 0) is |n| exactly (IEEE 754): an axis without the second term reads N.
            _ => Some(n.unwrap_or(0.0).hypot(out.unwrap_or(0.0))),
        }
    }

    /// The term of `effect` with its parameters, if the axis has it.
    pub fn term(&self, effect: Effect) -> Option<&Term> {
        self.terms[effect as usize].as_ref()
    }

    /// Set a term (adding it if absent, replacing it otherwise).
    pub fn set_term(&mut self, term: impl Into<Term>) {
        let term = term.into();
        let at = term.effect() as usize;
        self.terms[at] = Some(term);
    }

    /// This axis with `term` set.
    pub fn with(mut self, term: impl Into<Term>) -> AxisModel {
        self.set_term(term);
        self
    }

    /// Is the term present?
    pub fn has(&self, effect: Effect) -> bool {
        self.terms[effect as usize].is_some()
    }

    /// Remove a term (and its run-to-run spread).
    pub fn remove(&mut self, effect: Effect) {
        self.terms[effect as usize] = None;
        self.run_to_run.remove(&effect);
    }

    /// The run-to-run spreads of the axis' terms (docs/model.md §2.3), in `Effect` order: the
    /// standard deviation of the natural log of each listed level between power-ons.
    pub fn run_to_run(&self) -> &BTreeMap<Effect, f64> {
        &self.run_to_run
    }

    /// Set the run-to-run spread of `effect` (0 <= spread <= [`crate::run_to_run::MAX_SPREAD`]):
    /// refused for a term the axis lacks or one without a level.
    pub fn set_run_to_run(&mut self, effect: Effect, spread: f64) -> Result<(), ModelError> {
        let Some(term) = self.term(effect) else {
            return Err(ModelError {
                what: "run_to_run",
                expected: "a term the axis has",
                found: spread,
            });
        };
        if term.level().is_none() {
            return Err(ModelError {
                what: "run_to_run",
                expected: "a term with a level",
                found: spread,
            });
        }
        if !(0.0..=crate::run_to_run::MAX_SPREAD).contains(&spread) {
            return Err(ModelError {
                what: "run_to_run",
                expected: "a spread (sd of ln level) from 0 to 2",
                found: spread,
            });
        }
        self.run_to_run.insert(effect, spread);
        Ok(())
    }

    /// Drop every run-to-run spread.
    pub fn clear_run_to_run(&mut self) {
        self.run_to_run.clear();
    }

    /// Does any listed term have a spread above 0 (so that a run draws its levels)?
    pub fn varies_between_runs(&self) -> bool {
        self.run_to_run.values().any(|&s| s > 0.0)
    }

    /// Which groups ([`crate::run_to_run::LONG`], [`crate::run_to_run::SHORT`]) have a listed
    /// term with a spread above 0.
    pub fn varying_groups(&self) -> [bool; 2] {
        let mut out = [false; 2];
        for (&effect, &s) in &self.run_to_run {
            if s > 0.0 {
                out[crate::run_to_run::group_of(effect)] = true;
            }
        }
        out
    }

    /// The axis as one power-on with draws `z = [long, short]` sees it: each listed term at level
    /// `L exp(s z - s^2)` with its group's z (docs/model.md §2.3), the spreads dropped; the
    /// others unchanged.
    pub fn at_run_draws(&self, z: [f64; 2]) -> AxisModel {
        let mut out = self.clone();
        out.run_to_run.clear();
        for (&effect, &s) in &self.run_to_run {
            if s == 0.0 {
                continue;
            }
            let Some(term) = self.term(effect) else {
                continue;
            };
            let Some((_, level)) = term.level() else {
                continue;
            };
            let zg = z[crate::run_to_run::group_of(effect)];
            let scaled = term
                .with_level(level * crate::run_to_run::level_factor(s, zg))
                .expect("a positive finite multiple of a valid level is valid");
            out.set_term(scaled);
        }
        out
    }

    /// The terms present with their parameters, in `Effect` order.
    pub fn terms(&self) -> impl Iterator<Item = &Term> + '_ {
        self.terms.iter().flatten()
    }

    /// The terms present, in `Effect` order.
    pub fn effects(&self) -> Vec<Effect> {
        self.terms().map(Term::effect).collect()
    }

    /// Only the terms a static log's Allan deviation can show (drops biases, scale factor,
    /// misalignment, temperature bias, the warm-up transient: `Effect::shows_in_static_log`).
    pub fn stochastic_only(&self) -> AxisModel {
        let mut out = self.clone();
        for e in Effect::ALL {
            if !e.shows_in_static_log() {
                out.remove(e);
            }
        }
        out
    }
}

impl OtherTerms for AxisModel {
    fn allan_variance_with(&self, position: usize, avar: Option<f64>, tau_s: f64) -> f64 {
        self.terms
            .iter()
            .enumerate()
            .filter_map(|(i, t)| match i == position {
                true => avar,
                false => t.as_ref()?.as_error_term().allan_variance(tau_s),
            })
            .sum()
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

impl SensorModel {
    /// The run-to-run mixture of the model as a product Gauss-Hermite rule
    /// ([`crate::run_to_run::gauss_hermite_normal`]): (weight, the model at one node's draws,
    /// spreads dropped), the weights summing to 1, so that E f(levels of a run) = sum w f(model at
    /// node) for any law f of the levels (docs/model.md §2.3). One dimension per axis and group
    /// (long-term, short-term) with a spread above 0 (its own z); n nodes per dimension with
    /// n^d <= [`crate::run_to_run::QUADRATURE_BUDGET`] (20 at most, 2 at least). Empty when no
    /// axis varies between runs.
    pub fn run_to_run_quadrature(&self) -> Vec<(f64, SensorModel)> {
        use crate::run_to_run::{gauss_hermite_normal, QUADRATURE_BUDGET};
        let dims: Vec<(Sensor, usize, usize)> = Sensor::ALL
            .into_iter()
            .flat_map(|s| (0..3).map(move |a| (s, a)))
            .flat_map(|(s, a)| {
                let groups = self.axis(s, a).varying_groups();
                (0..2).filter(move |&g| groups[g]).map(move |g| (s, a, g))
            })
            .collect();
        if dims.is_empty() {
            return Vec::new();
        }
        let d = dims.len() as u32;
        let mut n = 20usize;
        while n > 2 && n.checked_pow(d).is_none_or(|p| p > QUADRATURE_BUDGET) {
            n -= 1;
        }
        let rule = gauss_hermite_normal(n);
        let count = n.checked_pow(d).unwrap_or(usize::MAX);
        (0..count)
            .map(|mut index| {
                let mut w = 1.0;
                let mut z = [[[0.0f64; 2]; 3]; 2];
                for &(s, a, g) in &dims {
                    let (zi, wi) = rule[index % n];
                    index /= n;
                    w *= wi;
                    z[s as usize][a][g] = zi;
                }
                let mut m = self.clone();
                for &(s, a, _) in &dims {
                    *m.axis_mut(s, a) = self.axis(s, a).at_run_draws(z[s as usize][a]);
                }
                (w, m)
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::terms::*;

    #[test]
    fn every_effect_has_one_term_that_round_trips() {
        let terms = crate::terms::samples();
        // One term per effect, in Effect order.
        assert_eq!(terms.clone().map(|t| t.effect()), Effect::ALL);
        let mut axis = AxisModel::default();
        for t in &terms {
            assert!(!axis.has(t.effect()));
            axis.set_term(t.clone());
            assert_eq!(axis.term(t.effect()), Some(t));
        }
        assert_eq!(axis.terms().cloned().collect::<Vec<_>>(), terms.to_vec());
        assert_eq!(axis.effects(), Effect::ALL.to_vec());
        assert_eq!(
            axis.get::<white_noise::WhiteNoise>().map(|w| w.density()),
            Some(2e-3)
        );
        for e in Effect::ALL {
            axis.remove(e);
            assert!(!axis.has(e));
        }
        assert_eq!(axis, AxisModel::default());
    }

    /// Every effect at level 0 (a level the bootstrap of `drift` can draw) generates finite
    /// values: zero added, or the values passed unchanged.
    #[test]
    fn every_effect_at_level_zero_generates_finite_values() {
        for t in crate::terms::samples() {
            let Some(zero) = t.level().and_then(|_| t.with_level(0.0).ok()) else {
                continue;
            };
            let mut model = SensorModel::default();
            model.gyro.axes[0].set_term(zero);
            model.gyro.axes[0].set_term(white_noise::WhiteNoise::new(1e-3).unwrap());
            let mut e = crate::ImuErrors::new(&model, 0.01, 1, 0);
            let mut out = vec![0.0; 2_000];
            e.channels_mut()[0].fill_static(0, &nalgebra::Vector3::zeros(), &mut out);
            assert!(
                out.iter().all(|v| v.is_finite()),
                "{:?} at level 0 gives {:?}",
                t.effect(),
                out.iter().find(|v| !v.is_finite())
            );
        }
    }
}
