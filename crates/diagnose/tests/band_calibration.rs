//! End-to-end calibration of the drift band with the fit's uncertainty (docs/drift.md,
//! "Parameter uncertainty"): logs generated from a known model are fitted from a wrong starting
//! model, and the drift of held-out logs of the same known model must fall inside the fitted
//! model's 95 % band (levels drawn by the parametric bootstrap) about 95 % of the time. The same
//! check with the fitted levels taken as exact is counted beside it.
//!
//! Each seed s: one training log (master seed 2 000 000 + s), `held_out` held-out logs (master
//! seed 3 000 000 + s, runs 0..), the fit (`bootstrap::fit_levels` of `START`'s levels, or the
//! whole `diagnose` from `START` with band seed 11 + s), the drift check of the held-out logs
//! pooled against the fitted model with 39 replicates (seed 5 + s; with 39 the band is the
//! smallest and largest replicate, 95 % by Wilks' rule).
//!
//! Heading, roll and pitch come from the independent channels gz, gx and gy (fitted, simulated and
//! measured independently), so per horizon they are 3 independent Bernoulli trials per seed:
//! the count inside is asserted against the binomial distribution of 3 x seeds trials at
//! p = 0.95 (`binomial_acceptance`). Position and velocity depend on the same channels as roll and
//! pitch; they are counted and printed, not asserted.

use diagnose::bootstrap::fit_levels;
use diagnose::drift_check::{
    check_drift_averaged, check_drift_fitted, CheckSettings, DriftCheck, Verdict,
};
use diagnose::fitted_on::FittedOn;
use diagnose::protocol::Protocol;
use diagnose::simulate::{static_log, SimSetup};
use diagnose::{diagnose, LogInput, Settings};
use noise::SensorModel;
use rayon::prelude::*;

/// The known model: gyro white noise, flicker bias instability and rate random walk (white meets
/// the flicker plateau at about 30 s); accelerometer white noise and flicker.
const TRUTH: &str = r#"
name = "truth"
[gyro.all]
white_noise = "0.3 deg/sqrt(h)"
bias_instability = "5 deg/h"
rate_random_walk = "3 deg/h/sqrt(h)"
turn_on_bias = "50 deg/h"
[accel.all]
white_noise = "60 ug/sqrt(Hz)"
bias_instability = "30 ug"
turn_on_bias = "2 mg"
"#;

/// Where the fit starts: the truth's terms at wrong levels (white noise twice the truth's, bias
/// instability 0.4 times, gyro rate random walk a third): a datasheet wrong in every level.
const START: &str = r#"
name = "start"
[gyro.all]
white_noise = "0.6 deg/sqrt(h)"
bias_instability = "2 deg/h"
rate_random_walk = "1 deg/h/sqrt(h)"
turn_on_bias = "50 deg/h"
[accel.all]
white_noise = "120 ug/sqrt(Hz)"
bias_instability = "12 ug"
turn_on_bias = "2 mg"
"#;

/// A known model whose slow wander is a Gauss-Markov process (sigma 3 deg/h, 30 min) rather than
/// a rate random walk: on a 2 h log the two are near alike on the Allan curve, so the drift loop
/// meets the near tie `diagnose` meets on real gyros (docs/drift.md, "Structure uncertainty").
const TRUTH_GM: &str = r#"
name = "truth, Gauss-Markov wander"
[gyro.all]
white_noise = "0.3 deg/sqrt(h)"
bias_instability = "5 deg/h"
gauss_markov = { sigma = "3 deg/h", time_constant = "1800 s" }
turn_on_bias = "50 deg/h"
[accel.all]
white_noise = "60 ug/sqrt(Hz)"
bias_instability = "30 ug"
turn_on_bias = "2 mg"
"#;

/// Quantities asserted (independent channels) and all of them.
const ATTITUDE: [&str; 3] = ["heading_rad", "roll_rad", "pitch_rad"];

