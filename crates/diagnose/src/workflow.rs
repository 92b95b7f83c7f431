//! The diagnose workflow (docs/diagnose.md, "The diagnose workflow", steps 0-6) as one `Run` whose
//! methods are the steps, in the order [`diagnose_observed`] calls them: detect and measure, simulate
//! the band, locate the gap, fit the candidates, accept the best, re-simulate, repeat; then the drift
//! consequence and the report.

use crate::detect::Preprocessed;
use crate::drift::{segment_drift, SegmentDrift};
use crate::error::DiagnoseError;
use crate::findings::{
    channel_curves, found_by_detector, found_by_fit, mark_stand_ins, merge_refinements,
    rejected_record, trial_records, verdict, Choice,
};
use crate::fit::{bic, predicted_ln_adev, FitData};
use crate::gap::{gap, Band, Curve, Gap};
use crate::input::{validate_runs, LogInput};
use crate::measure::{measure_runs, restrict, Measured, Runs};
use crate::model_terms::{current_term, restore_term, set_term};
use crate::observer::{Observer, Step};
use crate::report::{
    CandidateRecord, ChannelReport, Diagnosis, DriftRow, FoundEffect, LogBands, RunChannel,
    RunReport,
};
use crate::settings::Settings;
use crate::simulate::{simulate_runs, RunPlan, SimResult, SimSetup};
use crate::spectrum::SpectralPeak;
use crate::trials::{trials, ChannelFit, Trial};
use noise::{Channel, Effect, ImuChannels, SensorModel, Term};
use std::collections::BTreeMap;

pub use crate::findings::STAND_IN_GAP;

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
    let pre: Vec<Preprocessed> = logs
        .iter()
        .map(|l| crate::detect::preprocess_log(l, model))
        .collect();
    let start = Start {
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
    };
    let mut run = Run::start(start, model)?;
    run.time_domain_findings();
    // Steps 3-5: name, add, re-simulate, until nothing significant remains.
    for round in 1..=settings.max_rounds {
        let pending = run.name_effects(round);
        if pending.is_empty() {
            break;
        }
        run.resimulate(round, pending)?;
    }
    run.settle_drift()?;
    run.drift_rounds()?;
    Ok(run.report())
}

mod drift_rounds;

/// What a run starts from: the logs (runs) as measured, the logs after step 0's corrections, the
/// detectors' findings, and how to work.
struct Start<'a> {
    raw: Vec<LogInput<'a>>,
    logs: Vec<LogInput<'a>>,
    pre: &'a [Preprocessed],
    samples: Vec<usize>,
    settings: &'a Settings,
    observer: &'a dyn Observer,
}

/// Step 1's result: the common tau grid's averaging factors, and each channel's measurement on it
/// (pooled over the runs, and per run), of the corrected logs and of the raw ones.
struct Measurement {
    corrected: Runs,
    raw: Runs,
}

/// What the workflow knows about one channel so far.
#[derive(Default)]
struct ChannelState {
    /// The gap of the raw log (before step 0's corrections) against the original model's band.
    initial: Option<(Band, Gap)>,
    /// The effects named so far, in the order found.
    effects: Vec<FoundEffect>,
    /// Every candidate weighed, every round.
    records: Vec<CandidateRecord>,
    /// Nothing more to name: no disagreement left, no candidate good enough, or a round rejected.
    done: bool,
    /// The structures the drift loop's last weighing of this channel could not tell from the one
    /// kept (`alternatives`).
    alternatives: Vec<crate::alternatives::Alternative>,
}

/// A channel changed in this round: the changes in the order made (each effect with its level
/// before, to undo them) and the channel's gap at the round's start.
struct Pending {
    channel: Channel,
    changes: Vec<(Effect, Option<Term>)>,
    gap_before: f64,
}

/// One channel's round, worked out on its own copy of the model ([`Run::name_effects`]): the terms
/// to set on the channel in order, the channel's effects after the round (those named before it
/// and now), the candidates weighed, and the changes to check by re-simulation (None: no change).
struct RoundOutcome {
    terms: Vec<Term>,
    effects: Vec<FoundEffect>,
    records: Vec<CandidateRecord>,
    pending: Option<Pending>,
}

