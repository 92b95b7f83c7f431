//! The diagnose workflow (docs/diagnose.md, "The diagnose workflow", steps 0-6) as plain
//! functions, one per step, in the order [`diagnose_until`] calls them: detect and measure, simulate
//! the band ([`start`]), the time-domain findings, then rounds of naming effects
//! ([`name_effects`]) and re-simulating ([`resimulate`]); then the drift settled, the drift loop
//! (`drift_rounds`) and the report. Each step reads the [`Context`] (fixed after step 2) and takes
//! the parts of the [`LoopState`] it changes; the current model's drift is passed from step to step
//! as a value (`Option<Drift>`: `None` when the last simulation no longer describes the model).

use crate::detect::Preprocessed;
use crate::drift::{segment_drift, SegmentDrift};
use crate::error::DiagnoseError;
use crate::findings::{
    channel_curves, found_by_detector, found_by_fit, mark_stand_ins, merge_refinements,
    trial_records, verdict, Choice,
};
use crate::fit::{bic, FitData};
use crate::gap::{gap, Band, Curve, Gap};
use crate::input::{validate_runs, LogInput};
use crate::measure::{measure_runs, Measured, Runs};
use crate::model_terms::{clear_term, current_term, set_term};
use crate::observer::{Observer, RoundDone, Step};
use crate::report::{
    CandidateRecord, ChannelReport, Diagnosis, DriftRow, FoundEffect, LogBands, RunChannel,
    RunReport,
};
use crate::settings::Settings;
use crate::simulate::{simulate_runs, RunPlan, SimResult, SimSetup};
use crate::trials::{trials, ChannelFit, Trial};
use noise::{Channel, Effect, ImuChannels, SensorModel, Term};
use state::{gap_of, shifted_band, Bands, ChannelState, Context, Drift, LoopState, Models};
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, Ordering};

pub use crate::findings::STAND_IN_GAP;

mod drift_rounds;
mod state;

/// Run the diagnose workflow on a measured log against a sensor model.
pub fn diagnose(
    log: &LogInput,
    model: &SensorModel,
    settings: &Settings,
) -> Result<Diagnosis, DiagnoseError> {
    diagnose_observed(log, model, settings, &())
}

/// [`diagnose`], telling `observer` about each long step before it starts (for a progress display).
pub fn diagnose_observed(
    log: &LogInput,
    model: &SensorModel,
    settings: &Settings,
    observer: &dyn Observer,
) -> Result<Diagnosis, DiagnoseError> {
    diagnose_runs(std::slice::from_ref(log), model, settings, observer)
}

/// [`diagnose_observed`] of several runs of one sensor (same rate and channels) fitted together
/// (docs/diagnose.md, "Several runs"): step 0 on each run, the Allan variances pooled, the band
/// pooled the same way over simulated runs of the runs' lengths. One run is [`diagnose_observed`].
pub fn diagnose_runs(
    logs: &[LogInput],
    model: &SensorModel,
    settings: &Settings,
    observer: &dyn Observer,
) -> Result<Diagnosis, DiagnoseError> {
    diagnose_until(logs, model, settings, observer, &AtomicBool::new(false))
}