/// How the training log is fitted.
#[derive(Clone, Copy)]
enum Fit {
    /// The levels of `START`'s terms refitted jointly (`bootstrap::fit_levels`, the bootstrap's own
    /// estimator): the band's method checked on a fit of the kind it assumes.
    Levels,
    /// The whole `diagnose` workflow from `START` (its own choice of terms).
    Diagnose,
    /// The same with the drift check in the loop (the drift protocol of the design), the band
    /// averaged over the structures it could not tell apart.
    DiagnoseDrift,
}

/// One experiment's shape.
struct Design {
    fit: Fit,
    /// The known model the logs come from.
    truth: &'static str,
    /// Also check with the levels taken as exact (the contrast in docs/drift.md); with the drift
    /// loop, with the model's own structure alone instead.
    compare_exact: bool,
    seeds: u64,
    dt_s: f64,
    train_samples: usize,
    held_out: usize,
    held_samples: usize,
    protocol: Protocol,
}

/// Per horizon: (horizon, attitude inside with bootstrap, attitude inside exact, all five inside
/// with bootstrap, all five inside exact, attitude trials, all trials).
type Row = (f64, usize, usize, usize, usize, usize, usize);

fn log_of(model: &SensorModel, dt_s: f64, samples: usize, seed: u64, run: u64) -> [Vec<f64>; 6] {
    let setup = SimSetup::plain(dt_s, samples, noise::ImuChannels([true; 6]));
    static_log(model, &setup, seed, run).0
}

fn input(dt_s: f64, log: &[Vec<f64>; 6]) -> LogInput<'_> {
    LogInput {
        dt_s,
        channels: noise::ImuChannels(log.each_ref().map(|c| Some(c.as_slice()))),
        temperature_c: None,
    }
}

/// One seed: the drift checks of the held-out logs against the diagnosed model, with its levels
/// drawn and taken as exact.
fn one_seed(d: &Design, s: u64) -> (DriftCheck, Option<DriftCheck>) {
    let truth = SensorModel::from_toml_str(d.truth, "truth.toml").unwrap();
    let start = SensorModel::from_toml_str(START, "start.toml").unwrap();
    let train = log_of(&truth, d.dt_s, d.train_samples, 2_000_000 + s, 0);
    let train_input = input(d.dt_s, &train);
    let (model, fitted, alternatives) = match d.fit {
        Fit::Levels => {
            let (m, f) = fit_levels(&start, &[train_input], 0.0).unwrap();
            (m, f, Vec::new())
        }
        Fit::Diagnose | Fit::DiagnoseDrift => {
            let settings = Settings {
                seed: 11 + s,
                horizons_s: Vec::new(),
                drift_protocol: matches!(d.fit, Fit::DiagnoseDrift).then(|| d.protocol.clone()),
                ..Settings::default()
            };
            let diagnosis = diagnose(&train_input, &start, &settings).unwrap();
            let fitted = FittedOn::from_logs(&[train_input], settings.tau_min_s).unwrap();
            (diagnosis.model_final, fitted, diagnosis.alternatives)
        }
    };
    let held: Vec<[Vec<f64>; 6]> = (0..d.held_out as u64)
        .map(|l| log_of(&truth, d.dt_s, d.held_samples, 3_000_000 + s, l))
        .collect();
    let inputs: Vec<LogInput> = held.iter().map(|h| input(d.dt_s, h)).collect();
    let check = CheckSettings {
        protocol: d.protocol.clone(),
        replicates: 39,
        seed: 5 + s,
    };
    if !alternatives.is_empty() {
        let names: Vec<String> = alternatives
            .iter()
            .map(|a| format!("{} {:?} w {:.2}", a.channel.name(), a.effects, a.weight))
            .collect();
        eprintln!("seed {s}: alternatives {}", names.join("; "));
    }
    let drawn =
        check_drift_averaged(&inputs, &model, &alternatives, Some(&fitted), &check, &()).unwrap();
    // The contrast: the levels taken as exact, or with the drift loop the model's own structure
    // alone (its levels drawn).
    let contrast = match d.fit {
        Fit::DiagnoseDrift => Some(&fitted),
        _ => None,
    };
    let exact = d
        .compare_exact
        .then(|| check_drift_fitted(&inputs, &model, contrast, &check, &()).unwrap());
    (drawn, exact)
}

