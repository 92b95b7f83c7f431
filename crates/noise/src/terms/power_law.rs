//! Fractional power-law noise, S(f) ~ f^alpha with -2 < alpha < 0 (between flicker and a random
//! walk, or between white noise and flicker), realised as flicker is: a band of log-spaced
//! first-order Gauss-Markov processes (docs/model.md §3, "Power-law noise").

use super::gauss_markov::BankGenerator;
use super::term::{ErrorTerm, GenContext, TermKind, WriteContext};
use crate::closed_form as cf;
use crate::config::error::ConfigError;
use crate::config::read::{ReadContext, Text};
use crate::filter::FilteredAllan;
use crate::law_source::{LawSource, LawSourceContext};
use crate::model_error::{check, ModelError};
use crate::units::{Quantity, Signal};
use crate::ImuRng;

/// Power-law noise of one-sided PSD S(f) = h f^alpha, stated by its Allan deviation `level` at the
/// reference averaging time `tau_ref_s`: the ideal line sigma_A(tau) = level (tau / tau_ref)^((-alpha-1)/2)
/// (`closed_form::power_law_avar_constant`).
///
/// Generated exactly as the process it defines: a sum of independent stationary Gauss-Markov
/// processes with correlation times T_i log-spaced over `[tau_min_s, tau_max_s]` and variances
/// c T_i^beta w_i (beta = -alpha - 1; `closed_form::power_law_component_weight` gives c from h):
/// the rectangle rule in ln T of the Lorentzian integral whose PSD is h f^alpha, w_i = ln(rho)
/// inside, ln(rho)/2 + 1/(1 + beta) at tau_min and ln(rho)/2 + 1/(1 - beta) at tau_max. The end
/// weights carry the parts of the continuum outside the band (int_0^tau_min c T^beta T d(ln T) as
/// a white-like component, int_tau_max^inf c T^beta / T d(ln T) as a walk-like one), which keeps
/// the curve on the ideal line near the band's ends where, without them, it falls off by up to 45 %
/// at alpha = -1.9 or -0.1. Over [30 tau_min, tau_max / 30] the bank's closed-form Allan
/// deviation stays within 0.982 .. 1.010 of the ideal line with 1 component per decade and
/// 0.982 .. 1.001 with 2, for alpha in [`PowerLaw::ALPHA_MIN`, `PowerLaw::ALPHA_MAX`]
/// (`power_law_follows_the_ideal_line`). Its memory is the band's longest correlation time: the
/// process is stationary, and beyond tau_max its Allan deviation falls as a Gauss-Markov's.
#[derive(Clone, Debug, PartialEq)]
pub struct PowerLaw {
    alpha: f64,
    level: f64,
    tau_ref_s: f64,
    tau_min_s: f64,
    tau_max_s: f64,
    per_decade: u32,
}

/// Most Gauss-Markov components a power-law term may have (20 decades at 5 per decade), as flicker.
const MAX_COMPONENTS: f64 = 100.0;

impl PowerLaw {
    /// The slopes accepted: the end weights 1/(1 -+ beta) grow without bound as alpha nears -2 or
    /// 0, and within [-1.9, -0.1] the documented ratio to the ideal line holds.
    pub const ALPHA_MIN: f64 = -1.9;
    pub const ALPHA_MAX: f64 = -0.1;
    /// Default band, as flicker's: 0.1 s to 1e5 s, the ideal line over 3 s .. 3333 s.
    pub const DEFAULT_TAU_MIN_S: f64 = 0.1;
    pub const DEFAULT_TAU_MAX_S: f64 = 1e5;
    /// One per decade: within 0.982 .. 1.010 of the ideal line (two: 0.982 .. 1.001), at half the
    /// cost per sample and per closed-form evaluation.
    pub const DEFAULT_PER_DECADE: u32 = 1;
    /// The reference averaging time of the level when the config does not state one, s.
    pub const DEFAULT_TAU_REF_S: f64 = 1.0;

