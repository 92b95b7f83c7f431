//! Step 4, the joint re-level: the levels of the terms the model already has, fitted together.
//!
//! Each wrong-level candidate of step 4 moves one level with the others held, so a model whose
//! terms are right but whose levels are all wrong (a datasheet off in every figure) is corrected one
//! level per step, and a candidate with more freedom (an output filter that lowers the short-tau
//! noise, a Gauss-Markov bump between the flicker plateau and the random walk) can explain more of
//! the gap in one step than any single level: forward selection then names it, and the right terms
//! end up beside a stand-in. The joint re-level is the model's own terms at once: the Allan variance
//! is the sum of the terms' (IEEE 952 Annex C, docs/model.md §2), each linear in its squared level
//! c_j, so the prediction is `avar_band + sum_j (c_j - c0_j) f_j(tau)` with the signatures `f_j` of
//! the wrong-level candidates, and the levels minimise the same chi2 in ln adev as every candidate
//! (module `fit`), with c_j >= 0. The minimum is found by cyclic coordinate descent (each coordinate
//! the one-level fit of `fit::fit_linear` against the band moved by the others; Wright 2015,
//! "Coordinate descent algorithms", Math. Program. 151, 3-34), which converges for this smooth
//! objective over a box. It is weighed by the same BIC (k = one per level) against the single
//! candidates, on the model as given (round 1 only: later rounds refine the levels of the terms they
//! name one at a time), and taken when it gains `min_delta_bic` and its BIC is below the best single
//! candidate's (workflow `prefer_joint`).
//!
//! The intervals reported for each level are conditional on the others' fitted values (the profile
//! of that level alone, widened by the Birge ratio of the joint fit as for every candidate). A level
//! is wrong when holding it at the model's value, the others refitted, costs at least the BIC gain
//! naming an effect needs (`min_delta_bic`); the others are held and the rest refitted, so only levels the data call
//! wrong are changed and named.

use crate::candidates::role;
use crate::fit::CHI2_1_95;
use crate::fit::{aic, bic, birge_scale, fit_linear, linear_interval, predicted_ln_adev, FitData};
use crate::trials::{at_squared_level, Named, Trial};
use noise::Effect;

/// Sweeps of the coordinate descent at most, and the relative change of every level below which it
/// stops.
const SWEEPS: usize = 50;
const TOLERANCE: f64 = 1e-7;

/// The joint re-level of a channel: one trial per level (its new value, conditional interval and
/// its part of the change), and the whole change with its information criteria.
pub(crate) struct Relevel {
    pub(crate) levels: Vec<Trial>,
    pub(crate) bic: f64,
    pub(crate) delta_avar: Vec<f64>,
}

/// The model's squared level of a trial's term (0 when the model lacks it).
fn c0_of(t: &Trial) -> f64 {
    t.model
        .as_ref()
        .and_then(|m| m.first())
        .map_or(0.0, |&(_, v)| v * v)
}

/// The wrong-level candidates among `trials` that can move together: a term the model has, at a
/// level above 0, with its own shape; not an output filter (it refits its white noise with it),
/// nor a signed level (a ramp, a temperature coefficient: their squared level loses the sign).
fn joinable(trials: &[Trial]) -> Vec<&Trial> {
    let unsigned = |e: Effect| !role(e).signed;
    trials
        .iter()
        .filter(|t| t.effect != Effect::OutputFilter && unsigned(t.effect))
        .filter(|t| !t.signature.is_empty() && t.white_n.is_none())
        .filter(|t| {
            let fitted: Named = t.term.parameters();
            t.model
                .as_ref()
                .is_some_and(|m| m.len() == fitted.len() && m[1..] == fitted[1..])
                && c0_of(t) > 0.0
        })
        .collect()
}

/// chi2 of the band changed by `delta` (per tau).
fn chi2_of(data: &FitData, delta: &[f64]) -> f64 {
    (0..data.ln_meas.len())
        .map(|i| {
            let ln_pred = predicted_ln_adev(data.ln_band[i], data.avar_band[i], delta[i]);
            ((data.ln_meas[i] - ln_pred) / data.s[i]).powi(2)
        })
        .sum()
}

