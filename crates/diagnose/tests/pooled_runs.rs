//! Several runs of one sensor diagnosed together (docs/diagnose.md, "Several runs" and "Drift in
//! the loop"; issue 23 items 1 and 2), on logs generated from known models: clean runs name
//! nothing even with the drift check in the loop, and a slow rate random walk that one run's
//! Allan curve cannot resolve is named from the runs pooled.

mod common;

use common::{base_model, GeneratedLog};
use diagnose::{diagnose_runs, Diagnosis};
use noise::{Channel, Effect, SensorModel};

/// Samples per run (655 s at 100 Hz: taus up to 164 s).
const SAMPLES: usize = 1 << 16;

/// Diagnose the runs generated from `model` with seeds `seeds` against `base`, with the drift
/// check on horizons of 60 and 300 s when `drift`.
fn diagnose_generated(
    model: &SensorModel,
    base: &SensorModel,
    seeds: &[u64],
    drift: bool,
) -> Diagnosis {
    let logs: Vec<GeneratedLog> = seeds
        .iter()
        .map(|&s| GeneratedLog::new(model, SAMPLES, s, false))
        .collect();
    diagnose_runs(
        &common::run_inputs(&logs),
        base,
        &common::pooled_settings(drift),
        &(),
    )
    .expect("diagnose runs")
}

/// The effects named, and the run-to-run spreads named (`run_spread`), as `channel:effect`.
fn named(d: &Diagnosis) -> Vec<String> {
    d.channels
        .iter()
        .flat_map(|(ch, r)| r.effects.iter().map(move |e| format!("{ch}:{}", e.effect)))
        .chain(
            d.run_to_run
                .iter()
                .filter(|r| r.named)
                .map(|r| format!("{}:run_to_run", r.channel)),
        )
        .collect()
}

/// Clean runs (generated from the model diagnosed with), four runs pooled, the drift check in the
/// loop, six pooled diagnoses. Measured false-alarm rate of such a diagnosis (something named on
/// clean runs; docs/diagnose.md, "False alarms of the pooled rule", `pooled_null.rs`): 10 in 200
/// (5 %: 6 by the drift loop, 4 by the Allan rounds) with the drift pairs weighed by their
/// correlation, 20 in 200 before (here, seeds 7000+: 0 of 6, before 2 of 6), still above the
/// 1e-3 per log the BIC rule has on one log. At 5 % per diagnosis, 3 or more of 6 happen with
/// probability 0.2 %: this test fails when clean runs are named clearly more often than that.
/// The drift gaps of these correct models are printed (measured 0.59-1.90: the 10 z-scores of
/// one diagnosis are correlated, heading and attitude at 60 and 300 s coming from the same
/// channels, so their RMS scatters more than that of independent ones).
#[test]
fn clean_runs_pooled_with_the_drift_check_name_nothing() {
    let mut named_runs = Vec::new();
    for k in 0..6u64 {
        let base = base_model(k % 2 == 0);
        let seeds: Vec<u64> = (0..4).map(|r| 7000 + 10 * k + r).collect();
        let d = diagnose_generated(&base, &base, &seeds, true);
        let drift = d.drift_check.as_ref().expect("drift check");
        eprintln!(
            "clean runs {k}: named {:?}, drift gap {:.2} -> {:.2}",
            named(&d),
            drift.before.gap,
            drift.after.gap
        );
        assert_eq!(d.runs.len(), 4);
        if !named(&d).is_empty() {
            named_runs.push(format!("runs {k}: {:?}", named(&d)));
        }
    }
    assert!(named_runs.len() <= 2, "{}", named_runs.join("\n"));
}

/// A rate random walk on gz rising above the base model only at a run's longest taus (K = 5e-6
/// rad/s/sqrt(s): its Allan deviation equals the base's white plus flicker near 50 s and is 2.6
/// times it at 164 s, where one run has an EDF of about 2.5): one run's Allan curve mostly does
/// not name it (each of the eight runs diagnosed alone: at most half may; measured with the draws
/// of issue 26: 1 of 8, run 9100, which the previous draws did not name), eight runs pooled do
/// (their EDF add up; measured dBIC 77), on gz only, with K within 25 % or inside its 95 %
/// interval.
#[test]
fn a_random_walk_one_run_cannot_resolve_is_named_from_pooled_runs() {
    let base = base_model(true);
    let mut model = base.clone();
    let k_true = 5e-6;
    model
        .axis_mut(Channel::Gz.sensor(), Channel::Gz.axis())
        .set_term(noise::RateRandomWalk::new(k_true).unwrap());
    let seeds: Vec<u64> = (0..8).map(|r| 9100 + r).collect();
    let alone: Vec<u64> = seeds
        .iter()
        .copied()
        .filter(|&s| {
            let one = diagnose_generated(&model, &base, &[s], false);
            named(&one).contains(&"gz:rate_random_walk".to_string())
        })
        .collect();
    eprintln!("runs that name it alone: {alone:?}");
    let pooled = diagnose_generated(&model, &base, &seeds, false);
    eprintln!("eight runs: named {:?}", named(&pooled));
    assert!(
        alone.len() <= seeds.len() / 2,
        "one run alone names it too often: {alone:?}"
    );
    // The Allan rounds' findings (a random walk can pass for a warm-up transient in one run's
    // time-domain step: with these seeds one of the eight runs' gz, which the pooled model then
    // carries as a per-run transient; `detect`'s floor is the model's levels, which lack the walk).
    let fitted: Vec<String> = pooled
        .channels
        .iter()
        .flat_map(|(ch, r)| {
            r.effects
                .iter()
                .filter(|e| e.round > 0)
                .map(move |e| format!("{ch}:{}", e.effect))
        })
        .collect();
    assert_eq!(fitted, vec!["gz:rate_random_walk".to_string()]);
    let e = pooled.channels[&noise::Channel::Gz]
        .effects
        .iter()
        .find(|e| e.round > 0)
        .expect("a fitted effect");
    assert_eq!(e.effect, Effect::RateRandomWalk);
    let (k, lo, hi) = (
        e.parameters["k"],
        e.parameters_lo["k"],
        e.parameters_hi["k"],
    );
    eprintln!("K = {k:.3e} [{lo:.3e}, {hi:.3e}], truth {k_true:.1e}");
    assert!(
        common::parameter_ok(k_true, k, lo, hi),
        "K = {k} [{lo}, {hi}], truth {k_true}"
    );
}
