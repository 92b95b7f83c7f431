//! The drift check's between-log test (docs/drift.md, "Runs that differ"): logs of one model are
//! flagged at its stated level, logs of two sensors that differ in their bias wander are flagged.

use diagnose::drift_check::{check_drift, CheckSettings, DriftCheck};
use diagnose::protocol::{Calibration, Initialisation, Protocol};
use diagnose::simulate::{static_log, SimSetup};
use diagnose::LogInput;
use noise::SensorModel;

const MODEL: &str = r#"
name = "between-log model"
[gyro.all]
white_noise = "0.3 deg/sqrt(h)"
rate_random_walk = "3 deg/h/sqrt(h)"
[accel.all]
white_noise = "60 ug/sqrt(Hz)"
"#;

/// The same sensor with a rate random walk `factor` times the model's on every gyro.
fn wandering(factor: f64) -> SensorModel {
    let text = MODEL.replace(
        "3 deg/h/sqrt(h)",
        &format!("{} deg/h/sqrt(h)", 3.0 * factor),
    );
    SensorModel::from_toml_str(&text, "wandering.toml").unwrap()
}

const DT: f64 = 0.1;
const SAMPLES: usize = 36_000; // 1 h at 10 Hz: 12 segments of 300 s per log
const REPLICATES: usize = 40;

fn protocol() -> Protocol {
    Protocol {
        calibration: Calibration::LogMean,
        initialisation: Initialisation::Perfect,
        horizons_s: vec![60.0, 300.0],
        overlapping: false,
        latitude_deg: diagnose::protocol::Protocol::default().latitude_deg,
    }
}

/// Check logs drawn from `models` (log l from `models[l]`, master seed `seed`) against the
/// model of the file.
fn check(models: &[SensorModel], seed: u64) -> DriftCheck {
    let setup = SimSetup::plain(DT, SAMPLES, noise::ImuChannels([true; 6]));
    let logs: Vec<_> = models
        .iter()
        .enumerate()
        .map(|(l, m)| static_log(m, &setup, 5_000_000 + seed, l as u64))
        .collect();
    let inputs: Vec<LogInput> = logs
        .iter()
        .map(|log| LogInput {
            dt_s: DT,
            channels: noise::ImuChannels(log.0.each_ref().map(|c| Some(c.as_slice()))),
            temperature_c: None,
        })
        .collect();
    let settings = CheckSettings {
        protocol: protocol(),
        replicates: REPLICATES,
        seed: 11 + seed,
    };
    check_drift(&inputs, &wandering(1.0), &settings, &()).unwrap()
}

/// (flagged, tests) over every horizon and quantity of `checks`.
fn flagged(checks: &[DriftCheck], only_heading: bool) -> (usize, usize) {
    let mut n = (0, 0);
    for c in checks {
        for h in &c.horizons {
            for (name, q) in &h.channels {
                if only_heading && *name != "heading_rad" {
                    continue;
                }
                let b = q
                    .between_logs
                    .expect("two logs or more: a between-log test");
                assert!(b.p_value > 0.0 && b.p_value <= 1.0);
                n.1 += 1;
                n.0 += usize::from(b.runs_differ);
            }
        }
    }
    n
}

