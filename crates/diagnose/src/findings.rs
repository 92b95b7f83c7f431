//! How the workflow's findings are written into the report: a named effect from a detector or a
//! fitted candidate, the candidates weighed, refinements of an effect named before, stand-ins, and
//! the channel's verdict.

use crate::detect::Finding;
use crate::gap::{Band, Gap};
use crate::measure::Measured;
use crate::report::{
    BandView, Candidate, CandidateRecord, ChannelCurves, FindingKind, FoundEffect, Parameters,
};
use crate::trials::{named_map, Named, Trial};
use noise::Effect;
use std::collections::BTreeMap;

/// Above this final gap (RMS z) a channel's fitted Gauss-Markov terms, and sinusoids without a
/// spectral line in the log (`detect::is_spectral_line`), are called stand-ins: the hidden-effect
/// tests close a physical effect's gap to below 1.5.
pub const STAND_IN_GAP: f64 = 1.5;

/// The candidate chosen in one step: its trial, its BIC gain over the unchanged model and the
/// candidates the data cannot tell from it.
pub(crate) struct Choice<'t> {
    pub(crate) trial: &'t Trial,
    pub(crate) delta_bic: f64,
    pub(crate) cannot_tell_from: Vec<Effect>,
}

/// A time-domain detector's finding (round 0); `had`: the model has the term at another level.
pub(crate) fn found_by_detector(
    f: &Finding,
    had: bool,
    gap_before: f64,
    gap_after: f64,
) -> FoundEffect {
    let map = |j: usize| -> BTreeMap<String, f64> {
        f.parameters
            .iter()
            .map(|p| (p.0.to_string(), [p.1, p.2, p.3][j]))
            .collect()
    };
    FoundEffect {
        effect: f.term.effect(),
        parameters: map(0).into(),
        parameters_lo: map(1),
        parameters_hi: map(2),
        kind: if had {
            FindingKind::WrongLevel
        } else {
            FindingKind::Missing
        },
        model_parameters: None,
        gap_before,
        gap_predicted: gap_after,
        gap_after,
        delta_bic: f.delta_bic,
        cannot_tell_from: f.cannot_tell_from.clone(),
        round: 0,
        refinements: 0,
        stand_in: false,
        drift_gap_before: None,
        drift_gap_after: None,
        zero_level: false,
    }
}

/// A fitted candidate named in `round`; its gap after is known once the round is re-simulated.
pub(crate) fn found_by_fit(
    choice: Choice,
    round: usize,
    gap_before: f64,
    gap_predicted: f64,
    dt_s: f64,
) -> FoundEffect {
    let best = choice.trial;
    FoundEffect {
        effect: best.effect,
        parameters: parameters_of(best, &best.named(), dt_s),
        parameters_lo: parameters_of(best, &best.lo, dt_s).values,
        parameters_hi: parameters_of(best, &best.hi, dt_s).values,
        kind: if best.model.is_some() {
            FindingKind::WrongLevel
        } else {
            FindingKind::Missing
        },
        model_parameters: best.model.as_ref().map(named_map),
        gap_before,
        gap_predicted,
        gap_after: f64::NAN,
        delta_bic: choice.delta_bic,
        cannot_tell_from: choice.cannot_tell_from,
        round,
        refinements: 0,
        stand_in: false,
        drift_gap_before: None,
        drift_gap_after: None,
        zero_level: is_removal(best),
    }
}

/// A trial whose fitted level is 0 (a level candidate's non-negative fit at its bound, or a
/// re-levelled term set to 0): the change it makes removes the term.
pub(crate) fn is_removal(t: &Trial) -> bool {
    t.white_n.is_none() && t.term.level().is_some_and(|(_, v)| v == 0.0)
}

/// The records of the candidates weighed in one step (BIC and AIC gains over the unchanged model,
/// whose BIC is `base_bic` and chi2 `chi2_base`).
pub(crate) fn trial_records(
    round: usize,
    trials: &[Trial],
    base_bic: f64,
    chi2_base: f64,
) -> Vec<CandidateRecord> {
    trials
        .iter()
        .map(|t| CandidateRecord {
            round,
            effect: Candidate {
                effect: t.effect,
                rejected: false,
                withdrawn: false,
            },
            delta_bic: base_bic - t.bic,
            delta_aic: chi2_base - t.aic,
            parameters: named_map(&t.named()),
        })
        .collect()
}

/// The record of an effect named in `round` and rejected on re-simulation.
pub(crate) fn rejected_record(round: usize, rejected: FoundEffect) -> CandidateRecord {
    CandidateRecord {
        round,
        effect: Candidate {
            effect: rejected.effect,
            rejected: true,
            withdrawn: false,
        },
        delta_bic: rejected.delta_bic,
        delta_aic: f64::NAN,
        parameters: rejected.parameters.values,
    }
}