fn coverage(d: &Design) -> Vec<Row> {
    let checks: Vec<(DriftCheck, Option<DriftCheck>)> = (0..d.seeds)
        .into_par_iter()
        .map(|s| one_seed(d, s))
        .collect();
    let mut rows: Vec<Row> = d
        .protocol
        .horizons_s
        .iter()
        .map(|&h| (h, 0, 0, 0, 0, 0, 0))
        .collect();
    for (drawn, exact) in &checks {
        for (hi, row) in rows.iter_mut().enumerate() {
            for (name, q) in &drawn.horizons[hi].channels {
                assert_ne!(q.verdict, Verdict::NotInformed, "{name}");
                let a = ATTITUDE.contains(name);
                let inside_drawn = q.verdict == Verdict::Inside;
                let inside_exact = exact
                    .as_ref()
                    .is_some_and(|e| e.horizons[hi].channels[name].verdict == Verdict::Inside);
                row.1 += usize::from(a && inside_drawn);
                row.2 += usize::from(a && inside_exact);
                row.3 += usize::from(inside_drawn);
                row.4 += usize::from(inside_exact);
                row.5 += usize::from(a);
                row.6 += 1;
            }
        }
    }
    for &(h, ad, ae, d5, e5, na, n5) in &rows {
        let pct = |k: usize, n: usize| 100.0 * k as f64 / n as f64;
        println!(
            "{h} s: attitude {ad}/{na} ({:.1} %) drawn, {ae}/{na} ({:.1} %) contrast; all five {d5}/{n5} ({:.1} %) drawn, {e5}/{n5} ({:.1} %) contrast",
            pct(ad, na),
            pct(ae, na),
            pct(d5, n5),
            pct(e5, n5)
        );
    }
    rows
}

/// The accepted counts of n Bernoulli trials at p = 0.95: the largest [lo, hi] with
/// P(K < lo) <= alpha / 2 and P(K > hi) <= alpha / 2 under the binomial distribution (exact pmf,
/// by the recurrence ln pmf(k + 1) = ln pmf(k) + ln((n - k) / (k + 1)) + ln(p / (1 - p)), in
/// logarithms: 0.05^600 underflows).
fn binomial_acceptance(n: usize, alpha: f64) -> (usize, usize) {
    let p: f64 = 0.95;
    let mut ln_pmf = vec![n as f64 * (1.0 - p).ln(); n + 1];
    for k in 0..n {
        ln_pmf[k + 1] = ln_pmf[k] + ((n - k) as f64 / (k + 1) as f64).ln() + (p / (1.0 - p)).ln();
    }
    let pmf: Vec<f64> = ln_pmf.iter().map(|l| l.exp()).collect();
    let mut lo = 0;
    let mut tail = 0.0;
    while tail + pmf[lo] <= alpha / 2.0 {
        tail += pmf[lo];
        lo += 1;
    }
    let mut hi = n;
    let mut tail = 0.0;
    while tail + pmf[hi] <= alpha / 2.0 {
        tail += pmf[hi];
        hi -= 1;
    }
    (lo, hi)
}

/// False-alarm rate of each assertion (two-sided, per horizon).
const ALPHA: f64 = 1e-3;

fn assert_calibrated(rows: &[Row]) {
    for &(h, inside, _, _, _, n, _) in rows {
        let (lo, hi) = binomial_acceptance(n, ALPHA);
        assert!(
            (lo..=hi).contains(&inside),
            "{h} s: {inside}/{n} attitude verdicts inside, accepted {lo}..={hi}"
        );
    }
}

