//! The diagnose workflow (docs/diagnose.md, "The diagnose workflow", steps 0-6) as one `Run` whose
//! methods are the steps, in the order [`diagnose_observed`] calls them: detect and measure, simulate
//! the band, locate the gap, fit the candidates, accept the best, re-simulate, repeat; then the drift
//! consequence and the report.

use crate::candidates::TermParams;
use crate::detect::Preprocessed;
use crate::drift::{segment_drift, SegmentDrift};
use crate::error::DiagnoseError;
use crate::findings::{
    channel_curves, found_by_detector, found_by_fit, mark_stand_ins, merge_refinements,
    rejected_record, trial_records, verdict, Choice,
};
use crate::fit::{bic, predicted_ln_adev, FitData};
use crate::gap::{gap, Band, Curve, Gap};
use crate::input::LogInput;
use crate::measure::{measure, restrict, Measured};
use crate::model_terms::{clear_term, set_term, term_level};
use crate::observer::{Observer, Step};
use crate::report::{CandidateRecord, ChannelReport, Diagnosis, DriftRow, FoundEffect};
use crate::settings::Settings;
use crate::simulate::{simulate, SimResult, SimSetup};
use crate::trials::{trials, ChannelFit, Trial};
use noise::{Channel, Effect, ImuChannels, SensorModel};
use std::cell::RefCell;
use std::collections::{BTreeMap, HashMap};

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
    let samples = log.validate()?;
    // Step 0: time-domain detectors (`detect`); the Allan analysis sees the corrected channels.
    observer.step(Step::Detect);
    let pre = crate::detect::preprocess_log(log, model);
    let start = Start {
        raw: *log,
        log: log.with_channels(&pre.channels),
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
    Ok(run.report())
}

/// What a run starts from: the log as measured, the log after step 0's corrections, the detectors'
/// findings, and how to work.
struct Start<'a> {
    raw: LogInput<'a>,
    log: LogInput<'a>,
    pre: &'a Preprocessed,
    samples: usize,
    settings: &'a Settings,
    observer: &'a dyn Observer,
}

/// Step 1's result: the common tau grid's averaging factors, and each channel's measurement on it,
/// of the corrected log and of the raw one.
struct Measurement {
    grid_m: Vec<usize>,
    corrected: ImuChannels<Option<Measured>>,
    raw: ImuChannels<Option<Measured>>,
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
}

/// A channel changed in this round: the changes in the order made (each effect with its level
/// before, to undo them) and the channel's gap at the round's start.
struct Pending {
    channel: Channel,
    changes: Vec<(Effect, Option<TermParams>)>,
    gap_before: f64,
}

/// One diagnosis in progress.
struct Run<'a> {
    settings: &'a Settings,
    observer: &'a dyn Observer,
    /// The corrected log the Allan steps see.
    log: LogInput<'a>,
    pre: &'a Preprocessed,
    samples: usize,
    /// Averaging factors of the common tau grid, and each channel's measurement on it.
    grid_m: Vec<usize>,
    measured: ImuChannels<Option<Measured>>,
    /// Least-squares slope of each corrected channel against time (the rate-ramp level, see `trials`).
    ramp_slope: ImuChannels<f64>,
    setup: SimSetup<'a>,
    /// The model simulated (step 0's terms left out: their effects are removed from the log) and the
    /// corrected model reported (with them).
    sim_model: SensorModel,
    out_model: SensorModel,
    /// The original model's simulation (its bands and drift).
    sim0: SimResult,
    /// The current model's band per channel, and its drift (stale while `dirty`).
    bands: [Option<Band>; 6],
    last_drift: Vec<SegmentDrift>,
    dirty: bool,
    channels: ImuChannels<ChannelState>,
    /// Spectral-line checks by (channel, frequency): the same best sinusoid frequency recurs over the
    /// steps and rounds, and each check is a Welch DFT over the whole log.
    line_checks: RefCell<HashMap<(Channel, u64), bool>>,
    rounds: usize,
}

