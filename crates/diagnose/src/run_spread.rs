//! Run-to-run variation estimated from several runs (docs/diagnose.md, "Runs that differ"; the
//! model's side is docs/model.md §2.3): does a channel's slow wander change from one power-on to
//! the next by more than the runs' own sampling allows, and by how much?
//!
//! Per channel and group: the slow group (the terms that shape drift at long horizons,
//! `Effect::is_long_term`, that a static log shows and that have a level above 0; Gauss-Markov
//! processes of 1 s and more), and the short group (the white noise, which sets the drift at
//! short horizons: a run's angle or velocity random walk). The two are estimated apart, as the
//! model draws them apart (docs/model.md §2.3: one draw per axis for the long-term terms, another
//! for the short-term ones):
//! 1. **Per-run multiplier.** Each run's overlapping Allan variances a_ri on an octave grid are
//!    fitted as rest_i + q_r slow_i + q'_r other_i, slow the group's Allan variance at its pooled
//!    levels, other the channel's other group's (fitted jointly, so that a run whose wander is
//!    high is not read as a high white noise where the two overlap) and rest the channel's other
//!    terms held at the pooled fit (IEEE 952 Annex C: independent terms add), by weighted least
//!    squares with the weights of `bootstrap.rs`, w_i = nu_i / (2 A_i^2) (NIST SP 1065 §5.2, nu
//!    Greenhall's EDF for the local slope): the 2 x 2 normal equations, q and q' held at 1e-2 or
//!    above (the other refitted where one is held); ln m_r = ln(q_r) / 2 is the log of run r's
//!    group level relative to the pooled one. The grid starts at 8 coarse samples (below), so a
//!    white-noise multiplier is the white level seen at 0.64 s and beyond at 100 Hz: the level
//!    that sets the drift at the horizons of a few seconds and more.
//! 2. **Statistic.** V = the sample variance of ln m_r over the R runs.
//! 3. **Null.** V of R simulated runs of the same lengths from the pooled model with no spread,
//!    `NULL_REPLICATES` times, the same estimator. To keep within the budget the null runs are
//!    simulated at D = 8 times the sample interval (power-of-two decimation, about 10 Hz for a
//!    100 Hz log) without output filters and without tones above the coarser Nyquist frequency,
//!    and the grid starts at 8 coarse samples (0.64 s at 100 Hz): the Allan variance at tau is the
//!    variance of differences of tau-averages, which the finer samples do not change beyond the
//!    terms dropped (the filter acts at the shortest taus, the tones dropped add at most their
//!    sampled Allan variance, which both estimators take from their own model), and the estimator
//!    of each (the measured runs' and the null's) uses its own model's curves, so each is unbiased
//!    for its own data. p_mc = (1 + #{V_null >= V}) / (B + 1) (Davison & Hinkley 1997, §4.2.5).
//! 4. **Estimate and interval.** Under a spread s, ln m_r = s z_r - s^2 + e_r with e_r the
//!    estimation error, so V ~ (s^2 + sigma_e^2) chi2_{R-1} / (R - 1) for Gaussian parts, and
//!    sigma_e^2 is the null's mean V. s^2 = max(0, V - sigma_e^2) (method of moments, the
//!    random-effects estimator of DerSimonian & Laird 1986, Controlled Clinical Trials 7, 177-188,
//!    with the within-run variance from the null), and the 95 % interval inverts the chi-square
//!    test over s: s^2 in [(R-1) V / chi2_{0.975} - sigma_e^2, (R-1) V / chi2_{0.025} - sigma_e^2],
//!    clamped at 0. p_chi2 = P(chi2_{R-1} >= (R-1) V / sigma_e^2) at s = 0.
//! 5. **Naming.** The spread is named (the claim that the runs differ) when p_chi2 <= `NAMING_ALPHA`, the naming rule's false-alarm rate per channel
//!    (about 1e-3 per clean 6-channel log, docs/diagnose.md step 4), and the measured V is above
//!    every null replicate (p_mc at its floor): the same false-alarm rate as the other effects,
//!    from this test's own null. The chi-square form's calibration against the null replicates is
//!    reported (`null_over_chi2_90`: the share of null V beyond the scaled chi-square's 90 %
//!    point, 0.10 when it holds).
//! 6. **Into the model.** Every estimate above 0, named or not, is written into the corrected
//!    model as `run_to_run` on its group ([`with_estimated_spreads`]): what a next run's band
//!    needs is the best estimate of the spread, not the verdict of a test that it is not 0.

