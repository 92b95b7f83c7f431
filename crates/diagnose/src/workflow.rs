//! The diagnose loop (docs/diagnose.md, "The diagnose workflow", steps 1-6): measure, simulate, locate the gap,
//! name and fit the missing effect, add it, re-simulate, repeat; then the drift consequence.

use crate::candidates::{
    free_parameters, shape_grid, shape_search_penalty, unit_family_signature, unit_signature,
    TermParams, CANDIDATES,
};
use crate::drift::{segment_drift, DriftSummary, CHANNELS};
use crate::fit::{
    aic, bic, birge_scale, fit_family, fit_linear, linear_interval, predicted_ln_adev, FitData,
    LinearFit, CHI2_1_95,
};
use crate::gap::{gap, Band, Curve, Disagreement, Gap};
use crate::model_terms::{flicker_band, has_random_walk_bias_instability, set_term, term_level};
use crate::simulate::{adev_at, simulate, SimError, SimResult, SimSetup};
use allan::{DataKind, Estimator, TauGrid};
use noise::{Effect, SensorModel};
use serde::Serialize;
use std::collections::BTreeMap;

/// The measured log, SI, channels in the order gx gy gz ax ay az (None: not in the log).
#[derive(Clone, Copy, Debug)]
pub struct LogInput<'a> {
    pub dt_s: f64,
    pub channels: [Option<&'a [f64]>; 6],
    pub temperature_c: Option<&'a [f64]>,
}

/// Settings of the workflow.
#[derive(Clone, Debug)]
pub struct Settings {
    /// Master seed of the simulated logs (written into the report).
    pub seed: u64,
    /// Simulated logs per band.
    pub seeds: usize,
    /// Add-and-resimulate rounds at most.
    pub max_rounds: usize,
    /// Drift horizons, seconds (docs/cli.md: 60 s and 1 h).
    pub horizons_s: Vec<f64>,
    /// An effect is named only if it lowers BIC by at least this much. Above 10 is "very strong"
    /// evidence on the Kass & Raftery (1995) scale; 16 sets the false-alarm rate: for one parameter and
    /// M ~ 15 taus it needs delta chi2 >= 18.7, a chi2_1 tail of 1.5e-5 if nothing is missing, so about
    /// 1e-3 per 6-channel log over the ~8 candidates per channel (measured on clean logs: see the
    /// hidden-effect tests; the tails of ln adev at small EDF are heavier than Gaussian).
    pub min_delta_bic: f64,
    /// Candidates whose BIC is within this of the best are reported as indistinguishable from it
    /// (below 6 the evidence for the best is not "strong", Kass & Raftery 1995).
    pub ambiguity_delta_bic: f64,
    /// Effects a channel may take in one round before the model is re-simulated.
    pub effects_per_round: usize,
    /// Taus below this are left out (e.g. where a sensor's internal anti-alias filter shapes the curve,
    /// an effect outside the candidate set), s.
    pub tau_min_s: f64,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            seed: 1,
            seeds: 16,
            max_rounds: 6,
            horizons_s: vec![60.0, 3600.0],
            min_delta_bic: 16.0,
            ambiguity_delta_bic: 6.0,
            effects_per_round: 3,
            tau_min_s: 0.0,
        }
    }
}

/// Errors of the workflow (inputs the caller has to fix, or a failed simulation).
#[derive(Debug, thiserror::Error)]
pub enum DiagnoseError {
    #[error("the log has no gyro or accelerometer channel (expected columns gx gy gz ax ay az)")]
    NoChannels,
    #[error("channel {channel} has {got} samples, channel {first} has {expected}: all channels must have the same length")]
    Length {
        channel: &'static str,
        got: usize,
        first: &'static str,
        expected: usize,
    },
    #[error(
        "the log is too short for an Allan analysis ({samples} samples; at least 64 are needed)"
    )]
    TooShort { samples: usize },
    #[error("sample interval must be positive and finite, got {0} s")]
    BadInterval(f64),
    #[error("the temperature column has {got} samples, the log {expected}")]
    TemperatureLength { got: usize, expected: usize },
    #[error("no Allan point at or above --tau-min {tau_min_s} s")]
    NoTaus { tau_min_s: f64 },
    #[error("a log checked against the diagnosis must have its rate and length: got {samples} samples at {dt_s} s, expected {expected_samples} at {expected_dt_s} s")]
    CheckShape {
        samples: usize,
        dt_s: f64,
        expected_samples: usize,
        expected_dt_s: f64,
    },
    #[error(transparent)]
    Simulation(#[from] SimError),
}