/// A later round that changes the level of an effect already named on the channel refines that finding
/// rather than naming a second one: the earlier entry takes the new parameters and the new gap after,
/// and keeps its kind, model parameters and gap before (the same holds for a second change of one
/// effect within a round). `first_new` is where this round's entries start.
///
/// A refinement to level 0 of an effect the model lacked (kind `missing`) withdraws it: the
/// round removed the term (`workflow::accept`), so the effect is no finding, and its entry leaves
/// the list and comes back as the record returned (its `delta_bic` the naming's, with the
/// parameters it was named with). Summing the two rounds' gains into one entry named the effect
/// with size 0 and the sum as its evidence (ADIS16405 runs 1-3, gz: a 13 ms Gauss-Markov
/// stand-in named in round 2 with dBIC 153, refitted to 0 in round 3 with dBIC 471, was shown as
/// `sigma = 0 deg/h, dBIC 624` and written into the corrected model).
pub(crate) fn merge_refinements(
    effects: &mut Vec<FoundEffect>,
    first_new: usize,
) -> Vec<CandidateRecord> {
    let mut withdrawn = Vec::new();
    let mut i = first_new;
    while i < effects.len() {
        match effects[..i]
            .iter()
            .position(|e| e.effect == effects[i].effect)
        {
            Some(j) if effects[i].zero_level && effects[j].kind == FindingKind::Missing => {
                let last = effects.remove(i);
                let first = effects.remove(j);
                i -= 1;
                withdrawn.push(CandidateRecord {
                    round: last.round,
                    effect: Candidate {
                        effect: first.effect,
                        rejected: false,
                        withdrawn: true,
                    },
                    delta_bic: first.delta_bic,
                    delta_aic: f64::NAN,
                    parameters: first.parameters.values,
                });
            }
            Some(j) => {
                let mut last = effects.remove(i);
                let first = &mut effects[j];
                keep_found_intervals(first, &mut last);
                first.parameters = last.parameters;
                first.parameters_lo = last.parameters_lo;
                first.parameters_hi = last.parameters_hi;
                first.gap_predicted = last.gap_predicted;
                first.gap_after = last.gap_after;
                first.delta_bic += last.delta_bic;
                first.cannot_tell_from = last.cannot_tell_from;
                first.refinements += 1;
                first.zero_level = last.zero_level;
            }
            None => i += 1,
        }
    }
    withdrawn
}

/// A refinement that keeps a shape where it is (a Gauss-Markov time, a sinusoid's frequency: only
/// the level is refitted; a power law's slope is searched again, `trials::refit_power_law`) has a
/// point for its interval there; the interval the shape was found with in the earlier round is the
/// one that says how well it is known, and it stays with the finding. (Before, a shape named in
/// round 1 with an interval was reported as [v, v] after a later round refitted its level.)
fn keep_found_intervals(first: &FoundEffect, last: &mut FoundEffect) {
    for (key, &v) in last.parameters.iter() {
        let (Some(lo), Some(hi)) = (last.parameters_lo.get(key), last.parameters_hi.get(key))
        else {
            continue;
        };
        let (Some(&v0), Some(&lo0), Some(&hi0)) = (
            first.parameters.get(key),
            first.parameters_lo.get(key),
            first.parameters_hi.get(key),
        ) else {
            continue;
        };
        if *lo == v && *hi == v && v0 == v && lo0 < hi0 {
            last.parameters_lo.insert(key.clone(), lo0);
            last.parameters_hi.insert(key.clone(), hi0);
        }
    }
}

/// Shaped terms fitted where the model still disagrees are stand-ins, not physical findings. A
/// sinusoid whose frequency carries a spectral line in the channel is a physical tone (a
/// vibration, an interference), not a stand-in. `xs`: the channel in every run (empty: not measured).
pub(crate) fn mark_stand_ins(effects: &mut [FoundEffect], xs: &[&[f64]], dt_s: f64) {
    for e in effects {
        e.stand_in = match e.effect {
            Effect::GaussMarkov => true,
            Effect::Sinusoidal => !e
                .parameters
                .get("frequency_hz")
                .is_some_and(|&f| crate::spectrum::is_spectral_line_runs(xs, dt_s, f)),
            _ => false,
        };
    }
}

