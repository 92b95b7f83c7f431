//! Growth laws: the closed-form drift of each channel from its active error terms (docs/model.md §4:
//! 1-D, small angle, static level north-facing IMU, zero initial errors unless stated), built from
//! the noise crate's per-term functions (`noise::closed_form`, which owns the formulas).
//!
//! Coupling (static, level, north-facing; body forward-right-down = NED): a gyro error on body
//! axis x, y, z integrates into roll, pitch, yaw. An attitude error psi (nav-frame rotation vector)
//! turns the specific force (0, 0, -g) into (0, 0, -g) + psi x (0, 0, -g) = (-g psi_e, g psi_n, 0)
//! (docs/model.md §1.2: tilt projects g sin(eps) onto the horizontal), so roll error drives east and
//! pitch error drives north (negative sign); yaw has no first-order effect on a static IMU. An
//! accelerometer error on body x, y, z integrates into north, east, down velocity and position.
//! Independent terms add in variance; deterministic ones add in mean.

use crate::nav_quantity::NavQuantity;
use noise::closed_form::{self as cf, Integration};
use noise::LawSource;
use serde::{Deserialize, Serialize};
use strapdown::{Attitude, EarthModel};

/// Above this predicted attitude error (rad, rms) the small-angle laws are not printed
/// (sin(0.05) differs from 0.05 by 0.04 %, but second-order couplings of a 3-D attitude error
/// grow with the angle; 0.05 rad keeps them below ~2.5 %, inside a 2000-run interval).
pub const SMALL_ANGLE_LIMIT_RAD: f64 = 0.05;

/// Where an error enters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Entry {
    /// Gyro on body axis 0..3 (rad/s quantities).
    Gyro(usize),
    /// Accelerometer on body axis 0..3 (m/s^2 quantities).
    Accel(usize),
    /// Initial attitude error about axis 0..3 (roll, pitch, yaw; rad quantities).
    InitialAttitude(usize),
}

/// One active term: where it enters, what it is, and its docs/cli.md name (`gyro.white_noise`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Term {
    pub name: String,
    pub entry: Entry,
    pub source: LawSource,
}

/// Law of one channel at one time: signed mean and standard deviation, or why there is none.
/// `allowance`: the law's own stated relative uncertainty beyond the report's general ones (the
/// round Earth's bound on the products of errors the first-order model drops; 0 for the flat
/// closed forms), added to the interval of the simulated / law ratio.
#[derive(Debug, Clone, PartialEq)]
pub enum Law {
    Value { mean: f64, std: f64, allowance: f64 },
    NotApplicable(String),
}

impl Law {
    pub fn rms(&self) -> Option<f64> {
        match self {
            // A NaN mean marks "mean unknown" (mixed horizontal case): std then holds the rms.
            Law::Value { mean, std, .. } if mean.is_nan() => Some(*std),
            Law::Value { mean, std, .. } => Some(mean.hypot(*std)),
            Law::NotApplicable(_) => None,
        }
    }
}

/// Per-channel mean and variance contribution of one term through one integration path.
/// `folds` = 0 for the quantity itself (initial attitude error), 1, 2 or 3 (through tilt).
fn moments(source: &LawSource, t_s: f64, how: Option<Integration>) -> Result<(f64, f64), &str> {
    // A constant error seen without integration (an initial angle) is itself.
    let constant = |b: f64| how.map_or(b, |h| cf::constant_bias_growth(b, t_s, h));
    Ok(match source {
        LawSource::Bias(b) => (constant(*b), 0.0),
        LawSource::RandomConstant(s) => (0.0, constant(*s).powi(2)),
        LawSource::Ramp(r) => match how {
            Some(h) => (cf::rate_ramp_growth(*r, t_s, h), 0.0),
            None => return Err("a ramp needs an integration"),
        },
        LawSource::White(n) => match how {
            Some(h) => (0.0, cf::white_noise_growth_std(*n, t_s, h).powi(2)),
            None => return Err("white noise needs an integration"),
        },
        LawSource::RandomWalk(k) => match how {
            Some(h) => (0.0, cf::random_walk_growth_std(*k, t_s, h).powi(2)),
            None => return Err("a random walk needs an integration"),
        },
        LawSource::GaussMarkov { sigma, tc_s } => match how {
            Some(h) => (0.0, gauss_markov_variance(*sigma, *tc_s, t_s, h)),
            None => return Err("Gauss-Markov needs an integration"),
        },
        LawSource::GaussMarkovSum(parts) | LawSource::GaussMarkovSumFromStart(parts) => match how {
            Some(h) => {
                let law = if matches!(source, LawSource::GaussMarkovSum(_)) {
                    gauss_markov_variance
                } else {
                    gauss_markov_from_start_variance
                };
                (
                    0.0,
                    parts
                        .iter()
                        .map(|&(tc_s, sigma)| law(sigma, tc_s, t_s, h))
                        .sum(),
                )
            }
            None => return Err("Gauss-Markov needs an integration"),
        },
        LawSource::GaussMarkovSumFromWindow { parts, window_s } => match how {
            Some(h) => (
                0.0,
                parts
                    .iter()
                    .map(|&(tc_s, sigma)| {
                        gauss_markov_from_window_variance(sigma, tc_s, *window_s, t_s, h)
                    })
                    .sum(),
            ),
            None => return Err("Gauss-Markov needs an integration"),
        },
        LawSource::Sinusoid {
            amplitude,
            freq_hz,
            phase,
            sample_interval_s,
        } => match how {
            Some(h) => cf::sinusoid_growth_sampled(
                *amplitude,
                *freq_hz,
                *phase,
                t_s,
                *sample_interval_s,
                h,
            ),
            None => return Err("a sinusoid needs an integration"),
        },
        LawSource::Resonance {
            sigma,
            frequency_hz,
            bandwidth_hz,
        } => match how {
            Some(h) => (
                0.0,
                cf::resonance_kfold_variance(*sigma, *frequency_hz, *bandwidth_hz, t_s, h.folds())
                    .map_or(f64::NAN, |v| v * tilt_gain2(h)),
            ),
            None => return Err("a resonance needs an integration"),
        },
        LawSource::Transient {
            amplitude,
            tau_s,
            per_run,
        } => match how {
            Some(h) => {
                let v = cf::transient_growth(*amplitude, *tau_s, t_s, h);
                if *per_run {
                    (0.0, v * v)
                } else {
                    (v, 0.0)
                }
            }
            None => return Err("a transient needs an integration"),
        },
        LawSource::NoLaw(why) => return Err(why),
    })
}