use crate::bootstrap::{edf_at, local_slope};
use crate::fitted_on::SpreadFit;
use crate::input::LogInput;
use crate::simulate::{adev_at, map_static_logs, LogJob, SimSetup};
use noise::{AxisModel, Channel, Effect, ImuChannels, SensorModel};
use serde::Serialize;
use std::sync::atomic::AtomicBool;

/// Null replicates (sets of R simulated runs).
pub const NULL_REPLICATES: usize = 100;
/// The naming rule's false-alarm rate per channel: ~1e-3 per clean 6-channel log.
pub const NAMING_ALPHA: f64 = 1e-3 / 6.0;
/// The smallest squared multiplier a run is given (ln m >= -2.3: a run whose group is too weak
/// to show is held at a tenth of the pooled level rather than sent to minus infinity).
const Q_MIN: f64 = 1e-2;
/// The first run index of the null's simulated runs (apart from every other simulation of
/// `diagnose`, whose runs count up from 0).
const NULL_FIRST_RUN: u64 = 1 << 40;
/// The shortest averaging factor of the grid, in coarse (null) samples.
const M_MIN: usize = 8;

/// The estimate of one channel and group (JSON `run_to_run[]`, docs/cli.md).
#[derive(Clone, Debug, Serialize)]
pub struct RunSpread {
    pub channel: Channel,
    /// "long" (the slow group) or "short" (the white noise).
    pub group: &'static str,
    /// The group's terms, whose levels move together between runs.
    pub effects: Vec<&'static str>,
    /// ln m_r per run, in input order.
    pub ln_multipliers: Vec<f64>,
    /// V, the sample variance of the ln m_r.
    pub variance: f64,
    /// sigma_e^2: the null's mean V (the runs' sampling part).
    pub null_variance: f64,
    pub null_replicates: usize,
    /// The share of null V beyond the scaled chi-square's 90 % point (0.10 if it holds).
    pub null_over_chi2_90: f64,
    /// Monte Carlo p-value of V against the null.
    pub p_value: f64,
    /// p of the scaled chi-square at s = 0.
    pub p_chi2: f64,
    /// The estimated spread s (sd of ln level between power-ons) and its 95 % interval.
    pub spread: f64,
    pub interval: [f64; 2],
    /// Passed the naming rule (every spread above 0 is written into the corrected model).
    pub named: bool,
}

impl RunSpread {
    /// How this spread was estimated, for the model's `[fitted_on]` (`FittedOn::run_to_run`):
    /// None without a finite statistic, a null above 0 or a known term.
    pub fn fit(&self) -> Option<SpreadFit> {
        let effects: Vec<Effect> = self
            .effects
            .iter()
            .filter_map(|e| Effect::from_name(e))
            .collect();
        (self.variance.is_finite()
            && self.null_variance > 0.0
            && self.null_variance.is_finite()
            && !effects.is_empty()
            && self.ln_multipliers.len() >= 2)
            .then_some(SpreadFit {
                channel: self.channel,
                effects,
                runs: self.ln_multipliers.len(),
                variance: self.variance,
                null_variance: self.null_variance,
            })
    }
}

/// The slow group of an axis: long-term terms a static log shows, with a level above 0; a
/// Gauss-Markov process only with a correlation time of 1 s or more; the flicker bias
/// instability only when the axis has no other: its plateau is measured at the middle averaging
/// times, far more precisely per run than the wander beyond them, and one multiplier of both
/// would follow the plateau and miss the wander a drift integrates (on the ADIS16405 runs, gz's
/// flicker level varies by about 0.2 in ln between runs where its random walk's heading at 1 h
/// varies tenfold).
pub fn slow_group(axis: &AxisModel) -> Vec<Effect> {
    let all = long_terms(axis);
    if all.iter().any(|&e| e != Effect::BiasInstability) {
        all.into_iter()
            .filter(|&e| e != Effect::BiasInstability)
            .collect()
    } else {
        all
    }
}