/// A named effect: what, how much (95 % interval), and the gap around it.
#[derive(Clone, Debug, Serialize)]
pub struct FoundEffect {
    pub effect: String,
    /// SI parameters (docs/cli.md names).
    pub parameters: BTreeMap<String, f64>,
    /// 95 % profile-likelihood interval of each parameter.
    pub parameters_lo: BTreeMap<String, f64>,
    pub parameters_hi: BTreeMap<String, f64>,
    /// "missing" (the model lacks the term) or "wrong_level" (it has it at another level).
    pub kind: String,
    /// The model's own parameters when `kind` is "wrong_level".
    pub model_parameters: Option<BTreeMap<String, f64>>,
    /// Channel gap (RMS z) with the model before and after the round that added the effect (both
    /// simulated; effects found in the same round share them), and as the closed forms predicted it
    /// right after adding this effect.
    pub gap_before: f64,
    pub gap_predicted: f64,
    pub gap_after: f64,
    /// BIC improvement over the unchanged model.
    pub delta_bic: f64,
    /// Other candidates the data cannot tell from this one (BIC within `ambiguity_delta_bic`).
    pub cannot_tell_from: Vec<String>,
    /// Round in which it was found (1 = first).
    pub round: usize,
    /// Later rounds that refitted its level after re-simulation.
    pub refinements: usize,
}

/// Why a candidate was weighed: its BIC gain and fitted parameters (every candidate, every round).
#[derive(Clone, Debug, Serialize)]
pub struct CandidateRecord {
    pub round: usize,
    pub effect: String,
    /// BIC (the selection criterion) and AIC improvement over the model without it (both with the
    /// shape-search cost); `delta_aic` is NaN on the record of a rejected round.
    pub delta_bic: f64,
    pub delta_aic: f64,
    pub parameters: BTreeMap<String, f64>,
}

/// Curves of one channel for plots: measured with 1-sigma interval, band before and after.
#[derive(Clone, Debug, Serialize)]
pub struct ChannelCurves {
    pub tau_s: Vec<f64>,
    pub adev: Vec<f64>,
    pub adev_lo: Vec<f64>,
    pub adev_hi: Vec<f64>,
    pub edf: Vec<f64>,
    pub band_initial: BandView,
    pub band_final: BandView,
}

/// Band centre and 95 % seed range.
#[derive(Clone, Debug, Serialize)]
pub struct BandView {
    pub centre: Vec<f64>,
    pub lo: Vec<f64>,
    pub hi: Vec<f64>,
}

/// Everything diagnose says about one channel.
#[derive(Clone, Debug, Serialize)]
pub struct ChannelReport {
    pub gap_initial: f64,
    pub gap_final: f64,
    pub effects: Vec<FoundEffect>,
    pub z_initial: Vec<f64>,
    pub z_final: Vec<f64>,
    pub disagreements_initial: Vec<Disagreement>,
    pub disagreements_final: Vec<Disagreement>,
    /// One sentence: agrees, or what remains unexplained.
    pub verdict: String,
    pub candidates: Vec<CandidateRecord>,
    pub curves: ChannelCurves,
}

/// Drift over one horizon: measured-log segments vs the model before and after.
#[derive(Clone, Debug, Serialize)]
pub struct DriftRow {
    pub horizon_s: f64,
    pub measured: DriftSummary,
    pub model_initial: DriftSummary,
    pub model_final: DriftSummary,
}

/// The result of diagnose.
#[derive(Clone, Debug, Serialize)]
pub struct Diagnosis {
    pub seed: u64,
    pub seeds: usize,
    pub rounds: usize,
    pub dt_s: f64,
    pub samples: usize,
    pub channels: BTreeMap<String, ChannelReport>,
    pub drift: Vec<DriftRow>,
    /// Shortest tau analysed, s.
    pub tau_min_s: f64,
    /// The corrected model (written as TOML by the CLI).
    #[serde(skip)]
    pub model_final: SensorModel,
    /// Averaging factors of the tau grid and the bands of the original and corrected models (for
    /// checking held-out logs).
    #[serde(skip)]
    pub grid_m: Vec<usize>,
    #[serde(skip)]
    pub bands_initial: [Option<Band>; 6],
    #[serde(skip)]
    pub bands_final: [Option<Band>; 6],
}

/// One channel's measurement on the common grid: indices into the grid it has valid points at.
struct Measured {
    idx: Vec<usize>,
    curve: Curve,
    lo: Vec<f64>,
    hi: Vec<f64>,
}

