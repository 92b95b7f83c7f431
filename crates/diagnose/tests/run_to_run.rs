//! Run-to-run variation estimated from several runs (`diagnose::run_spread`, docs/diagnose.md
//! "Runs that differ"): runs generated from a model whose gz rate random walk varies between
//! power-ons by a known spread, estimated against the model without the
//! spread (the pooled fit's levels are the RMS over power-ons: docs/model.md §2.3).

mod common;

use common::{run_inputs, GeneratedLog};
use diagnose::run_spread::{draw_spreads, estimate, with_estimated_spreads};
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
    assert_eq!(out.len(), 2, "gz alone has a slow and a short group");
    assert!(out.iter().all(|e| e.channel == Channel::Gz));
    assert_eq!(out[1].group, "short");
    assert_eq!(out[1].effects, vec!["white_noise"]);
    assert_eq!(out[0].group, "long");
    assert_eq!(out[0].effects, vec!["rate_random_walk"]);
    out[0].clone()
}

/// The same runs with the spread `s` on gz's white noise instead (the short group): the estimate
/// of the short group.
fn estimate_gz_white(s: f64, first: u64) -> diagnose::run_spread::RunSpread {
    let text = format!(
        "name = \"spread\"\n[gyro.z]\nwhite_noise = \"0.3 deg/sqrt(h)\"\nbias_instability = {{ value = \"5 deg/h\", convention = \"ieee\" }}\nrate_random_walk = \"120 deg/h/sqrt(h)\"\nrun_to_run = {{ white_noise = {s} }}\n"
    );
    let truth = SensorModel::from_toml_str(&text, "white.toml").unwrap();
    let logs: Vec<GeneratedLog> = (0..6)
        .map(|r| GeneratedLog::new(&truth, 1 << 18, first + r, false))
        .collect();
    let inputs = run_inputs(&logs);
    let out = estimate(&model(0.0), &inputs, 0.01, 7 + first, None).expect("not stopped");
    out.into_iter()
        .find(|e| e.group == "short")
        .expect("gz has a short group")
}

/// A white-noise level that changes between power-ons (0.1 in ln) is found by the short group
/// and written on the white noise alone; the slow group of the same runs is not named. Fixed
/// seeds.
#[test]
fn a_white_noise_spread_is_found_apart_from_the_wander() {
    let e = estimate_gz_white(0.1, 300);
    assert!(e.named, "{e:?}");
    assert!(e.interval[0] <= 0.1 && 0.1 <= e.interval[1], "{e:?}");
    let written = with_estimated_spreads(&model(0.0), std::slice::from_ref(&e));
    let gz = written.axis(noise::Sensor::Gyro, 2);
    assert_eq!(gz.run_to_run().get(&Effect::WhiteNoise), Some(&e.spread));
    // The wander keeps the pooled model's spread of 0.
    assert_eq!(gz.run_to_run().get(&Effect::RateRandomWalk), Some(&0.0));
}

/// A large spread (0.6) is named and its interval holds it; no spread is not named and its
/// interval starts at 0. Fixed seeds; the rates behind them are the ignored test's (the interval
/// leaves 0 out for 2.5 % of seeds by construction: seed 200 is one of them since the two groups
/// are fitted jointly, so the check of no spread uses seed 210).
#[test]
fn a_spread_is_found_and_none_is_not_named() {
    let big = estimate_gz(0.6, 100);
    assert!(big.named, "{big:?}");
    assert!(big.interval[0] <= 0.6 && 0.6 <= big.interval[1], "{big:?}");
    let written = with_estimated_spreads(&model(0.0), std::slice::from_ref(&big));
    let gz = written.axis(noise::Sensor::Gyro, 2);
    assert_eq!(
        gz.run_to_run().get(&Effect::RateRandomWalk),
        Some(&big.spread)
    );
    assert_eq!(gz.run_to_run().get(&Effect::BiasInstability), None);
    let none = estimate_gz(0.0, 210);
    assert!(!none.named, "{none:?}");
    assert_eq!(none.interval[0], 0.0, "{none:?}");
}