/// Whether a term's contribution is random and not Gaussian (a sinusoid of random phase), so the
/// Rayleigh mean of a horizontal magnitude does not hold for it.
fn non_gaussian(source: &LawSource) -> bool {
    matches!(source, LawSource::Sinusoid { phase: None, .. })
}

/// The variance gain of an integration path: g^2 (standard gravity) through tilt, else 1.
fn tilt_gain2(how: Integration) -> f64 {
    let g0 = noise::units::STANDARD_GRAVITY_MPS2;
    if how == Integration::Tilt {
        g0 * g0
    } else {
        1.0
    }
}

/// Variance of the k-fold integral (k = `how.folds()`, times the tilt gain g^2 through tilt) of a
/// stationary Gauss-Markov process of std `sigma` and correlation time `tc_s`, at time `t_s`: the
/// noise crate's exact closed forms (`noise::closed_form::gauss_markov_kfold_variance`, which holds
/// for every t, where docs/model.md §4 gives the once-integrated form and the t >> T asymptotes).
pub fn gauss_markov_variance(sigma: f64, tc_s: f64, t_s: f64, how: Integration) -> f64 {
    let gain2 = tilt_gain2(how);
    cf::gauss_markov_kfold_variance(sigma, tc_s, t_s, how.folds()).map_or(f64::NAN, |v| v * gain2)
}

/// Variance of the k-fold integral (k = `how.folds()`, times g^2 through tilt) at time `t_s` of a
/// stationary Gauss-Markov process referenced to its value at t = 0 (the bias perfectly calibrated
/// at turn-on): `noise::closed_form::gauss_markov_kfold_from_start_variance`, where it is derived.
pub fn gauss_markov_from_start_variance(sigma: f64, tc_s: f64, t_s: f64, how: Integration) -> f64 {
    cf::gauss_markov_kfold_from_start_variance(sigma, tc_s, t_s, how.folds()) * tilt_gain2(how)
}

/// As [`gauss_markov_from_start_variance`] with the process referenced to its mean over a
/// calibration window of `window_s` before t = 0:
/// `noise::closed_form::gauss_markov_kfold_from_window_variance`, where it is derived.
pub fn gauss_markov_from_window_variance(
    sigma: f64,
    tc_s: f64,
    window_s: f64,
    t_s: f64,
    how: Integration,
) -> f64 {
    cf::gauss_markov_kfold_from_window_variance(sigma, tc_s, window_s, t_s, how.folds())
        * tilt_gain2(how)
}

/// The single-axis channels an entry drives, each with (channel, integration, sign x gain factor).
/// The tilt gain g is inside `Integration::Tilt` (standard gravity); `g_scale` rescales it for a
/// scenario gravity other than standard; for initial attitude the tilt acts as an accelerometer bias
/// g sin(eps) (docs/model.md §1.2), integrated once and twice.
fn paths(entry: Entry, gravity_mps2: f64) -> Vec<(NavQuantity, Option<Integration>, f64)> {
    use NavQuantity::*;
    let g_scale = gravity_mps2 / noise::units::STANDARD_GRAVITY_MPS2;
    // roll error drives east (+g), pitch error drives north (-g); yaw nothing at first order.
    let tilt = |axis: usize| -> Option<(NavQuantity, NavQuantity, f64)> {
        match axis {
            0 => Some((VelEast, PosEast, 1.0)),
            1 => Some((VelNorth, PosNorth, -1.0)),
            _ => None,
        }
    };
    let angle = [Roll, Pitch, Yaw];
    match entry {
        Entry::Gyro(a) => {
            let mut v = vec![(angle[a], Some(Integration::Once), 1.0)];
            if let Some((vel, pos, sign)) = tilt(a) {
                // velocity through tilt = g x (angle integrated twice); position = Integration::Tilt.
                v.push((vel, Some(Integration::Twice), sign * gravity_mps2));
                v.push((pos, Some(Integration::Tilt), sign * g_scale));
            }
            v
        }
        Entry::Accel(a) => {
            let (vel, pos) = [(VelNorth, PosNorth), (VelEast, PosEast), (VelDown, PosDown)][a];
            vec![
                (vel, Some(Integration::Once), 1.0),
                (pos, Some(Integration::Twice), 1.0),
            ]
        }
        Entry::InitialAttitude(a) => {
            let mut v = vec![(angle[a], None, 1.0)];
            if let Some((vel, pos, sign)) = tilt(a) {
                v.push((vel, Some(Integration::Once), sign * gravity_mps2));
                v.push((pos, Some(Integration::Twice), sign * gravity_mps2));
            }
            v
        }
    }
}