/// [`diagnose_runs`] that a front end can stop (Ctrl-C): once `stop` is set no further simulated
/// log starts (a stop lands within one simulated log per worker thread, or one step of the
/// workflow between simulations) and the result is [`DiagnoseError::Stopped`]. The same inputs
/// give the same diagnosis as [`diagnose_runs`].
pub fn diagnose_until(
    logs: &[LogInput],
    model: &SensorModel,
    settings: &Settings,
    observer: &dyn Observer,
    stop: &AtomicBool,
) -> Result<Diagnosis, DiagnoseError> {
    let samples = validate_runs(logs)?;
    if logs.len() > 1 && settings.seeds <= logs.len() {
        return Err(DiagnoseError::SeedsForRuns {
            seeds: settings.seeds,
            runs: logs.len(),
        });
    }
    // Step 0: time-domain detectors (`detect`) on each run; the Allan analysis sees the corrected
    // channels.
    observer.step(Step::Detect);
    let mut pre: Vec<Preprocessed> = Vec::with_capacity(logs.len());
    for l in logs {
        if stop.load(Ordering::Relaxed) {
            return Err(DiagnoseError::Stopped);
        }
        pre.push(crate::detect::preprocess_log(l, model));
    }
    let start_from = Start {
        raw: logs.to_vec(),
        logs: logs
            .iter()
            .zip(&pre)
            .map(|(l, p)| l.with_channels(&p.channels))
            .collect(),
        pre: &pre,
        samples,
        settings,
        observer,
        stop,
    };
    let (cx, mut state) = start(start_from, model)?;
    time_domain_findings(&cx, &mut state);
    // The current model's drift: the original model's until a round re-simulates every channel.
    let mut drift = Some(Drift {
        segments: cx.sim0.drift.clone(),
        protocol: cx.sim0.protocol_errors.clone(),
    });
    // Steps 3-5: name, add, re-simulate, until nothing significant remains.
    for round in 1..=settings.max_rounds {
        cx.check_stop()?;
        let pending = name_effects(&cx, &mut state, round);
        if pending.is_empty() {
            break;
        }
        cx.check_stop()?;
        drift = resimulate(&cx, &mut state, round, pending)?;
    }
    cx.check_stop()?;
    let drift = settle_drift(&cx, &state.models, drift)?;
    let drift = drift_rounds::drift_rounds(&cx, &mut state, drift)?;
    cx.check_stop()?;
    // Several runs: the run-to-run variation of each channel's slow group (`run_spread`), the
    // estimates above 0 written into the corrected model (named or not).
    let spreads = crate::run_spread::estimate(
        &state.models.out,
        &cx.logs,
        settings.tau_min_s,
        settings.seed,
        Some(stop),
    )
    .ok_or(DiagnoseError::Stopped)?;
    state.models.out = crate::run_spread::with_estimated_spreads(&state.models.out, &spreads);
    let mut diagnosis = report(cx, state, drift);
    diagnosis.run_to_run = spreads;
    Ok(diagnosis)
}

/// What a diagnosis starts from: the logs (runs) as measured, the logs after step 0's
/// corrections, the detectors' findings, and how to work.
struct Start<'a> {
    raw: Vec<LogInput<'a>>,
    logs: Vec<LogInput<'a>>,
    pre: &'a [Preprocessed],
    samples: Vec<usize>,
    settings: &'a Settings,
    observer: &'a dyn Observer,
    stop: &'a AtomicBool,
}

/// Step 1's result: the common tau grid's averaging factors, and each channel's measurement on it
/// (pooled over the runs, and per run), of the corrected logs and of the raw ones.
struct Measurement {
    corrected: Runs,
    raw: Runs,
}

/// A channel changed in this round: the changes in the order made (each effect with its level
/// before, to undo them) and the channel's gap at the round's start.
struct Pending {
    channel: Channel,
    changes: Vec<(Effect, Option<Term>)>,
    gap_before: f64,
}

/// One channel's round, worked out on its own copy of the model ([`name_effects`]): the terms
/// to set on the channel in order, the channel's effects after the round (those named before it
/// and now), the candidates weighed, and the changes to check by re-simulation (None: no change).
struct RoundOutcome {
    terms: Vec<(Effect, Option<Term>)>,
    effects: Vec<FoundEffect>,
    records: Vec<CandidateRecord>,
    pending: Option<Pending>,
}