impl<'a> Run<'a> {
    /// Steps 1 and 2: measure the log, simulate the model's band, and the gap before any change.
    fn start(s: Start<'a>, model: &SensorModel) -> Result<Run<'a>, DiagnoseError> {
        let Measurement {
            grid_m,
            corrected: measured,
            raw: measured_raw,
        } = Self::measure(&s)?;
        let setup = SimSetup {
            dt_s: s.log.dt_s,
            samples: s.samples,
            grid_m: grid_m.clone(),
            active: std::array::from_fn(|c| s.raw.channels[c].is_some()),
            horizons_s: s.settings.horizons_s.clone(),
            temperature_c: s.log.temperature_c,
            temp_coeff: [0.0; 6],
        };
        let sim0 = Self::band(model, &setup, s.settings, s.observer)?;
        let log = s.log;
        let mut run = Run {
            settings: s.settings,
            observer: s.observer,
            log,
            pre: s.pre,
            samples: s.samples,
            grid_m,
            measured,
            ramp_slope: ImuChannels::from_fn(|c| {
                log.channels[c.index()].map_or(0.0, |x| crate::stats::slope(x, log.dt_s))
            }),
            sim_model: model.clone(),
            out_model: model.clone(),
            bands: sim0.bands.clone(),
            last_drift: sim0.drift.clone(),
            sim0,
            dirty: false,
            channels: ImuChannels::default(),
            line_checks: RefCell::default(),
            rounds: 0,
            setup,
        };
        for c in Channel::ALL {
            let band = run.bands[c.index()].as_ref();
            run.channels[c].initial = Self::gap_of(measured_raw[c].as_ref(), band);
            run.channels[c].done = !run.setup.active[c.index()];
        }
        Ok(run)
    }

    /// Step 1: measured Allan deviations with EDF (Greenhall, noise type by lag-1 ACF) on the octave
    /// grid, of the corrected log and of the raw one (for the gap before step 0's corrections).
    fn measure(s: &Start) -> Result<Measurement, DiagnoseError> {
        s.observer.step(Step::Measure);
        let tau_min_s = s.settings.tau_min_s;
        let (grid_m, corrected) = measure(&s.log, tau_min_s);
        let (_, raw) = measure(&s.raw, tau_min_s);
        if corrected
            .values()
            .iter()
            .flatten()
            .all(|m| m.idx.is_empty())
        {
            return Err(DiagnoseError::NoTaus { tau_min_s });
        }
        Ok(Measurement {
            grid_m,
            corrected,
            raw,
        })
    }

    /// Step 2: the model's band (and drift), simulated.
    fn band(
        model: &SensorModel,
        setup: &SimSetup,
        settings: &Settings,
        observer: &dyn Observer,
    ) -> Result<SimResult, DiagnoseError> {
        observer.step(Step::Band);
        Ok(simulate(model, setup, settings.seed, settings.seeds)?)
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
        Self::gap_of(self.measured[c].as_ref(), self.bands[c.index()].as_ref())
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
            for f in &self.pre.findings[c.index()] {
                let axis = self.out_model.axis_mut(c.sensor(), c.axis());
                let had = axis.term(f.term.effect()).is_some();
                axis.set_term(f.term.clone());
                let found = found_by_detector(f, had, gap_before, gap_after);
                self.channels[c].effects.push(found);
            }
        }
    }

    /// Steps 3 and 4 of one round on every channel not done; the channels changed.
    fn name_effects(&mut self, round: usize) -> Vec<Pending> {
        let mut pending = Vec::new();
        for c in Channel::ALL {
            if self.channels[c].done {
                continue;
            }
            match self.channel_round(c, round) {
                Some(p) => pending.push(p),
                None => self.channels[c].done = true,
            }
        }
        pending
    }

    /// One round on channel `c`: up to `effects_per_round` effects by forward selection on the
    /// closed-form prediction (so a short-tau disagreement with huge z does not hold back a long-tau
    /// one for many rounds); the round's re-simulation then checks them together. None when the
    /// channel has nothing (more) to name.
    fn channel_round(&mut self, c: Channel, round: usize) -> Option<Pending> {
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
        let mut predicted = band;
        let mut g_pred = g.clone();
        let mut changes = Vec::new();
        for _step in 0..self.settings.effects_per_round {
            if g_pred.disagreements.is_empty() {
                break;
            }
            let ts = self.candidates(c, &curve, &predicted, &g_pred);
            let data = FitData {
                ln_meas: &ln_meas,
                ln_band: &predicted.ln_mean,
                avar_band: &predicted.avar_mean,
                s: &g_pred.s,
            };
            let base_bic = bic(data.chi2_base(), 0, ln_meas.len());
            let records = trial_records(round, &ts, base_bic, data.chi2_base());
            self.channels[c].records.extend(records);
            let Some(choice) = self.select(c, &ts, base_bic) else {
                break;
            };
            changes.extend(self.accept(c, choice.trial));
            // The closed-form prediction of the band with this change, for the next step.
            predicted = shifted_band(&predicted, &choice.trial.delta_avar);
            g_pred = gap(&curve, &predicted);
            let found = found_by_fit(choice, round, g.rms, g_pred.rms, self.log.dt_s);
            self.channels[c].effects.push(found);
        }
        (!changes.is_empty()).then_some(Pending {
            channel: c,
            changes,
            gap_before: g.rms,
        })
    }