/// The CI version: 40 seeds, a 2 h training log and three 2 h held-out logs at 10 Hz, horizons
/// 60 s and 10 min; 120 attitude trials per horizon, accepted 106..=120 at ALPHA.
#[test]
fn held_out_drift_falls_inside_the_band_with_the_fit_uncertainty() {
    let design = Design {
        fit: Fit::Levels,
        truth: TRUTH,
        compare_exact: false,
        seeds: 40,
        dt_s: 0.1,
        train_samples: 72_000,
        held_out: 3,
        held_samples: 72_000,
        protocol: Protocol {
            horizons_s: vec![60.0, 600.0],
            ..Protocol::default()
        },
    };
    assert_calibrated(&coverage(&design));
}

/// The documented figure (docs/drift.md): 200 seeds (`BAND_SEEDS` to change), the same logs,
/// horizons 10 s, 60 s, 10 min and 1 h; accepted 551..=586 attitude verdicts inside of 600. Run with `cargo test --release -p imudrift-diagnose --test band_calibration --
/// --ignored --nocapture`.
#[test]
#[ignore = "long: the documented calibration figure"]
fn calibration_figure() {
    let design = Design {
        fit: Fit::Levels,
        truth: TRUTH,
        compare_exact: true,
        seeds: std::env::var("BAND_SEEDS").map_or(200, |v| v.parse().unwrap()),
        dt_s: 0.1,
        train_samples: 72_000,
        held_out: 3,
        held_samples: 72_000,
        protocol: Protocol {
            horizons_s: vec![10.0, 60.0, 600.0, 3600.0],
            ..Protocol::default()
        },
    };
    assert_calibrated(&coverage(&design));
}

#[test]
fn binomial_acceptance_matches_a_direct_sum() {
    // n = 600 (the figure's trials): about 95 % +- 3.3 standard deviations (0.89 %).
    let (lo, hi) = binomial_acceptance(600, ALPHA);
    assert!(
        (549..=553).contains(&lo) && (584..=588).contains(&hi),
        "{lo} {hi}"
    );
    // n = 120, p = 0.95: P(K > 119) = 0.95^120 = 2.1e-3 > 5e-4, so hi = 120; the lower bound
    // leaves at most 5e-4 below it.
    let (lo, hi) = binomial_acceptance(120, ALPHA);
    assert_eq!(hi, 120);
    let pmf = |k: u64| {
        let mut c = 1.0f64;
        for i in 0..k {
            c *= (120 - i) as f64 / (i + 1) as f64;
        }
        c * 0.95f64.powi(k as i32) * 0.05f64.powi(120 - k as i32)
    };
    let below: f64 = (0..lo as u64).map(pmf).sum();
    assert!(
        below <= ALPHA / 2.0 && below + pmf(lo as u64) > ALPHA / 2.0,
        "{lo} {below}"
    );
}

/// The same with `diagnose`'s whole workflow as the fit (its own choice of terms from `START`),
/// asserted like the figure: what issue 23 asks of the whole chain (docs/drift.md, "Calibration
/// of the method"). Ignored in CI for its length (about 12 minutes on the shared 2-core machine; the
/// `Levels` version above runs instead). Run with `cargo test --release -p imudrift-diagnose --test
/// band_calibration diagnosed -- --ignored --nocapture`.
#[test]
#[ignore = "long: about 12 minutes on 2 cores (docs/drift.md)"]
fn diagnosed_coverage_figure() {
    let design = Design {
        fit: Fit::Diagnose,
        truth: TRUTH,
        compare_exact: true,
        seeds: std::env::var("BAND_SEEDS").map_or(40, |v| v.parse().unwrap()),
        dt_s: 0.1,
        train_samples: 72_000,
        held_out: 3,
        held_samples: 72_000,
        protocol: Protocol {
            horizons_s: vec![60.0, 600.0],
            ..Protocol::default()
        },
    };
    assert_calibrated(&coverage(&design));
}