/// Step 4: put the chosen term into `model` on channel `c` and append it to `terms` (what the
/// round then sets in both of the run's models; None: the effect removed); the changes made, each
/// with the term before. A trial whose parameters the terms' constructors refuse changes nothing.
/// A trial whose fitted level is 0 (`findings::is_removal`) removes the term: a term of size 0
/// would be written into the corrected model as `sigma = "0 deg/s"`.
fn accept(
    model: &mut SensorModel,
    terms: &mut Vec<(Effect, Option<Term>)>,
    c: Channel,
    best: &Trial,
) -> Vec<(Effect, Option<Term>)> {
    if crate::findings::is_removal(best) {
        let effect = best.effect;
        let before = current_term(model, c, effect);
        clear_term(model, c, effect);
        terms.push((effect, None));
        return vec![(effect, before)];
    }
    let mut new = vec![best.term.clone()];
    if let Some(n) = best.white_n {
        // The filter is fitted with the white-noise level: undoing it restores both.
        match noise::WhiteNoise::new(n) {
            Ok(white) => new.insert(0, white.into()),
            Err(_) => return Vec::new(),
        }
    }
    let mut changes = Vec::new();
    for term in new {
        changes.push((term.effect(), current_term(model, c, term.effect())));
        set_term(model, c, term.clone());
        terms.push((term.effect(), Some(term)));
    }
    changes
}

/// Steps 1 and 2: measure the logs, simulate the model's band; the context every later step reads
/// and the loop's first state (the gap before any change on each channel).
fn start<'a>(s: Start<'a>, model: &SensorModel) -> Result<(Context<'a>, LoopState), DiagnoseError> {
    let Measurement { corrected, raw } = measure(&s)?;
    let first = s.logs[0];
    let plan = RunPlan {
        samples: s.samples.clone(),
        weights: corrected.weights.clone(),
        protocol: s.settings.drift_protocol.clone(),
    };
    let setup = SimSetup {
        dt_s: first.dt_s,
        samples: s.samples.iter().copied().max().unwrap_or(0),
        grid_m: corrected.grid_m.clone(),
        active: ImuChannels::from_fn(|c| first.channels[c].is_some()),
        horizons_s: s.settings.horizons_s.clone(),
        temperature_c: if s.logs.len() == 1 {
            first.temperature_c
        } else {
            None
        },
        temp_coeff: ImuChannels::default(),
        latitude_deg: s.settings.latitude_deg,
        stop: Some(s.stop),
    };
    let sim0 = band(model, &setup, &plan, s.settings, s.observer)?;
    let logs = s.logs;
    let (peaks, lines) = if logs.len() == 1 {
        (s.pre[0].peaks, s.pre[0].lines.clone())
    } else {
        let both = ImuChannels::from_fn(|c| {
            let xs: Vec<&[f64]> = logs.iter().filter_map(|l| l.channels[c]).collect();
            if xs.is_empty() {
                (None, Vec::new())
            } else {
                crate::spectrum::peak_and_lines_runs(&xs, first.dt_s)
            }
        });
        (
            ImuChannels::from_fn(|c| both[c].0),
            ImuChannels::from_fn(|c| both[c].1.clone()),
        )
    };
    let several = logs.len() > 1;
    let drift_measured = s
        .settings
        .drift_protocol
        .as_ref()
        .map_or(Vec::new(), |p| crate::drift_gap::measured(&logs, p));
    let state = LoopState {
        models: Models {
            sim: model.clone(),
            out: model.clone(),
        },
        bands: Bands {
            pooled: sim0.bands.clone(),
            per_length: sim0.log_bands.clone(),
        },
        channels: ImuChannels::from_fn(|c| ChannelState {
            initial: gap_of(raw.pooled[c].as_ref(), sim0.bands[c].as_ref()),
            done: !setup.active[c],
            ..ChannelState::default()
        }),
        rounds: 0,
    };
    let cx = Context {
        settings: s.settings,
        observer: s.observer,
        stop: s.stop,
        pre: s.pre,
        samples: s.samples,
        grid_m: corrected.grid_m,
        measured: corrected.pooled,
        run_measured: if several { corrected.runs } else { Vec::new() },
        run_raw: if several { raw.runs } else { Vec::new() },
        ramp_slope: ImuChannels::from_fn(|c| crate::runs::ramp_slope(&logs, c)),
        peaks,
        lines,
        logs,
        setup,
        plan,
        sim0,
        drift_measured,
    };
    Ok((cx, state))
}