/// The short group of an axis: its white noise, when its level is above 0.
pub fn short_group(axis: &AxisModel) -> Vec<Effect> {
    axis.term(Effect::WhiteNoise)
        .filter(|t| t.level().is_some_and(|(_, v)| v.abs() > 0.0))
        .map(|_| vec![Effect::WhiteNoise])
        .unwrap_or_default()
}

/// The group named `group` ("long": [`slow_group`], "short": [`short_group`]).
fn group_of(axis: &AxisModel, group: &str) -> Vec<Effect> {
    if group == "long" {
        slow_group(axis)
    } else {
        short_group(axis)
    }
}

/// The other group's name.
fn other_kind(group: &str) -> &'static str {
    if group == "long" {
        "short"
    } else {
        "long"
    }
}

/// The long-term terms of [`slow_group`] before the flicker rule.
fn long_terms(axis: &AxisModel) -> Vec<Effect> {
    axis.terms()
        .filter(|t| {
            let e = t.effect();
            let level = t.level().map_or(0.0, |(_, v)| v.abs());
            let slow_enough = t
                .as_error_term()
                .shape()
                .iter()
                .find(|(name, _)| *name == "tau_s")
                .is_none_or(|&(_, tau)| tau >= 1.0);
            e.is_long_term() && e.shows_in_static_log() && level > 0.0 && slow_enough
        })
        .map(|t| t.effect())
        .collect()
}

/// The estimator's fixed parts on one grid: per tau the model's total Allan variance, the
/// group's, the channel's other group's (the short group for the slow one and the other way
/// round; zero when the axis has none), the rest, and the local slope.
struct GroupFit {
    ms: Vec<usize>,
    total: Vec<f64>,
    slow: Vec<f64>,
    other: Vec<f64>,
    rest: Vec<f64>,
    mu: Vec<f64>,
}

impl GroupFit {
    fn new(
        axis: &AxisModel,
        group: &[Effect],
        other: &[Effect],
        dt: f64,
        ms: Vec<usize>,
    ) -> GroupFit {
        let taus: Vec<f64> = ms.iter().map(|&m| m as f64 * dt).collect();
        let total = axis.allan_variance_sampled_many(&taus, dt);
        let curve = |effects: &[Effect]| {
            if effects.is_empty() {
                return vec![0.0; taus.len()];
            }
            let mut only = AxisModel::default();
            if let Some(f) = axis.term(Effect::OutputFilter) {
                only.set_term(f.clone());
            }
            for &e in effects {
                if let Some(t) = axis.term(e) {
                    only.set_term(t.clone());
                }
            }
            only.allan_variance_sampled_many(&taus, dt)
        };
        let slow = curve(group);
        let other = curve(other);
        let rest = (0..taus.len())
            .map(|i| total[i] - slow[i] - other[i])
            .collect();
        let mu = (0..taus.len())
            .map(|i| local_slope(&taus, &total, i))
            .collect();
        GroupFit {
            ms,
            total,
            slow,
            other,
            rest,
            mu,
        }
    }

    /// ln m of one run of `n` samples with Allan variances `avar` (on the first `avar.len()`
    /// taus): the group's squared multiplier q fitted jointly with the other group's q' (both
    /// held at `Q_MIN` or above, the other refitted with the first held where it is clamped).
    fn ln_multiplier(&self, avar: &[f64], n: usize) -> f64 {
        // The weighted normal equations of a - rest = q slow + q' other.
        let (mut s11, mut s12, mut s22, mut b1, mut b2) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for (i, &a) in avar.iter().enumerate() {
            if !(a.is_finite() && self.total[i] > 0.0) {
                continue;
            }
            let w = edf_at(self.mu[i], self.ms[i], n) / (2.0 * self.total[i] * self.total[i]);
            let (g, o, y) = (self.slow[i], self.other[i], a - self.rest[i]);
            s11 += w * g * g;
            s12 += w * g * o;
            s22 += w * o * o;
            b1 += w * g * y;
            b2 += w * o * y;
        }
        if s11 <= 0.0 {
            return f64::NAN;
        }
        let q = if s22 > 0.0 {
            let det = s11 * s22 - s12 * s12;
            let (q1, q2) = if det > 0.0 {
                ((b1 * s22 - b2 * s12) / det, (b2 * s11 - b1 * s12) / det)
            } else {
                (b1 / s11, 1.0)
            };
            if q2 < Q_MIN {
                (b1 - s12 * Q_MIN) / s11
            } else {
                q1
            }
        } else {
            b1 / s11
        };
        0.5 * q.max(Q_MIN).ln()
    }
}