/// Measured Allan deviations of every channel in the log on the octave grid, and the grid's averaging
/// factors. Points without a positive deviation and EDF, or below `tau_min_s`, are left out.
fn measure(log: &LogInput, tau_min_s: f64) -> (Vec<usize>, [Option<Measured>; 6]) {
    let mut grid_m: Vec<usize> = Vec::new();
    let mut points: [Vec<allan::AllanPoint>; 6] = Default::default();
    for c in 0..6 {
        if let Some(s) = log.channels[c] {
            points[c] = allan::deviation(
                s,
                DataKind::Rate,
                log.dt_s,
                Estimator::Overlapping,
                &TauGrid::Octave,
            );
            if grid_m.is_empty() {
                grid_m = points[c].iter().map(|p| p.m).collect();
            }
        }
    }
    let measured = std::array::from_fn(|c| {
        log.channels[c]?;
        let mut idx = Vec::new();
        let (mut tau, mut adev, mut edf, mut lo, mut hi) = (vec![], vec![], vec![], vec![], vec![]);
        for p in &points[c] {
            let Some(i) = grid_m.iter().position(|&m| m == p.m) else {
                continue;
            };
            let valid = p.dev > 0.0 && p.dev.is_finite() && p.edf > 0.0 && p.edf.is_finite();
            if valid && p.tau_s >= tau_min_s {
                idx.push(i);
                tau.push(p.tau_s);
                adev.push(p.dev);
                edf.push(p.edf);
                lo.push(p.lo);
                hi.push(p.hi);
            }
        }
        Some(Measured {
            idx,
            curve: Curve {
                tau_s: tau,
                adev,
                edf,
            },
            lo,
            hi,
        })
    });
    (grid_m, measured)
}

/// Gap of a held-out log against the model before and after diagnosis.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct HeldOutGap {
    pub gap_model: f64,
    pub gap_corrected: f64,
}

impl Diagnosis {
    /// The gap of another log of the same rate and length (data the diagnosis did not see) against the
    /// original model's band and the corrected model's band, per channel.
    pub fn check(&self, log: &LogInput) -> Result<BTreeMap<String, HeldOutGap>, DiagnoseError> {
        let samples = validate(log)?;
        if samples != self.samples || (log.dt_s - self.dt_s).abs() > 1e-12 * self.dt_s {
            return Err(DiagnoseError::CheckShape {
                samples,
                dt_s: log.dt_s,
                expected_samples: self.samples,
                expected_dt_s: self.dt_s,
            });
        }
        let (grid_m, measured) = measure(log, self.tau_min_s);
        let mut out = BTreeMap::new();
        for c in 0..6 {
            let (Some(m), Some(b0), Some(b1)) = (
                measured[c].as_ref(),
                self.bands_initial[c].as_ref(),
                self.bands_final[c].as_ref(),
            ) else {
                continue;
            };
            if grid_m != self.grid_m {
                return Err(DiagnoseError::CheckShape {
                    samples,
                    dt_s: log.dt_s,
                    expected_samples: self.samples,
                    expected_dt_s: self.dt_s,
                });
            }
            out.insert(
                CHANNELS[c].to_string(),
                HeldOutGap {
                    gap_model: gap(&m.curve, &restrict(b0, &m.idx)).rms,
                    gap_corrected: gap(&m.curve, &restrict(b1, &m.idx)).rms,
                },
            );
        }
        Ok(out)
    }
}

/// Check the log's shape; returns the number of samples.
fn validate(log: &LogInput) -> Result<usize, DiagnoseError> {
    if !(log.dt_s > 0.0 && log.dt_s.is_finite()) {
        return Err(DiagnoseError::BadInterval(log.dt_s));
    }
    let first = (0..6)
        .find(|&c| log.channels[c].is_some())
        .ok_or(DiagnoseError::NoChannels)?;
    let samples = log.channels[first].map(|c| c.len()).unwrap_or(0);
    for c in 0..6 {
        if let Some(s) = log.channels[c] {
            if s.len() != samples {
                return Err(DiagnoseError::Length {
                    channel: CHANNELS[c],
                    got: s.len(),
                    first: CHANNELS[first],
                    expected: samples,
                });
            }
        }
    }
    if samples < 64 {
        return Err(DiagnoseError::TooShort { samples });
    }
    if let Some(t) = log.temperature_c {
        if t.len() != samples {
            return Err(DiagnoseError::TemperatureLength {
                got: t.len(),
                expected: samples,
            });
        }
    }
    Ok(samples)
}

/// Restrict a band to a channel's valid grid indices.
fn restrict(band: &Band, idx: &[usize]) -> Band {
    let pick = |v: &[f64]| idx.iter().map(|&i| v[i]).collect::<Vec<f64>>();
    Band {
        tau_s: pick(&band.tau_s),
        ln_mean: pick(&band.ln_mean),
        ln_sd: pick(&band.ln_sd),
        avar_mean: pick(&band.avar_mean),
        adev_lo: pick(&band.adev_lo),
        adev_hi: pick(&band.adev_hi),
        seeds: band.seeds,
    }
}

/// A channel changed in this round: (channel, [(effect, previous level)], gap at the round's start).
type Pending = (usize, Vec<(Effect, Option<TermParams>)>, f64);

