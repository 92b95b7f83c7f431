//! The uncertainty of a fitted model's levels, by a parametric bootstrap (docs/drift.md,
//! "Parameter uncertainty").
//!
//! A model fitted on finite logs (`FittedOn`) would have come out otherwise on other logs of the
//! same sensor. Replicate r of a drift check therefore simulates its experiment not with the fitted
//! levels but with levels drawn from their sampling distribution, estimated by the parametric
//! bootstrap (Efron & Tibshirani 1993, "An Introduction to the Bootstrap", §6.5): logs like the
//! fitted ones (same sample interval, lengths and channels) simulated from the fitted model, their
//! Allan variances on the octave grid from `tau_min_s`, and the levels refitted. Drawing each
//! replicate's parameters from the bootstrap distribution and its data from those parameters is
//! the bootstrap predictive distribution (Harris 1989, "Predictive fit for natural exponential
//! families", Biometrika 76, 675-684), so the band of the replicates' statistic holds the spread of
//! the data and of the fit.
//!
//! Decimated logs: long logs of 20 Hz and more are simulated at up to 8 times their sample
//! interval (without output filters and tones above the coarse Nyquist frequency, `coarse_model`)
//! and the refit's grid starts at 8 coarse samples, 1 s or sooner (0.64 s at 100 Hz): the levels'
//! uncertainty comes from the long averaging times, which the finer samples do not change, at an
//! eighth of the work (`bootstrap_decimation`).
//!
//! The refit, per channel: the Allan variance is the sum of the terms' (IEEE 952 Annex C; docs/model.md
//! §2), each linear in its squared level, so with the terms' exact sampled Allan variances b_j(tau) at
//! the fitted levels and the rest r(tau) held, the multipliers s_j >= 0 of the squared levels minimise
//! sum_i w_i (avar_i - r_i - sum_j s_j b_ij)^2, the weighted non-negative least squares of Lawson &
//! Hanson (1974, ch. 23). The weights are the inverse variances of the Allan variance estimates,
//! w_i = nu_i / (2 A_i^2) (the estimate is A_i chi2(nu_i)/nu_i, NIST SP 1065 §5.2), A_i the fitted
//! model's Allan variance and nu_i Greenhall's EDF for the noise type of its local slope
//! (mu = -alpha - 1, SP 1065 Table 2); several logs are pooled with weights nu (their EDFs add).
//! The weights fix only the estimator's efficiency: it is linear in the Allan variances, which are
//! unbiased, so it is unbiased but where s_j is clamped at 0. The draws are centred on the fitted
//! levels by dividing each multiplier by its bootstrap mean (the multiplicative form of the
//! bootstrap bias correction, Efron & Tibshirani §10.2), so that a closed form that does not match
//! the generator exactly or the clamp moves no level.
//!
//! Drawn: the stochastic levels (quantisation, white noise, flicker bias instability, rate random
//! walk, Gauss-Markov sigma, sinusoid amplitude, resonance sigma) of the fitted channels. Held as
//! fitted: shapes (Gauss-Markov times, frequencies, output filters), deterministic and per-run terms
//! (biases, ramp, temperature, scale factor, misalignment), Woodman's random-walk bias instability
//! and every term of a channel the logs did not have. A level no refit sees (every multiplier 0)
//! keeps its value and is reported as not informed. A term at level 0 (fitted to 0) is drawn
//! too, uncentred, from a unit reference level: its draws are the refits' (0 or above), so that
//! the levels it trades with (a flicker level against a rate random walk) spread as they would.

use crate::candidates::drawn;
use crate::fitted_on::FittedOn;
use crate::model_terms::{fitted_term, set_term, squared_level};
use crate::simulate::{adev_at, map_static_logs, LogJob, SimSetup};
use allan::{EdfMethod, Estimator};
use noise::{AxisModel, Channel, Effect, ImuChannels, SensorModel, Term};
use rayon::prelude::*;
use serde::Serialize;
use std::collections::BTreeMap;
use std::sync::atomic::AtomicBool;

/// Most levels refitted together on one channel (the refit tries every subset of them).
const MAX_TERMS: usize = 10;