/// Step 1: measured Allan deviations with EDF (Greenhall, noise type by lag-1 ACF) on the octave
/// grid, of the corrected logs and of the raw ones (for the gap before step 0's corrections),
/// pooled over the runs.
fn measure(s: &Start) -> Result<Measurement, DiagnoseError> {
    s.observer.step(Step::Measure);
    let tau_min_s = s.settings.tau_min_s;
    let corrected = measure_runs(&s.logs, tau_min_s);
    if s.stop.load(Ordering::Relaxed) {
        return Err(DiagnoseError::Stopped);
    }
    let raw = measure_runs(&s.raw, tau_min_s);
    if corrected
        .pooled
        .values()
        .iter()
        .flatten()
        .all(|m| m.idx.is_empty())
    {
        return Err(DiagnoseError::NoTaus { tau_min_s });
    }
    Ok(Measurement { corrected, raw })
}

/// Step 2: the model's band (and drift), simulated.
fn band(
    model: &SensorModel,
    setup: &SimSetup,
    plan: &RunPlan,
    settings: &Settings,
    observer: &dyn Observer,
) -> Result<SimResult, DiagnoseError> {
    observer.step(Step::Band);
    Ok(simulate_runs(
        model,
        setup,
        plan,
        settings.seed,
        settings.seeds,
    )?)
}

/// Round 0: the time-domain detectors' findings enter the corrected model (their effects are
/// already removed from the log the Allan rounds see).
fn time_domain_findings(cx: &Context, state: &mut LoopState) {
    for c in Channel::ALL {
        let (Some((_, g0)), Some((_, g1))) = (
            state.channels[c].initial.as_ref(),
            cx.gap(c, &state.bands.pooled),
        ) else {
            continue;
        };
        let (gap_before, gap_after) = (g0.rms, g1.rms);
        let per_run: Vec<&[crate::detect::Finding]> =
            cx.pre.iter().map(|p| p.findings[c].as_slice()).collect();
        for f in &crate::runs::pooled_findings(&per_run, &cx.hours()) {
            let axis = state.models.out.axis_mut(c.sensor(), c.axis());
            let had = axis.term(f.term.effect()).is_some();
            axis.set_term(f.term.clone());
            let found = found_by_detector(f, had, gap_before, gap_after);
            state.channels[c].effects.push(found);
        }
    }
}

/// Steps 3 and 4 of one round on every channel not done; the channels changed. Each
/// channel's round reads only its own axis of the model and its own findings (the candidates,
/// the selection and the changes are per channel), so the rounds run side by side on a copy
/// of the model each and are applied in channel order: the state one after the other leaves.
fn name_effects(cx: &Context, state: &mut LoopState, round: usize) -> Vec<Pending> {
    use rayon::prelude::*;
    let todo: Vec<Channel> = Channel::ALL
        .into_iter()
        .filter(|&c| !state.channels[c].done)
        .collect();
    let outcomes: Vec<Option<RoundOutcome>> = {
        let state: &LoopState = state;
        todo.par_iter()
            .map(|&c| channel_round(cx, state, c, round))
            .collect()
    };
    let mut pending = Vec::new();
    for (c, outcome) in todo.into_iter().zip(outcomes) {
        let Some(o) = outcome else {
            state.channels[c].done = true;
            continue;
        };
        for (effect, term) in o.terms {
            state.models.restore(c, effect, term);
        }
        state.channels[c].records.extend(o.records);
        state.channels[c].effects = o.effects;
        match o.pending {
            Some(p) => pending.push(p),
            None => state.channels[c].done = true,
        }
    }
    pending
}