/// Sample variance.
fn sample_variance(x: &[f64]) -> f64 {
    let n = x.len() as f64;
    let mean = x.iter().sum::<f64>() / n;
    x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)
}

/// The null's model: `model` as the bootstrap simulates it at the coarse interval
/// (`bootstrap::coarse_model`: without output filters and without tones the coarse interval cannot
/// carry), with no spread.
fn null_model(model: &SensorModel, dt_null: f64) -> SensorModel {
    let mut m = crate::bootstrap::coarse_model(model, dt_null).unwrap_or_else(|| model.clone());
    for ch in Channel::ALL {
        let axis = m.axis_mut(ch.sensor(), ch.axis());
        axis.remove(Effect::OutputFilter);
        axis.clear_run_to_run();
    }
    m
}

/// The run-to-run estimate of every channel of `model` with a slow group, from the runs `logs`
/// (two or more, one sample interval). `seed` seeds the null's simulated runs. None when stopped.
pub fn estimate(
    model: &SensorModel,
    logs: &[LogInput],
    tau_min_s: f64,
    seed: u64,
    stop: Option<&AtomicBool>,
) -> Option<Vec<RunSpread>> {
    if logs.len() < 2 {
        return Some(Vec::new());
    }
    let dt = logs[0].dt_s;
    let decimation = 8usize;
    let dt_null = dt * decimation as f64;
    let samples: Vec<usize> = logs
        .iter()
        .map(|l| {
            l.channels
                .0
                .iter()
                .flatten()
                .map(|c| c.len())
                .max()
                .unwrap_or(0)
        })
        .collect();
    let n_max = *samples.iter().max()?;
    // Coarse factors: M_MIN, 2 M_MIN, ... up to a quarter of the longest coarse run.
    let coarse: Vec<usize> = std::iter::successors(Some(M_MIN), |m| m.checked_mul(2))
        .take_while(|&m| m <= n_max / decimation / 4)
        .filter(|&m| m as f64 * dt_null >= tau_min_s * (1.0 - 1e-9))
        .collect();
    if coarse.is_empty() {
        return Some(Vec::new());
    }
    let fine: Vec<usize> = coarse.iter().map(|&m| m * decimation).collect();
    let nulls = null_model(model, dt_null);
    let channels: Vec<(Channel, Vec<Effect>, &'static str)> = Channel::ALL
        .into_iter()
        .filter(|&c| logs.iter().all(|l| l.channels[c].is_some()))
        .flat_map(|c| {
            ["long", "short"].map(|k| (c, group_of(model.axis(c.sensor(), c.axis()), k), k))
        })
        .filter(|(c, g, k)| {
            !g.is_empty() && group_of(nulls.axis(c.sensor(), c.axis()), k).len() == g.len()
        })
        .collect();
    if channels.is_empty() {
        return Some(Vec::new());
    }
    let held = |n: usize, ms: &[usize]| ms.iter().filter(|&&m| m <= n / 4).count();
    // The measured runs.
    let measured: Vec<Vec<f64>> = channels
        .iter()
        .map(|(c, g, k)| {
            let axis = model.axis(c.sensor(), c.axis());
            let other = group_of(axis, other_kind(k));
            let fit = GroupFit::new(axis, g, &other, dt, fine.clone());
            logs.iter()
                .zip(&samples)
                .map(|(l, &n)| {
                    let x = l.channels[*c].unwrap_or(&[]);
                    let ms = &fine[..held(n, &fine)];
                    let avar: Vec<f64> = adev_at(x, dt, ms).iter().map(|a| a * a).collect();
                    fit.ln_multiplier(&avar, n)
                })
                .collect()
        })
        .collect();
    // The null: NULL_REPLICATES sets of R runs at the coarse interval.
    let active = ImuChannels::from_fn(|c| channels.iter().any(|(k, _, _)| *k == c));
    let runs = logs.len();
    let jobs: Vec<LogJob> = (0..NULL_REPLICATES * runs)
        .map(|j| LogJob {
            model: &nulls,
            setup: SimSetup::plain(dt_null, samples[j % runs] / decimation, active)
                .stopped_by(stop),
            seed,
            run: NULL_FIRST_RUN + j as u64,
        })
        .collect();
    let null_fits: Vec<GroupFit> = channels
        .iter()
        .map(|(c, g, k)| {
            let axis = nulls.axis(c.sensor(), c.axis());
            let other = group_of(axis, other_kind(k));
            GroupFit::new(axis, g, &other, dt_null, coarse.clone())
        })
        .collect();
    let per_job: Vec<Vec<f64>> = map_static_logs(&jobs, |j, log| {
        let n = samples[j % runs] / decimation;
        channels
            .iter()
            .zip(&null_fits)
            .map(|((c, _, _), fit)| {
                let ms = &coarse[..held(n, &coarse)];
                let avar: Vec<f64> = adev_at(&log[*c], dt_null, ms)
                    .iter()
                    .map(|a| a * a)
                    .collect();
                fit.ln_multiplier(&avar, n)
            })
            .collect()
    })?;
    let r = runs as f64;
    let out = channels
        .iter()
        .enumerate()
        .map(|(k, (c, g, group))| {
            let v = sample_variance(&measured[k]);
            let null_v: Vec<f64> = (0..NULL_REPLICATES)
                .map(|b| {
                    let x: Vec<f64> = (0..runs).map(|t| per_job[b * runs + t][k]).collect();
                    sample_variance(&x)
                })
                .collect();
            let sigma2 = null_v.iter().sum::<f64>() / NULL_REPLICATES as f64;
            let chi2_90 = allan::chi2::chi2_ppf(0.90, r - 1.0) / (r - 1.0) * sigma2;
            let over =
                null_v.iter().filter(|&&x| x > chi2_90).count() as f64 / NULL_REPLICATES as f64;
            let p_value = (1 + null_v.iter().filter(|&&x| x >= v).count()) as f64
                / (NULL_REPLICATES + 1) as f64;
            let p_chi2 = if sigma2 > 0.0 && v.is_finite() {
                1.0 - allan::chi2::chi2_cdf((r - 1.0) * v / sigma2, r - 1.0)
            } else {
                f64::NAN
            };
            let s2 = (v - sigma2).max(0.0);
            let bound =
                |p: f64| spread_given(v, sigma2, r - 1.0, allan::chi2::chi2_ppf(p, r - 1.0));
            let floor = 1.0 / (NULL_REPLICATES + 1) as f64;
            RunSpread {
                channel: *c,
                group,
                effects: g.iter().map(|e| e.name()).collect(),
                ln_multipliers: measured[k].clone(),
                variance: v,
                null_variance: sigma2,
                null_replicates: NULL_REPLICATES,
                null_over_chi2_90: over,
                p_value,
                p_chi2,
                spread: s2.sqrt().min(noise::run_to_run::MAX_SPREAD),
                interval: [bound(0.975), bound(0.025)],
                named: p_chi2 <= NAMING_ALPHA && p_value <= floor * (1.0 + 1e-9),
            }
        })
        .collect();
    Some(out)
}

/// `model` with every spread estimated above 0 written on its group (`run_to_run`), named or
/// not: the band of a next run holds the best estimate of how far it may stray (the
/// random-effects prediction of Higgins, Thompson & Spiegelhalter 2009, J. R. Stat. Soc. A 172,
/// 137-159, which takes the between-study variance's estimate whatever the heterogeneity test
/// says). Naming is the separate claim that the runs differ (module doc, step 5). A spread of 0
/// leaves the group as it was.
pub fn with_estimated_spreads(model: &SensorModel, spreads: &[RunSpread]) -> SensorModel {
    let mut out = model.clone();
    for s in spreads.iter().filter(|s| s.spread > 0.0) {
        let axis = out.axis_mut(s.channel.sensor(), s.channel.axis());
        for name in &s.effects {
            if let Some(e) = Effect::from_name(name) {
                let _ = axis.set_run_to_run(e, s.spread);
            }
        }
    }
    out
}

/// Index of the spread draws' stream among `noise::extra_rng`'s (per replicate; the channel and
/// group are added in its low bits): apart from the alignment stream (0) of the drift runs.
const SPREAD_STREAM: u32 = 0x5250_0000;

/// One spread drawn from its confidence distribution (docs/drift.md, "The spread's own
/// uncertainty"): the interval of
/// [`estimate`] inverts V ~ (s^2 + sigma_e^2) chi2_{R-1} / (R - 1) over s, so s^2 = max(0,
/// (R - 1) V / X - sigma_e^2) with X ~ chi2_{R-1} has that interval's limits as its 2.5 and 97.5 %
/// points (the fiducial distribution of s, Fisher 1935; for a variance component with the
/// within-part known, as the null's sigma_e^2 is here). `x` is the chi-square draw; capped at
/// `MAX_SPREAD`.
pub fn spread_at(fit: &SpreadFit, x: f64) -> f64 {
    let df = fit.runs.saturating_sub(1) as f64;
    // Without a chi-square (one run, or a draw of 0): V itself, the point estimate.
    let (df, x) = if df > 0.0 && x > 0.0 {
        (df, x)
    } else {
        (1.0, 1.0)
    };
    spread_given(fit.variance, fit.null_variance, df, x).min(noise::run_to_run::MAX_SPREAD)
}

/// The spread s with (s^2 + sigma_e^2) = df V / x, clamped at 0: the interval's limits of
/// [`estimate`] at chi-square quantiles x, a draw of [`spread_at`] at a chi-square draw.
fn spread_given(variance: f64, null_variance: f64, df: f64, x: f64) -> f64 {
    (df * variance / x - null_variance).max(0.0).sqrt()
}

/// Each replicate's run-to-run spreads drawn from their confidence distribution ([`spread_at`]),
/// written on the replicate's model (replicate r is `models[r]`; its group's terms the axis has
/// with a level; a draw of 0 leaves its runs at the pooled levels). Replicate r's draw for fit
/// `f` comes from `noise::extra_rng(seed, r, SPREAD_STREAM + 2 channel + group)`: the same for any
/// thread count and whatever the other fits. Returns the draws, [fit][replicate].
///
/// Why: a spread estimated from a handful of runs is far from exact (from six runs whose V is
/// near its null, anything from 0 to about 0.7), and a band for a next run drawn with the point
/// estimate alone is too narrow exactly where the runs say least; the random-effects prediction
/// for a new study takes the between-study variance's uncertainty in (Higgins, Thompson &
/// Spiegelhalter 2009, J. R. Stat. Soc. A 172, 137-159, §3.2: a t rather than a normal quantile).
pub fn draw_spreads(models: &mut [SensorModel], fits: &[SpreadFit], seed: u64) -> Vec<Vec<f64>> {
    fits.iter()
        .map(|f| {
            let group = f
                .effects
                .first()
                .map_or(0, |&e| noise::run_to_run::group_of(e)) as u32;
            let stream = SPREAD_STREAM + 2 * f.channel.index() as u32 + group;
            models
                .iter_mut()
                .enumerate()
                .map(|(r, m)| {
                    let mut rng = noise::extra_rng(seed, r as u64, stream);
                    let x = noise::run_to_run::chi_square(&mut rng, f.runs.saturating_sub(1));
                    let s = spread_at(f, x);
                    let axis = m.axis_mut(f.channel.sensor(), f.channel.axis());
                    for &e in &f.effects {
                        let _ = axis.set_run_to_run(e, s);
                    }
                    s
                })
                .collect()
        })
        .collect()
}