/// The models of the replicates and how their levels spread.
#[derive(Clone, Debug)]
pub struct Draws {
    /// One model per replicate.
    pub models: Vec<SensorModel>,
    pub spread: ParameterSpread,
}

/// How the levels were drawn and how far they spread (the JSON `parameters` of a drift check).
#[derive(Clone, Debug, Serialize)]
pub struct ParameterSpread {
    /// "parametric_bootstrap".
    pub method: &'static str,
    pub fitted_on: FittedOn,
    /// Per channel, each drawn level.
    pub levels: BTreeMap<&'static str, Vec<LevelSpread>>,
    /// Each run-to-run spread the fit recorded, drawn per replicate from its confidence
    /// distribution (`run_spread::draw_spreads`).
    pub run_to_run: Vec<SpreadDraws>,
}

/// One group's run-to-run spread over the replicates: the model's value (its point estimate), the
/// share of replicates drawn at 0 and the 2.5, 50 and 97.5 % quantiles (sd of ln level).
#[derive(Clone, Debug, Serialize)]
pub struct SpreadDraws {
    pub channel: Channel,
    pub effects: Vec<Effect>,
    pub model: f64,
    pub share_zero: f64,
    pub p2_5: f64,
    pub p50: f64,
    pub p97_5: f64,
}

/// One drawn level: the model's value and the 2.5, 50 and 97.5 % quantiles of the draws (SI).
#[derive(Clone, Debug, Serialize)]
pub struct LevelSpread {
    pub effect: Effect,
    /// The parameter's JSON name (n, b, k, q, sigma, amplitude).
    pub parameter: &'static str,
    pub model: f64,
    pub p2_5: f64,
    pub p50: f64,
    pub p97_5: f64,
    /// False when no refit saw the term: its level is kept as fitted.
    pub informed: bool,
}