    /// Checks alpha (in [ALPHA_MIN, ALPHA_MAX]), the level (finite, >= 0), the reference time
    /// and the band (finite, > 0, end after start), and 1 to 20 components per decade with at most
    /// 100 in all.
    pub fn new(
        alpha: f64,
        level: f64,
        tau_ref_s: f64,
        tau_min_s: f64,
        tau_max_s: f64,
        per_decade: u32,
    ) -> Result<PowerLaw, ModelError> {
        if !(Self::ALPHA_MIN..=Self::ALPHA_MAX).contains(&alpha) {
            return Err(ModelError {
                what: "power-law alpha",
                expected: "a slope from -1.9 to -0.1 (S(f) ~ f^alpha)",
                found: alpha,
            });
        }
        check("power-law level", level, false)?;
        check("power-law reference tau", tau_ref_s, true)?;
        super::bias_instability::check_band(
            [
                "power-law band start",
                "power-law band end",
                "power-law per_decade",
            ],
            tau_min_s,
            tau_max_s,
            per_decade,
        )?;
        let components = (tau_max_s / tau_min_s).log10() * f64::from(per_decade);
        if components > MAX_COMPONENTS {
            return Err(ModelError {
                what: "power-law band",
                expected: "at most 100 components (decades x per_decade)",
                found: components,
            });
        }
        Ok(PowerLaw {
            alpha,
            level,
            tau_ref_s,
            tau_min_s,
            tau_max_s,
            per_decade,
        })
    }

    /// With the default band and density (checked as in [`PowerLaw::new`]).
    pub fn with_alpha(alpha: f64, level: f64, tau_ref_s: f64) -> Result<PowerLaw, ModelError> {
        PowerLaw::new(
            alpha,
            level,
            tau_ref_s,
            Self::DEFAULT_TAU_MIN_S,
            Self::DEFAULT_TAU_MAX_S,
            Self::DEFAULT_PER_DECADE,
        )
    }

    /// The PSD slope alpha (S(f) ~ f^alpha).
    pub fn alpha(&self) -> f64 {
        self.alpha
    }

    /// The ideal line's Allan deviation at the reference time (signal units).
    pub fn level(&self) -> f64 {
        self.level
    }

    /// The reference averaging time of the level, s.
    pub fn tau_ref_s(&self) -> f64 {
        self.tau_ref_s
    }

    /// Shortest correlation time of the band, s.
    pub fn tau_min_s(&self) -> f64 {
        self.tau_min_s
    }

    /// Longest correlation time of the band, s: the process' memory.
    pub fn tau_max_s(&self) -> f64 {
        self.tau_max_s
    }

    /// Gauss-Markov components per decade of correlation time.
    pub fn per_decade(&self) -> u32 {
        self.per_decade
    }

    /// The slope of the ideal Allan deviation in log-log, (-alpha - 1) / 2.
    pub fn adev_slope(&self) -> f64 {
        (-self.alpha - 1.0) / 2.0
    }

    /// The ideal power law's Allan variance, level^2 (tau / tau_ref)^(-alpha-1).
    pub fn ideal_avar(&self, tau_s: f64) -> f64 {
        self.level * self.level * (tau_s / self.tau_ref_s).powf(-self.alpha - 1.0)
    }

    /// The Gauss-Markov components as (correlation time s, stationary std), shortest first (see
    /// [`PowerLaw`] for the weights).
    pub fn components(&self) -> Vec<(f64, f64)> {
        let decades = (self.tau_max_s / self.tau_min_s).log10();
        let intervals = ((decades * f64::from(self.per_decade)).round() as usize).max(1);
        let ln_rho = (self.tau_max_s / self.tau_min_s).ln() / intervals as f64;
        let beta = -self.alpha - 1.0;
        let h = cf::power_law_h(self.alpha, self.level, self.tau_ref_s);
        let c = cf::power_law_component_weight(self.alpha, h);
        (0..=intervals)
            .map(|i| {
                let tc = self.tau_min_s * (ln_rho * i as f64).exp();
                let w = if i == 0 {
                    ln_rho / 2.0 + 1.0 / (1.0 + beta)
                } else if i == intervals {
                    ln_rho / 2.0 + 1.0 / (1.0 - beta)
                } else {
                    ln_rho
                };
                // T^beta relative to the band start keeps the power finite for any band.
                let var = c * self.tau_min_s.powf(beta) * (tc / self.tau_min_s).powf(beta) * w;
                (tc, var.sqrt())
            })
            .collect()
    }

    /// Allan variance of the component sum (Hou 4.60 per component, summed), continuous or
    /// sampled at `dt_s`.
    pub fn avar_at(&self, tau_s: f64, dt_s: Option<f64>) -> f64 {
        self.components()
            .iter()
            .map(|&(tc, s)| cf::gauss_markov_avar_at(s, tc, tau_s, dt_s))
            .sum()
    }

