//! The drift loop of the workflow (docs/diagnose.md, "Drift in the loop"): after the Allan rounds,
//! while the runs' drift under the protocol leaves the model's band, the long-averaging-time terms
//! are fitted to the Allan gap and the drift gap together (`drift_fit`) on every channel an
//! outside quantity comes from; each channel's best candidate that passes the BIC rule is named,
//! the corrected model re-simulated (every channel: the drift needs them all), and the round kept
//! only if the joint chi2 (the drift gap's and the changed channels' Allan gaps') shrank.

use super::{shifted_band, Run};
use crate::alternatives::{
    differing_effects, removed_effects, weights, Alternative, MAX_PER_CHANNEL, OCCAM_DELTA_BIC,
};
use crate::drift_fit::{
    allan_dispersion, DriftFitInput, DriftTrial, Partner, UnitDrift, SUPPORT_SHARE,
};
use crate::drift_gap::DriftGap;
use crate::error::DiagnoseError;
use crate::findings::{found_by_fit, merge_refinements, rejected_record, Choice};
use crate::gap::gap;
use crate::model_terms::{current_term, restore_term, set_term};
use crate::report::{Candidate, CandidateRecord, DriftLoop};
use crate::trials::{named_map, Trial};
use noise::{AxisModel, Channel, Effect, ImuChannels, Term};

/// A change the drift loop made: the channel, the effect and its term before.
type Change = (Channel, Effect, Option<Term>);