/// Step 4: put the chosen term into `model` on channel `c` and append it to `terms` (what the
/// round then sets in both of the run's models); the changes made, each with the term before. A
/// trial whose parameters the terms' constructors refuse changes nothing.
fn accept(
    model: &mut SensorModel,
    terms: &mut Vec<Term>,
    c: Channel,
    best: &Trial,
) -> Vec<(Effect, Option<Term>)> {
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
        terms.push(term);
    }
    changes
}

/// One diagnosis in progress.
struct Run<'a> {
    settings: &'a Settings,
    observer: &'a dyn Observer,
    /// The corrected logs (runs) the Allan steps see.
    logs: Vec<LogInput<'a>>,
    pre: &'a [Preprocessed],
    samples: Vec<usize>,
    /// Averaging factors of the common tau grid, and each channel's measurement on it (pooled).
    grid_m: Vec<usize>,
    measured: ImuChannels<Option<Measured>>,
    /// Each run's own measurement, corrected and raw (several runs only).
    run_measured: Vec<ImuChannels<Option<Measured>>>,
    run_raw: Vec<ImuChannels<Option<Measured>>>,
    /// Least-squares slope of each corrected channel against time (the rate-ramp level, see `trials`).
    ramp_slope: ImuChannels<f64>,
    /// The broad spectral peak and the spectral lines of each channel (over all runs' segments).
    peaks: ImuChannels<Option<SpectralPeak>>,
    lines: ImuChannels<Vec<f64>>,
    setup: SimSetup<'a>,
    plan: RunPlan,
    /// The model simulated (step 0's terms left out: their effects are removed from the log) and the
    /// corrected model reported (with them).
    sim_model: SensorModel,
    out_model: SensorModel,
    /// The original model's simulation (its bands and drift).
    sim0: SimResult,
    /// The current model's band per channel (pooled, and of one log at each run length), and its
    /// drift (stale while `dirty`).
    bands: ImuChannels<Option<Band>>,
    log_bands: Vec<(usize, ImuChannels<Option<Band>>)>,
    last_drift: Vec<SegmentDrift>,
    /// The drift check (`Settings::drift_protocol`): the runs' segment errors under the protocol,
    /// the original model's drift gap, and the current model's simulated segment errors.
    drift_measured: Vec<crate::protocol::SegmentErrors>,
    drift_gap0: Option<crate::drift_gap::DriftGap>,
    last_protocol: Vec<Vec<Vec<crate::protocol::SegmentErrors>>>,
    dirty: bool,
    channels: ImuChannels<ChannelState>,
    rounds: usize,
}

impl<'a> Run<'a> {
    /// Steps 1 and 2: measure the logs, simulate the model's band, and the gap before any change.
    fn start(s: Start<'a>, model: &SensorModel) -> Result<Run<'a>, DiagnoseError> {
        let Measurement { corrected, raw } = Self::measure(&s)?;
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
        };
        let sim0 = Self::band(model, &setup, &plan, s.settings, s.observer)?;
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
        let mut run = Run {
            settings: s.settings,
            observer: s.observer,
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
            sim_model: model.clone(),
            out_model: model.clone(),
            bands: sim0.bands.clone(),
            log_bands: sim0.log_bands.clone(),
            last_drift: sim0.drift.clone(),
            drift_measured,
            drift_gap0: None,
            last_protocol: sim0.protocol_errors.clone(),
            sim0,
            dirty: false,
            channels: ImuChannels::default(),
            rounds: 0,
            setup,
            plan,
        };
        for c in Channel::ALL {
            let band = run.bands[c].as_ref();
            run.channels[c].initial = Self::gap_of(raw.pooled[c].as_ref(), band);
            run.channels[c].done = !run.setup.active[c];
        }
        run.drift_gap0 = run.drift_gap();
        Ok(run)
    }