/// The change of the band's Allan variance at levels `c` (c0 the model's).
fn change(ts: &[&Trial], c: &[f64], skip: Option<usize>, m: usize) -> Vec<f64> {
    let mut d = vec![0.0; m];
    for (j, t) in ts.iter().enumerate() {
        if Some(j) == skip {
            continue;
        }
        let c0 = c0_of(t);
        for (di, fi) in d.iter_mut().zip(&t.signature) {
            *di += (c[j] - c0) * fi;
        }
    }
    d
}

/// The band moved by `delta`, as the fit sees it (ln adev centre and mean Allan variance).
fn moved(data: &FitData, delta: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let ln = (0..delta.len())
        .map(|i| predicted_ln_adev(data.ln_band[i], data.avar_band[i], delta[i]))
        .collect();
    let avar = (0..delta.len())
        .map(|i| data.avar_band[i] + delta[i])
        .collect();
    (ln, avar)
}

/// The levels of `ts` fitted together (cyclic coordinate descent from the model's levels `c0`).
fn descend(data: &FitData, ts: &[&Trial], c0: &[f64]) -> Vec<f64> {
    let m = data.ln_meas.len();
    let mut c = c0.to_vec();
    for _ in 0..SWEEPS {
        let mut largest: f64 = 0.0;
        for j in 0..ts.len() {
            let (ln, avar) = moved(data, &change(ts, &c, Some(j), m));
            let shifted = FitData {
                ln_band: &ln,
                avar_band: &avar,
                ..data.clone()
            };
            let fit = fit_linear(&shifted, &ts[j].signature, c0[j]);
            let scale = c[j].abs().max(fit.c.abs()).max(f64::MIN_POSITIVE);
            largest = largest.max((fit.c - c[j]).abs() / scale);
            c[j] = fit.c;
        }
        if largest < TOLERANCE {
            break;
        }
    }
    c
}

/// Level j's 95 % interval (squared level) at the others' fitted values, widened by `scale`.
fn interval(data: &FitData, ts: &[&Trial], c: &[f64], c0: f64, j: usize, scale: f64) -> (f64, f64) {
    let (ln, avar) = moved(data, &change(ts, c, Some(j), data.ln_meas.len()));
    let shifted = FitData {
        ln_band: &ln,
        avar_band: &avar,
        ..data.clone()
    };
    let f = &ts[j].signature;
    let fit = fit_linear(&shifted, f, c0);
    linear_interval(&shifted, f, c0, &fit, CHI2_1_95 * scale * scale)
}