/// One round on channel `c`: up to `effects_per_round` effects by forward selection on the
/// closed-form prediction (so a short-tau disagreement with huge z does not hold back a long-tau
/// one for many rounds); the round's re-simulation then checks them together. None when the
/// channel has no disagreement left; an outcome without `pending` when nothing was changed.
fn channel_round(
    cx: &Context,
    state: &LoopState,
    c: Channel,
    round: usize,
) -> Option<RoundOutcome> {
    let settings = cx.settings;
    let (band, g) = cx.gap(c, &state.bands.pooled)?;
    if g.disagreements.is_empty() {
        return None;
    }
    let curve = cx.measured[c]
        .as_ref()
        .expect("active channel is measured")
        .curve
        .clone();
    let ln_meas: Vec<f64> = curve.adev.iter().map(|a| a.ln()).collect();
    let mut model = state.models.sim.clone();
    let mut out = RoundOutcome {
        terms: Vec::new(),
        effects: state.channels[c].effects.clone(),
        records: Vec::new(),
        pending: None,
    };
    let mut predicted = band;
    let mut g_pred = g.clone();
    let mut changes = Vec::new();
    for _step in 0..settings.effects_per_round {
        if g_pred.disagreements.is_empty() {
            break;
        }
        let ts = candidates(cx, &model, c, &curve, &predicted, &g_pred);
        let data = FitData {
            ln_meas: &ln_meas,
            ln_band: &predicted.ln_mean,
            avar_band: &predicted.avar_mean,
            s: &g_pred.s,
        };
        let base_bic = bic(data.chi2_base(), 0, ln_meas.len());
        out.records
            .extend(trial_records(round, &ts, base_bic, data.chi2_base()));
        let choice = select(settings, &out.effects, &ts, base_bic);
        // The joint re-level is of the model as given (round 1): later rounds refine the levels
        // of the terms they name one at a time, as before.
        let joint = (round == 1)
            .then(|| crate::relevel::joint_relevel(&data, &ts, settings.min_delta_bic))
            .flatten();
        if let Some(joint) = joint.filter(|j| prefer_joint(settings, j, choice.as_ref(), base_bic))
        {
            for t in &joint.levels {
                changes.extend(accept(&mut model, &mut out.terms, c, t));
            }
            predicted = shifted_band(&predicted, &joint.delta_avar);
            g_pred = gap(&curve, &predicted);
            for trial in &joint.levels {
                let choice = Choice {
                    trial,
                    delta_bic: base_bic - joint.bic,
                    cannot_tell_from: Vec::new(),
                };
                let found = found_by_fit(choice, round, g.rms, g_pred.rms, cx.dt_s());
                out.effects.push(found);
            }
            continue;
        }
        let Some(choice) = choice else {
            break;
        };
        changes.extend(accept(&mut model, &mut out.terms, c, choice.trial));
        // The closed-form prediction of the band with this change, for the next step.
        predicted = shifted_band(&predicted, &choice.trial.delta_avar);
        g_pred = gap(&curve, &predicted);
        let found = found_by_fit(choice, round, g.rms, g_pred.rms, cx.dt_s());
        out.effects.push(found);
    }
    out.pending = (!changes.is_empty()).then_some(Pending {
        channel: c,
        changes,
        gap_before: g.rms,
    });
    Some(out)
}

/// Step 4: every candidate fitted to channel `c`'s gap against `band`.
fn candidates(
    cx: &Context,
    model: &SensorModel,
    c: Channel,
    curve: &Curve,
    band: &Band,
    g: &Gap,
) -> Vec<Trial> {
    let dt_s = cx.dt_s();
    let series = cx.series(c);
    trials(&ChannelFit {
        model,
        channel: c,
        measured: curve,
        band,
        gap: g,
        dt_s,
        ramp_slope: cx.ramp_slope[c],
        peak: cx.peaks[c],
        lines: &cx.lines[c],
        line_resolution_hz: crate::spectrum::line_resolution_hz(&series, dt_s),
        line_frequency_resolution_hz: crate::spectrum::line_frequency_resolution_hz(&series, dt_s),
    })
}