    /// Step 4: every candidate fitted to channel `c`'s gap against `band`.
    fn candidates(&self, c: Channel, curve: &Curve, band: &Band, g: &Gap) -> Vec<Trial> {
        let dt_s = self.log.dt_s;
        let line_allowed = |f: f64| {
            *self
                .line_checks
                .borrow_mut()
                .entry((c, f.to_bits()))
                .or_insert_with(|| {
                    self.pre.channels[c.index()]
                        .as_deref()
                        .is_none_or(|x| crate::detect::line_allowed(x, dt_s, f))
                })
        };
        trials(&ChannelFit {
            model: &self.sim_model,
            channel: c,
            measured: curve,
            band,
            gap: g,
            dt_s,
            ramp_slope: self.ramp_slope[c],
            peak: self.pre.peaks[c.index()],
            line_allowed: &line_allowed,
        })
    }

    /// Step 4: the candidate to name, if any improves BIC by `min_delta_bic`.
    fn select<'t>(&self, c: Channel, ts: &'t [Trial], base_bic: f64) -> Option<Choice<'t>> {
        let settings = self.settings;
        let mut best = ts.iter().min_by(|a, b| a.bic.total_cmp(&b.bic))?;
        // Occam: re-levelling an effect already named on this channel is preferred to naming
        // another one unless the other is better by the ambiguity margin.
        let named = &self.channels[c].effects;
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

    /// Step 4: put the chosen term into both models; the changes made, each with the level before.
    fn accept(&mut self, c: Channel, best: &Trial) -> Vec<(Effect, Option<TermParams>)> {
        let ch = c;
        let mut changes = Vec::new();
        if best.effect == Effect::OutputFilter {
            // The filter is fitted with the white-noise level: undoing it restores both.
            let white = term_level(&self.sim_model, ch, Effect::WhiteNoise);
            changes.push((Effect::WhiteNoise, white));
        }
        let previous = term_level(&self.sim_model, ch, best.effect);
        set_term(&mut self.sim_model, ch, best.effect, &best.params);
        set_term(&mut self.out_model, ch, best.effect, &best.params);
        changes.push((best.effect, previous));
        changes
    }

    /// Undo one change of [`Run::accept`] in both models.
    fn undo(&mut self, c: Channel, effect: Effect, previous: Option<TermParams>) {
        for model in [&mut self.sim_model, &mut self.out_model] {
            match previous {
                Some(p) => set_term(model, c, effect, &p),
                None => clear_term(model, c, effect),
            }
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
        let changed: [bool; 6] =
            std::array::from_fn(|c| active[c] && pending.iter().any(|p| p.channel.index() == c));
        let partial = changed != active;
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
        let sim = simulate(&self.sim_model, &round_setup, settings.seed, settings.seeds)?;
        self.dirty = partial;
        for p in pending {
            let band = sim.bands[p.channel.index()].clone();
            self.keep_or_undo(round, p, band);
        }
        if !partial {
            self.last_drift = sim.drift;
        }
        Ok(())
    }

    /// Step 5 for one channel: its re-simulated `band` is kept if the gap shrank; otherwise the
    /// round's changes are undone (recorded as rejected) and the channel is done.
    fn keep_or_undo(&mut self, round: usize, p: Pending, band: Option<Band>) {
        let c = p.channel;
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
            self.bands[c.index()] = band;
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

    /// After the rounds: the corrected model's drift, simulated again when the last full
    /// simulation is stale (a partial or rejected round).
    fn settle_drift(&mut self) -> Result<(), DiagnoseError> {
        if self.dirty {
            let settings = self.settings;
            let sim = simulate(&self.sim_model, &self.setup, settings.seed, settings.seeds)?;
            self.last_drift = sim.drift;
        }
        Ok(())
    }

    /// Step 6: drift consequence, measured log segments vs model before vs model after.
    fn drift(&self) -> Vec<DriftRow> {
        self.settings
            .horizons_s
            .iter()
            .enumerate()
            .map(|(h, &horizon)| DriftRow {
                horizon_s: horizon,
                measured: segment_drift(&self.log.channels, self.log.dt_s, horizon).summary(),
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
        let state = &mut self.channels[c];
        if g1.rms > STAND_IN_GAP {
            mark_stand_ins(
                &mut state.effects,
                self.log.channels[c.index()],
                self.log.dt_s,
            );
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

    /// The diagnosis.
    fn report(mut self) -> Diagnosis {
        let drift = self.drift();
        let mut channels = BTreeMap::new();
        for c in Channel::ALL {
            if let Some(r) = self.channel_report(c) {
                channels.insert(c.name().to_string(), r);
            }
        }
        Diagnosis {
            seed: self.settings.seed,
            seeds: self.settings.seeds,
            rounds: self.rounds,
            dt_s: self.log.dt_s,
            samples: self.samples,
            channels,
            drift,
            tau_min_s: self.settings.tau_min_s,
            model_final: self.out_model,
            grid_m: self.grid_m,
            bands_initial: self.sim0.bands,
            bands_final: self.bands,
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