/// Conditions under which the laws hold, known from the scenario.
#[derive(Debug, Clone, PartialEq)]
pub struct LawContext {
    /// Static, level and north-facing. Otherwise every law is "not applicable", except:
    pub static_level: bool,
    /// Rotation at a constant rate about body z from level: the yaw channel keeps the laws of the z
    /// gyro terms (rotations about one axis commute), the other channels have none.
    pub yaw_rate_rad_s: Option<f64>,
    /// Why the scenario is outside the laws, if it is (e.g. "motion").
    pub reason: String,
    pub gravity_mps2: f64,
    /// The Earth of the scenario: the flat one's closed forms, or the round one's error model
    /// (`earth_laws::round_laws`), which holds for a static IMU at any `attitude`.
    pub earth: EarthModel,
    /// The static IMU's attitude (identity when it moves).
    pub attitude: Attitude,
}

/// The laws of every channel at time `t_s` outside the static level case: none, but the yaw law
/// of the z gyro terms under a constant rate about body z (`LawContext::yaw_rate_rad_s`).
fn laws_in_motion(terms: &[Term], ctx: &LawContext, t_s: f64) -> Vec<Law> {
    let why = format!("no closed-form law: {}", ctx.reason);
    let mut laws: Vec<Law> = NavQuantity::ALL
        .iter()
        .map(|_| Law::NotApplicable(why.clone()))
        .collect();
    if ctx.yaw_rate_rad_s.is_some() {
        let static_ctx = LawContext {
            static_level: true,
            yaw_rate_rad_s: None,
            ..ctx.clone()
        };
        let yaw_terms: Vec<Term> = terms
            .iter()
            .filter(|t| matches!(t.entry, Entry::Gyro(2) | Entry::InitialAttitude(2)))
            .cloned()
            .collect();
        let yaw = NavQuantity::Yaw as usize;
        laws[yaw] = channel_laws(&yaw_terms, &static_ctx, t_s).swap_remove(yaw);
    }
    laws
}

/// The vertical channels' law is first order; a tilt eps adds g (1 - cos eps) ~ g eps^2/2 to the
/// vertical specific force (docs/model.md §1.2). Bound its effect with the final tilt mean square
/// `tilt_ms` (tilt grows with t, so this overestimates) and withhold the law where it exceeds 10 %
/// of it.
fn withhold_incomplete_vertical(laws: &mut [Law], tilt_ms: f64, gravity_mps2: f64, t_s: f64) {
    let second_order = gravity_mps2 * tilt_ms / 2.0;
    for (ch, growth) in [
        (NavQuantity::VelDown, t_s),
        (NavQuantity::PosDown, t_s * t_s / 2.0),
    ] {
        let i = ch as usize;
        if let Some(first) = laws[i].rms() {
            let bound = second_order * growth;
            if bound > 0.1 * first {
                laws[i] = Law::NotApplicable(format!(
                    "first-order law incomplete: the second-order tilt term g(1-cos eps) (docs/model.md §1.2) may reach {bound:.3e}, over 10 % of the law {first:.3e}"
                ));
            }
        }
    }
}