    /// Step 1: measured Allan deviations with EDF (Greenhall, noise type by lag-1 ACF) on the octave
    /// grid, of the corrected logs and of the raw ones (for the gap before step 0's corrections),
    /// pooled over the runs.
    fn measure(s: &Start) -> Result<Measurement, DiagnoseError> {
        s.observer.step(Step::Measure);
        let tau_min_s = s.settings.tau_min_s;
        let corrected = measure_runs(&s.logs, tau_min_s);
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

    /// Step 3: the gap of a measurement against a band on the measurement's own taus.
    fn gap_of(measured: Option<&Measured>, band: Option<&Band>) -> Option<(Band, Gap)> {
        let m = measured?;
        let b = restrict(band?, &m.idx);
        let g = gap(&m.curve, &b);
        Some((b, g))
    }

    /// Step 3 for channel `c` against the current model's band.
    fn gap(&self, c: Channel) -> Option<(Band, Gap)> {
        Self::gap_of(self.measured[c].as_ref(), self.bands[c].as_ref())
    }

    /// Round 0: the time-domain detectors' findings enter the corrected model (their effects are
    /// already removed from the log the Allan rounds see).
    fn time_domain_findings(&mut self) {
        for c in Channel::ALL {
            let (Some((_, g0)), Some((_, g1))) = (self.channels[c].initial.as_ref(), self.gap(c))
            else {
                continue;
            };
            let (gap_before, gap_after) = (g0.rms, g1.rms);
            let per_run: Vec<&[crate::detect::Finding]> =
                self.pre.iter().map(|p| p.findings[c].as_slice()).collect();
            for f in &crate::runs::pooled_findings(&per_run, &self.hours()) {
                let axis = self.out_model.axis_mut(c.sensor(), c.axis());
                let had = axis.term(f.term.effect()).is_some();
                axis.set_term(f.term.clone());
                let found = found_by_detector(f, had, gap_before, gap_after);
                self.channels[c].effects.push(found);
            }
        }
    }

    /// Steps 3 and 4 of one round on every channel not done; the channels changed. Each
    /// channel's round reads only its own axis of the model and its own findings (the candidates,
    /// the selection and the changes are per channel), so the rounds run side by side on a copy
    /// of the model each and are applied in channel order: the state one after the other leaves.
    fn name_effects(&mut self, round: usize) -> Vec<Pending> {
        use rayon::prelude::*;
        let todo: Vec<Channel> = Channel::ALL
            .into_iter()
            .filter(|&c| !self.channels[c].done)
            .collect();
        let outcomes: Vec<Option<RoundOutcome>> = todo
            .par_iter()
            .map(|&c| self.channel_round(c, round))
            .collect();
        let mut pending = Vec::new();
        for (c, outcome) in todo.into_iter().zip(outcomes) {
            let Some(o) = outcome else {
                self.channels[c].done = true;
                continue;
            };
            for term in o.terms {
                set_term(&mut self.sim_model, c, term.clone());
                set_term(&mut self.out_model, c, term);
            }
            self.channels[c].records.extend(o.records);
            self.channels[c].effects = o.effects;
            match o.pending {
                Some(p) => pending.push(p),
                None => self.channels[c].done = true,
            }
        }
        pending
    }

    /// One round on channel `c`: up to `effects_per_round` effects by forward selection on the
    /// closed-form prediction (so a short-tau disagreement with huge z does not hold back a long-tau
    /// one for many rounds); the round's re-simulation then checks them together. None when the
    /// channel has no disagreement left; an outcome without `pending` when nothing was changed.
    fn channel_round(&self, c: Channel, round: usize) -> Option<RoundOutcome> {
        let (band, g) = self.gap(c)?;
        if g.disagreements.is_empty() {
            return None;
        }
        let curve = self.measured[c]
            .as_ref()
            .expect("active channel is measured")
            .curve
            .clone();
        let ln_meas: Vec<f64> = curve.adev.iter().map(|a| a.ln()).collect();
        let mut model = self.sim_model.clone();
        let mut out = RoundOutcome {
            terms: Vec::new(),
            effects: self.channels[c].effects.clone(),
            records: Vec::new(),
            pending: None,
        };
        let mut predicted = band;
        let mut g_pred = g.clone();
        let mut changes = Vec::new();
        for _step in 0..self.settings.effects_per_round {
            if g_pred.disagreements.is_empty() {
                break;
            }
            let ts = self.candidates(&model, c, &curve, &predicted, &g_pred);
            let data = FitData {
                ln_meas: &ln_meas,
                ln_band: &predicted.ln_mean,
                avar_band: &predicted.avar_mean,
                s: &g_pred.s,
            };
            let base_bic = bic(data.chi2_base(), 0, ln_meas.len());
            out.records
                .extend(trial_records(round, &ts, base_bic, data.chi2_base()));
            let choice = self.select(&out.effects, &ts, base_bic);
            // The joint re-level is of the model as given (round 1): later rounds refine the levels
            // of the terms they name one at a time, as before.
            let joint = (round == 1)
                .then(|| crate::relevel::joint_relevel(&data, &ts, self.settings.min_delta_bic))
                .flatten();
            if let Some(joint) = joint.filter(|j| self.prefer_joint(j, choice.as_ref(), base_bic)) {
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
                    let found = found_by_fit(choice, round, g.rms, g_pred.rms, self.dt_s());
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
            let found = found_by_fit(choice, round, g.rms, g_pred.rms, self.dt_s());
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
        &self,
        model: &SensorModel,
        c: Channel,
        curve: &Curve,
        band: &Band,
        g: &Gap,
    ) -> Vec<Trial> {
        let dt_s = self.dt_s();
        let series = self.series(c);
        trials(&ChannelFit {
            model,
            channel: c,
            measured: curve,
            band,
            gap: g,
            dt_s,
            ramp_slope: self.ramp_slope[c],
            peak: self.peaks[c],
            lines: &self.lines[c],
            line_resolution_hz: crate::spectrum::line_resolution_hz(&series, dt_s),
            line_frequency_resolution_hz: crate::spectrum::line_frequency_resolution_hz(
                &series, dt_s,
            ),
        })
    }

    /// Step 4: the candidate to name, if any improves BIC by `min_delta_bic`.
    fn select<'t>(
        &self,
        named: &[FoundEffect],
        ts: &'t [Trial],
        base_bic: f64,
    ) -> Option<Choice<'t>> {
        let settings = self.settings;
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
        &self,
        joint: &crate::relevel::Relevel,
        best: Option<&Choice>,
        base_bic: f64,
    ) -> bool {
        base_bic - joint.bic >= self.settings.min_delta_bic
            && best.is_none_or(|b| joint.bic < b.trial.bic)
    }

    /// Undo one change of [`accept`] in both models.
    fn undo(&mut self, c: Channel, effect: Effect, previous: Option<Term>) {
        for model in [&mut self.sim_model, &mut self.out_model] {
            restore_term(model, c, effect, previous.clone());
        }
    }

    /// Step 5: simulate the corrected model and keep each changed channel's round only if its gap
    /// shrank. Only the channels changed in this round are simulated: each channel draws from its own
    /// streams, so its band is the same whichever others are generated. The drift needs every
    /// channel; a partial round leaves it to a full simulation after the loop.
    fn resimulate(&mut self, round: usize, pending: Vec<Pending>) -> Result<(), DiagnoseError> {
        self.rounds = round;
        self.observer.step(Step::Resimulate { round });
        let active = self.setup.active;
        let changed = ImuChannels::from_fn(|c| active[c] && pending.iter().any(|p| p.channel == c));
        let partial = changed != active;
        let round_plan = RunPlan {
            protocol: if partial {
                None
            } else {
                self.plan.protocol.clone()
            },
            ..self.plan.clone()
        };
        let round_setup = SimSetup {
            active: changed,
            // A partial round's drift is not used (it needs every channel): not computed.
            horizons_s: if partial {
                Vec::new()
            } else {
                self.setup.horizons_s.clone()
            },
            ..self.setup.clone()
        };
        let settings = self.settings;
        let sim = simulate_runs(
            &self.sim_model,
            &round_setup,
            &round_plan,
            settings.seed,
            settings.seeds,
        )?;
        self.dirty = partial;
        for p in pending {
            self.keep_or_undo(round, p, &sim);
        }
        if !partial {
            self.last_drift = sim.drift;
            self.last_protocol = sim.protocol_errors;
        }
        Ok(())
    }

    /// Step 5 for one channel: its re-simulated `band` is kept if the gap shrank; otherwise the
    /// round's changes are undone (recorded as rejected) and the channel is done.
    fn keep_or_undo(&mut self, round: usize, p: Pending, sim: &SimResult) {
        let c = p.channel;
        let band = sim.bands[c].clone();
        let after = Self::gap_of(self.measured[c].as_ref(), band.as_ref())
            .map(|(_, g)| g.rms)
            .unwrap_or(f64::NAN);
        let state = &mut self.channels[c];
        let first_new = state
            .effects
            .iter()
            .position(|e| e.round == round)
            .unwrap_or(state.effects.len());
        for found in &mut state.effects[first_new..] {
            found.gap_after = after;
        }
        if !(after.is_nan() || after >= p.gap_before) {
            self.bands[c] = band;
            for (mine, new) in self.log_bands.iter_mut().zip(&sim.log_bands) {
                mine.1[c] = new.1[c].clone();
            }
            merge_refinements(&mut state.effects, first_new);
            return;
        }
        // The re-simulated model is no closer: undo this round's changes and stop here.
        let rejected: Vec<CandidateRecord> = state
            .effects
            .drain(first_new..)
            .map(|e| rejected_record(round, e))
            .collect();
        state.records.extend(rejected);
        state.done = true;
        for (effect, previous) in p.changes.into_iter().rev() {
            self.undo(c, effect, previous);
        }
        self.dirty = true;
    }

    /// The corrected model simulated on the whole plan (every run's length), as the band is.
    fn simulate_whole(&self) -> Result<SimResult, DiagnoseError> {
        let settings = self.settings;
        Ok(simulate_runs(
            &self.sim_model,
            &self.setup,
            &self.plan,
            settings.seed,
            settings.seeds,
        )?)
    }

    /// After the rounds: the corrected model's drift, simulated again when the last full
    /// simulation is stale (a partial or rejected round).
    fn settle_drift(&mut self) -> Result<(), DiagnoseError> {
        if self.dirty {
            // Only the drift is wanted here: no Allan deviations of the simulated logs (an empty
            // grid), the same logs and so the same drift.
            let setup = SimSetup {
                grid_m: Vec::new(),
                ..self.setup.clone()
            };
            let settings = self.settings;
            let sim = simulate_runs(
                &self.sim_model,
                &setup,
                &self.plan,
                settings.seed,
                settings.seeds,
            )?;
            self.last_drift = sim.drift;
            self.last_protocol = sim.protocol_errors;
            self.dirty = false;
        }
        Ok(())
    }

    /// The current model's drift gap under the drift protocol (None without one).
    fn drift_gap(&self) -> Option<crate::drift_gap::DriftGap> {
        self.plan.protocol.as_ref()?;
        let (_, of_run) = self.plan.lengths();
        Some(crate::drift_gap::drift_gap(
            &self.drift_measured,
            &self.last_protocol,
            &of_run,
            &self.setup.active,
        ))
    }

    /// Step 6: drift consequence, measured log segments vs model before vs model after.
    fn drift(&self) -> Vec<DriftRow> {
        self.settings
            .horizons_s
            .iter()
            .enumerate()
            .map(|(h, &horizon)| DriftRow {
                horizon_s: horizon,
                measured: self.measured_drift(horizon).summary(),
                model_initial: self.sim0.drift[h].summary(),
                model_final: self.last_drift[h].summary(),
            })
            .collect()
    }

    /// What diagnose says about channel `c` (None when it is not measured).
    fn channel_report(&mut self, c: Channel) -> Option<ChannelReport> {
        let (b1, g1) = self.gap(c)?;
        let m = self.measured[c].as_ref()?;
        let (b0, g0) = self.channels[c].initial.clone()?;
        let (xs, dt_s) = (self.series(c), self.dt_s());
        let state = &mut self.channels[c];
        if g1.rms > STAND_IN_GAP {
            mark_stand_ins(&mut state.effects, &xs, dt_s);
        }
        Some(ChannelReport {
            gap_initial: g0.rms,
            gap_final: g1.rms,
            verdict: verdict(&g1, &state.effects),
            effects: std::mem::take(&mut state.effects),
            z_initial: g0.z,
            z_final: g1.z.clone(),
            disagreements_initial: g0.disagreements,
            disagreements_final: g1.disagreements,
            candidates: std::mem::take(&mut state.records),
            curves: channel_curves(m, &b0, b1),
        })
    }

    /// Each run's curves, gaps and step-0 findings (several runs only; the pooled findings are
    /// the channels').
    fn run_reports(&self) -> Vec<RunReport> {
        let band_at = |bands: &[(usize, ImuChannels<Option<Band>>)], n: usize, c: Channel| {
            bands.iter().find(|b| b.0 == n).and_then(|b| b.1[c].clone())
        };
        (0..self.run_measured.len())
            .map(|r| {
                let n = self.samples[r];
                let mut channels = BTreeMap::new();
                let mut findings = BTreeMap::new();
                for c in Channel::ALL {
                    let (Some(m), Some(raw)) = (
                        self.run_measured[r][c].as_ref(),
                        self.run_raw[r][c].as_ref(),
                    ) else {
                        continue;
                    };
                    let b0 = band_at(&self.sim0.log_bands, n, c);
                    let b1 = band_at(&self.log_bands, n, c);
                    let rms = |m: &Measured, b: &Option<Band>| {
                        Self::gap_of(Some(m), b.as_ref()).map_or(f64::NAN, |g| g.1.rms)
                    };
                    let (g0, g_corr, g1) = (rms(raw, &b0), rms(m, &b0), rms(m, &b1));
                    let found: Vec<FoundEffect> = self.pre[r].findings[c]
                        .iter()
                        .map(|f| {
                            let had = self.channels[c].effects.iter().any(|e| {
                                e.round == 0
                                    && e.effect == f.term.effect()
                                    && e.kind == crate::report::FindingKind::WrongLevel
                            });
                            found_by_detector(f, had, g0, g_corr)
                        })
                        .collect();
                    if !found.is_empty() {
                        findings.insert(c.name().to_string(), found);
                    }
                    channels.insert(
                        c.name().to_string(),
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

    /// The diagnosis.
    fn report(mut self) -> Diagnosis {
        let drift = self.drift();
        let runs = self.run_reports();
        let drift_check = self.drift_report();
        let alternatives = Channel::ALL
            .into_iter()
            .flat_map(|c| std::mem::take(&mut self.channels[c].alternatives))
            .collect();
        let mut channels = BTreeMap::new();
        for c in Channel::ALL {
            if let Some(r) = self.channel_report(c) {
                channels.insert(c.name().to_string(), r);
            }
        }
        let log_bands = self
            .sim0
            .log_bands
            .iter()
            .zip(self.log_bands)
            .map(|(b0, b1)| LogBands {
                samples: b0.0,
                initial: b0.1.clone(),
                corrected: b1.1,
            })
            .collect();
        Diagnosis {
            seed: self.settings.seed,
            seeds: self.settings.seeds,
            rounds: self.rounds,
            dt_s: self.logs[0].dt_s,
            samples: self.samples.iter().sum(),
            channels,
            drift,
            runs,
            drift_check,
            alternatives,
            tau_min_s: self.settings.tau_min_s,
            model_final: self.out_model,
            grid_m: self.grid_m,
            log_bands,
        }
    }

    /// The sample interval of the logs.
    fn dt_s(&self) -> f64 {
        self.logs[0].dt_s
    }

    /// Each run's length, hours.
    fn hours(&self) -> Vec<f64> {
        self.samples
            .iter()
            .map(|&n| n as f64 * self.dt_s() / 3600.0)
            .collect()
    }

    /// Channel `c` of every corrected run (empty when not measured).
    fn series(&self, c: Channel) -> Vec<&'a [f64]> {
        self.logs.iter().filter_map(|l| l.channels[c]).collect()
    }

    /// The measured segment drifts of one horizon, every run's segments in run order (each run
    /// calibrated by its own mean).
    fn measured_drift(&self, horizon_s: f64) -> SegmentDrift {
        let mut all = SegmentDrift {
            horizon_s,
            ..Default::default()
        };
        for l in &self.logs {
            all.extend(&segment_drift(
                &l.channels.0,
                l.dt_s,
                horizon_s,
                self.settings.latitude_deg,
            ));
        }
        all
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