/// Null: 4 logs of the model itself, 20 checks x 2 horizons x 5 quantities = 200 tests. With
/// R = 40 replicates the test flags at p <= 2/41 = 4.9 %. Accepted: at most 12 % flagged. For 200
/// independent tests at 4.9 % that is 4.6 binomial standard deviations above (false alarm below
/// 1e-5); the quantities of one check are correlated (fewer independent tests, a wider spread:
/// at 40 independent tests it is still 2.1 standard deviations, 2 %). Measured: 14/300 (4.7 %)
/// with 30 checks; 18/200 (9.0 %) with these 20 after the sampler's change of draws.
#[test]
fn logs_of_one_model_are_flagged_at_the_stated_level() {
    let one = vec![wandering(1.0); 4];
    let checks: Vec<DriftCheck> = (0..20).map(|s| check(&one, s)).collect();
    let (f, n) = flagged(&checks, false);
    println!("null: {f}/{n} flagged");
    let rejected = checks
        .iter()
        .filter(|c| !c.joint.as_ref().expect("informed cells").consistent)
        .count();
    println!(
        "null: joint test rejected {rejected}/{} checks",
        checks.len()
    );
    // The joint test (docs/drift.md, "Every cell at once") rejects at most 2/41 = 4.9 % of
    // checks of the model's own logs: at most 4 of 20 (P(X >= 5) = 0.3 % at 4.9 %).
    assert!(
        rejected <= 4,
        "joint test: {rejected}/20 rejected under the null"
    );
    assert!(
        (f as f64) <= 0.12 * n as f64,
        "{f}/{n} flagged under the null"
    );
    // The between-log tests of every cell together (max-T, exact at 2/41): at most 4 of 20
    // checks say the runs differ (P(X >= 5) = 0.3 %).
    let differ = checks
        .iter()
        .filter(|c| c.between_logs_joint.as_ref().expect("4 logs").runs_differ)
        .count();
    println!("null: between-log joint test says the runs differ in {differ}/20 checks");
    assert!(differ <= 4, "between-log joint: {differ}/20 under the null");
}

/// Two logs of a sensor with 6x the random walk (36x its variance) beside two of the model's:
/// the heading at 300 s, which the gyro random walk then rules, is flagged in at least 7 of 10
/// checks (measured 9/10, 8/10 after the sampler's change of draws; at 4.9 % a correct model would be flagged 7 times in 10 with
/// probability below 1e-7).
#[test]
fn logs_of_two_sensors_are_flagged() {
    let mixed = vec![
        wandering(1.0),
        wandering(1.0),
        wandering(6.0),
        wandering(6.0),
    ];
    let checks: Vec<DriftCheck> = (0..10).map(|s| check(&mixed, 100 + s)).collect();
    let hits = checks
        .iter()
        .filter(|c| {
            let h = c.horizons.iter().find(|h| h.t_s == 300.0).unwrap();
            h.channels["heading_rad"].between_logs.unwrap().runs_differ
        })
        .count();
    println!("two sensors: heading at 300 s flagged in {hits}/10 checks");
    // All cells together: the joint test finds the two sensors too (it loses some power to the
    // cells the random walk does not rule; at 4.9 % a right model says so in 5 or more of 10
    // checks with probability 6e-5).
    let joint = checks
        .iter()
        .filter(|c| c.between_logs_joint.as_ref().expect("4 logs").runs_differ)
        .count();
    println!("two sensors: between-log joint test says the runs differ in {joint}/10 checks");
    assert!(joint >= 5, "between-log joint: {joint}/10");
    let rejected = checks
        .iter()
        .filter(|c| !c.joint.as_ref().expect("informed cells").consistent)
        .count();
    println!("two sensors: joint test rejected {rejected}/10 checks");
    // And rejects the pooled logs as a whole (measured 10/10; a right model: at most 2 in 10
    // with probability 0.99).
    assert!(rejected >= 7, "joint test: {rejected}/10 rejected");
    assert!(hits >= 7, "{hits}/10");
}

/// The joint test's level end to end (run by hand, `--ignored`): 200 checks of 4 logs of the model
/// itself, R = 40, the rate of rejected checks within 2.0-8.5 % (4.9 % +- 2.9 binomial standard
/// deviations of 200 checks; below 2 % would say the test is conservative). Measured 13/200;
/// it prints the between-log test's flags over the same checks too (measured 123/2000, 6.2 %).
#[test]
#[ignore]
fn joint_test_level_over_200_checks() {
    let one = vec![wandering(1.0); 4];
    let checks: Vec<DriftCheck> = (0..200).map(|s| check(&one, 1000 + s)).collect();
    let rejected = checks
        .iter()
        .filter(|c| !c.joint.as_ref().unwrap().consistent)
        .count();
    println!("null: joint test rejected {rejected}/200 checks");
    let (f, n) = flagged(&checks, false);
    println!("null: between-log test flagged {f}/{n} over the same checks");
    assert!((4..=17).contains(&rejected), "{rejected}/200");
}