impl Run<'_> {
    /// The drift loop (module doc), at most `max_rounds` rounds.
    pub(super) fn drift_rounds(&mut self) -> Result<(), DiagnoseError> {
        if self.plan.protocol.is_none() {
            return Ok(());
        }
        for _ in 0..self.settings.max_rounds {
            let Some(before) = self.drift_gap() else {
                break;
            };
            let round = self.rounds + 1;
            let alternatives = ImuChannels::from_fn(|c| self.channels[c].alternatives.clone());
            let changes: Vec<Change> = before
                .channels_outside()
                .into_iter()
                .filter_map(|c| self.drift_choice(c, &before, round))
                .flatten()
                .collect();
            if changes.is_empty() {
                break;
            }
            if !self.drift_resimulate(round, &before, changes)? {
                // The round's alternatives were weighed against a structure undone.
                for c in Channel::ALL {
                    self.channels[c].alternatives = alternatives[c].clone();
                }
                break;
            }
        }
        Ok(())
    }

    /// The drift candidates of channel `c` weighed, and the best one that passes the BIC rule
    /// named (put into both models, with the rate random walk re-levelled beside it when that fit
    /// better: `DriftFitInput::with_random_walk`); the changes made.
    fn drift_choice(&mut self, c: Channel, drift: &DriftGap, round: usize) -> Option<Vec<Change>> {
        let (band, g) = self.gap(c)?;
        let curve = self.measured[c].as_ref()?.curve.clone();
        let protocol = self.plan.protocol.clone()?;
        let input = DriftFitInput {
            model: &self.sim_model,
            channel: c,
            measured: &curve,
            band: &band,
            gap: &g,
            dt_s: self.dt_s(),
            ramp_slope: self.ramp_slope[c],
            drift: drift.of_channel(c),
            correlation: drift.correlation_of_channel(c),
            unit: UnitDrift {
                dt_s: self.dt_s(),
                samples: &self.samples,
                protocol: &protocol,
                seed: self.settings.seed,
                logs: (4 * self.settings.seeds).max(64),
            },
        };
        let trials = input.trials();
        self.channels[c]
            .records
            .extend(trials.iter().map(|t| CandidateRecord {
                round,
                effect: Candidate {
                    effect: t.trial.effect,
                    rejected: false,
                },
                delta_bic: t.delta_bic,
                delta_aic: f64::NAN,
                parameters: named_map(&t.trial.named()),
            }));
        let best = trials
            .iter()
            .filter(|t| t.delta_bic >= self.settings.min_delta_bic)
            .max_by(|a, b| a.delta_bic.total_cmp(&b.delta_bic));
        self.channels[c].alternatives = self.alternatives_of(c, &trials, best);
        let best: &DriftTrial = best?;
        let cannot_tell_from = trials
            .iter()
            .filter(|t| {
                t.trial.effect != best.trial.effect
                    && best.delta_bic - t.delta_bic < self.settings.ambiguity_delta_bic
            })
            .map(|t| t.trial.effect)
            .collect();
        let effect = best.trial.effect;
        let previous = current_term(&self.sim_model, c, effect);
        set_term(&mut self.sim_model, c, best.trial.term.clone());
        set_term(&mut self.out_model, c, best.trial.term.clone());
        let mut delta_avar = best.trial.delta_avar.clone();
        if let Some(p) = &best.partner {
            for (d, r) in delta_avar.iter_mut().zip(&p.delta_avar) {
                *d += r;
            }
        }
        let predicted = gap(&curve, &shifted_band(&band, &delta_avar)).rms;
        let choice = Choice {
            trial: &best.trial,
            delta_bic: best.delta_bic,
            cannot_tell_from,
        };
        let mut found = found_by_fit(choice, round, g.rms, predicted, self.dt_s());
        found.drift_gap_before = Some(drift.gap);
        self.channels[c].effects.push(found);
        let mut changes = vec![(c, effect, previous)];
        if let Some(p) = &best.partner {
            changes.push(self.relevel_random_walk(
                c,
                p,
                best.delta_bic,
                round,
                (g.rms, predicted, drift.gap),
            ));
        }
        Some(changes)
    }

    /// The structures of channel `c` the evidence cannot tell from the one kept (`alternatives`),
    /// after this round's weighing `trials`: the channel's axis before the round, and with each
    /// trial's term (and its re-levelled random walk). Each is scored by its BIC gain less the
    /// naming rule's threshold for a change (`min_delta_bic`, read as the prior odds e^(-T/2)
    /// against a change that the rule's null calibration stands for: a change is named exactly
    /// when its posterior odds reach 1), so a candidate the rule did not name weighs less than the
    /// structure kept, and the structure before a named change stays in the average when the
    /// change barely passed. Those within Occam's window of the kept one are its alternatives.
    /// When `best` is named they replace the channel's earlier alternatives (weighed against a
    /// structure this round changed); otherwise they join them.
    fn alternatives_of(
        &self,
        c: Channel,
        trials: &[DriftTrial],
        best: Option<&DriftTrial>,
    ) -> Vec<Alternative> {
        let base = self.out_model.axis(c.sensor(), c.axis());
        let with = |t: &DriftTrial| {
            let mut a = base.clone();
            a.set_term(t.trial.term.clone());
            if let Some(p) = &t.partner {
                match &p.term {
                    Some(term) => a.set_term(term.clone()),
                    None => a.remove(Effect::RateRandomWalk),
                }
            }
            a
        };
        let prior = self.settings.min_delta_bic;
        let kept = best.map_or(0.0, |b| b.delta_bic - prior);
        let own = best.map_or_else(|| base.clone(), with);
        let mut near: Vec<(f64, AxisModel)> = match best {
            Some(_) => Vec::new(),
            None => self.channels[c]
                .alternatives
                .iter()
                .map(|a| (a.delta_bic, a.axis.clone()))
                .collect(),
        };
        let scored = std::iter::once((0.0, base.clone()))
            .chain(trials.iter().map(|t| (t.delta_bic - prior, with(t))));
        for (score, axis) in scored {
            let d = kept - score;
            if d.is_finite()
                && d <= OCCAM_DELTA_BIC
                && axis != own
                && near.iter().all(|(_, a)| *a != axis)
            {
                near.push((d, axis));
            }
        }
        near.sort_by(|a, b| a.0.total_cmp(&b.0));
        near.truncate(MAX_PER_CHANNEL);
        let d: Vec<f64> = near.iter().map(|(d, _)| *d).collect();
        let w = weights(&d);
        near.into_iter()
            .zip(&w[1..])
            .map(|((delta_bic, axis), &weight)| Alternative {
                channel: c,
                weight,
                delta_bic,
                effects: differing_effects(&own, &axis),
                removed: removed_effects(&own, &axis),
                axis,
            })
            .collect()
    }

    /// Put the rate random walk re-levelled with a drift candidate into both models (removed at
    /// level 0) and report it as a wrong level; the change made.
    fn relevel_random_walk(
        &mut self,
        c: Channel,
        p: &Partner,
        delta_bic: f64,
        round: usize,
        (gap_before, gap_predicted, drift_gap): (f64, f64, f64),
    ) -> Change {
        let effect = Effect::RateRandomWalk;
        let previous = current_term(&self.sim_model, c, effect);
        for model in [&mut self.sim_model, &mut self.out_model] {
            restore_term(model, c, effect, p.term.clone());
        }
        let zero = previous.as_ref().and_then(|t| t.with_level(0.0).ok());
        let Some(term) = p.term.clone().or(zero) else {
            return (c, effect, previous);
        };
        let trial = Trial {
            effect,
            term,
            white_n: None,
            lo: p.lo.clone(),
            hi: p.hi.clone(),
            model: Some(p.model.clone()),
            bic: f64::NAN,
            aic: f64::NAN,
            delta_avar: p.delta_avar.clone(),
            signature: p.signature.clone(),
        };
        let choice = Choice {
            trial: &trial,
            delta_bic,
            cannot_tell_from: Vec::new(),
        };
        let mut found = found_by_fit(choice, round, gap_before, gap_predicted, self.dt_s());
        found.drift_gap_before = Some(drift_gap);
        self.channels[c].effects.push(found);
        (c, effect, previous)
    }

    /// The round's re-simulation: kept (true) if the joint chi2 of the drift gap and the changed
    /// channels' Allan gaps shrank, else undone (the state before it kept).
    fn drift_resimulate(
        &mut self,
        round: usize,
        before: &DriftGap,
        changes: Vec<Change>,
    ) -> Result<bool, DiagnoseError> {
        self.observer
            .step(crate::observer::Step::Resimulate { round });
        let sim = self.simulate_whole()?;
        let (_, of_run) = self.plan.lengths();
        let after = crate::drift_gap::drift_gap(
            &self.drift_measured,
            &sim.protocol_errors,
            &of_run,
            &self.setup.active,
        );
        // Each changed channel's Allan chi2, divided by its dispersion before the round over the
        // taus the round moved by `SUPPORT_SHARE` or more (`drift_fit::allan_dispersion`), counted once
        // per channel.
        let mut channels: Vec<Channel> = changes.iter().map(|(c, _, _)| *c).collect();
        channels.dedup();
        let gap_on = |run: &Self, bands: &ImuChannels<Option<crate::gap::Band>>, c: Channel| {
            Self::gap_of(run.measured[c].as_ref(), bands[c].as_ref())
        };
        let dispersion: Vec<f64> = channels
            .iter()
            .map(|&c| {
                let (Some((b0, g0)), Some((b1, _))) =
                    (gap_on(self, &self.bands, c), gap_on(self, &sim.bands, c))
                else {
                    return 1.0;
                };
                let moved: Vec<f64> =
                    g0.z.iter()
                        .zip(b0.avar_mean.iter().zip(&b1.avar_mean))
                        .filter(|(_, (a0, a1))| (*a1 - *a0).abs() >= SUPPORT_SHARE * *a0)
                        .map(|(z, _)| *z)
                        .collect();
                allan_dispersion(moved.iter().map(|z| z * z).sum(), moved.len())
            })
            .collect();
        let allan_chi2 = |run: &Self, bands: &ImuChannels<Option<crate::gap::Band>>| -> f64 {
            channels
                .iter()
                .zip(&dispersion)
                .filter_map(|(&c, d)| {
                    gap_on(run, bands, c).map(|(_, g)| g.z.iter().map(|z| z * z).sum::<f64>() / d)
                })
                .sum()
        };
        let kept = after.chi2() + allan_chi2(self, &sim.bands)
            < before.chi2() + allan_chi2(self, &self.bands);
        for (c, _, _) in &changes {
            let allan_after = Self::gap_of(self.measured[*c].as_ref(), sim.bands[*c].as_ref())
                .map_or(f64::NAN, |(_, g)| g.rms);
            let state = &mut self.channels[*c];
            let first_new = state
                .effects
                .iter()
                .position(|e| e.round == round)
                .unwrap_or(state.effects.len());
            for e in &mut state.effects[first_new..] {
                e.gap_after = allan_after;
                e.drift_gap_after = Some(after.gap);
            }
            if kept {
                merge_refinements(&mut state.effects, first_new);
            } else {
                let rejected: Vec<CandidateRecord> = state
                    .effects
                    .drain(first_new..)
                    .map(|e| rejected_record(round, e))
                    .collect();
                state.records.extend(rejected);
            }
        }
        if kept {
            self.rounds = round;
            self.bands = sim.bands;
            self.log_bands = sim.log_bands;
            self.last_drift = sim.drift;
            self.last_protocol = sim.protocol_errors;
        } else {
            for (c, effect, previous) in changes.into_iter().rev() {
                self.undo(c, effect, previous);
            }
        }
        Ok(kept)
    }

    /// The drift check's report: the original and the corrected model's drift gaps.
    pub(super) fn drift_report(&self) -> Option<DriftLoop> {
        let protocol = self.plan.protocol.clone()?;
        Some(DriftLoop {
            protocol_text: protocol.describe(),
            protocol,
            before: self.drift_gap0.clone()?,
            after: self.drift_gap()?,
        })
    }
}