    /// The averaging times where the bank follows the ideal line within the documented ratio,
    /// [30 tau_min, tau_max / 30].
    pub fn ideal_window(&self) -> (f64, f64) {
        (30.0 * self.tau_min_s, self.tau_max_s / 30.0)
    }
}

/// `power_law = { alpha, level, tau?, band?, per_decade? }` as written.
#[derive(serde::Deserialize, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawPowerLaw {
    alpha: Option<toml::Spanned<f64>>,
    level: Option<Text>,
    tau: Option<Text>,
    band: Option<Vec<Text>>,
    per_decade: Option<i64>,
}

impl ErrorTerm for PowerLaw {
    /// The band as realised, a sum of stationary Gauss-Markov components (as flicker's): the
    /// growth laws and their calibrated forms need nothing new.
    fn law_sources(&self, _cx: &LawSourceContext) -> Vec<LawSource> {
        vec![LawSource::GaussMarkovSum(self.components())]
    }

    /// The Allan deviation at the reference time, named `level` (docs/cli.md).
    fn level(&self) -> Option<(&'static str, f64)> {
        Some(("level", self.level))
    }

    /// The PSD slope, named `alpha`; the reference time and the band are conventions.
    fn shape(&self) -> Vec<(&'static str, f64)> {
        vec![("alpha", self.alpha)]
    }

    fn allan_variance(&self, tau_s: f64) -> Option<f64> {
        Some(self.avar_at(tau_s, None))
    }

    fn allan_variance_sampled(&self, tau_s: f64, dt_s: f64) -> Option<f64> {
        Some(self.avar_at(tau_s, Some(dt_s)))
    }

    fn allan_variance_filtered(&self, tau_s: f64, _dt_s: f64, fa: &FilteredAllan) -> Option<f64> {
        Some(
            self.components()
                .iter()
                .map(|&(tc, s)| fa.gauss_markov(s, tc, tau_s))
                .sum(),
        )
    }

    /// Every parameter written, alpha as Rust's shortest round-trip decimal, so it reads back bit
    /// for bit.
    fn config_value(&self, cx: &WriteContext) -> String {
        format!(
            "{{ alpha = {:?}, level = {}, tau = {}, band = [{}, {}], per_decade = {} }}",
            self.alpha,
            cx.quoted(self.level, Quantity::Signal(cx.sig)),
            cx.quoted(self.tau_ref_s, Quantity::Time),
            cx.quoted(self.tau_min_s, Quantity::Time),
            cx.quoted(self.tau_max_s, Quantity::Time),
            self.per_decade
        )
    }
}

impl TermKind for PowerLaw {
    const STOCHASTIC: bool = true;
    const LONG_TERM: bool = true;
    const FREE_PARAMETERS: usize = 2;
    const SHOWS_IN_STATIC_LOG: bool = true;
    type Raw = RawPowerLaw;
    const EXAMPLE: Option<&'static str> =
        Some("power_law = { alpha = -1.5, level = \"20 ug\", tau = \"100 s\" }");

    /// Alpha, the reference time and the band kept.
    fn with_level(&self, level: f64) -> Result<PowerLaw, ModelError> {
        Ok(PowerLaw {
            level: check("power-law level", level, false)?,
            ..self.clone()
        })
    }