/// The joint re-level of the model's own levels on one channel, from its step-4 `trials`. A level
/// the profile likelihood does not call wrong is held at the model's value and the others
/// refitted, until every level that moves is wrong. None when fewer than two
/// levels are left (one is the single wrong-level candidate's case).
pub(crate) fn joint_relevel(
    data: &FitData,
    trials: &[Trial],
    min_delta_bic: f64,
) -> Option<Relevel> {
    let mut ts = joinable(trials);
    let m = data.ln_meas.len();
    loop {
        if ts.len() < 2 {
            return None;
        }
        let c0: Vec<f64> = ts.iter().map(|t| c0_of(t)).collect();
        let c = descend(data, &ts, &c0);
        let delta = change(&ts, &c, None, m);
        let chi2 = chi2_of(data, &delta);
        let k = ts.len();
        let scale = birge_scale(chi2, k, m);
        let intervals: Vec<(f64, f64)> = (0..k)
            .map(|j| interval(data, &ts, &c, c0[j], j, scale))
            .collect();
        // Level j is wrong when holding it at the model's value, the others refitted, costs more
        // BIC than naming an effect must gain (`min_delta_bic`, the evidence every step asks): the
        // profile likelihood of that level (Wilks 1938), not its conditional interval, which would
        // ignore how the levels trade with each other.
        let wrong: Vec<bool> = (0..k)
            .map(|j| {
                let held: Vec<&Trial> = (0..k).filter(|&i| i != j).map(|i| ts[i]).collect();
                let held_c0: Vec<f64> = (0..k).filter(|&i| i != j).map(|i| c0[i]).collect();
                let held_c = descend(data, &held, &held_c0);
                let chi2_held = chi2_of(data, &change(&held, &held_c, None, m));
                bic(chi2_held, k - 1, m) - bic(chi2, k, m) >= min_delta_bic
            })
            .collect();
        if wrong.iter().any(|w| !w) {
            ts = ts
                .into_iter()
                .zip(&wrong)
                .filter(|(_, &w)| w)
                .map(|(t, _)| t)
                .collect();
            continue;
        }
        let mut levels = Vec::with_capacity(k);
        for (j, t) in ts.iter().enumerate() {
            // A level the term's constructor refuses ends the joint re-level (none is taken).
            let term = t.term.with_level(c[j].max(0.0).sqrt()).ok()?;
            let named = term.parameters();
            levels.push(Trial {
                effect: t.effect,
                lo: at_squared_level(&named, intervals[j].0),
                hi: at_squared_level(&named, intervals[j].1),
                term,
                white_n: None,
                model: t.model.clone(),
                bic: bic(chi2, k, m),
                aic: aic(chi2, k),
                delta_avar: t.signature.iter().map(|v| (c[j] - c0[j]) * v).collect(),
                signature: t.signature.clone(),
            });
        }
        return Some(Relevel {
            levels,
            bic: bic(chi2, k, m),
            delta_avar: delta,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn level_trial(effect: Effect, c0: f64, f: Vec<f64>) -> Trial {
        let term: noise::Term = match effect {
            Effect::WhiteNoise => noise::WhiteNoise::new(c0.sqrt()).unwrap().into(),
            _ => noise::RateRandomWalk::new(c0.sqrt()).unwrap().into(),
        };
        let named = term.parameters();
        Trial {
            effect,
            term,
            white_n: None,
            lo: named.clone(),
            hi: named.clone(),
            model: Some(named),
            bic: 0.0,
            aic: 0.0,
            delta_avar: vec![0.0; f.len()],
            signature: f,
        }
    }

    /// Two levels both wrong (white noise twice, random walk a third): the joint fit finds both
    /// from data made exactly of the true terms (chi2 0), which no single level can.
    #[test]
    fn finds_two_wrong_levels_together() {
        let tau: Vec<f64> = (0..16).map(|i| 0.1 * 2f64.powi(i)).collect();
        let white: Vec<f64> = tau.iter().map(|t| 1.0 / t).collect();
        let rrw: Vec<f64> = tau.iter().map(|t| t / 3.0).collect();
        let (n2, k2) = (1e-4, 1e-8);
        let (n2_model, k2_model) = (4.0 * n2, k2 / 9.0);
        let avar_band: Vec<f64> = (0..tau.len())
            .map(|i| n2_model * white[i] + k2_model * rrw[i])
            .collect();
        let truth: Vec<f64> = (0..tau.len())
            .map(|i| n2 * white[i] + k2 * rrw[i])
            .collect();
        let ln_band: Vec<f64> = avar_band.iter().map(|a| 0.5 * a.ln()).collect();
        let ln_meas: Vec<f64> = truth.iter().map(|a| 0.5 * a.ln()).collect();
        let s = vec![0.05; tau.len()];
        let data = FitData {
            ln_meas: &ln_meas,
            ln_band: &ln_band,
            avar_band: &avar_band,
            s: &s,
        };
        let trials = vec![
            level_trial(Effect::WhiteNoise, n2_model, white),
            level_trial(Effect::RateRandomWalk, k2_model, rrw),
        ];
        let r = joint_relevel(&data, &trials, 16.0).expect("two levels");
        let sq = |n: &Named| n[0].1 * n[0].1;
        let c: Vec<f64> = r.levels.iter().map(|t| sq(&t.term.parameters())).collect();
        assert!((c[0] / n2 - 1.0).abs() < 1e-4, "white {c:?}");
        assert!((c[1] / k2 - 1.0).abs() < 1e-4, "rrw {c:?}");
        assert!(chi2_of(&data, &r.delta_avar) < 1e-6);
        // Each interval holds its level.
        for t in &r.levels {
            let v = sq(&t.term.parameters());
            assert!(sq(&t.lo) <= v && v <= sq(&t.hi));
        }
    }

    /// One level cannot move jointly: no joint re-level.
    #[test]
    fn needs_two_levels() {
        let f = vec![1.0; 4];
        let (ln, avar, s) = (vec![0.0; 4], vec![1.0; 4], vec![0.1; 4]);
        let data = FitData {
            ln_meas: &ln,
            ln_band: &ln,
            avar_band: &avar,
            s: &s,
        };
        assert!(joint_relevel(&data, &[level_trial(Effect::WhiteNoise, 1.0, f)], 16.0).is_none());
    }
}
