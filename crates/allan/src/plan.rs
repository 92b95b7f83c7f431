//! Record-length planning: how long a static log must be to read a noise term off its Allan
//! deviation to a stated relative uncertainty, and how well a log of a given length reads it.
//!
//! A term is read where it dominates the model's Allan variance, as the `allan` command's
//! readings do ([`crate::fit::readings`]): white noise (ARW / VRW) on the slope -1/2 tangent, i.e.
//! at the tau minimising sigma(tau) sqrt(tau); bias instability at the minimum of sigma(tau); rate
//! random walk on the slope +1/2 tangent, taken at the shortest tau where the random walk is at
//! least [`DOMINANT_SHARE`] of the Allan variance (the tangent itself only touches at infinity;
//! the same rule reads a bias-instability floor that has no minimum after it).
//!
//! The overlapping Allan variance at averaging factor m from N samples is chi-squared with nu
//! equivalent degrees of freedom (Greenhall & Riley 2003, NIST SP 1065 §5.3, computed by
//! [`crate::edf::greenhall`] for the noise type that dominates there), so
//! var(s^2 / sigma^2) = 2 / nu and, to first order, the relative standard uncertainty of the
//! deviation, hence of the reading, is u = 1 / sqrt(2 nu). The log must also hold at least
//! [`MIN_BINS`] non-overlapping averaging intervals of the reading's tau (Woodman TR-696 §5.1).

use crate::edf::greenhall;

/// Share of the Allan variance a term must reach before it is read where the curve has no
/// turning point to read it at (a rate random walk; a flat floor with nothing rising after it):
/// the rest biases the reading high by 1/sqrt(share) - 1, under 12 % at 0.8.
pub const DOMINANT_SHARE: f64 = 0.8;
/// Fewest non-overlapping averaging intervals at the reading's tau (Woodman's 9 bins).
pub const MIN_BINS: f64 = 9.0;

/// The terms a plan covers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PlanTerm {
    WhiteNoise,
    BiasInstability,
    RateRandomWalk,
}

impl PlanTerm {
    /// The power-law exponent of the rate PSD of the term (IEEE 952 annex C): white FM 0,
    /// flicker FM -1, random-walk FM -2.
    pub fn alpha(self) -> i32 {
        match self {
            PlanTerm::WhiteNoise => 0,
            PlanTerm::BiasInstability => -1,
            PlanTerm::RateRandomWalk => -2,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            PlanTerm::WhiteNoise => "white_noise",
            PlanTerm::BiasInstability => "bias_instability",
            PlanTerm::RateRandomWalk => "rate_random_walk",
        }
    }
}

/// The model's Allan variance of a sampled rate signal: the total and one term's part.
pub struct Curve<'a> {
    pub total: &'a dyn Fn(f64) -> f64,
    pub term: &'a dyn Fn(f64) -> f64,
}

/// How one term is read and what a log length gives.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct TermPlan {
    pub term: PlanTerm,
    /// Averaging time at which the term is read, s (`None`: the model's curve never lets it be read).
    pub tau_s: Option<f64>,
    /// The term's share of the model's Allan variance there.
    pub share: Option<f64>,
    /// Shortest log that reads the term to the target uncertainty, s.
    pub required_duration_s: Option<f64>,
    /// Relative standard uncertainty of the reading from a log of the duration asked about.
    pub uncertainty_at_duration: Option<f64>,
    /// Why a value is missing.
    pub note: Option<String>,
}

/// Relative standard uncertainty 1/sqrt(2 nu) of the overlapping Allan deviation at `tau_s` from
/// `n` samples at `dt_s` for noise `alpha`; `None` when the log is too short for that tau.
pub fn relative_uncertainty(alpha: i32, tau_s: f64, dt_s: f64, n: f64) -> Option<f64> {
    let m = (tau_s / dt_s).round().max(1.0);
    if n * dt_s < MIN_BINS * m * dt_s || n < 2.0 * m + 1.0 {
        return None;
    }
    let nu = greenhall(alpha, 2, m as usize, n as usize + 1, true, false)?;
    (nu > 0.0).then(|| 1.0 / (2.0 * nu).sqrt())
}