/// A fitted candidate before selection.
struct Trial {
    effect: Effect,
    params: TermParams,
    lo: TermParams,
    hi: TermParams,
    model: Option<TermParams>,
    bic: f64,
    aic: f64,
    /// (c - c0) f(tau): the change of the band's Allan variance.
    delta_avar: Vec<f64>,
}

fn sqrt_params(p: TermParams, c: f64) -> TermParams {
    match p {
        TermParams::Level(v) => {
            TermParams::Level(c.max(0.0).sqrt().copysign(if v < 0.0 { -1.0 } else { 1.0 }))
        }
        TermParams::GaussMarkov { tau_s, .. } => TermParams::GaussMarkov {
            sigma: c.max(0.0).sqrt(),
            tau_s,
        },
        TermParams::Sinusoid { frequency_hz, .. } => TermParams::Sinusoid {
            amplitude: c.max(0.0).sqrt(),
            frequency_hz,
        },
    }
}

/// Fit every candidate to one channel; the trials are in CANDIDATES order.
#[allow(clippy::too_many_arguments)]
fn trials(
    model: &SensorModel,
    ch: usize,
    measured: &Curve,
    band: &Band,
    g: &Gap,
    dt_s: f64,
    temp: Option<(&[f64], f64, f64)>,
    ramp_slope: f64,
) -> Vec<Trial> {
    let ln_meas: Vec<f64> = measured.adev.iter().map(|a| a.ln()).collect();
    let data = FitData {
        ln_meas: &ln_meas,
        ln_band: &band.ln_mean,
        avar_band: &band.avar_mean,
        s: &g.s,
    };
    let m = ln_meas.len();
    let tau = &measured.tau_s;
    let mut out = Vec::new();
    for effect in CANDIDATES {
        // A Woodman random-walk bias instability occupies the axis's one bias-instability slot; a flicker
        // candidate would replace it, so it is not offered (its level shows as a rate random walk).
        if effect == Effect::BiasInstability && has_random_walk_bias_instability(model, ch) {
            continue;
        }
        let k = free_parameters(effect);
        let current = term_level(model, ch, effect);
        // Signature(s) of this candidate.
        let shaped = matches!(effect, Effect::GaussMarkov | Effect::Sinusoidal);
        let (fit, params, shape_lo, shape_hi, f, penalty): (
            LinearFit,
            TermParams,
            f64,
            f64,
            Vec<f64>,
            f64,
        ) = if shaped {
            // A term the model has keeps its shape (a wrong level); an absent one is searched over shapes.
            let shapes = match current.and_then(|c| c.shape()) {
                Some(s) => vec![s],
                None => shape_grid(effect, tau[0], tau[m - 1], dt_s),
            };
            let sigs: Vec<Vec<f64>> = shapes
                .iter()
                .map(|&s| {
                    tau.iter()
                        .map(|&t| unit_family_signature(effect, s, t, dt_s))
                        .collect()
                })
                .collect();
            let c0 = current.map(|c| c.c()).unwrap_or(0.0);
            let Some(ff) = fit_family(&data, &shapes, &sigs, &|_| c0) else {
                continue;
            };
            let j = shapes.iter().position(|&s| s == ff.shape).unwrap_or(0);
            let p = match effect {
                Effect::GaussMarkov => TermParams::GaussMarkov {
                    sigma: ff.fit.c.sqrt(),
                    tau_s: ff.shape,
                },
                _ => TermParams::Sinusoid {
                    amplitude: ff.fit.c.sqrt(),
                    frequency_hz: ff.shape,
                },
            };
            // Shape interval at the 95 % threshold widened by this fit's Birge ratio.
            let scale = birge_scale(ff.fit.chi2, k, m);
            let (shape_lo, shape_hi) = ff.shape_interval(CHI2_1_95 * scale * scale);
            (
                ff.fit,
                p,
                shape_lo,
                shape_hi,
                sigs[j].clone(),
                shape_search_penalty(shapes.len()),
            )
        } else if effect == Effect::TemperatureBias {
            // The sign comes from the correlation with temperature (the Allan signature is even).
            let Some((temp_avar, sign, current_k)) = temp else {
                continue;
            };
            let f: Vec<f64> = temp_avar.to_vec();
            let fit = fit_linear(&data, &f, current_k * current_k);
            (
                fit,
                TermParams::Level(fit.c.sqrt() * sign),
                0.0,
                0.0,
                f,
                0.0,
            )
        } else {
            let flicker = flicker_band(model, ch);
            let f: Vec<f64> = tau
                .iter()
                .map(|&t| unit_signature(effect, t, dt_s, &flicker))
                .collect();
            let c0 = current.map(|c| c.c()).unwrap_or(0.0);
            let fit = fit_linear(&data, &f, c0);
            if effect == Effect::RateRamp {
                // A ramp is deterministic: its level is the least-squares slope of the log (the ML
                // estimate of a ramp in white noise), not a free Allan parameter. A long-tau rise that is
                // really a random walk then fits as a ramp only if the log does drift that way, which the
                // last two or three Allan points (a handful of EDF) cannot tell.
                let c = ramp_slope * ramp_slope;
                let ramp = LinearFit {
                    c,
                    chi2: data.chi2(&f, c - c0),
                    ..fit
                };
                (ramp, TermParams::Level(ramp_slope), 0.0, 0.0, f, 0.0)
            } else {
                (fit, TermParams::Level(fit.c.sqrt()), 0.0, 0.0, f, 0.0)
            }
        };
        let c0 = match (effect, temp) {
            (Effect::TemperatureBias, Some((_, _, k))) => k * k,
            _ => current.map(|c| c.c()).unwrap_or(0.0),
        };
        // 95 % interval widened by the Birge ratio of this fit.
        let scale = birge_scale(fit.chi2, k, m);
        // (For the ramp: the profile interval of the Allan fit alone, around its own optimum.)
        let allan_fit = if effect == Effect::RateRamp {
            fit_linear(&data, &f, c0)
        } else {
            fit
        };
        let (c_lo, c_hi) = linear_interval(&data, &f, c0, &allan_fit, CHI2_1_95 * scale * scale);
        let mut lo = sqrt_params(params, c_lo);
        let mut hi = sqrt_params(params, c_hi);
        if let (TermParams::Level(l), TermParams::Level(h)) = (lo, hi) {
            if l > h {
                (lo, hi) = (TermParams::Level(h), TermParams::Level(l));
            }
        }
        match (&mut lo, &mut hi) {
            (
                TermParams::GaussMarkov { tau_s: a, .. },
                TermParams::GaussMarkov { tau_s: b, .. },
            )
            | (
                TermParams::Sinusoid {
                    frequency_hz: a, ..
                },
                TermParams::Sinusoid {
                    frequency_hz: b, ..
                },
            ) => {
                *a = shape_lo;
                *b = shape_hi;
            }
            _ => {}
        }
        out.push(Trial {
            effect,
            params,
            lo,
            hi,
            model: if effect == Effect::TemperatureBias {
                None
            } else {
                current
            },
            bic: bic(fit.chi2, k, m) + penalty,
            aic: aic(fit.chi2, k) + penalty,
            delta_avar: f.iter().map(|v| (fit.c - c0) * v).collect(),
        });
    }
    out
}