/// The laws of every channel at time `t_s`, in [`NavQuantity::ALL`] order.
pub fn channel_laws(terms: &[Term], ctx: &LawContext, t_s: f64) -> Vec<Law> {
    if !ctx.static_level {
        return laws_in_motion(terms, ctx, t_s);
    }
    let n = NavQuantity::ALL.len();
    let mut mean = vec![0.0f64; n];
    let mut var = vec![0.0f64; n];
    let mut missing: Vec<Option<String>> = vec![None; n];
    let mut not_gaussian = vec![false; n];
    for term in terms {
        for (ch, how, factor) in paths(term.entry, ctx.gravity_mps2) {
            let i = ch as usize;
            match moments(&term.source, t_s, how) {
                Ok((m, v)) => {
                    mean[i] += factor * m;
                    var[i] += factor * factor * v;
                    not_gaussian[i] |= v > 0.0 && non_gaussian(&term.source);
                }
                Err(why) => {
                    missing[i].get_or_insert_with(|| format!("{}: {why}", term.name));
                }
            }
        }
    }
    // Small-angle check on the predicted attitude error of the three angle channels.
    let worst_angle = [NavQuantity::Roll, NavQuantity::Pitch, NavQuantity::Yaw]
        .iter()
        .map(|&c| mean[c as usize].hypot(var[c as usize].sqrt()))
        .fold(0.0, f64::max);
    let large = worst_angle > SMALL_ANGLE_LIMIT_RAD;
    // An attitude error without a law couples into every velocity and position channel at second
    // order (g (1 - cos eps) vertically, docs/model.md §1.2), so those channels have no law either.
    let angle_missing = [NavQuantity::Roll, NavQuantity::Pitch, NavQuantity::Yaw]
        .iter()
        .find_map(|&c| missing[c as usize].clone());
    let single = |i: usize| -> Law {
        let is_angle = i <= NavQuantity::Yaw as usize;
        if let Some(why) = missing[i].as_ref().or(if is_angle {
            None
        } else {
            angle_missing.as_ref()
        }) {
            Law::NotApplicable(format!("no closed-form law ({why})"))
        } else if large {
            Law::NotApplicable(format!(
                "small-angle law does not apply: predicted attitude error {worst_angle:.3} rad > {SMALL_ANGLE_LIMIT_RAD} rad"
            ))
        } else {
            Law::Value {
                mean: mean[i],
                std: var[i].sqrt(),
                allowance: 0.0,
            }
        }
    };
    let mut laws: Vec<Law> = (0..n).map(single).collect();
    let tilt_ms: f64 = [NavQuantity::Roll, NavQuantity::Pitch]
        .iter()
        .map(|&c| mean[c as usize].powi(2) + var[c as usize])
        .sum();
    withhold_incomplete_vertical(&mut laws, tilt_ms, ctx.gravity_mps2, t_s);
    for (h, a, b) in [
        (
            NavQuantity::PosHorizontal,
            NavQuantity::PosNorth,
            NavQuantity::PosEast,
        ),
        (
            NavQuantity::VelHorizontal,
            NavQuantity::VelNorth,
            NavQuantity::VelEast,
        ),
    ] {
        let gaussian = !not_gaussian[a as usize] && !not_gaussian[b as usize];
        laws[h as usize] = horizontal_law(&laws[a as usize], &laws[b as usize], gaussian);
    }
    laws
}

/// Law of the horizontal magnitude sqrt(n^2 + e^2) of two independent Gaussian components.
/// rms^2 = (m_n^2 + s_n^2) + (m_e^2 + s_e^2) always. The mean: deterministic components give the
/// magnitude itself; zero-mean components give, writing (n, e) = (s_n R cos th, s_e R sin th) with R
/// Rayleigh (E R = sqrt(pi/2)) and th uniform, E|h| = sqrt(pi/2) (1/2pi) int sqrt(s_n^2 cos^2 + s_e^2 sin^2)
/// d th, which for s_n = s_e = s is the Rayleigh mean s sqrt(pi/2) (docs/model.md §4). Mixed cases,
/// and random components that are not Gaussian (`gaussian = false`: a random-phase sinusoid),
/// report only the rms (mean = NaN marks "mean unknown").
fn horizontal_law(north: &Law, east: &Law, gaussian: bool) -> Law {
    let (
        Law::Value {
            mean: mn, std: sn, ..
        },
        Law::Value {
            mean: me, std: se, ..
        },
    ) = (north, east)
    else {
        let why = [north, east]
            .iter()
            .find_map(|l| match l {
                Law::NotApplicable(w) => Some(w.clone()),
                _ => None,
            })
            .unwrap_or_default();
        return Law::NotApplicable(why);
    };
    horizontal_magnitude([*mn, *me], [*sn, *se], 0.0, gaussian)
}

/// The law of the horizontal magnitude of Gaussian components of means `mean`, standard
/// deviations `std` and covariance `cross` (0 on the flat Earth, where the channels are
/// independent; the rotating Earth couples them): rms^2 = m_n^2 + s_n^2 + m_e^2 + s_e^2 always; the
/// mean |mean| for deterministic components, the Rayleigh-type mean of the covariance's principal
/// axes for zero-mean Gaussian ones ([`horizontal_rayleigh_mean`]; the axes are the channels when
/// `cross` is 0), else unknown (NaN).
pub(crate) fn horizontal_magnitude(
    mean: [f64; 2],
    std: [f64; 2],
    cross: f64,
    gaussian: bool,
) -> Law {
    let ([mn, me], [sn, se]) = (mean, std);
    let rms2 = mn * mn + sn * sn + me * me + se * se;
    let mean = if sn == 0.0 && se == 0.0 {
        mn.hypot(me)
    } else if mn == 0.0 && me == 0.0 && gaussian {
        if cross == 0.0 {
            horizontal_rayleigh_mean(sn, se)
        } else {
            let eig =
                nalgebra::Matrix2::new(sn * sn, cross, cross, se * se).symmetric_eigenvalues();
            horizontal_rayleigh_mean(eig[0].max(0.0).sqrt(), eig[1].max(0.0).sqrt())
        }
    } else {
        return Law::Value {
            mean: f64::NAN,
            std: rms2.sqrt(),
            allowance: 0.0,
        };
    };
    Law::Value {
        allowance: 0.0,
        mean,
        // Rounding can make the difference slightly negative; NaN must stay NaN.
        std: {
            let var = rms2 - mean * mean;
            if var.is_nan() {
                f64::NAN
            } else {
                var.max(0.0).sqrt()
            }
        },
    }
}