/// Errors of the bootstrap.
#[derive(Debug, thiserror::Error)]
pub enum BootstrapError {
    #[error("the model's output filter does not fit the fitted logs' rate: {0}")]
    Rate(String),
    #[error("channel {channel} has {terms} levels to refit; at most {MAX_TERMS} are supported")]
    TooManyTerms { channel: &'static str, terms: usize },
    /// The front end's stop flag was set (Ctrl-C): no draws.
    #[error("stopped")]
    Stopped,
}

/// A drawn term: the term at the reference level the multipliers refer to (the fitted one, or a
/// unit squared level for a term fitted at 0), that level with its JSON name, and its fitted
/// squared level.
#[derive(Clone)]
struct DrawnTerm {
    effect: Effect,
    reference: Term,
    level: (&'static str, f64),
    fitted_c: f64,
}

/// One channel's refit: its drawn terms, the grid and the fixed parts of the least squares.
struct ChannelFit {
    ch: Channel,
    terms: Vec<DrawnTerm>,
    /// Octave averaging factors of the longest log from `tau_min_s`, and per log how many of them
    /// it holds (a log of n samples holds m <= n / 4, the overlapping estimator's Stable32 limit).
    grid_m: Vec<usize>,
    held: Vec<usize>,
    /// Per tau: the terms' Allan variances at their reference levels, the rest of the model's, and the
    /// least-squares weight of one unit of EDF (1 / (2 A^2)).
    basis: Vec<Vec<f64>>,
    rest: Vec<f64>,
    weight_per_edf: Vec<f64>,
    /// Per log, per tau: the EDF.
    edf: Vec<Vec<f64>>,
    /// The grid's sample interval: the fitted logs' times `decimation`.
    dt: f64,
    /// Samples of the fitted logs per sample of the grid's logs (1: the logs themselves).
    decimation: usize,
}

/// The EDF of the overlapping Allan variance at factor `m` of a log of `n` samples, for noise of
/// Allan-variance slope `mu` (alpha = -mu - 1, SP 1065 Table 2, rounded and clamped to the
/// power-law range; Greenhall & Riley 2004 through `allan::edf`).
pub(crate) fn edf_at(mu: f64, m: usize, n: usize) -> f64 {
    let alpha = (-mu - 1.0).round().clamp(-2.0, 2.0) as i32;
    let nu = allan::edf::edf_for(
        Estimator::Overlapping,
        EdfMethod::Greenhall,
        alpha,
        m,
        n + 1,
        0,
    );
    if nu.is_finite() && nu > 0.0 {
        nu
    } else {
        allan::edf::simple(n + 1, m, alpha)
    }
}

impl ChannelFit {
    /// The refit of channel `ch` of `model` on data like `fitted`, seen at `decimation` times
    /// its sample interval (None: nothing to draw there). With a decimation above 1 the grid
    /// starts at `DECIMATED_M_MIN` coarse samples.
    fn new(
        model: &SensorModel,
        ch: Channel,
        fitted: &FittedOn,
        decimation: usize,
    ) -> Option<ChannelFit> {
        let terms = drawn_terms(model, ch);
        if terms.is_empty() || !fitted.channels[ch] {
            return None;
        }
        let dt = fitted.sample_interval_s * decimation as f64;
        let n_max = *fitted.samples.iter().max()? / decimation;
        let m_min = if decimation > 1 { DECIMATED_M_MIN } else { 1 };
        let grid_m: Vec<usize> = std::iter::successors(Some(m_min), |m| m.checked_mul(2))
            .take_while(|&m| m <= n_max / 4)
            .filter(|&m| m as f64 * dt >= fitted.tau_min_s * (1.0 - 1e-9))
            .collect();
        if grid_m.is_empty() {
            return None;
        }
        let held = fitted
            .samples
            .iter()
            .map(|&n| grid_m.iter().filter(|&&m| m <= n / decimation / 4).count())
            .collect();
        let taus: Vec<f64> = grid_m.iter().map(|&m| m as f64 * dt).collect();
        let total = model
            .axis(ch.sensor(), ch.axis())
            .allan_variance_sampled_many(&taus, dt);
        let basis = basis(model, ch, &terms, &taus, dt);
        // The model's Allan variance less its drawn terms' (a term fitted at 0 adds nothing).
        let rest = (0..taus.len())
            .map(|i| {
                let drawn: f64 = (0..terms.len())
                    .filter(|&j| terms[j].fitted_c > 0.0)
                    .map(|j| basis[i][j])
                    .sum();
                total[i] - drawn
            })
            .collect();
        let weight_per_edf = total
            .iter()
            .map(|&a| {
                if a > 0.0 && a.is_finite() {
                    0.5 / (a * a)
                } else {
                    0.0
                }
            })
            .collect();
        let edf = fitted
            .samples
            .iter()
            .map(|&n| {
                (0..taus.len())
                    .map(|i| edf_at(local_slope(&taus, &total, i), grid_m[i], n / decimation))
                    .collect()
            })
            .collect();
        Some(ChannelFit {
            ch,
            terms,
            grid_m,
            held,
            basis,
            rest,
            weight_per_edf,
            edf,
            dt,
            decimation,
        })
    }