/// The whole chain with the drift check in the loop on a sensor whose slow wander is a
/// Gauss-Markov process (`TRUTH_GM`, from `START`'s random walk): the drift loop's near ties become
/// the corrected model's alternatives and the held-out band averages over them (docs/drift.md,
/// "Structure uncertainty"). Asserted like the figure. Run with `cargo test --release -p
/// imudrift-diagnose --test band_calibration averaged -- --ignored --nocapture`.
#[test]
#[ignore = "long: about 15 minutes on 2 cores (docs/drift.md)"]
fn structure_averaged_coverage_figure() {
    let design = Design {
        fit: Fit::DiagnoseDrift,
        truth: TRUTH_GM,
        compare_exact: true,
        seeds: std::env::var("BAND_SEEDS").map_or(40, |v| v.parse().unwrap()),
        dt_s: 0.1,
        train_samples: 72_000,
        held_out: 3,
        held_samples: 72_000,
        protocol: Protocol {
            horizons_s: vec![60.0, 600.0],
            ..Protocol::default()
        },
    };
    assert_calibrated(&coverage(&design));
}

/// The chain from the drift loop's near tie to `drift`'s averaged band, on one seed of
/// `structure_averaged_coverage_figure` whose corrected model carries alternatives (seed 194:
/// gz's rate random walk at another level, alone and with a Gauss-Markov process): the weights
/// are valid, the corrected model's text carries them back unchanged (what `drift` reads), and the
/// drift check shares its replicates among the structures.
#[test]
fn a_diagnosis_with_alternatives_reaches_the_drift_band_through_its_model_file() {
    let s = 194;
    let truth = SensorModel::from_toml_str(TRUTH_GM, "truth.toml").unwrap();
    let start = SensorModel::from_toml_str(START, "start.toml").unwrap();
    let train = log_of(&truth, 0.1, 72_000, 2_000_000 + s, 0);
    let train_input = input(0.1, &train);
    let protocol = Protocol {
        horizons_s: vec![60.0, 600.0],
        ..Protocol::default()
    };
    let settings = Settings {
        seed: 11 + s,
        horizons_s: Vec::new(),
        drift_protocol: Some(protocol.clone()),
        ..Settings::default()
    };
    let diagnosis = diagnose(&train_input, &start, &settings).unwrap();
    let alternatives = diagnosis.alternatives.clone();
    assert!(
        !alternatives.is_empty(),
        "seed {s} no longer meets a near tie"
    );
    for c in noise::Channel::ALL {
        let total: f64 = alternatives
            .iter()
            .filter(|a| a.channel == c)
            .map(|a| a.weight)
            .sum();
        assert!((0.0..1.0).contains(&total), "{}: {total}", c.name());
    }
    for a in &alternatives {
        assert!(a.weight > 0.0 && a.delta_bic <= diagnose::alternatives::OCCAM_DELTA_BIC);
    }
    let fitted = FittedOn::from_logs(&[train_input], settings.tau_min_s).unwrap();
    let style = noise::UnitStyle::from_config_text(START);
    let text = diagnose::document::corrected_model_toml(&diagnosis, &start, &style, Some(&fitted));
    let read = diagnose::alternatives::from_model_text(&text, "corrected.toml").unwrap();
    let key = |a: &diagnose::alternatives::Alternative| {
        (
            a.channel,
            a.weight,
            a.delta_bic,
            a.effects.clone(),
            a.removed.clone(),
        )
    };
    assert_eq!(
        read.iter().map(key).collect::<Vec<_>>(),
        alternatives.iter().map(key).collect::<Vec<_>>()
    );
    let model = SensorModel::from_toml_str(&text, "corrected.toml").unwrap();
    let held = log_of(&truth, 0.1, 72_000, 3_000_000 + s, 0);
    let check = CheckSettings {
        protocol,
        replicates: 39,
        seed: 5 + s,
    };
    let c = check_drift_averaged(
        &[input(0.1, &held)],
        &model,
        &read,
        Some(&fitted),
        &check,
        &(),
    )
    .unwrap();
    assert!(c.structures.len() > 1);
    assert_eq!(c.structures.iter().map(|s| s.replicates).sum::<usize>(), 39);
}
