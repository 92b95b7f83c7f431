//! The drift loop of the workflow (docs/diagnose.md, "Drift in the loop"): after the Allan rounds,
//! while the runs' drift under the protocol leaves the model's band, the long-averaging-time terms
//! are fitted to the Allan gap and the drift gap together (`drift_fit`) on every channel an
//! outside quantity comes from; each channel's best candidate that passes the BIC rule is named,
//! the corrected model re-simulated (every channel: the drift needs them all), and the round kept
//! only if the joint chi2 (the drift gap's and the changed channels' Allan gaps') shrank.

use super::state::{gap_of, shifted_band, Bands, Context, Drift, LoopState};
use crate::alternatives::{
    differing_effects, removed_effects, weights, Alternative, MAX_PER_CHANNEL, OCCAM_DELTA_BIC,
};
use crate::drift_fit::{
    allan_dispersion, DriftFitInput, DriftTrial, Partner, UnitDrift, SUPPORT_SHARE,
};
use crate::drift_gap::DriftGap;
use crate::error::DiagnoseError;
use crate::findings::{found_by_fit, merge_refinements, Choice};
use crate::gap::{gap, Band};
use crate::model_terms::current_term;
use crate::observer::{RoundDone, Step};
use crate::report::{Candidate, CandidateRecord, DriftLoop};
use crate::trials::{named_map, Trial};
use noise::{AxisModel, Channel, Effect, ImuChannels, Term};

/// A change the drift loop made: the channel, the effect and its term before.
type Change = (Channel, Effect, Option<Term>);

/// The drift loop (module doc), at most `max_rounds` rounds, from the corrected model's `drift`;
/// the drift of the model it leaves.
pub(super) fn drift_rounds(
    cx: &Context,
    state: &mut LoopState,
    drift: Drift,
) -> Result<Drift, DiagnoseError> {
    if cx.plan.protocol.is_none() {
        return Ok(drift);
    }
    let mut drift = drift;
    for _ in 0..cx.settings.max_rounds {
        cx.check_stop()?;
        let Some(before) = cx.drift_gap(&drift.protocol) else {
            break;
        };
        let round = state.rounds + 1;
        let alternatives = ImuChannels::from_fn(|c| state.channels[c].alternatives.clone());
        let changes: Vec<Change> = before
            .channels_outside()
            .into_iter()
            .filter_map(|c| drift_choice(cx, state, c, &before, round))
            .flatten()
            .collect();
        // A stop during the fits leaves them unfinished: nothing of this round is used.
        cx.check_stop()?;
        if changes.is_empty() {
            break;
        }
        match drift_resimulate(cx, state, round, &before, changes)? {
            Some(kept) => drift = kept,
            None => {
                // The round's alternatives were weighed against a structure undone.
                for c in Channel::ALL {
                    state.channels[c].alternatives = alternatives[c].clone();
                }
                break;
            }
        }
    }
    Ok(drift)
}