    /// The multipliers of the squared levels refitted to the Allan variances `avar[log][tau]`
    /// (NaN where a log has no value), pooled over the logs with EDF weights.
    fn refit(&self, avar: &[Vec<f64>]) -> Vec<f64> {
        let mut rows = Vec::new();
        let mut rhs = Vec::new();
        for i in 0..self.grid_m.len() {
            let (mut sum, mut nu) = (0.0, 0.0);
            for (l, a) in avar.iter().enumerate() {
                if i < a.len() && a[i].is_finite() {
                    sum += self.edf[l][i] * a[i];
                    nu += self.edf[l][i];
                }
            }
            let w = (nu * self.weight_per_edf[i]).sqrt();
            if nu > 0.0 && w > 0.0 && w.is_finite() {
                rows.push(self.basis[i].iter().map(|b| w * b).collect::<Vec<f64>>());
                rhs.push(w * (sum / nu - self.rest[i]));
            }
        }
        nnls_small(&rows, &rhs, self.terms.len())
    }
}

/// The terms of channel `ch` whose level is drawn (module doc), each at its reference level.
fn drawn_terms(model: &SensorModel, ch: Channel) -> Vec<DrawnTerm> {
    drawn()
        .into_iter()
        .filter_map(|effect| {
            let p = fitted_term(model, ch, effect)?;
            let fitted_c = squared_level(Some(p));
            let reference = if fitted_c > 0.0 {
                p.clone()
            } else {
                scaled(p, 0.0, 1.0)?
            };
            let level = reference.level()?;
            (fitted_c >= 0.0).then_some(DrawnTerm {
                effect,
                reference,
                level,
                fitted_c,
            })
        })
        .collect()
}

/// Per tau, each term's Allan variance at its reference level alone on the channel (behind the
/// channel's output filter, if it has one): the columns of the least squares.
fn basis(
    model: &SensorModel,
    ch: Channel,
    terms: &[DrawnTerm],
    taus: &[f64],
    dt: f64,
) -> Vec<Vec<f64>> {
    let filter = model
        .axis(ch.sensor(), ch.axis())
        .get::<noise::OutputFilter>();
    let columns: Vec<Vec<f64>> = terms
        .iter()
        .map(|t| {
            let mut only = AxisModel::default();
            if let Some(f) = filter {
                only.set_term(*f);
            }
            only.set_term(t.reference.clone());
            only.allan_variance_sampled_many(taus, dt)
        })
        .collect();
    (0..taus.len())
        .map(|i| columns.iter().map(|c| c[i]).collect())
        .collect()
}

/// d ln A / d ln tau at grid point `i` (central between the neighbours, one-sided at the ends).
pub(crate) fn local_slope(taus: &[f64], avar: &[f64], i: usize) -> f64 {
    if taus.len() < 2 {
        return -1.0;
    }
    let (a, b) = (i.saturating_sub(1), (i + 1).min(taus.len() - 1));
    let mu = (avar[b] / avar[a]).ln() / (taus[b] / taus[a]).ln();
    if mu.is_finite() {
        mu
    } else {
        -1.0
    }
}

/// Non-negative least squares, min |G x - y|^2 subject to x >= 0, for a few columns (`rows` of G):
/// the best non-negative unconstrained least-squares solution over every subset of the columns
/// (the NNLS solution is the least-squares solution on its own support, Lawson & Hanson 1974,
/// ch. 23, so it is among them). Columns are scaled to unit norm for the normal equations; a
/// subset whose normal matrix is not positive definite is skipped.
fn nnls_small(rows: &[Vec<f64>], y: &[f64], k: usize) -> Vec<f64> {
    let norms: Vec<f64> = (0..k)
        .map(|j| rows.iter().map(|r| r[j] * r[j]).sum::<f64>().sqrt())
        .collect();
    let usable: Vec<usize> = (0..k)
        .filter(|&j| norms[j] > 0.0 && norms[j].is_finite())
        .collect();
    let mut best = vec![0.0; k];
    let mut best_sse: f64 = y.iter().map(|v| v * v).sum();
    for mask in 1u32..(1u32 << usable.len()) {
        let cols: Vec<usize> = (0..usable.len())
            .filter(|&b| mask & (1 << b) != 0)
            .map(|b| usable[b])
            .collect();
        let p = cols.len();
        let g = nalgebra::DMatrix::from_fn(rows.len(), p, |i, j| rows[i][cols[j]] / norms[cols[j]]);
        let yv = nalgebra::DVector::from_column_slice(y);
        let Some(chol) = (g.transpose() * &g).cholesky() else {
            continue;
        };
        let x = chol.solve(&(g.transpose() * &yv));
        if x.iter().any(|&v| v.is_nan() || v < 0.0) {
            continue;
        }
        let sse = (&g * &x - &yv).norm_squared();
        if sse < best_sse {
            best_sse = sse;
            best = vec![0.0; k];
            for (j, &c) in cols.iter().enumerate() {
                best[c] = x[j] / norms[c];
            }
        }
    }
    best
}

/// `term` with its level multiplied by `factor` plus `unit` (a squared level multiplied by
/// factor^2, or set to unit^2 with factor 0); None when it has no level or the term's constructor
/// refuses the new one (not a finite number).
fn scaled(term: &Term, factor: f64, unit: f64) -> Option<Term> {
    let (_, v) = term.level()?;
    term.with_level(v * factor.max(0.0) + unit).ok()
}

/// Simulated logs like the fitted ones: replicate r, log t is run `first_run + r T + t` of `seed`
/// (T logs). Per replicate, per fitted channel (in `fits` order), per log: the Allan variances on
/// the channel's grid. `tick` is called once per simulated log.
fn simulate_fitted_logs(
    model: &SensorModel,
    fitted: &FittedOn,
    fits: &[ChannelFit],
    (seed, first_run, replicates): (u64, u64, usize),
    tick: &(dyn Fn() + Sync),
    stop: Option<&AtomicBool>,
) -> Option<Vec<Vec<Vec<Vec<f64>>>>> {
    let logs = fitted.samples.len();
    let (dt, decimation) = (fits[0].dt, fits[0].decimation);
    let jobs: Vec<(usize, usize)> = (0..replicates)
        .flat_map(|r| (0..logs).map(move |t| (r, t)))
        .collect();
    let active = noise::ImuChannels::from_fn(|c| fits.iter().any(|f| f.ch == c));
    let log_jobs: Vec<LogJob> = jobs
        .iter()
        .map(|&(r, t)| LogJob {
            model,
            setup: SimSetup::plain(dt, fitted.samples[t] / decimation, active).stopped_by(stop),
            seed,
            run: first_run + (r * logs + t) as u64,
        })
        .collect();
    let per_job: Vec<Vec<Vec<f64>>> = map_static_logs(&log_jobs, |j, log| {
        let t = jobs[j].1;
        let out = fits
            .iter()
            .map(|f| {
                let ms = &f.grid_m[..f.held[t]];
                adev_at(&log[f.ch], dt, ms).iter().map(|a| a * a).collect()
            })
            .collect();
        tick();
        out
    })?;
    // Regroup as [replicate][channel][log].
    let regrouped = (0..replicates)
        .map(|r| {
            (0..fits.len())
                .map(|k| {
                    (0..logs)
                        .map(|t| per_job[r * logs + t][k].clone())
                        .collect()
                })
                .collect()
        })
        .collect();
    Some(regrouped)
}

/// Draw each replicate's levels (module doc). Replicate r's logs like the fitted ones are runs
/// `first_run + r T + t` (t < T, the fitted logs) of `seed`: the caller keeps them apart from its
/// own runs. `tick` is called once per simulated log (`replicates` times the fitted logs).
/// Once `stop` is set no further log is simulated and the result is [`BootstrapError::Stopped`].
pub fn draw_models(
    model: &SensorModel,
    fitted: &FittedOn,
    runs: (u64, u64, usize),
    tick: &(dyn Fn() + Sync),
    stop: Option<&AtomicBool>,
) -> Result<Draws, BootstrapError> {
    draw_models_on(model, fitted, ImuChannels([true; 6]), runs, tick, stop)
}

/// [`draw_models`] on the channels `only` alone: only they are simulated and refitted, the other
/// channels keep the model's levels. The refit is per channel and each channel's errors come from
/// its own random streams, so a channel's draws do not depend on which others are drawn with it
/// (for the same runs).
pub fn draw_models_on(
    model: &SensorModel,
    fitted: &FittedOn,
    only: ImuChannels<bool>,
    (seed, first_run, replicates): (u64, u64, usize),
    tick: &(dyn Fn() + Sync),
    stop: Option<&AtomicBool>,
) -> Result<Draws, BootstrapError> {
    noise::ImuErrors::check_rate(model, fitted.sample_interval_s)
        .map_err(|e| BootstrapError::Rate(e.to_string()))?;
    let dt_s = fitted.sample_interval_s;
    let (unfiltered, decimation) = match bootstrap_decimation(fitted)
        .and_then(|d| Some((coarse_model(model, dt_s * d as f64)?, d)))
    {
        Some(coarse) => coarse,
        None => (without_output_filters(model, dt_s), 1),
    };
    let fits: Vec<ChannelFit> = Channel::ALL
        .into_iter()
        .filter(|&ch| only[ch])
        .filter_map(|ch| ChannelFit::new(&unfiltered, ch, fitted, decimation))
        .collect();
    if fits.is_empty() {
        let s: Vec<Vec<Vec<f64>>> = vec![Vec::new(); replicates];
        let models = s.iter().map(|r| drawn_model(model, &fits, r)).collect();
        let spread = spread(fitted, &fits, &s, &[]);
        return Ok(Draws { models, spread });
    }
    if let Some(f) = fits.iter().find(|f| f.terms.len() > MAX_TERMS) {
        return Err(BootstrapError::TooManyTerms {
            channel: f.ch.name(),
            terms: f.terms.len(),
        });
    }
    let avar = simulate_fitted_logs(
        &unfiltered,
        fitted,
        &fits,
        (seed, first_run, replicates),
        tick,
        stop,
    )
    .ok_or(BootstrapError::Stopped)?;
    // Multipliers [replicate][channel][term] of the reference squared levels; those of a fitted
    // level centred on 1 by their bootstrap mean, those of a level fitted at 0 left as drawn.
    let mut s: Vec<Vec<Vec<f64>>> = avar
        .par_iter()
        .map(|per_channel| {
            fits.iter()
                .zip(per_channel)
                .map(|(f, a)| f.refit(a))
                .collect()
        })
        .collect();
    let mut informed: Vec<Vec<bool>> = Vec::new();
    for (k, f) in fits.iter().enumerate() {
        let mut row = Vec::new();
        for (j, t) in f.terms.iter().enumerate() {
            // One multiplier per replicate (none: NaN, and the level is not informed).
            let mean = stats::mean(&s.iter().map(|r| r[k][j]).collect::<Vec<f64>>());
            row.push(mean > 0.0);
            if t.fitted_c > 0.0 {
                for r in s.iter_mut() {
                    r[k][j] = if mean > 0.0 { r[k][j] / mean } else { 1.0 };
                }
            }
        }
        informed.push(row);
    }
    let models = s.iter().map(|r| drawn_model(model, &fits, r)).collect();
    let spread = spread(fitted, &fits, &s, &informed);
    Ok(Draws { models, spread })
}

/// The shortest averaging factor of a decimated bootstrap's grid, in coarse samples.
const DECIMATED_M_MIN: usize = 8;
/// The largest decimation of the bootstrap's logs (module doc, "Decimated logs").
const DECIMATION: usize = 8;
/// The longest first averaging time a decimated grid may start at (s).
const DECIMATED_TAU_MAX_S: f64 = 1.0;

/// The bootstrap's decimation for logs like `fitted`: the largest power of two up to
/// [`DECIMATION`] whose grid starts at [`DECIMATED_TAU_MAX_S`] or sooner (`DECIMATED_M_MIN`
/// coarse samples) and whose shortest log holds at least 2^12 coarse samples (8 octaves or
/// more); None when not even 2 qualifies (the logs as they are: a 10 Hz log keeps its samples).
fn bootstrap_decimation(fitted: &FittedOn) -> Option<usize> {
    let n_min = fitted.samples.iter().copied().min().unwrap_or(0);
    let dt = fitted.sample_interval_s;
    [DECIMATION, 4, 2].into_iter().find(|&d| {
        (DECIMATED_M_MIN * d) as f64 * dt <= DECIMATED_TAU_MAX_S * (1.0 + 1e-9)
            && n_min / d >= 1 << 12
    })
}

/// `model` as the bootstrap (and `run_spread`'s null) simulate it at the interval `dt_coarse`
/// (a power-of-two multiple of the logs' `dt_s`): without output filters and without the tones
/// the coarse interval cannot carry (a resonance or sinusoid at 0.4 / dt_coarse or above).
///
/// An output filter (DC gain 1) shapes the Allan variance only at averaging times of the order of
/// its length, and a decimating one makes every term run at the raw rate, up to 16 times the work;
/// the grid starts at `DECIMATED_M_MIN` coarse samples (8 logs' samples and more), where the
/// Allan variance at tau is the variance of differences of tau-averages, which finer samples do
/// not change beyond the terms dropped. The refit needs only the *relative* spread of the levels,
/// which comes from the long averaging times where a level has few degrees of freedom, and the
/// draws are centred by their bootstrap mean (module doc), which absorbs what the dropped terms
/// change in the Allan variances themselves; the basis columns and the simulated logs both come
/// from this model, so they agree with each other. A dropped tone's level is not drawn: it keeps
/// its fitted value and is not among the listed draws. The drawn levels are then set on the full model
/// (`drawn_model`). The end-to-end check is the calibration test (`tests/band_calibration.rs`).
/// None when the model cannot run at the coarse interval even without its tones.
pub(crate) fn coarse_model(model: &SensorModel, dt_coarse: f64) -> Option<SensorModel> {
    let mut m = model.clone();
    for ch in Channel::ALL {
        let axis = m.axis_mut(ch.sensor(), ch.axis());
        axis.remove(Effect::OutputFilter);
        for e in [Effect::Sinusoidal, Effect::Resonance] {
            let fast = axis.term(e).is_some_and(|t| {
                t.as_error_term()
                    .shape()
                    .iter()
                    .any(|(name, f)| *name == "frequency_hz" && *f >= 0.4 / dt_coarse)
            });
            if fast {
                axis.remove(e);
            }
        }
    }
    if noise::ImuErrors::check_rate(&m, dt_coarse).is_ok() {
        return Some(m);
    }
    for ch in Channel::ALL {
        let axis = m.axis_mut(ch.sensor(), ch.axis());
        axis.remove(Effect::Sinusoidal);
        axis.remove(Effect::Resonance);
    }
    noise::ImuErrors::check_rate(&m, dt_coarse)
        .is_ok()
        .then_some(m)
}

/// `model` without its output filters, at the logs' own interval (the bootstrap without
/// decimation): a model that cannot run at `dt_s` without them keeps them.
fn without_output_filters(model: &SensorModel, dt_s: f64) -> SensorModel {
    let mut m = model.clone();
    for ch in Channel::ALL {
        m.axis_mut(ch.sensor(), ch.axis())
            .remove(Effect::OutputFilter);
    }
    if noise::ImuErrors::check_rate(&m, dt_s).is_ok() {
        m
    } else {
        model.clone()
    }
}

/// Rounds of [`fit_levels`]: each refits with the weights of the previous round's levels.
const FIT_ROUNDS: usize = 3;

/// The drawn levels (module doc) of `model` refitted jointly to `logs` by the bootstrap's own
/// estimator (weighted non-negative least squares of the Allan variances on the octave grid from
/// `tau_min_s`), iteratively reweighted: the weights of each round are those of the previous
/// round's levels. A level refitted to 0 stays in the model at 0 (so that the bootstrap still
/// draws it); a term the model lacks is not added (that is `diagnose`'s part). With the data it was fitted on, for [`draw_models`]; None when the logs
/// have no common channel.
pub fn fit_levels(
    model: &SensorModel,
    logs: &[crate::input::LogInput],
    tau_min_s: f64,
) -> Option<(SensorModel, FittedOn)> {
    let fitted = FittedOn::from_logs(logs, tau_min_s)?;
    let mut current = model.clone();
    for _ in 0..FIT_ROUNDS {
        let fits: Vec<ChannelFit> = Channel::ALL
            .into_iter()
            .filter_map(|ch| ChannelFit::new(&current, ch, &fitted, 1))
            .filter(|f| f.terms.len() <= MAX_TERMS)
            .collect();
        let s: Vec<Vec<f64>> = fits
            .iter()
            .map(|f| {
                let avar: Vec<Vec<f64>> = logs
                    .iter()
                    .enumerate()
                    .map(|(t, l)| {
                        let x = l.channels[f.ch].unwrap_or(&[]);
                        let ms = &f.grid_m[..f.held[t]];
                        adev_at(x, fitted.sample_interval_s, ms)
                            .iter()
                            .map(|a| a * a)
                            .collect()
                    })
                    .collect();
                f.refit(&avar)
            })
            .collect();
        current = drawn_model(&current, &fits, &s);
    }
    Some((current, fitted))
}

/// The model with every drawn term at its reference squared level times its multiplier
/// `s[channel][term]` (a level 0 stays in the model, at 0; a multiplier that is not a finite
/// number leaves the model's level).
fn drawn_model(model: &SensorModel, fits: &[ChannelFit], s: &[Vec<f64>]) -> SensorModel {
    let mut out = model.clone();
    for (f, mult) in fits.iter().zip(s) {
        for (t, &m) in f.terms.iter().zip(mult) {
            if let Some(term) = scaled(&t.reference, m.max(0.0).sqrt(), 0.0) {
                set_term(&mut out, f.ch, term);
            }
        }
    }
    out
}

/// The spread of every drawn level over the replicates.
fn spread(
    fitted: &FittedOn,
    fits: &[ChannelFit],
    s: &[Vec<Vec<f64>>],
    informed: &[Vec<bool>],
) -> ParameterSpread {
    let mut levels = BTreeMap::new();
    for (k, f) in fits.iter().enumerate() {
        let rows = f
            .terms
            .iter()
            .enumerate()
            .map(|(j, t)| {
                let (parameter, reference) = t.level;
                let mut v: Vec<f64> = s.iter().map(|r| reference * r[k][j].sqrt()).collect();
                v.sort_by(f64::total_cmp);
                LevelSpread {
                    effect: t.effect,
                    parameter,
                    model: t.fitted_c.sqrt(),
                    p2_5: stats::quantile(&v, 0.025),
                    p50: stats::quantile(&v, 0.5),
                    p97_5: stats::quantile(&v, 0.975),
                    informed: informed[k][j],
                }
            })
            .collect();
        levels.insert(f.ch.name(), rows);
    }
    ParameterSpread {
        method: "parametric_bootstrap",
        fitted_on: fitted.clone(),
        levels,
        run_to_run: Vec::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The decimation: 8 for long 100 Hz logs (grid from 0.64 s), less where 8 coarse samples
    /// would pass 1 s or the shortest log would hold under 2^12 coarse samples, none at 10 Hz.
    #[test]
    fn decimation_keeps_the_grid_start_and_length() {
        let at = |dt: f64, samples: Vec<usize>| {
            bootstrap_decimation(&FittedOn {
                sample_interval_s: dt,
                samples,
                channels: ImuChannels([true; 6]),
                tau_min_s: 0.0,
                run_to_run: Vec::new(),
            })
        };
        assert_eq!(at(0.01, vec![1_000_000, 1_000_000]), Some(8));
        assert_eq!(at(0.01, vec![1_000_000, 20_000]), Some(4));
        assert_eq!(at(0.01, vec![8_000]), None);
        assert_eq!(at(0.05, vec![1_000_000]), Some(2));
        assert_eq!(at(0.1, vec![216_000]), None);
        assert_eq!(at(0.001, vec![1_000_000]), Some(8));
    }

    /// NNLS against a brute-force check: an exact non-negative solution is found, and a column
    /// whose unconstrained coefficient is negative is set to 0 with the others refitted.
    #[test]
    fn nnls_finds_the_constrained_optimum() {
        let cols = [[1.0, 1.0, 1.0, 1.0], [1.0, 2.0, 3.0, 4.0]];
        let rows: Vec<Vec<f64>> = (0..4).map(|i| vec![cols[0][i], cols[1][i]]).collect();
        let y: Vec<f64> = (0..4)
            .map(|i| 2.0 * cols[0][i] + 0.5 * cols[1][i])
            .collect();
        let x = nnls_small(&rows, &y, 2);
        assert!(
            (x[0] - 2.0).abs() < 1e-12 && (x[1] - 0.5).abs() < 1e-12,
            "{x:?}"
        );
        // y = 5 - t: the unconstrained slope is negative, so x1 = 0 and x0 = mean(y) = 2.5.
        let y: Vec<f64> = (0..4).map(|i| 5.0 - cols[1][i]).collect();
        let x = nnls_small(&rows, &y, 2);
        assert_eq!(x[1], 0.0);
        assert!((x[0] - 2.5).abs() < 1e-12, "{x:?}");
    }
}