/// E sqrt(X^2 + Y^2) for independent zero-mean Gaussians with std `sn`, `se` (see
/// `horizontal_law`); the angular average by the midpoint rule over a full period, which is
/// spectrally accurate for a smooth periodic integrand (4096 points: error far below 1e-12; second
/// order, ~1e-7, in the degenerate case of one zero std).
pub fn horizontal_rayleigh_mean(sn: f64, se: f64) -> f64 {
    const POINTS: usize = 4096;
    let avg = (0..POINTS)
        .map(|i| {
            let th = std::f64::consts::TAU * (i as f64 + 0.5) / POINTS as f64;
            (sn * sn * th.cos().powi(2) + se * se * th.sin().powi(2)).sqrt()
        })
        .sum::<f64>()
        / POINTS as f64;
    (std::f64::consts::PI / 2.0).sqrt() * avg
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ctx() -> LawContext {
        LawContext {
            static_level: true,
            yaw_rate_rad_s: None,
            reason: String::new(),
            gravity_mps2: 9.80665,
            earth: EarthModel::Flat {
                gravity_mps2: 9.80665,
            },
            attitude: Attitude::identity(),
        }
    }

    #[test]
    fn rayleigh_mean_for_equal_axes() {
        let m = horizontal_rayleigh_mean(2.0, 2.0);
        assert!((m - 2.0 * (std::f64::consts::PI / 2.0).sqrt()).abs() < 1e-12);
        // One axis only: E|X| = s sqrt(2/pi).
        // |cos| has kinks, so the midpoint rule is only second order here: 1e-6 relative.
        let m = horizontal_rayleigh_mean(3.0, 0.0);
        assert!((m / (3.0 * (2.0 / std::f64::consts::PI).sqrt()) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn woodman_white_noise_mean_matches_theory_note() {
        // docs/model.md §1.4: MTx Table-4 ARWs, white noise only, 60 s: analytic Rayleigh mean 102.4 m.
        let arw = [0.075f64, 0.078, 0.079].map(|d| d.to_radians());
        let terms: Vec<Term> = (0..3)
            .map(|a| Term {
                name: "gyro.white_noise".into(),
                entry: Entry::Gyro(a),
                source: LawSource::White(arw[a]),
            })
            .collect();
        let laws = channel_laws(&terms, &ctx(), 60.0);
        let Law::Value { mean, .. } = laws[NavQuantity::PosHorizontal as usize] else {
            panic!()
        };
        // The note rounds to 0.1 m.
        assert!((mean - 102.4).abs() < 0.1, "{mean}");
    }

    /// Independent numerical check of the closed forms: by Cauchy's formula for repeated
    /// integration I_k(t) = int_0^t w(u) x(u) du with w(u) = (t-u)^{k-1}/(k-1)!, so
    /// Var I_k = 2 int_0^t R(s) g(s) ds with R(s) = sigma^2 e^{-|s|/T} and g(s) = int_0^{t-s} w(a+s) w(a) da
    /// (a polynomial, integrated exactly); the outer integral by composite Gauss-Legendre on panels
    /// graded with T.
    fn quadrature_variance(sigma: f64, tc_s: f64, t_s: f64, how: Integration) -> f64 {
        let k = how.folds() as usize;
        // Through tilt the angle drives g theta (Integration::Tilt's gain, standard gravity).
        let g0 = noise::units::STANDARD_GRAVITY_MPS2;
        let gain2 = if how == Integration::Tilt {
            g0 * g0
        } else {
            1.0
        };
        let fact = |n: usize| (1..=n).map(|i| i as f64).product::<f64>();
        let binom = |n: usize, j: usize| fact(n) / (fact(j) * fact(n - j));
        // g(s) = 1/((k-1)!)^2 sum_j C(k-1, j) s^{k-1-j} L^{j+k}/(j+k), L = t - s.
        let g = |s: f64| -> f64 {
            let l = t_s - s;
            (0..k)
                .map(|j| {
                    binom(k - 1, j) * s.powi((k - 1 - j) as i32) * l.powi((j + k) as i32)
                        / (j + k) as f64
                })
                .sum::<f64>()
                / fact(k - 1).powi(2)
        };
        // Composite Gauss-Legendre on panels graded with T (0, T/8, T/4, ..., then t), so both the
        // exponential scale and the polynomial scale are resolved.
        let (nodes, weights) = gauss_legendre(GL_POINTS);
        let edges = graded_edges(tc_s, t_s);
        let mut total = 0.0;
        for w in edges.windows(2) {
            let (a, b) = (w[0], w[1]);
            let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
            total += half
                * nodes
                    .iter()
                    .zip(&weights)
                    .map(|(&x, &wt)| {
                        let s = mid + half * x;
                        wt * (-s / tc_s).exp() * g(s)
                    })
                    .sum::<f64>();
        }
        2.0 * sigma * sigma * total * gain2
    }

    /// Quadrature panel edges 0, T/8, T/4, T/2, ... (doubling), then t.
    fn graded_edges(tc_s: f64, t_s: f64) -> Vec<f64> {
        let mut edges = vec![0.0];
        let mut e = tc_s / 8.0;
        while e < t_s {
            edges.push(e);
            e *= 2.0;
        }
        edges.push(t_s);
        edges
    }

    /// Gauss-Legendre points per panel: exact for polynomials of degree 2 GL_POINTS - 1 = 39.
    const GL_POINTS: usize = 20;

    /// Gauss-Legendre nodes and weights on [-1, 1] by Newton iteration on P_n (Golub-Welsch's
    /// classical alternative; Abramowitz & Stegun 25.4.29 for the weights 2/((1-x^2) P_n'(x)^2)).
    fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
        let mut nodes = vec![0.0; n];
        let mut weights = vec![0.0; n];
        for i in 0..n.div_ceil(2) {
            let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            let mut dp = 1.0;
            for _ in 0..100 {
                // Bonnet's recursion for P_n(x) and its derivative.
                let (mut p0, mut p1) = (1.0, x);
                for m in 2..=n {
                    let p2 = ((2 * m - 1) as f64 * x * p1 - (m - 1) as f64 * p0) / m as f64;
                    p0 = p1;
                    p1 = p2;
                }
                dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
                let dx = p1 / dp;
                x -= dx;
                if dx.abs() < 1e-16 {
                    break;
                }
            }
            nodes[i] = -x;
            nodes[n - 1 - i] = x;
            let w = 2.0 / ((1.0 - x * x) * dp * dp);
            weights[i] = w;
            weights[n - 1 - i] = w;
        }
        (nodes, weights)
    }

    /// Independent 2-D quadrature of the referenced process's variance:
    /// Var I_k[x](t) = 2 int_0^t int_0^s w(s) w(u) C(s, u) du ds (u < s, by symmetry), with
    /// w(u) = (t-u)^{k-1}/(k-1)! and C(s, u) = sigma^2 (e^{-(s-u)/T} - e^{-s/T} - e^{-u/T} + 1)
    /// = sigma^2 (1 - e^{-u/T}) (1 + e^{-(s-u)/T}) (factored, so nothing cancels for s, u << T);
    /// composite Gauss-Legendre on panels graded with T in both variables.
    fn quadrature_from_start_variance(sigma: f64, tc_s: f64, t_s: f64, how: Integration) -> f64 {
        let k = how.folds();
        let gain2 = tilt_gain2(how);
        let fact = (1..k).map(f64::from).product::<f64>();
        let w = |u: f64| (t_s - u).powi(k - 1) / fact;
        let (nodes, weights) = gauss_legendre(GL_POINTS);
        let edges = graded_edges(tc_s, t_s);
        // int_0^upper f(u) du over the graded panels clipped to [0, upper].
        let integrate = |upper: f64, f: &dyn Fn(f64) -> f64| -> f64 {
            let mut total = 0.0;
            for p in edges.windows(2) {
                let (a, b) = (p[0], p[1].min(upper));
                if b <= a {
                    break;
                }
                let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
                total += half
                    * nodes
                        .iter()
                        .zip(&weights)
                        .map(|(&x, &wt)| wt * f(mid + half * x))
                        .sum::<f64>();
            }
            total
        };
        // The e^{-(s-u)/T} part varies on the scale T near u = s: integrate it in v = s - u, so
        // the graded panels resolve it.
        let c0 = |u: f64| -(-u / tc_s).exp_m1();
        let outer = integrate(t_s, &|s: f64| {
            w(s) * (integrate(s, &|u: f64| w(u) * c0(u))
                + integrate(s, &|v: f64| w(s - v) * c0(s - v) * (-v / tc_s).exp()))
        });
        2.0 * sigma * sigma * outer * gain2
    }

    /// int_0^upper f over panels graded with T (0, T/8, T/4, ..., upper), Gauss-Legendre on each.
    fn graded_integral(tc_s: f64, upper: f64, f: impl Fn(f64) -> f64) -> f64 {
        let (nodes, weights) = gauss_legendre(GL_POINTS);
        graded_edges(tc_s, upper)
            .windows(2)
            .map(|p| {
                let (mid, half) = (0.5 * (p[0] + p[1]), 0.5 * (p[1] - p[0]));
                half * nodes
                    .iter()
                    .zip(&weights)
                    .map(|(&x, &wt)| wt * f(mid + half * x))
                    .sum::<f64>()
            })
            .sum()
    }

    /// Independent quadrature of the window-referenced variance. x = b - m has covariance
    /// C_x(s, u) = C_start(s, u) + sigma^2 [(1 - rho)(e^{-s/T} + e^{-u/T}) + vm - 1] with
    /// C_start that of b - b(0) (`quadrature_from_start_variance`, 2-D), rho = Cov(m, b(0))/sigma^2
    /// and vm = Var(m)/sigma^2 themselves by quadrature over the window
    /// (rho = (1/W) int_0^W e^{-v/T} dv, vm = (2/W^2) int_0^W (W - v) e^{-v/T} dv), so with
    /// w(u) = (t-u)^{k-1}/(k-1)!, int_0^t w = a = t^k/k!:
    ///   Var I_k[x] = Var I_k[b - b(0)] + sigma^2 [2 (1 - rho) a int_0^t w(s) e^{-s/T} ds + (vm - 1) a^2].
    fn quadrature_from_window_variance(
        sigma: f64,
        tc_s: f64,
        window_s: f64,
        t_s: f64,
        how: Integration,
    ) -> f64 {
        let k = how.folds();
        let fact = (1..k).map(f64::from).product::<f64>();
        let a = t_s.powi(k) / (fact * f64::from(k));
        let rho = graded_integral(tc_s, window_s, |v| (-v / tc_s).exp()) / window_s;
        let vm = 2.0 * graded_integral(tc_s, window_s, |v| (window_s - v) * (-v / tc_s).exp())
            / (window_s * window_s);
        let jw = graded_integral(tc_s, t_s, |u| {
            (t_s - u).powi(k - 1) / fact * (-u / tc_s).exp()
        });
        quadrature_from_start_variance(sigma, tc_s, t_s, how)
            + sigma * sigma * (2.0 * (1.0 - rho) * a * jw + (vm - 1.0) * a * a) * tilt_gain2(how)
    }

    #[test]
    fn gauss_markov_from_window_matches_quadrature_and_its_limits() {
        for &(sigma, tc) in &[(0.3, 2.0), (1e-4, 600.0), (2e-5, 1e5), (1e-3, 0.1)] {
            for &w in &[0.5, 10.0, 60.0] {
                for &t in &[
                    0.01,
                    0.7,
                    0.99 * tc / 2.0,
                    1.01 * tc / 2.0,
                    9.0,
                    60.0,
                    3600.0,
                ] {
                    for how in [Integration::Once, Integration::Twice, Integration::Tilt] {
                        let a = gauss_markov_from_window_variance(sigma, tc, w, t, how);
                        let b = quadrature_from_window_variance(sigma, tc, w, t, how);
                        // Relative 1e-7: the closed form loses at most ~4 digits (above x = 0.5
                        // as the from-start form), the quadrature ~3 where its parts cancel
                        // (t, W >> T, the parts ~a^2, the sum ~a^2 T/W).
                        assert!(
                            (a / b - 1.0).abs() < 1e-7,
                            "{how:?} t={t} T={tc} W={w}: {a} vs {b}"
                        );
                    }
                }
            }
            // W -> 0: the from-start law; W >> T, t: the uncalibrated law plus Var(m) a^2, m ~ 0.
            for how in [Integration::Once, Integration::Twice, Integration::Tilt] {
                let t = 0.3 * tc;
                let a = gauss_markov_from_window_variance(sigma, tc, 1e-9 * tc, t, how);
                let b = gauss_markov_from_start_variance(sigma, tc, t, how);
                assert!((a / b - 1.0).abs() < 1e-6, "{how:?} T={tc}: {a} vs {b}");
                let a = gauss_markov_from_window_variance(sigma, tc, 1e9 * tc, t, how);
                let b = gauss_markov_variance(sigma, tc, t, how);
                assert!((a / b - 1.0).abs() < 1e-6, "{how:?} T={tc}: {a} vs {b}");
            }
        }
    }

    #[test]
    fn gauss_markov_from_start_matches_quadrature_and_random_walk_limit() {
        for &(sigma, tc) in &[(0.3, 2.0), (1e-4, 600.0), (2e-5, 1e5)] {
            for &t in &[
                0.01,
                0.7,
                0.99 * tc / 2.0,
                1.01 * tc / 2.0,
                2.0,
                9.0,
                60.0,
                3600.0,
            ] {
                for how in [Integration::Once, Integration::Twice, Integration::Tilt] {
                    let a = gauss_markov_from_start_variance(sigma, tc, t, how);
                    let b = quadrature_from_start_variance(sigma, tc, t, how);
                    // Relative 1e-8: the quadrature is far more accurate; the closed form
                    // loses at most ~4 digits to cancellation just above the switch x = 0.5.
                    assert!(
                        (a / b - 1.0).abs() < 1e-8,
                        "{how:?} t={t} T={tc}: {a} vs {b}"
                    );
                }
            }
            // t << T: b(t) - b(0) is a random walk of density K^2 = 2 sigma^2/T, to O(t/T).
            let t = 1e-5 * tc;
            let k = (2.0 * sigma * sigma / tc).sqrt();
            for how in [Integration::Once, Integration::Twice, Integration::Tilt] {
                let rw = cf::random_walk_growth_std(k, t, how).powi(2);
                let a = gauss_markov_from_start_variance(sigma, tc, t, how);
                assert!((a / rw - 1.0).abs() < 1e-4, "{how:?}: {a} vs {rw}");
            }
        }
    }

    #[test]
    fn gauss_markov_closed_forms_match_quadrature() {
        for &(sigma, tc) in &[(0.3, 2.0), (1e-4, 600.0)] {
            for &t in &[0.01, 0.7, 2.0, 9.0, 60.0, 3600.0] {
                for how in [Integration::Once, Integration::Twice, Integration::Tilt] {
                    let a = gauss_markov_variance(sigma, tc, t, how);
                    let b = quadrature_variance(sigma, tc, t, how);
                    // Relative 1e-9: quadrature error far below, rounding of the closed forms'
                    // cancellation (series below t/T = 0.5) of that order.
                    assert!(
                        (a / b - 1.0).abs() < 1e-9,
                        "{how:?} t={t} T={tc}: {a} vs {b}"
                    );
                }
            }
        }
    }

    #[test]
    fn gauss_markov_law_matches_exact_form_and_both_asymptotes() {
        let (sigma, tc) = (0.3, 2.0);
        let g = 9.80665;
        // Once: the closed form itself.
        for &t in &[0.01, 1.0, 5.0, 100.0] {
            let exact = cf::gauss_markov_growth_std(sigma, tc, t, Integration::Once)
                .unwrap()
                .powi(2);
            assert!(
                (gauss_markov_variance(sigma, tc, t, Integration::Once) / exact - 1.0).abs()
                    < 1e-12
            );
        }
        // t >> T: docs/model.md §4 asymptotes 2 sigma^2 T t^3/3 and g^2 2 sigma^2 T t^5/20; the
        // relative correction is O(T/t), so at t = 1e5 T agreement to 1e-4 (k = 2, 3 leading terms).
        let t = 1e5 * tc;
        let a2 = cf::gauss_markov_growth_std(sigma, tc, t, Integration::Twice)
            .unwrap()
            .powi(2);
        let a3 = cf::gauss_markov_growth_std(sigma, tc, t, Integration::Tilt)
            .unwrap()
            .powi(2);
        assert!((gauss_markov_variance(sigma, tc, t, Integration::Twice) / a2 - 1.0).abs() < 1e-4);
        assert!((gauss_markov_variance(sigma, tc, t, Integration::Tilt) / a3 - 1.0).abs() < 1e-4);
        // t << T: a random constant of std sigma: sigma t^2/2 and g sigma t^3/6, to O(t/T).
        let t = 1e-5 * tc;
        let c2 = (sigma * t * t / 2.0).powi(2);
        let c3 = (g * sigma * t.powi(3) / 6.0).powi(2);
        assert!((gauss_markov_variance(sigma, tc, t, Integration::Twice) / c2 - 1.0).abs() < 1e-4);
        assert!((gauss_markov_variance(sigma, tc, t, Integration::Tilt) / c3 - 1.0).abs() < 1e-4);
    }

    #[test]
    fn gauss_legendre_integrates_polynomials_exactly() {
        let (x, w) = gauss_legendre(GL_POINTS);
        for p in 0..(2 * GL_POINTS as i32) {
            let num: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(p)).sum();
            let exact = if p % 2 == 1 {
                0.0
            } else {
                2.0 / (p + 1) as f64
            };
            assert!((num - exact).abs() < 1e-13, "degree {p}: {num} vs {exact}");
        }
    }

    #[test]
    fn bias_signs_and_no_law_cases() {
        let b = 1e-4;
        let terms = vec![Term {
            name: "gyro.constant_bias".into(),
            entry: Entry::Gyro(1),
            source: LawSource::Bias(b),
        }];
        let laws = channel_laws(&terms, &ctx(), 10.0);
        let Law::Value { mean, std, .. } = laws[NavQuantity::PosNorth as usize] else {
            panic!()
        };
        assert_eq!(std, 0.0);
        assert!((mean + 9.80665 * b * 1000.0 / 6.0).abs() < 1e-12);
        let Law::Value { mean, .. } = laws[NavQuantity::Pitch as usize] else {
            panic!()
        };
        assert!((mean - b * 10.0).abs() < 1e-15);
        // Flicker: no law on pitch, north, horizontal; roll unaffected.
        let terms = vec![Term {
            name: "gyro.bias_instability".into(),
            entry: Entry::Gyro(1),
            source: LawSource::NoLaw("flicker".into()),
        }];
        let laws = channel_laws(&terms, &ctx(), 10.0);
        assert!(matches!(
            laws[NavQuantity::PosHorizontal as usize],
            Law::NotApplicable(_)
        ));
        assert_eq!(
            laws[NavQuantity::Roll as usize],
            Law::Value {
                mean: 0.0,
                std: 0.0,
                allowance: 0.0
            }
        );
        // Large angle.
        let terms = vec![Term {
            name: "gyro.constant_bias".into(),
            entry: Entry::Gyro(2),
            source: LawSource::Bias(0.01),
        }];
        assert!(matches!(
            channel_laws(&terms, &ctx(), 10.0)[0],
            Law::NotApplicable(_)
        ));
    }
}