fn named_map(effect: Effect, p: &TermParams) -> BTreeMap<String, f64> {
    p.named(effect)
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect()
}

/// Run the diagnose workflow on a measured log against a sensor model.
pub fn diagnose(
    log: &LogInput,
    model: &SensorModel,
    settings: &Settings,
) -> Result<Diagnosis, DiagnoseError> {
    diagnose_with_progress(log, model, settings, &|_| {})
}

/// [`diagnose`], telling `progress` what it is doing before each long step (for a progress display).
pub fn diagnose_with_progress(
    log: &LogInput,
    model: &SensorModel,
    settings: &Settings,
    progress: &dyn Fn(&str),
) -> Result<Diagnosis, DiagnoseError> {
    let samples = validate(log)?;
    progress("measuring the log's Allan deviations");
    let active: [bool; 6] = std::array::from_fn(|c| log.channels[c].is_some());

    // Step 1: measured Allan deviations with EDF (Greenhall, noise type by lag-1 ACF) on the octave grid.
    let (grid_m, measured) = measure(log, settings.tau_min_s);
    if measured.iter().flatten().all(|m| m.idx.is_empty()) {
        return Err(DiagnoseError::NoTaus {
            tau_min_s: settings.tau_min_s,
        });
    }

    // Temperature signature per grid point and the sign of each channel's correlation with temperature.
    let temp_avar: Option<Vec<f64>> = log.temperature_c.map(|t| {
        adev_at(t, log.dt_s, &grid_m)
            .iter()
            .map(|a| a * a)
            .collect()
    });
    let temp_sign: [f64; 6] = std::array::from_fn(|c| match (log.channels[c], log.temperature_c) {
        (Some(x), Some(t)) => {
            let (mx, mt) = (mean(x), mean(t));
            let cov: f64 = x.iter().zip(t).map(|(a, b)| (a - mx) * (b - mt)).sum();
            if cov < 0.0 {
                -1.0
            } else {
                1.0
            }
        }
        _ => 1.0,
    });

    // Least-squares slope of each channel against time (the rate-ramp level, see `trials`).
    let ramp_slope: [f64; 6] =
        std::array::from_fn(|c| log.channels[c].map_or(0.0, |x| slope(x, log.dt_s)));

    // Step 2: the model's band.
    let mut setup = SimSetup {
        dt_s: log.dt_s,
        samples,
        grid_m: grid_m.clone(),
        active,
        horizons_s: settings.horizons_s.clone(),
        temperature_c: log.temperature_c,
        temp_coeff: [0.0; 6],
    };
    let mut sim_model = model.clone();
    let mut out_model = model.clone();
    progress("simulating the model's band");
    let sim0: SimResult = simulate(&sim_model, &setup, settings.seed, settings.seeds)?;
    let mut bands: [Option<Band>; 6] = sim0.bands.clone();
    let mut last_drift = sim0.drift.clone();
    let mut dirty = false;

    let gap_of = |c: usize, bands: &[Option<Band>; 6]| -> Option<(Band, Gap)> {
        let m = measured[c].as_ref()?;
        let b = restrict(bands[c].as_ref()?, &m.idx);
        let g = gap(&m.curve, &b);
        Some((b, g))
    };
    let initial: [Option<(Band, Gap)>; 6] = std::array::from_fn(|c| gap_of(c, &bands));
    let mut effects: [Vec<FoundEffect>; 6] = Default::default();
    let mut records: [Vec<CandidateRecord>; 6] = Default::default();
    let mut done: [bool; 6] = std::array::from_fn(|c| !active[c]);
    let mut rounds = 0;

    // Steps 3-5: name, add, re-simulate, until nothing significant remains. Within a round a channel
    // takes up to `effects_per_round` effects by forward selection on the closed-form prediction (so a
    // short-tau disagreement with huge z does not hold back a long-tau one for many rounds); the round's
    // re-simulation then checks them together.
    for round in 1..=settings.max_rounds {
        let mut pending: Vec<Pending> = Vec::new();
        for c in 0..6 {
            if done[c] {
                continue;
            }
            let Some((band, g)) = gap_of(c, &bands) else {
                done[c] = true;
                continue;
            };
            let m = measured[c].as_ref().expect("active channel is measured");
            if g.disagreements.is_empty() {
                done[c] = true;
                continue;
            }
            let temp = temp_avar.as_ref().map(|t| {
                (
                    m.idx.iter().map(|&i| t[i]).collect::<Vec<f64>>(),
                    temp_sign[c],
                )
            });
            let ln_meas: Vec<f64> = m.curve.adev.iter().map(|a| a.ln()).collect();
            let mut predicted = band.clone();
            let mut g_pred = g.clone();
            let mut changes: Vec<(Effect, Option<TermParams>)> = Vec::new();
            for _step in 0..settings.effects_per_round {
                if g_pred.disagreements.is_empty() {
                    break;
                }
                let ts = trials(
                    &sim_model,
                    c,
                    &m.curve,
                    &predicted,
                    &g_pred,
                    log.dt_s,
                    temp.as_ref()
                        .map(|(v, s)| (v.as_slice(), *s, setup.temp_coeff[c])),
                    ramp_slope[c],
                );
                let data = FitData {
                    ln_meas: &ln_meas,
                    ln_band: &predicted.ln_mean,
                    avar_band: &predicted.avar_mean,
                    s: &g_pred.s,
                };
                let base_bic = bic(data.chi2_base(), 0, ln_meas.len());
                for t in &ts {
                    records[c].push(CandidateRecord {
                        round,
                        effect: t.effect.name().to_string(),
                        delta_bic: base_bic - t.bic,
                        delta_aic: data.chi2_base() - t.aic,
                        parameters: named_map(t.effect, &t.params),
                    });
                }
                let Some(mut best) = ts.iter().min_by(|a, b| a.bic.total_cmp(&b.bic)) else {
                    break;
                };
                // Occam: re-levelling an effect already named on this channel is preferred to naming
                // another one unless the other is better by the ambiguity margin.
                if let Some(refine) = ts
                    .iter()
                    .filter(|t| effects[c].iter().any(|e| e.effect == t.effect.name()))
                    .min_by(|a, b| a.bic.total_cmp(&b.bic))
                {
                    if refine.bic - best.bic < settings.ambiguity_delta_bic {
                        best = refine;
                    }
                }
                let delta = base_bic - best.bic;
                if delta < settings.min_delta_bic {
                    break;
                }
                let cannot_tell_from: Vec<String> = ts
                    .iter()
                    .filter(|t| {
                        t.effect != best.effect && t.bic - best.bic < settings.ambiguity_delta_bic
                    })
                    .map(|t| t.effect.name().to_string())
                    .collect();
                let previous = if best.effect == Effect::TemperatureBias {
                    (setup.temp_coeff[c] != 0.0).then_some(TermParams::Level(setup.temp_coeff[c]))
                } else {
                    term_level(&sim_model, c, best.effect)
                };
                if best.effect == Effect::TemperatureBias {
                    if let TermParams::Level(k) = best.params {
                        setup.temp_coeff[c] = k;
                    }
                } else {
                    set_term(&mut sim_model, c, best.effect, &best.params);
                }
                set_term(&mut out_model, c, best.effect, &best.params);
                // The closed-form prediction of the band with this change, for the next step.
                predicted = shifted_band(&predicted, &best.delta_avar);
                g_pred = gap(&m.curve, &predicted);
                effects[c].push(FoundEffect {
                    effect: best.effect.name().to_string(),
                    parameters: named_map(best.effect, &best.params),
                    parameters_lo: named_map(best.effect, &best.lo),
                    parameters_hi: named_map(best.effect, &best.hi),
                    kind: if best.model.is_some() {
                        "wrong_level"
                    } else {
                        "missing"
                    }
                    .to_string(),
                    model_parameters: best.model.map(|p| named_map(best.effect, &p)),
                    gap_before: g.rms,
                    gap_predicted: g_pred.rms,
                    gap_after: f64::NAN,
                    delta_bic: delta,
                    cannot_tell_from,
                    round,
                    refinements: 0,
                });
                changes.push((best.effect, previous));
            }
            if changes.is_empty() {
                done[c] = true;
            } else {
                pending.push((c, changes, g.rms));
            }
        }
        if pending.is_empty() {
            break;
        }
        rounds = round;
        progress(&format!("round {round}: re-simulating the corrected model"));
        let sim = simulate(&sim_model, &setup, settings.seed, settings.seeds)?;
        dirty = false;
        for (c, changes, gap_before) in pending {
            let new_bands = {
                let mut b = bands.clone();
                b[c] = sim.bands[c].clone();
                b
            };
            let after = gap_of(c, &new_bands)
                .map(|(_, g)| g.rms)
                .unwrap_or(f64::NAN);
            let first_new = effects[c].len() - changes.len();
            for found in &mut effects[c][first_new..] {
                found.gap_after = after;
            }
            if after.is_nan() || after >= gap_before {
                // The re-simulated model is no closer: undo this round's changes and stop here.
                for rejected in effects[c].drain(first_new..) {
                    records[c].push(CandidateRecord {
                        round,
                        effect: format!(
                            "{} rejected: gap did not shrink on re-simulation",
                            rejected.effect
                        ),
                        delta_bic: rejected.delta_bic,
                        delta_aic: f64::NAN,
                        parameters: rejected.parameters,
                    });
                }
                for (effect, previous) in changes.into_iter().rev() {
                    restore(
                        &mut sim_model,
                        &mut out_model,
                        &mut setup,
                        c,
                        effect,
                        previous,
                    );
                }
                done[c] = true;
                dirty = true;
            } else {
                bands[c] = sim.bands[c].clone();
                merge_refinements(&mut effects[c], first_new);
            }
        }
        last_drift = sim.drift;
    }
    if dirty {
        last_drift = simulate(&sim_model, &setup, settings.seed, settings.seeds)?.drift;
    }

    // Step 6: drift consequence, measured log segments vs model before vs model after.
    let gyro_accel: [Option<&[f64]>; 6] = log.channels;
    let drift = settings
        .horizons_s
        .iter()
        .enumerate()
        .map(|(h, &horizon)| DriftRow {
            horizon_s: horizon,
            measured: segment_drift(&gyro_accel, log.dt_s, horizon).summary(),
            model_initial: sim0.drift[h].summary(),
            model_final: last_drift[h].summary(),
        })
        .collect();

    let mut channels = BTreeMap::new();
    for c in 0..6 {
        let (Some(m), Some((b0, g0)), Some((b1, g1))) =
            (measured[c].as_ref(), initial[c].clone(), gap_of(c, &bands))
        else {
            continue;
        };
        let verdict = verdict(&g1, &effects[c]);
        channels.insert(
            CHANNELS[c].to_string(),
            ChannelReport {
                gap_initial: g0.rms,
                gap_final: g1.rms,
                effects: std::mem::take(&mut effects[c]),
                z_initial: g0.z,
                z_final: g1.z.clone(),
                disagreements_initial: g0.disagreements,
                disagreements_final: g1.disagreements,
                verdict,
                candidates: std::mem::take(&mut records[c]),
                curves: ChannelCurves {
                    tau_s: m.curve.tau_s.clone(),
                    adev: m.curve.adev.clone(),
                    adev_lo: m.lo.clone(),
                    adev_hi: m.hi.clone(),
                    edf: m.curve.edf.clone(),
                    band_initial: BandView {
                        centre: b0.centre(),
                        lo: b0.adev_lo.clone(),
                        hi: b0.adev_hi.clone(),
                    },
                    band_final: BandView {
                        centre: b1.centre(),
                        lo: b1.adev_lo,
                        hi: b1.adev_hi,
                    },
                },
            },
        );
    }
    Ok(Diagnosis {
        seed: settings.seed,
        seeds: settings.seeds,
        rounds,
        dt_s: log.dt_s,
        samples,
        channels,
        drift,
        tau_min_s: settings.tau_min_s,
        model_final: out_model,
        grid_m,
        bands_initial: sim0.bands,
        bands_final: bands,
    })
}