/// Log-spaced taus from `dt_s` to `max_s`, 40 per decade (the reading's tau is found on it).
fn grid(dt_s: f64, max_s: f64) -> Vec<f64> {
    let decades = (max_s / dt_s).log10().max(0.0);
    let n = (40.0 * decades).ceil() as usize;
    (0..=n)
        .map(|i| dt_s * 10f64.powf(decades * i as f64 / n.max(1) as f64))
        .collect()
}

/// The shortest tau where the term is at least [`DOMINANT_SHARE`] of the Allan variance.
fn dominant_from(taus: &[f64], curve: &Curve) -> Option<f64> {
    taus.iter()
        .copied()
        .find(|&t| (curve.term)(t) >= DOMINANT_SHARE * (curve.total)(t))
}

/// Where `term` is read on the model's curve (see the module doc), searched up to `max_tau_s`.
pub fn reading_tau(term: PlanTerm, curve: &Curve, dt_s: f64, max_tau_s: f64) -> Option<f64> {
    let taus = grid(dt_s, max_tau_s);
    let argmin = |f: &dyn Fn(f64) -> f64| {
        taus.iter()
            .copied()
            .filter(|&t| f(t).is_finite())
            .min_by(|&a, &b| f(a).total_cmp(&f(b)))
    };
    match term {
        PlanTerm::WhiteNoise => argmin(&|t| (curve.total)(t) * t),
        PlanTerm::BiasInstability => {
            let t = argmin(&|t| (curve.total)(t))?;
            // A minimum at the search limit is no minimum: the curve still falls there (e.g.
            // white noise over a flat flicker floor with nothing rising after it). The floor is
            // then read where it begins to dominate.
            if t < max_tau_s * 0.99 {
                Some(t)
            } else {
                dominant_from(&taus, curve)
            }
        }
        PlanTerm::RateRandomWalk => dominant_from(&taus, curve),
    }
}