    fn from_raw(raw: &RawPowerLaw, cx: &ReadContext) -> Result<PowerLaw, ConfigError> {
        let alpha_at = raw
            .alpha
            .as_ref()
            .map(|a| Text::new(a.span(), a.get_ref().to_string()));
        let alpha = match &raw.alpha {
            None => {
                return Err(cx.ctx.invalid(
                    &cx.sub("alpha"),
                    "the PSD slope alpha (S(f) ~ f^alpha), a number from -1.9 to -0.1",
                    "nothing",
                ))
            }
            Some(a) => *a.get_ref(),
        };
        if !(PowerLaw::ALPHA_MIN..=PowerLaw::ALPHA_MAX).contains(&alpha) {
            return Err(cx.ctx.invalid_at(
                &cx.sub("alpha"),
                alpha_at.as_ref(),
                "a slope from -1.9 to -0.1 (-1 is flicker, use bias_instability; -2 a random walk, use rate_random_walk)",
                alpha.to_string(),
            ));
        }
        let level_text = raw.level.as_ref().ok_or_else(|| {
            cx.ctx.invalid(
                &cx.sub("level"),
                "the Allan deviation at the reference time `tau`, e.g. \"20 ug\"",
                "nothing",
            )
        })?;
        let level = cx.sub_value("level", level_text, Quantity::Signal(cx.sig), true)?;
        let tau_ref_s = match &raw.tau {
            None => PowerLaw::DEFAULT_TAU_REF_S,
            Some(t) => cx.sub_positive("tau", t, Quantity::Time)?,
        };
        let (tau_min_s, tau_max_s) = match &raw.band {
            None => (PowerLaw::DEFAULT_TAU_MIN_S, PowerLaw::DEFAULT_TAU_MAX_S),
            Some(b) if b.len() == 2 => (
                cx.ctx
                    .positive(&format!("{}[0]", cx.sub("band")), &b[0], Quantity::Time)?,
                cx.ctx
                    .positive(&format!("{}[1]", cx.sub("band")), &b[1], Quantity::Time)?,
            ),
            Some(b) => {
                return Err(cx.ctx.invalid_at(
                    &cx.sub("band"),
                    b.first(),
                    "two correlation times [shortest, longest], e.g. [\"0.1 s\", \"1e5 s\"]",
                    format!("{} values", b.len()),
                ))
            }
        };
        let band_at = raw.band.as_ref().and_then(|b| b.first());
        if tau_max_s <= tau_min_s {
            return Err(cx.ctx.invalid_at(
                &cx.sub("band"),
                band_at,
                "the longest time after the shortest",
                format!("{tau_min_s} s .. {tau_max_s} s"),
            ));
        }
        let per_decade = match raw.per_decade {
            None => PowerLaw::DEFAULT_PER_DECADE,
            Some(n) if (1..=20).contains(&n) => n as u32,
            Some(n) => {
                return Err(cx.ctx.invalid(
                    &cx.sub("per_decade"),
                    "an integer from 1 to 20",
                    n.to_string(),
                ))
            }
        };
        PowerLaw::new(alpha, level, tau_ref_s, tau_min_s, tau_max_s, per_decade).map_err(|e| {
            cx.ctx.invalid_at(
                &cx.key,
                band_at.or(alpha_at.as_ref()),
                e.expected,
                format!("{:.4e} ({})", e.found, e.what),
            )
        })
    }

    /// The level is of the signal, the reference time and the band of time.
    fn note_units(value: &toml::Value, sig: Signal, note: &mut dyn FnMut(Quantity, &toml::Value)) {
        if let Some(t) = value.as_table() {
            for (k, inner) in t {
                match k.as_str() {
                    "level" => note(Quantity::Signal(sig), inner),
                    "tau" => note(Quantity::Time, inner),
                    _ => {}
                }
            }
        }
    }

    type Generator = BankGenerator;

    /// The band, its initial states drawn from the term's stream.
    fn generator(&self, cx: &GenContext, rng: &dyn Fn() -> ImuRng) -> BankGenerator {
        BankGenerator::new(&self.components(), cx.dt_raw_s, rng())
    }
}

