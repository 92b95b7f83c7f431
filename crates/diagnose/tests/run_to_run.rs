//! Run-to-run variation estimated from several runs (`diagnose::run_spread`, docs/diagnose.md
//! "Runs that differ"): runs generated from a model whose gz rate random walk varies between
//! power-ons by a known spread, estimated against the model without the
//! spread (the pooled fit's levels are the RMS over power-ons: docs/model.md §2.3).

mod common;

use common::{run_inputs, GeneratedLog};
use diagnose::run_spread::{estimate, with_named_spreads};
use noise::{Channel, Effect, SensorModel};

/// gz only: white noise, flicker and a rate random walk that dominates beyond ~8 s.
fn model(spread: f64) -> SensorModel {
    let text = format!(
        "name = \"spread\"\n[gyro.z]\nwhite_noise = \"0.3 deg/sqrt(h)\"\nbias_instability = {{ value = \"5 deg/h\", convention = \"ieee\" }}\nrate_random_walk = \"120 deg/h/sqrt(h)\"\nrun_to_run = {{ rate_random_walk = {spread} }}\n"
    );
    SensorModel::from_toml_str(&text, "spread.toml").expect("the test model parses")
}

/// Six runs of 2^18 samples at 100 Hz (44 min) with spread `s`, seeds `first..first + 6`; the estimate of
/// gz against the model without spread.
fn estimate_gz(s: f64, first: u64) -> diagnose::run_spread::RunSpread {
    let truth = model(s);
    let logs: Vec<GeneratedLog> = (0..6)
        .map(|r| GeneratedLog::new(&truth, 1 << 18, first + r, false))
        .collect();
    let inputs = run_inputs(&logs);
    let pooled = model(0.0);
    let out = estimate(&pooled, &inputs, 0.01, 7 + first, None).expect("not stopped");
    assert_eq!(out.len(), 1, "gz alone has a slow group");
    assert_eq!(out[0].channel, Channel::Gz);
    assert_eq!(out[0].effects, vec!["rate_random_walk"]);
    out[0].clone()
}

/// A large spread (0.6) is named and its interval holds it; no spread is not named and its
/// interval starts at 0. Fixed seeds; the rates behind them are the ignored test's.
#[test]
fn a_spread_is_found_and_none_is_not_named() {
    let big = estimate_gz(0.6, 100);
    assert!(big.named, "{big:?}");
    assert!(big.interval[0] <= 0.6 && 0.6 <= big.interval[1], "{big:?}");
    let written = with_named_spreads(&model(0.0), std::slice::from_ref(&big));
    let gz = written.axis(noise::Sensor::Gyro, 2);
    assert_eq!(
        gz.run_to_run().get(&Effect::RateRandomWalk),
        Some(&big.spread)
    );
    assert_eq!(gz.run_to_run().get(&Effect::BiasInstability), None);
    let none = estimate_gz(0.0, 200);
    assert!(!none.named, "{none:?}");
    assert_eq!(none.interval[0], 0.0, "{none:?}");
}

/// Coverage over seeds (`IMUDRIFT_SPREAD_SEEDS=40 cargo test --release -p imudrift-diagnose
/// --test run_to_run -- --ignored --nocapture`): the 95 % interval holds the truth (0 and 0.3) at
/// its stated rate, and a spread of 0 is named at about the naming rule's rate (1.7e-4 per
/// channel). Prints the counts.
#[test]
#[ignore]
fn interval_coverage_over_seeds() {
    let seeds: u64 = std::env::var("IMUDRIFT_SPREAD_SEEDS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(40);
    for s in [0.0, 0.3] {
        let (mut held, mut named, mut over90) = (0, 0, 0.0);
        for k in 0..seeds {
            let e = estimate_gz(s, 1000 + 10 * k);
            held += usize::from(e.interval[0] <= s && s <= e.interval[1]);
            named += usize::from(e.named);
            over90 += e.null_over_chi2_90;
        }
        println!(
            "spread {s}: interval holds the truth in {held}/{seeds}, named {named}/{seeds}, null share beyond the chi-square's 90 % point {:.3}",
            over90 / seeds as f64
        );
    }
}
