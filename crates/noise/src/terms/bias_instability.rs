//! Bias instability: flicker (1/f) noise as IEEE 952 defines it, realised as a band of Gauss-Markov
//! processes, or Woodman's bias random walk (TR-696 §3.2.3).

use super::gauss_markov::BankGenerator;
use super::rate_random_walk::RandomWalkGenerator;
use super::term::{ErrorTerm, GenContext, Generate, RawClock, Stage, TermKind};
use crate::closed_form as cf;
use crate::discrete::RandomWalk;
use crate::filter::FilteredAllan;
use crate::model_error::{check, ModelError};
use crate::ImuRng;

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
            .map(|&(tc, s)| cf::gauss_markov_avar_at(s, tc, tau_s, dt_s))
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

    /// Continuous (`dt_s` None) or sampled.
    fn avar_at(&self, tau_s: f64, dt_s: Option<f64>) -> f64 {
        match self {
            BiasInstability::Flicker(f) => f.avar_at(tau_s, dt_s),
            BiasInstability::RandomWalk {
                stability,
                period_s,
            } => cf::rate_random_walk_avar_at(
                cf::woodman_bias_random_walk(*stability, *period_s),
                tau_s,
                dt_s,
            ),
        }
    }
}

impl ErrorTerm for BiasInstability {
    fn allan_variance(&self, tau_s: f64) -> Option<f64> {
        Some(self.avar(tau_s))
    }

    fn allan_variance_sampled(&self, tau_s: f64, dt_s: f64) -> Option<f64> {
        Some(self.avar_sampled(tau_s, dt_s))
    }

    /// Each flicker component, or the walk, behind the filter.
    fn allan_variance_filtered(&self, tau_s: f64, _dt_s: f64, fa: &FilteredAllan) -> Option<f64> {
        Some(match self {
            BiasInstability::Flicker(f) => f
                .components()
                .iter()
                .map(|&(tc, s)| fa.gauss_markov(s, tc, tau_s))
                .sum(),
            BiasInstability::RandomWalk {
                stability,
                period_s,
            } => fa.random_walk(cf::woodman_bias_random_walk(*stability, *period_s), tau_s),
        })
    }
}

impl TermKind for BiasInstability {
    const STOCHASTIC: bool = true;
    const SHOWS_IN_STATIC_LOG: bool = true;
    type Generator = BiasInstabilityGenerator;

    fn generator(&self, cx: &GenContext, rng: &dyn Fn() -> ImuRng) -> BiasInstabilityGenerator {
        match self {
            BiasInstability::Flicker(f) => BiasInstabilityGenerator::Flicker(BankGenerator::new(
                &f.components(),
                cx.dt_raw_s,
                rng(),
            )),
            // Woodman eq 9 / AirSim: K = BS / sqrt(T_BS), so BS·sqrt(dt/T_BS) per step.
            BiasInstability::RandomWalk {
                stability,
                period_s,
            } => BiasInstabilityGenerator::RandomWalk(RandomWalkGenerator {
                walk: RandomWalk::new(stability / period_s.sqrt(), cx.dt_raw_s),
                rng: rng(),
            }),
        }
    }
}

/// Flicker's band of Gauss-Markov processes, or Woodman's random walk.
#[derive(Clone, Debug)]
pub enum BiasInstabilityGenerator {
    Flicker(BankGenerator),
    RandomWalk(RandomWalkGenerator),
}

impl Generate for BiasInstabilityGenerator {
    fn stage(&self) -> Stage {
        Stage::Raw
    }

    #[inline]
    fn add_raw(&mut self, clock: RawClock, out: &mut [f64], scratch: &mut Vec<f64>) {
        match self {
            BiasInstabilityGenerator::Flicker(g) => g.add_raw(clock, out, scratch),
            BiasInstabilityGenerator::RandomWalk(g) => g.add_raw(clock, out, scratch),
        }
    }

    /// The flicker band is referenced; a random walk already starts at 0.
    fn calibrate_start(&mut self) {
        if let BiasInstabilityGenerator::Flicker(g) = self {
            g.calibrate_start();
        }
    }

    fn calibrate_window(&mut self, window_s: f64, rng: &dyn Fn() -> ImuRng) {
        if let BiasInstabilityGenerator::Flicker(g) = self {
            g.calibrate_window(window_s, rng);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