/// Step 4: the candidate to name, if any improves BIC by `min_delta_bic`.
fn select<'t>(
    settings: &Settings,
    named: &[FoundEffect],
    ts: &'t [Trial],
    base_bic: f64,
) -> Option<Choice<'t>> {
    let mut best = ts.iter().min_by(|a, b| a.bic.total_cmp(&b.bic))?;
    // Occam: re-levelling an effect already named on this channel is preferred to naming
    // another one unless the other is better by the ambiguity margin.
    if let Some(refine) = ts
        .iter()
        .filter(|t| named.iter().any(|e| e.effect == t.effect))
        .min_by(|a, b| a.bic.total_cmp(&b.bic))
    {
        if refine.bic - best.bic < settings.ambiguity_delta_bic {
            best = refine;
        }
    }
    let delta_bic = base_bic - best.bic;
    if delta_bic < settings.min_delta_bic {
        return None;
    }
    let cannot_tell_from = ts
        .iter()
        .filter(|t| t.effect != best.effect && t.bic - best.bic < settings.ambiguity_delta_bic)
        .map(|t| t.effect)
        .collect();
    Some(Choice {
        trial: best,
        delta_bic,
        cannot_tell_from,
    })
}

/// Step 4: is the joint re-level of the model's own levels (module `relevel`) the step to take?
/// When it gains `min_delta_bic` and has a lower BIC than the best single candidate.
fn prefer_joint(
    settings: &Settings,
    joint: &crate::relevel::Relevel,
    best: Option<&Choice>,
    base_bic: f64,
) -> bool {
    base_bic - joint.bic >= settings.min_delta_bic && best.is_none_or(|b| joint.bic < b.trial.bic)
}

/// Step 5: simulate the corrected model and keep each changed channel's round only if its gap
/// shrank. Only the channels changed in this round are simulated: each channel draws from its own
/// streams, so its band is the same whichever others are generated. The drift needs every
/// channel: the round's drift when it simulated every channel and kept every change, else None
/// (left to a full simulation after the loop).
fn resimulate(
    cx: &Context,
    state: &mut LoopState,
    round: usize,
    pending: Vec<Pending>,
) -> Result<Option<Drift>, DiagnoseError> {
    state.rounds = round;
    cx.observer.step(Step::Resimulate { round });
    let active = cx.setup.active;
    let changed = ImuChannels::from_fn(|c| active[c] && pending.iter().any(|p| p.channel == c));
    let partial = changed != active;
    let round_plan = RunPlan {
        protocol: if partial {
            None
        } else {
            cx.plan.protocol.clone()
        },
        ..cx.plan.clone()
    };
    let round_setup = SimSetup {
        active: changed,
        // A partial round's drift is not used (it needs every channel): not computed.
        horizons_s: if partial {
            Vec::new()
        } else {
            cx.setup.horizons_s.clone()
        },
        ..cx.setup.clone()
    };
    let settings = cx.settings;
    let sim = simulate_runs(
        &state.models.sim,
        &round_setup,
        &round_plan,
        settings.seed,
        settings.seeds,
    )?;
    let mut done = RoundDone {
        round,
        drift: false,
        kept: Vec::new(),
        undone: Vec::new(),
    };
    for p in pending {
        let c = p.channel;
        match keep_or_undo(cx, state, round, p, &sim) {
            Some(named) => done.kept.push((c, named)),
            None => done.undone.push(c),
        }
    }
    cx.observer.round_done(&done);
    Ok((!partial && done.undone.is_empty()).then(|| Drift::of(sim)))
}