/// `drift` draws each experiment's spread from the estimate's confidence distribution
/// (`draw_spreads`): its 2.5 and 97.5 % points are the estimate's 95 % interval, the share drawn at
/// 0 is P(chi2_{R-1} >= (R - 1) V / sigma_e^2), each draw is written on the group's terms, and a
/// replicate's draw does not depend on how many replicates there are. Tolerances: 4.4 binomial
/// standard deviations of the 20 000 draws (two-sided 1e-5).
#[test]
fn spread_draws_have_the_estimates_interval() {
    let n = 20_000;
    let tol = |p: f64| 4.4 * (p * (1.0 - p) / n as f64).sqrt();
    let big = estimate_gz(0.6, 100);
    assert!(big.interval[0] > 0.0, "{big:?}");
    let fit = big.fit().expect("a fit of six runs");
    assert_eq!(
        (fit.runs, fit.effects.clone()),
        (6, vec![Effect::RateRandomWalk])
    );
    let mut models = vec![model(0.0); n];
    let drawn = draw_spreads(&mut models, std::slice::from_ref(&fit), 5);
    let d = &drawn[0];
    let share = |f: &dyn Fn(f64) -> bool| d.iter().filter(|&&x| f(x)).count() as f64 / n as f64;
    let below = share(&|x| x < big.interval[0]);
    // The draws are capped at the largest spread a model may state (2, this interval's end).
    let upper = big.interval[1].min(noise::run_to_run::MAX_SPREAD);
    let above = share(&|x| x >= upper);
    assert!(
        (below - 0.025).abs() < tol(0.025),
        "{below} below {:?}",
        big.interval
    );
    assert!(
        (above - 0.025).abs() < tol(0.025),
        "{above} above {:?}",
        big.interval
    );
    for (m, &s) in models.iter().zip(d) {
        let gz = m.axis(noise::Sensor::Gyro, 2);
        assert_eq!(gz.run_to_run().get(&Effect::RateRandomWalk), Some(&s));
        assert_eq!(gz.run_to_run().get(&Effect::BiasInstability), None);
    }
    // A variance below its null: a share of the draws at 0.
    let low = diagnose::fitted_on::SpreadFit {
        variance: 0.1,
        null_variance: 0.12,
        ..fit.clone()
    };
    let zero = draw_spreads(&mut models, std::slice::from_ref(&low), 5)[0]
        .iter()
        .filter(|&&x| x == 0.0)
        .count() as f64
        / n as f64;
    let expected = 1.0 - allan::chi2::chi2_cdf(5.0 * 0.1 / 0.12, 5.0);
    assert!(
        (zero - expected).abs() < tol(expected),
        "{zero} vs {expected}"
    );
    // The first replicates' draws are the same with fewer replicates.
    let few = draw_spreads(&mut models[..10], std::slice::from_ref(&fit), 5);
    assert_eq!(few[0][..], d[..10]);
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

/// The held-out run end to end (`IMUDRIFT_SPREAD_SEEDS=40 cargo test --release -p
/// imudrift-diagnose --test run_to_run -- --ignored --nocapture held_out`; seeds from
/// `IMUDRIFT_SPREAD_SKIP` on, default 0, to run a longer series in parts): per seed, six runs of
/// the known model (gz's rate random walk with spread 0 or 0.3); each run in turn is held out, the
/// spread is estimated on the other five (`estimate` against the pooled levels, the estimated spread
/// written with `with_estimated_spreads`, as `diagnose` does) and the held-out run's heading is
/// checked against that model's 95 % band (39 simulated experiments, each drawing its spread from
/// the estimate's confidence distribution as `drift` does; Wilks' band) at 1 min and 10 min. The pooled levels are the truth's (the bootstrap's part is `band_calibration.rs`), so
/// what is checked is the spread's. The count inside is asserted against the binomial
/// distribution of 6 x seeds trials per horizon at p = 0.95 (two-sided 1e-3; the six trials of a
/// seed share runs, so the count is a little more spread than the binomial's) and printed.
#[test]
#[ignore = "long: the documented end-to-end figure"]
fn held_out_run_inside_the_band_with_the_estimated_spread() {
    use diagnose::drift_check::{check_drift_until, CheckSettings, Models, Verdict};
    use diagnose::protocol::Protocol;
    let seeds: u64 = std::env::var("IMUDRIFT_SPREAD_SEEDS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(40);
    // Seeds `skip..skip + seeds` (`IMUDRIFT_SPREAD_SKIP`, default 0): a longer series in parts.
    let skip: u64 = std::env::var("IMUDRIFT_SPREAD_SKIP")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0);
    let horizons = [60.0, 600.0];
    for s in [0.0, 0.3] {
        let truth = model(s);
        let mut inside = [0usize; 2];
        let (mut trials, mut named) = (0usize, 0usize);
        for k in skip..skip + seeds {
            let first = 5000 + 10 * k;
            let logs: Vec<GeneratedLog> = (0..6)
                .map(|r| GeneratedLog::new(&truth, 1 << 18, first + r, false))
                .collect();
            let inputs = run_inputs(&logs);
            for held in 0..6 {
                let train: Vec<_> = (0..6).filter(|&r| r != held).map(|r| inputs[r]).collect();
                let est = estimate(&model(0.0), &train, 0.01, 7 + first + held as u64, None)
                    .expect("not stopped");
                named += est.iter().filter(|e| e.named && e.group == "long").count();
                let fitted = with_estimated_spreads(&model(0.0), &est);
                let fits: Vec<_> = est.iter().filter_map(|e| e.fit()).collect();
                let check = CheckSettings {
                    protocol: Protocol {
                        horizons_s: horizons.to_vec(),
                        ..Protocol::default()
                    },
                    replicates: 39,
                    seed: 9 + first + held as u64,
                };
                // As `drift` takes a diagnosed model: each experiment draws its spreads from the
                // estimate's confidence distribution (the levels are the truth's: no bootstrap).
                let models = Models {
                    model: &fitted,
                    alternatives: &[],
                    fitted_on: None,
                    run_spreads: &fits,
                };
                let never = std::sync::atomic::AtomicBool::new(false);
                let out = check_drift_until(&inputs[held..=held], models, &check, &(), &never)
                    .expect("the check runs");
                for (hi, h) in out.horizons.iter().enumerate() {
                    let q = &h.channels["heading_rad"];
                    inside[hi] += usize::from(q.verdict == Verdict::Inside);
                }
                trials += 1;
            }
        }
        println!(
            "spread {s}: heading inside the 95 % band at 1 min {}/{trials} ({:.1} %), at 10 min {}/{trials} ({:.1} %); slow spread named in {named}/{trials} fits",
            inside[0],
            100.0 * inside[0] as f64 / trials as f64,
            inside[1],
            100.0 * inside[1] as f64 / trials as f64,
        );
        for (hi, &n_in) in inside.iter().enumerate() {
            // Two-sided 1e-3 under Binomial(trials, 0.95): +- 3.3 standard deviations.
            let sd = (trials as f64 * 0.95 * 0.05).sqrt();
            let expected = 0.95 * trials as f64;
            assert!(
                (n_in as f64 - expected).abs() <= 3.3 * sd + 1.0,
                "spread {s}, horizon {}: {n_in}/{trials} inside",
                horizons[hi]
            );
        }
    }
}