/// Plan one term: the reading's tau, the shortest log for relative uncertainty `target`, and
/// the uncertainty from a log of `duration_s` (if given). `dt_s` is the sample interval.
pub fn plan_term(
    term: PlanTerm,
    curve: &Curve,
    dt_s: f64,
    target: f64,
    duration_s: Option<f64>,
    max_tau_s: f64,
) -> TermPlan {
    let mut plan = TermPlan {
        term,
        tau_s: None,
        share: None,
        required_duration_s: None,
        uncertainty_at_duration: None,
        note: None,
    };
    let Some(tau) = reading_tau(term, curve, dt_s, max_tau_s) else {
        plan.note = Some(match term {
            PlanTerm::BiasInstability => format!(
                "the model's Allan deviation has no minimum below tau = {}, and the floor never reaches 80 % of it: other terms hide it",
                crate::plan::fmt_s(max_tau_s)
            ),
            PlanTerm::RateRandomWalk => format!(
                "the random walk never reaches {:.0} % of the Allan variance below tau = {}",
                100.0 * DOMINANT_SHARE,
                crate::plan::fmt_s(max_tau_s)
            ),
            PlanTerm::WhiteNoise => "no tau to read the white noise at".into(),
        });
        return plan;
    };
    plan.tau_s = Some(tau);
    plan.share = Some((curve.term)(tau) / (curve.total)(tau));
    let alpha = term.alpha();
    let u = |n: f64| relative_uncertainty(alpha, tau, dt_s, n);
    // Shortest n with u(n) <= target: double until met, then bisect (u falls as n grows).
    let mut hi = (MIN_BINS * tau / dt_s).ceil().max(3.0);
    let mut met = false;
    for _ in 0..60 {
        if u(hi).is_some_and(|v| v <= target) {
            met = true;
            break;
        }
        hi *= 2.0;
    }
    if met {
        let mut lo = hi / 2.0;
        while hi - lo > (hi * 1e-3).max(1.0) {
            let mid = 0.5 * (lo + hi);
            if u(mid).is_some_and(|v| v <= target) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        plan.required_duration_s = Some(hi.ceil() * dt_s);
    } else {
        plan.note = Some(format!("no log length reaches {:.0} %", 100.0 * target));
    }
    if let Some(d) = duration_s {
        plan.uncertainty_at_duration = u((d / dt_s).round());
        if plan.uncertainty_at_duration.is_none() {
            plan.note.get_or_insert_with(|| {
                format!(
                    "a {} log is shorter than {} averaging intervals of tau = {}: it cannot read this term",
                    fmt_s(d),
                    MIN_BINS,
                    fmt_s(tau)
                )
            });
        }
    }
    plan
}

/// A duration with its unit, compactly, for messages.
pub fn fmt_s(s: f64) -> String {
    if s >= 3600.0 {
        format!("{:.3} h", s / 3600.0)
    } else {
        format!("{s:.3} s")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn white_noise_uncertainty_matches_the_count_of_independent_averages() {
        // White FM at m = 1: the overlapping Allan variance from N samples has about N - 1
        // degrees of freedom... for large N Greenhall's EDF for white FM at m = 1 is
        // (N - 2) * 2/3 * ... ; check the m = 1 value against SP 1065 Table 5's simple formula
        // nu = (3(N-1)/(2m) - 2(N-2)/N) * 4m^2/(4m^2+5) within 2 %.
        let n: f64 = 100_000.0;
        let m = 100.0;
        let u = relative_uncertainty(0, m, 1.0, n).unwrap();
        let simple =
            (3.0 * (n - 1.0) / (2.0 * m) - 2.0 * (n - 2.0) / n) * 4.0 * m * m / (4.0 * m * m + 5.0);
        let u_simple = 1.0 / (2.0 * simple).sqrt();
        assert!((u / u_simple - 1.0).abs() < 0.02, "{u} vs {u_simple}");
        // Too short for the tau: no reading.
        assert!(relative_uncertainty(0, m, 1.0, 8.0 * m).is_none());
    }

    #[test]
    fn required_duration_meets_the_target_and_no_shorter_log_does() {
        // White noise N, a flat floor 0.664 B and a rate random walk K: the Allan variance has a
        // minimum where the floor dominates.
        let (nn, b, k) = (1e-3f64, 1e-4f64, 1e-6f64);
        let floor = (0.664 * b).powi(2);
        let total = |t: f64| nn * nn / t + floor + k * k * t / 3.0;
        let term = |_t: f64| floor;
        let curve = Curve {
            total: &total,
            term: &term,
        };
        let p = plan_term(
            PlanTerm::BiasInstability,
            &curve,
            0.01,
            0.1,
            Some(3600.0),
            1e6,
        );
        let tau = p.tau_s.expect("a minimum");
        // d/dtau (N^2/tau + K^2 tau/3) = 0 at tau = sqrt(3) N / K.
        let expected = 3f64.sqrt() * nn / k;
        assert!((tau / expected - 1.0).abs() < 0.06, "{tau} vs {expected}");
        let d = p.required_duration_s.unwrap();
        let n = d / 0.01;
        assert!(relative_uncertainty(-1, tau, 0.01, n).unwrap() <= 0.1);
        assert!(relative_uncertainty(-1, tau, 0.01, n * 0.99).is_none_or(|u| u > 0.1));
        // A 1 h log is shorter than 9 intervals of tau = 1732 s: it cannot read the minimum.
        assert!(p.uncertainty_at_duration.is_none() && p.note.is_some());
        // Without the random walk the curve has no minimum: the floor is read where it is 80 %
        // of the variance, N^2/tau = floor/4, tau = 4 N^2 / floor.
        let total_flat = |t: f64| nn * nn / t + floor;
        let flat = Curve {
            total: &total_flat,
            term: &term,
        };
        let p = plan_term(PlanTerm::BiasInstability, &flat, 0.01, 0.1, None, 1e5);
        let tau = p.tau_s.unwrap();
        assert!((tau / (4.0 * nn * nn / floor) - 1.0).abs() < 0.06, "{tau}");
        // White noise alone never lets a floor be read.
        let white = |t: f64| nn * nn / t;
        let none = |_t: f64| 0.0;
        let p = plan_term(
            PlanTerm::BiasInstability,
            &Curve {
                total: &white,
                term: &none,
            },
            0.01,
            0.1,
            None,
            1e5,
        );
        assert!(p.tau_s.is_none() && p.note.is_some());
    }
}