fn restore(
    sim_model: &mut SensorModel,
    out_model: &mut SensorModel,
    setup: &mut SimSetup,
    c: usize,
    effect: Effect,
    previous: Option<TermParams>,
) {
    if effect == Effect::TemperatureBias {
        match previous {
            Some(TermParams::Level(k)) => {
                setup.temp_coeff[c] = k;
                set_term(out_model, c, effect, &TermParams::Level(k));
            }
            _ => {
                setup.temp_coeff[c] = 0.0;
                crate::model_terms::clear_term(out_model, c, effect);
            }
        }
        return;
    }
    for model in [sim_model, out_model] {
        match previous {
            Some(p) => set_term(model, c, effect, &p),
            None => crate::model_terms::clear_term(model, c, effect),
        }
    }
}

/// A later round that changes the level of an effect already named on the channel refines that finding
/// rather than naming a second one: the earlier entry takes the new parameters and the new gap after,
/// and keeps its kind, model parameters and gap before (the same holds for a second change of one
/// effect within a round). `first_new` is where this round's entries start.
fn merge_refinements(effects: &mut Vec<FoundEffect>, first_new: usize) {
    let mut i = first_new;
    while i < effects.len() {
        match effects[..i]
            .iter()
            .position(|e| e.effect == effects[i].effect)
        {
            Some(j) => {
                let last = effects.remove(i);
                let first = &mut effects[j];
                first.parameters = last.parameters;
                first.parameters_lo = last.parameters_lo;
                first.parameters_hi = last.parameters_hi;
                first.gap_predicted = last.gap_predicted;
                first.gap_after = last.gap_after;
                first.delta_bic += last.delta_bic;
                first.cannot_tell_from = last.cannot_tell_from;
                first.refinements += 1;
            }
            None => i += 1,
        }
    }
}

