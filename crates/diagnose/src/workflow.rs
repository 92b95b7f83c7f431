//! The diagnose loop (docs/diagnose.md, "The diagnose workflow", steps 1-6): measure, simulate, locate the gap,
//! name and fit the missing effect, add it, re-simulate, repeat; then the drift consequence.

use crate::candidates::TermParams;
use crate::drift::{segment_drift, CHANNELS};
use crate::fit::{bic, predicted_ln_adev, FitData};
use crate::gap::{gap, Band, Gap};
use crate::measure::*;
use crate::model_terms::{set_term, term_level};
use crate::report::*;
use crate::simulate::{adev_at, simulate, SimResult, SimSetup};
use crate::trials::*;
use noise::{Effect, SensorModel};
use std::collections::BTreeMap;

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
    progress("looking for outliers, temperature effects and a warm-up transient");
    let active: [bool; 6] = std::array::from_fn(|c| log.channels[c].is_some());
    let raw_log = log;
    // Step 0: time-domain detectors (`detect`); the Allan analysis sees the corrected channels.
    let pre = crate::detect::preprocess(
        log.channels,
        log.temperature_c,
        log.dt_s,
        &crate::detect::model_levels(model),
    );
    let corrected = LogInput {
        dt_s: log.dt_s,
        channels: std::array::from_fn(|c| pre.channels[c].as_deref()),
        temperature_c: log.temperature_c,
    };
    let log = &corrected;

    // Step 1: measured Allan deviations with EDF (Greenhall, noise type by lag-1 ACF) on the octave grid.
    progress("measuring the log's Allan deviations");
    let (grid_m, measured) = measure(log, settings.tau_min_s);
    let (_, measured_raw) = measure(raw_log, settings.tau_min_s);
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
    let gap_raw = |c: usize| -> Option<(Band, Gap)> {
        let m = measured_raw[c].as_ref()?;
        let b = restrict(bands[c].as_ref()?, &m.idx);
        let g = gap(&m.curve, &b);
        Some((b, g))
    };
    let initial: [Option<(Band, Gap)>; 6] = std::array::from_fn(gap_raw);
    let mut effects: [Vec<FoundEffect>; 6] = Default::default();
    for c in 0..6 {
        let (Some((_, g0)), Some((_, g1))) = (initial[c].as_ref(), gap_of(c, &bands)) else {
            continue;
        };
        for f in &pre.findings[c] {
            let effect = f.term.effect();
            let map = |j: usize| -> BTreeMap<String, f64> {
                f.parameters
                    .iter()
                    .map(|p| (p.0.to_string(), [p.1, p.2, p.3][j]))
                    .collect()
            };
            let (sensor, axis) = crate::model_terms::channel_axis(c);
            let had = out_model.axis(sensor, axis).term(effect).is_some();
            out_model.axis_mut(sensor, axis).set_term(f.term.clone());
            effects[c].push(FoundEffect {
                effect,
                parameters: map(0).into(),
                parameters_lo: map(1),
                parameters_hi: map(2),
                kind: if had {
                    FindingKind::WrongLevel
                } else {
                    FindingKind::Missing
                },
                model_parameters: None,
                gap_before: g0.rms,
                gap_predicted: g1.rms,
                gap_after: g1.rms,
                delta_bic: f.delta_bic,
                cannot_tell_from: f.cannot_tell_from.clone(),
                round: 0,
                refinements: 0,
                stand_in: false,
            });
        }
    }
    let mut records: [Vec<CandidateRecord>; 6] = Default::default();
    // Spectral-line checks by (channel, frequency): the same best sinusoid frequency recurs over the
    // steps and rounds, and each check is a Welch DFT over the whole log.
    let line_checks: std::cell::RefCell<std::collections::HashMap<(usize, u64), bool>> =
        Default::default();
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
            // The temperature is regressed in the time domain (step 0), where its phase is seen;
            // its Allan signature alone cannot tell it from a slow bias wander.
            let temp: Option<(Vec<f64>, f64)> = None;
            let _ = (&temp_avar, &temp_sign);
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
                    pre.peaks[c],
                    &|f| {
                        *line_checks
                            .borrow_mut()
                            .entry((c, f.to_bits()))
                            .or_insert_with(|| {
                                pre.channels[c]
                                    .as_deref()
                                    .is_none_or(|x| crate::detect::line_allowed(x, log.dt_s, f))
                            })
                    },
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
                        effect: Candidate {
                            effect: t.effect,
                            rejected: false,
                        },
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
                    .filter(|t| effects[c].iter().any(|e| e.effect == t.effect))
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
                let cannot_tell_from: Vec<Effect> = ts
                    .iter()
                    .filter(|t| {
                        t.effect != best.effect && t.bic - best.bic < settings.ambiguity_delta_bic
                    })
                    .map(|t| t.effect)
                    .collect();
                if best.effect == Effect::OutputFilter {
                    // The filter is fitted with the white-noise level: undoing it restores both.
                    changes.push((
                        Effect::WhiteNoise,
                        term_level(&sim_model, c, Effect::WhiteNoise),
                    ));
                }
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
                    effect: best.effect,
                    parameters: parameters_of(best.effect, &best.params, log.dt_s),
                    parameters_lo: bounds_of(best.effect, &best.lo, log.dt_s),
                    parameters_hi: bounds_of(best.effect, &best.hi, log.dt_s),
                    kind: if best.model.is_some() {
                        FindingKind::WrongLevel
                    } else {
                        FindingKind::Missing
                    },
                    model_parameters: best.model.map(|p| named_map(best.effect, &p)),
                    gap_before: g.rms,
                    gap_predicted: g_pred.rms,
                    gap_after: f64::NAN,
                    delta_bic: delta,
                    cannot_tell_from,
                    round,
                    refinements: 0,
                    stand_in: false,
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
        // Only the channels changed in this round: each channel draws from its own streams, so its
        // band is the same whichever others are generated. The drift needs every channel; a partial
        // round leaves it to a full simulation after the loop.
        let changed: [bool; 6] =
            std::array::from_fn(|c| active[c] && pending.iter().any(|p| p.0 == c));
        let partial = changed != active;
        let round_setup = SimSetup {
            active: changed,
            // A partial round's drift is not used (it needs every channel): not computed.
            horizons_s: if partial {
                Vec::new()
            } else {
                setup.horizons_s.clone()
            },
            ..setup.clone()
        };
        let sim = simulate(&sim_model, &round_setup, settings.seed, settings.seeds)?;
        dirty = partial;
        for (c, changes, gap_before) in pending {
            let new_bands = {
                let mut b = bands.clone();
                b[c] = sim.bands[c].clone();
                b
            };
            let after = gap_of(c, &new_bands)
                .map(|(_, g)| g.rms)
                .unwrap_or(f64::NAN);
            let first_new = effects[c]
                .iter()
                .position(|e| e.round == round)
                .unwrap_or(effects[c].len());
            for found in &mut effects[c][first_new..] {
                found.gap_after = after;
            }
            if after.is_nan() || after >= gap_before {
                // The re-simulated model is no closer: undo this round's changes and stop here.
                for rejected in effects[c].drain(first_new..) {
                    records[c].push(CandidateRecord {
                        round,
                        effect: Candidate {
                            effect: rejected.effect,
                            rejected: true,
                        },
                        delta_bic: rejected.delta_bic,
                        delta_aic: f64::NAN,
                        parameters: rejected.parameters.values,
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
        if !partial {
            last_drift = sim.drift;
        }
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
        // Shaped terms fitted where the model still disagrees are stand-ins, not physical findings.
        // A sinusoid whose frequency carries a spectral line in the log is a physical tone (a
        // vibration, an interference), not a stand-in.
        if g1.rms > STAND_IN_GAP {
            for e in &mut effects[c] {
                e.stand_in = match e.effect {
                    Effect::GaussMarkov => true,
                    Effect::Sinusoidal => !e.parameters.get("frequency_hz").is_some_and(|&f| {
                        log.channels[c]
                            .is_some_and(|x| crate::detect::is_spectral_line(x, log.dt_s, f))
                    }),
                    _ => false,
                };
            }
        }
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

/// Above this final gap (RMS z) a channel's fitted Gauss-Markov terms, and sinusoids without a
/// spectral line in the log (`detect::is_spectral_line`), are called stand-ins: the hidden-effect
/// tests close a physical effect's gap to below 1.5.
pub const STAND_IN_GAP: f64 = 1.5;

fn verdict(g: &Gap, effects: &[FoundEffect]) -> String {
    let named = if effects.is_empty() {
        "no effect named".to_string()
    } else {
        effects
            .iter()
            .map(|e| {
                if e.stand_in {
                    format!("{} (stand-in)", e.effect.name())
                } else {
                    e.effect.name().to_string()
                }
            })
            .collect::<Vec<_>>()
            .join(" + ")
    };
    if effects.iter().any(|e| e.stand_in) && !g.disagreements.is_empty() {
        return format!(
            "{named}; no physical candidate explains the remaining gap, the terms marked stand-in only fill it"
        );
    }
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

/// A bound of a fitted term's parameters; a filter's noise bandwidth is a property of the chosen
/// filter (its bound is itself: the filter's shape is selected, not interval-estimated).
fn bounds_of(effect: Effect, params: &TermParams, dt_s: f64) -> BTreeMap<String, f64> {
    parameters_of(effect, params, dt_s).values
}

/// The JSON parameters of a fitted term (an output filter's kind and one-sided noise bandwidth added).
fn parameters_of(effect: Effect, params: &TermParams, dt_s: f64) -> Parameters {
    let mut p: Parameters = named_map(effect, params).into();
    if let TermParams::Filter { filter, .. } = params {
        p.kind = Some(filter.kind.name());
        p.values
            .insert("noise_bandwidth_hz".into(), filter.noise_bandwidth_hz(dt_s));
    }
    p
}