/// Step 5 for one channel: its re-simulated band is kept if the gap shrank (the effects named
/// this round returned); otherwise the round's changes are undone (recorded as rejected), the
/// channel is done and the result is None.
fn keep_or_undo(
    cx: &Context,
    state: &mut LoopState,
    round: usize,
    p: Pending,
    sim: &SimResult,
) -> Option<Vec<Effect>> {
    let c = p.channel;
    let band = sim.bands[c].clone();
    let after = gap_of(cx.measured[c].as_ref(), band.as_ref())
        .map(|(_, g)| g.rms)
        .unwrap_or(f64::NAN);
    let ch = &mut state.channels[c];
    let first_new = ch.first_in(round);
    for found in &mut ch.effects[first_new..] {
        found.gap_after = after;
    }
    if !(after.is_nan() || after >= p.gap_before) {
        let named = ch.effects[first_new..].iter().map(|e| e.effect).collect();
        state.bands.pooled[c] = band;
        for (mine, new) in state.bands.per_length.iter_mut().zip(&sim.log_bands) {
            mine.1[c] = new.1[c].clone();
        }
        let withdrawn = merge_refinements(&mut ch.effects, first_new);
        ch.records.extend(withdrawn);
        return Some(named);
    }
    // The re-simulated model is no closer: undo this round's changes and stop here.
    ch.reject_from(round, first_new);
    ch.done = true;
    for (effect, previous) in p.changes.into_iter().rev() {
        state.models.restore(c, effect, previous);
    }
    None
}

/// After the rounds: the corrected model's drift, simulated again when the rounds left none
/// (a partial or rejected round).
fn settle_drift(
    cx: &Context,
    models: &Models,
    drift: Option<Drift>,
) -> Result<Drift, DiagnoseError> {
    if let Some(drift) = drift {
        return Ok(drift);
    }
    // Only the drift is wanted here: no Allan deviations of the simulated logs (an empty
    // grid), the same logs and so the same drift.
    let setup = SimSetup {
        grid_m: Vec::new(),
        ..cx.setup.clone()
    };
    let settings = cx.settings;
    let sim = simulate_runs(&models.sim, &setup, &cx.plan, settings.seed, settings.seeds)?;
    Ok(Drift::of(sim))
}

/// Step 6: drift consequence, measured log segments vs model before vs model after (`last`).
fn drift_rows(cx: &Context, last: &[SegmentDrift]) -> Vec<DriftRow> {
    cx.settings
        .horizons_s
        .iter()
        .enumerate()
        .map(|(h, &horizon)| DriftRow {
            horizon_s: horizon,
            measured: measured_drift(cx, horizon).summary(),
            model_initial: cx.sim0.drift[h].summary(),
            model_final: last[h].summary(),
        })
        .collect()
}

/// What diagnose says about channel `c` (None when it is not measured).
fn channel_report(
    cx: &Context,
    bands: &Bands,
    ch: &mut ChannelState,
    c: Channel,
) -> Option<ChannelReport> {
    let (b1, g1) = cx.gap(c, &bands.pooled)?;
    let m = cx.measured[c].as_ref()?;
    let (b0, g0) = ch.initial.clone()?;
    let (xs, dt_s) = (cx.series(c), cx.dt_s());
    if g1.rms > STAND_IN_GAP {
        mark_stand_ins(&mut ch.effects, &xs, dt_s);
    }
    Some(ChannelReport {
        gap_initial: g0.rms,
        gap_final: g1.rms,
        verdict: verdict(&g1, &ch.effects),
        effects: std::mem::take(&mut ch.effects),
        z_initial: g0.z,
        z_final: g1.z.clone(),
        disagreements_initial: g0.disagreements,
        disagreements_final: g1.disagreements,
        candidates: std::mem::take(&mut ch.records),
        curves: channel_curves(m, &b0, b1),
    })
}