/// The band with `delta_avar` added to its mean Allan variance, ln adev moved accordingly (the spread is
/// kept: it is re-estimated when the changed model is simulated).
fn shifted_band(band: &Band, delta_avar: &[f64]) -> Band {
    let mut out = band.clone();
    for i in 0..out.avar_mean.len() {
        let ln = predicted_ln_adev(band.ln_mean[i], band.avar_mean[i], delta_avar[i]);
        let factor = (ln - band.ln_mean[i]).exp();
        out.ln_mean[i] = ln;
        out.avar_mean[i] = (2.0 * ln)
            .exp()
            .max(band.avar_mean[i] + delta_avar[i])
            .max(0.0);
        out.adev_lo[i] = band.adev_lo[i] * factor;
        out.adev_hi[i] = band.adev_hi[i] * factor;
    }
    out
}

fn verdict(g: &Gap, effects: &[FoundEffect]) -> String {
    let named = if effects.is_empty() {
        "no effect named".to_string()
    } else {
        effects
            .iter()
            .map(|e| e.effect.as_str())
            .collect::<Vec<_>>()
            .join(" + ")
    };
    if g.disagreements.is_empty() {
        format!("model agrees with the measurement ({named}); no tau with |z| > 3")
    } else {
        let ranges: Vec<String> = g
            .disagreements
            .iter()
            .map(|d| {
                format!(
                    "{:.4}-{:.4} s (max |z| {:.1})",
                    d.tau_lo_s, d.tau_hi_s, d.max_abs_z
                )
            })
            .collect();
        format!(
            "{named}; still disagreeing at {} and no candidate improves BIC enough to explain it",
            ranges.join(", ")
        )
    }
}

/// Ordinary least-squares slope of x_k against t_k = k dt: sum (t - t_mean)(x - x_mean) / sum (t - t_mean)^2.
fn slope(x: &[f64], dt_s: f64) -> f64 {
    let n = x.len() as f64;
    let t_mean = (n - 1.0) / 2.0 * dt_s;
    let x_mean = mean(x);
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (k, &v) in x.iter().enumerate() {
        let dt = k as f64 * dt_s - t_mean;
        sxy += dt * (v - x_mean);
        sxx += dt * dt;
    }
    if sxx > 0.0 {
        sxy / sxx
    } else {
        0.0
    }
}

fn mean(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len().max(1) as f64
}