/// A valid term of the effect, for the registry's tests (`terms::samples`).
#[cfg(test)]
pub(crate) fn sample() -> PowerLaw {
    PowerLaw::with_alpha(-1.5, 2e-4, 100.0).unwrap()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Quadrature of 2 int_0^inf x^alpha sin^4(pi x) / (pi x)^2 dx: composite Simpson on [0, 1]
    /// in u = x^(1/4) (the integrand ~ x^(alpha+2) is not smooth at 0) and on each period [j, j+1]
    /// up to 4000, then the tail as sin^4's mean 3/8 times int_X^inf x^(alpha-2) / pi^2 dx.
    fn k_by_quadrature(alpha: f64) -> f64 {
        let pi = std::f64::consts::PI;
        let f = |x: f64| {
            if x == 0.0 {
                0.0
            } else {
                x.powf(alpha) * (pi * x).sin().powi(4) / (pi * x).powi(2)
            }
        };
        let simpson = |g: &dyn Fn(f64) -> f64, a: f64, b: f64, n: usize| {
            let h = (b - a) / n as f64;
            (0..n / 2)
                .map(|i| {
                    let x = a + 2.0 * i as f64 * h;
                    h / 3.0 * (g(x) + 4.0 * g(x + h) + g(x + 2.0 * h))
                })
                .sum::<f64>()
        };
        let first = simpson(&|u: f64| f(u.powi(4)) * 4.0 * u.powi(3), 0.0, 1.0, 4096);
        let periods = 4000usize;
        let rest: f64 = (1..periods)
            .map(|j| simpson(&f, j as f64, j as f64 + 1.0, 64))
            .sum();
        let x = periods as f64;
        let tail = 3.0 / 8.0 / (pi * pi) * x.powf(alpha - 1.0) / (1.0 - alpha);
        2.0 * (first + rest + tail)
    }

    #[test]
    fn power_law_constant_matches_quadrature() {
        // The closed form against the integral 2 int x^alpha sin^4(pi x)/(pi x)^2 dx, and its
        // three textbook limits (white h/2, flicker 2 ln 2 h, random walk 2 pi^2 h / 3).
        for alpha in [-1.9, -1.5, -1.2, -1.0, -0.8, -0.5, -0.1] {
            let (closed, quad) = (cf::power_law_avar_constant(alpha), k_by_quadrature(alpha));
            assert!(
                (closed / quad - 1.0).abs() < 1e-5,
                "alpha {alpha}: {closed} vs {quad}"
            );
        }
        assert!((cf::power_law_avar_constant(-1.0) - 2.0 * std::f64::consts::LN_2).abs() < 1e-14);
        assert!((cf::power_law_avar_constant(-1e-9) - 0.5).abs() < 1e-6);
        let rw = 2.0 * std::f64::consts::PI.powi(2) / 3.0;
        assert!((cf::power_law_avar_constant(-2.0 + 1e-9) / rw - 1.0).abs() < 1e-6);
    }

    #[test]
    fn power_law_follows_the_ideal_line() {
        // The documented ratios (`PowerLaw`) on 400 taus of [30 tau_min, tau_max / 30] of the
        // default band, for slopes across the range; the reference time off the line's window.
        for (per_decade, lo, hi) in [(1, 0.982, 1.010), (2, 0.982, 1.001)] {
            for alpha in [-1.9, -1.7, -1.5, -1.3, -1.0, -0.7, -0.5, -0.3, -0.1] {
                let p = PowerLaw::new(alpha, 1.0, 1.0, 0.1, 1e5, per_decade).unwrap();
                let (a, b) = p.ideal_window();
                for i in 0..=400 {
                    let tau = a * (b / a).powf(i as f64 / 400.0);
                    let r = (p.avar_at(tau, None) / p.ideal_avar(tau)).sqrt();
                    assert!(
                        r > lo - 1e-3 && r < hi + 1e-3,
                        "alpha {alpha}, {per_decade}/decade, tau {tau}: {r}"
                    );
                }
            }
        }
    }

    #[test]
    fn power_law_at_minus_one_is_flicker() {
        // alpha = -1 is IEEE flicker: the ideal line is flat at level, and level = 0.664 B.
        let p = PowerLaw::new(-1.0, 1.0, 1.0, 0.1, 1e5, 2).unwrap();
        let f = super::super::bias_instability::Flicker::new(
            1.0 / cf::FLICKER_PLATEAU_PER_B,
            0.1,
            1e5,
            2,
        )
        .unwrap();
        for tau in [10.0, 100.0, 1000.0] {
            let r = (p.avar_at(tau, None) / f.avar(tau)).sqrt();
            assert!((r - 1.0).abs() < 0.015, "tau {tau}: {r}");
        }
    }

    #[test]
    fn power_law_refuses_out_of_range() {
        assert!(PowerLaw::with_alpha(-2.0, 1.0, 1.0).is_err());
        assert!(PowerLaw::with_alpha(0.0, 1.0, 1.0).is_err());
        assert!(PowerLaw::with_alpha(f64::NAN, 1.0, 1.0).is_err());
        assert!(PowerLaw::with_alpha(-1.5, -1.0, 1.0).is_err());
        assert!(PowerLaw::new(-1.5, 1.0, 1.0, 10.0, 1.0, 1).is_err());
        assert!(PowerLaw::new(-1.5, 1.0, 1.0, 1e-10, 1e20, 5).is_err());
        assert!(PowerLaw::with_alpha(-1.9, 1.0, 1.0).is_ok());
        assert!(PowerLaw::with_alpha(-0.1, 1.0, 1.0).is_ok());
    }
}