/// The drift candidates of channel `c` weighed, and the best one that passes the BIC rule
/// named (put into both models, with the rate random walk re-levelled beside it when that fit
/// better: `DriftFitInput::with_random_walk`); the changes made.
fn drift_choice(
    cx: &Context,
    state: &mut LoopState,
    c: Channel,
    drift: &DriftGap,
    round: usize,
) -> Option<Vec<Change>> {
    let settings = cx.settings;
    let (band, g) = cx.gap(c, &state.bands.pooled)?;
    let curve = cx.measured[c].as_ref()?.curve.clone();
    let protocol = cx.plan.protocol.clone()?;
    let input = DriftFitInput {
        model: &state.models.sim,
        channel: c,
        measured: &curve,
        band: &band,
        gap: &g,
        dt_s: cx.dt_s(),
        ramp_slope: cx.ramp_slope[c],
        drift: drift.of_channel(c),
        correlation: drift.correlation_of_channel(c),
        unit: UnitDrift {
            dt_s: cx.dt_s(),
            samples: &cx.samples,
            protocol: &protocol,
            seed: settings.seed,
            logs: (4 * settings.seeds).max(64),
            stop: Some(cx.stop),
        },
    };
    let trials = input.trials();
    state.channels[c]
        .records
        .extend(trials.iter().map(|t| CandidateRecord {
            round,
            effect: Candidate {
                effect: t.trial.effect,
                rejected: false,
                withdrawn: false,
            },
            delta_bic: t.delta_bic,
            delta_aic: f64::NAN,
            parameters: named_map(&t.trial.named()),
        }));
    let best = trials
        .iter()
        .filter(|t| t.delta_bic >= settings.min_delta_bic)
        .max_by(|a, b| a.delta_bic.total_cmp(&b.delta_bic));
    state.channels[c].alternatives = alternatives_of(cx, state, c, &trials, best);
    let best: &DriftTrial = best?;
    let cannot_tell_from = trials
        .iter()
        .filter(|t| {
            t.trial.effect != best.trial.effect
                && best.delta_bic - t.delta_bic < settings.ambiguity_delta_bic
        })
        .map(|t| t.trial.effect)
        .collect();
    let effect = best.trial.effect;
    let previous = current_term(&state.models.sim, c, effect);
    // A level refitted to 0 removes the term (`findings::is_removal`), as in the Allan rounds.
    let kept_term = (!crate::findings::is_removal(&best.trial)).then(|| best.trial.term.clone());
    state.models.restore(c, effect, kept_term);
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
    let mut found = found_by_fit(choice, round, g.rms, predicted, cx.dt_s());
    found.drift_gap_before = Some(drift.gap);
    state.channels[c].effects.push(found);
    let mut changes = vec![(c, effect, previous)];
    if let Some(p) = &best.partner {
        changes.push(relevel_random_walk(
            cx,
            state,
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
    cx: &Context,
    state: &LoopState,
    c: Channel,
    trials: &[DriftTrial],
    best: Option<&DriftTrial>,
) -> Vec<Alternative> {
    let base = state.models.out.axis(c.sensor(), c.axis());
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
    let prior = cx.settings.min_delta_bic;
    let kept = best.map_or(0.0, |b| b.delta_bic - prior);
    let own = best.map_or_else(|| base.clone(), with);
    let mut near: Vec<(f64, AxisModel)> = match best {
        Some(_) => Vec::new(),
        None => state.channels[c]
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
    cx: &Context,
    state: &mut LoopState,
    c: Channel,
    p: &Partner,
    delta_bic: f64,
    round: usize,
    (gap_before, gap_predicted, drift_gap): (f64, f64, f64),
) -> Change {
    let effect = Effect::RateRandomWalk;
    let previous = current_term(&state.models.sim, c, effect);
    state.models.restore(c, effect, p.term.clone());
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
    let mut found = found_by_fit(choice, round, gap_before, gap_predicted, cx.dt_s());
    found.drift_gap_before = Some(drift_gap);
    state.channels[c].effects.push(found);
    (c, effect, previous)
}

/// The round's re-simulation: kept if the joint chi2 of the drift gap and the changed channels'
/// Allan gaps shrank (the new model's drift returned), else undone (the state before it kept,
/// None returned).
fn drift_resimulate(
    cx: &Context,
    state: &mut LoopState,
    round: usize,
    before: &DriftGap,
    changes: Vec<Change>,
) -> Result<Option<Drift>, DiagnoseError> {
    cx.observer.step(Step::Resimulate { round });
    let sim = cx.simulate_whole(&state.models.sim)?;
    let after = cx
        .drift_gap(&sim.protocol_errors)
        .expect("the drift loop runs with a protocol");
    // Each changed channel's Allan chi2, divided by its dispersion before the round over the
    // taus the round moved by `SUPPORT_SHARE` or more (`drift_fit::allan_dispersion`), counted once
    // per channel.
    let mut channels: Vec<Channel> = changes.iter().map(|(c, _, _)| *c).collect();
    channels.dedup();
    let gap_on = |bands: &ImuChannels<Option<Band>>, c: Channel| cx.gap(c, bands);
    let dispersion: Vec<f64> = channels
        .iter()
        .map(|&c| {
            let (Some((b0, g0)), Some((b1, _))) =
                (gap_on(&state.bands.pooled, c), gap_on(&sim.bands, c))
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
    let allan_chi2 = |bands: &ImuChannels<Option<Band>>| -> f64 {
        channels
            .iter()
            .zip(&dispersion)
            .filter_map(|(&c, d)| {
                gap_on(bands, c).map(|(_, g)| g.z.iter().map(|z| z * z).sum::<f64>() / d)
            })
            .sum()
    };
    let kept =
        after.chi2() + allan_chi2(&sim.bands) < before.chi2() + allan_chi2(&state.bands.pooled);
    let mut done = RoundDone {
        round,
        drift: true,
        kept: Vec::new(),
        undone: Vec::new(),
    };
    for (c, _, _) in &changes {
        let allan_after = gap_of(cx.measured[*c].as_ref(), sim.bands[*c].as_ref())
            .map_or(f64::NAN, |(_, g)| g.rms);
        let ch = &mut state.channels[*c];
        let first_new = ch.first_in(round);
        for e in &mut ch.effects[first_new..] {
            e.gap_after = allan_after;
            e.drift_gap_after = Some(after.gap);
        }
        if kept {
            if !done.kept.iter().any(|(k, _)| k == c) {
                let named = ch.effects[first_new..].iter().map(|e| e.effect).collect();
                done.kept.push((*c, named));
            }
            let withdrawn = merge_refinements(&mut ch.effects, first_new);
            ch.records.extend(withdrawn);
        } else {
            if !done.undone.contains(c) {
                done.undone.push(*c);
            }
            ch.reject_from(round, first_new);
        }
    }
    cx.observer.round_done(&done);
    if kept {
        state.rounds = round;
        state.bands = Bands {
            pooled: sim.bands.clone(),
            per_length: sim.log_bands.clone(),
        };
        return Ok(Some(Drift::of(sim)));
    }
    for (c, effect, previous) in changes.into_iter().rev() {
        state.models.restore(c, effect, previous);
    }
    Ok(None)
}

/// The drift check's report: the original and the corrected model's (`drift`) drift gaps.
pub(super) fn drift_report(cx: &Context, drift: &Drift) -> Option<DriftLoop> {
    let protocol = cx.plan.protocol.clone()?;
    Some(DriftLoop {
        protocol_text: protocol.describe(),
        protocol,
        before: cx.drift_gap(&cx.sim0.protocol_errors)?,
        after: cx.drift_gap(&drift.protocol)?,
    })
}