/// Each run's curves, gaps and step-0 findings (several runs only; the pooled findings are
/// the channels').
fn run_reports(cx: &Context, state: &LoopState) -> Vec<RunReport> {
    let band_at = |bands: &[(usize, ImuChannels<Option<Band>>)], n: usize, c: Channel| {
        bands.iter().find(|b| b.0 == n).and_then(|b| b.1[c].clone())
    };
    (0..cx.run_measured.len())
        .map(|r| {
            let n = cx.samples[r];
            let mut channels = BTreeMap::new();
            let mut findings = BTreeMap::new();
            for c in Channel::ALL {
                let (Some(m), Some(raw)) =
                    (cx.run_measured[r][c].as_ref(), cx.run_raw[r][c].as_ref())
                else {
                    continue;
                };
                let b0 = band_at(&cx.sim0.log_bands, n, c);
                let b1 = band_at(&state.bands.per_length, n, c);
                let rms = |m: &Measured, b: &Option<Band>| {
                    gap_of(Some(m), b.as_ref()).map_or(f64::NAN, |g| g.1.rms)
                };
                let (g0, g_corr, g1) = (rms(raw, &b0), rms(m, &b0), rms(m, &b1));
                let found: Vec<FoundEffect> = cx.pre[r].findings[c]
                    .iter()
                    .map(|f| {
                        let had = state.channels[c].effects.iter().any(|e| {
                            e.round == 0
                                && e.effect == f.term.effect()
                                && e.kind == crate::report::FindingKind::WrongLevel
                        });
                        found_by_detector(f, had, g0, g_corr)
                    })
                    .collect();
                if !found.is_empty() {
                    findings.insert(c, found);
                }
                channels.insert(
                    c,
                    RunChannel {
                        tau_s: m.curve.tau_s.clone(),
                        adev: m.curve.adev.clone(),
                        edf: m.curve.edf.clone(),
                        gap_initial: g0,
                        gap_final: g1,
                    },
                );
            }
            RunReport {
                samples: n,
                channels,
                findings,
            }
        })
        .collect()
}

/// The diagnosis, from the loop's last state and the corrected model's drift.
fn report(cx: Context, mut state: LoopState, drift: Drift) -> Diagnosis {
    let drift_table = drift_rows(&cx, &drift.segments);
    let runs = run_reports(&cx, &state);
    let drift_check = drift_rounds::drift_report(&cx, &drift);
    let alternatives = Channel::ALL
        .into_iter()
        .flat_map(|c| std::mem::take(&mut state.channels[c].alternatives))
        .collect();
    let mut channels = BTreeMap::new();
    for c in Channel::ALL {
        if let Some(r) = channel_report(&cx, &state.bands, &mut state.channels[c], c) {
            channels.insert(c, r);
        }
    }
    let log_bands = cx
        .sim0
        .log_bands
        .iter()
        .zip(state.bands.per_length)
        .map(|(b0, b1)| LogBands {
            samples: b0.0,
            initial: b0.1.clone(),
            corrected: b1.1,
        })
        .collect();
    Diagnosis {
        seed: cx.settings.seed,
        seeds: cx.settings.seeds,
        rounds: state.rounds,
        dt_s: cx.dt_s(),
        samples: cx.samples.iter().sum(),
        channels,
        drift: drift_table,
        runs,
        drift_check,
        alternatives,
        run_to_run: Vec::new(),
        tau_min_s: cx.settings.tau_min_s,
        model_final: state.models.out,
        grid_m: cx.grid_m,
        log_bands,
    }
}

/// The measured segment drifts of one horizon, every run's segments in run order (each run
/// calibrated by its own mean).
fn measured_drift(cx: &Context, horizon_s: f64) -> SegmentDrift {
    let mut all = SegmentDrift {
        horizon_s,
        ..Default::default()
    };
    for l in &cx.logs {
        all.extend(&segment_drift(
            &l.channels.0,
            l.dt_s,
            horizon_s,
            cx.settings.latitude_deg,
        ));
    }
    all
}