/// One sentence on a channel: agrees, or what remains unexplained.
pub(crate) fn verdict(g: &Gap, effects: &[FoundEffect]) -> String {
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

/// A channel's curves for plots: measured with its interval, the band before and after.
pub(crate) fn channel_curves(m: &Measured, initial: &Band, last: Band) -> ChannelCurves {
    ChannelCurves {
        tau_s: m.curve.tau_s.clone(),
        adev: m.curve.adev.clone(),
        adev_lo: m.lo.clone(),
        adev_hi: m.hi.clone(),
        edf: m.curve.edf.clone(),
        band_initial: BandView {
            centre: initial.centre(),
            lo: initial.adev_lo.clone(),
            hi: initial.adev_hi.clone(),
        },
        band_final: BandView {
            centre: last.centre(),
            lo: last.adev_lo,
            hi: last.adev_hi,
        },
    }
}

/// The JSON parameters `named` of a fitted term or a bound of them; an output filter's kind and
/// one-sided noise bandwidth added (a property of the chosen filter, so a bound's is the filter's
/// own: its shape is selected, not interval-estimated).
fn parameters_of(trial: &Trial, named: &Named, dt_s: f64) -> Parameters {
    let mut p: Parameters = named_map(named).into();
    if let noise::Term::OutputFilter(filter) = &trial.term {
        p.kind = Some(filter.kind().name());
        p.values
            .insert("noise_bandwidth_hz".into(), filter.noise_bandwidth_hz(dt_s));
    }
    p
}

#[cfg(test)]
mod tests {
    use super::*;

    fn found(
        effect: Effect,
        kind: FindingKind,
        round: usize,
        level: f64,
        dbic: f64,
    ) -> FoundEffect {
        let values: BTreeMap<String, f64> = [("sigma".to_string(), level), ("tau_s".into(), 0.013)]
            .into_iter()
            .collect();
        FoundEffect {
            effect,
            parameters: values.clone().into(),
            parameters_lo: values.clone(),
            parameters_hi: values,
            kind,
            model_parameters: None,
            gap_before: 17.0,
            gap_predicted: 13.0,
            gap_after: 13.0,
            delta_bic: dbic,
            cannot_tell_from: Vec::new(),
            round,
            stand_in: false,
            refinements: 0,
            drift_gap_before: None,
            drift_gap_after: None,
            zero_level: level == 0.0,
        }
    }

    /// Issue 45 item 5: an effect the model lacked, named in round 2 and refitted to level 0 in
    /// round 3, is withdrawn (no entry of size 0 whose evidence is the sum of the two rounds'
    /// gains), and comes back as a record with the naming's parameters and gain.
    #[test]
    fn a_named_effect_refitted_to_zero_is_withdrawn() {
        let gm = Effect::GaussMarkov;
        let white = Effect::WhiteNoise;
        let mut effects = vec![
            found(white, FindingKind::WrongLevel, 1, 6.7e-4, 98826.0),
            found(gm, FindingKind::Missing, 2, 5.65e-4, 153.0),
            found(gm, FindingKind::Missing, 3, 0.0, 471.0),
        ];
        let withdrawn = merge_refinements(&mut effects, 2);
        assert_eq!(effects.len(), 1);
        assert_eq!(effects[0].effect, white);
        assert_eq!(withdrawn.len(), 1);
        let w = &withdrawn[0];
        assert!(w.effect.withdrawn && !w.effect.rejected && w.effect.effect == gm);
        assert_eq!((w.round, w.delta_bic), (3, 153.0));
        assert_eq!(w.parameters["sigma"], 5.65e-4);
        assert_eq!(
            serde_json::to_value(w.effect).unwrap(),
            "gauss_markov withdrawn: a later round refitted its level to 0"
        );
    }

    /// A refinement to another level than 0 still merges into the first entry, as before; a
    /// model's own term refitted to 0 (kind `wrong_level`) is kept as the finding it is.
    #[test]
    fn other_refinements_merge_as_before() {
        let gm = Effect::GaussMarkov;
        let mut effects = vec![
            found(gm, FindingKind::Missing, 2, 5.65e-4, 153.0),
            found(gm, FindingKind::Missing, 3, 6.0e-4, 20.0),
        ];
        assert!(merge_refinements(&mut effects, 1).is_empty());
        assert_eq!(effects.len(), 1);
        assert_eq!(effects[0].parameters["sigma"], 6.0e-4);
        assert_eq!((effects[0].delta_bic, effects[0].refinements), (173.0, 1));
        let mut own = vec![
            found(gm, FindingKind::WrongLevel, 1, 5.0e-4, 40.0),
            found(gm, FindingKind::WrongLevel, 2, 0.0, 30.0),
        ];
        assert!(merge_refinements(&mut own, 1).is_empty());
        assert_eq!(own.len(), 1);
        assert!(own[0].zero_level);
    }
}
