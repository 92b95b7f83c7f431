//! The round, rotating Earth's growth laws (montecarlo `earth_laws`: the error model of
//! strapdown's `error_model` for every term) against Monte Carlo runs of the round-Earth
//! mechanisation (WGS-84, rotating, 45 deg N unless stated, height held).
//!
//! Judged as a whole per experiment, never cell by cell: the 99.9 % interval of simulated rms /
//! law rms (and of the mean ratio where the law has a mean) is computed for every checkpoint and
//! quantity with a law; under a right model each cell misses with probability 1e-3, so the count
//! of misses among n cells is at most Binomial(n, 1e-3) if the cells were independent (they are
//! positively correlated, which makes a few misses cluster but does not move the mean). An
//! experiment is consistent when P(misses >= observed) >= 0.05 under that binomial: for the
//! ~100-300 cells here, at most one miss. The seeds are fixed (not tuned).

use imudrift_montecarlo::experiment::{Experiment, Overrides};
use imudrift_montecarlo::nav_quantity::NavQuantity;
use imudrift_montecarlo::report::DriftReport;
use imudrift_montecarlo::run_range;
use imudrift_montecarlo::scenario::Scenario;
use noise::SensorModel;
use std::path::Path;

fn simulate(model: &SensorModel, scenario: &str, runs: u64) -> DriftReport {
    let scenario = Scenario::from_toml_str(
        &format!("sensor = \"x.toml\"\nruns = {runs}\nseed = 1\n{scenario}"),
        "round-earth-test.toml",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let exp = Experiment::new(scenario, model, &Overrides::default()).unwrap();
    let r = run_range(&exp.kernel(), 0..exp.runs, &|_| {});
    assert!(r.failures.is_empty(), "{:?}", r.failures);
    exp.report(&r.matrix, &r.failures)
}

fn model(toml: &str) -> SensorModel {
    SensorModel::from_toml_str(&format!("name = \"test\"\n{toml}"), "test-sensor.toml")
        .unwrap_or_else(|e| panic!("{e}"))
}

/// P(X >= k) for X ~ Binomial(n, p).
fn binomial_tail(n: usize, p: f64, k: usize) -> f64 {
    let mut pmf = (1.0 - p).powi(n as i32);
    let mut below = 0.0;
    for i in 0..k {
        below += pmf;
        pmf *= (n - i) as f64 / (i + 1) as f64 * p / (1.0 - p);
    }
    (1.0 - below).max(0.0)
}

/// The joint verdict over every cell with a law; `expect` quantities must have a law at the last
/// checkpoint. Returns the number of cells.
fn check(name: &str, report: &DriftReport, expect: &[NavQuantity]) -> usize {
    let mut cells = 0;
    let mut misses = Vec::new();
    for cp in &report.checkpoints {
        for (q, c) in &cp.quantities {
            for (r, lo, hi, what) in [
                (c.ratio, c.ratio_lo, c.ratio_hi, "rms"),
                (c.mean_ratio, c.mean_ratio_lo, c.mean_ratio_hi, "mean"),
            ] {
                if let (Some(r), Some(lo), Some(hi)) = (r, lo, hi) {
                    cells += 1;
                    if !(lo <= 1.0 && 1.0 <= hi) {
                        misses.push(format!(
                            "t={} {q} {what}: {r:.4} [{lo:.4}, {hi:.4}]",
                            cp.t_s
                        ));
                    }
                }
            }
        }
    }
    let last = report.checkpoints.last().unwrap();
    for q in expect {
        assert!(
            last.quantities[q.name()].ratio.is_some(),
            "{name}: {} has no law: {:?}",
            q.name(),
            last.quantities[q.name()].law_note
        );
    }
    let p = binomial_tail(cells, 1e-3, misses.len());
    eprintln!(
        "{name}: {} of {cells} cells outside their 99.9 % intervals (P = {p:.3})",
        misses.len()
    );
    assert!(
        p >= 0.05,
        "{name}: {} of {cells} outside (P = {p:.4} < 0.05):\n{}",
        misses.len(),
        misses.join("\n")
    );
    cells
}

/// One hour at 10 Hz from 1 min: the Schuler loop (84.4 min) and Earth rate act fully.
const HOUR: &str = "duration_s = 3600.0\nrate_hz = 10.0\n[earth]\nlatitude_deg = 45.0\n[checkpoints]\nlog_count = 8\nfirst_s = 60.0\n";

#[test]
fn every_term_alone_follows_its_round_earth_law() {
    use NavQuantity::*;
    let horizontal = [
        PosNorth,
        PosEast,
        PosHorizontal,
        VelNorth,
        VelEast,
        VelHorizontal,
    ];
    // Navigation-grade magnitudes (small angles for an hour).
    let cases: &[(&str, &str)] = &[
        ("gyro white_noise", "[gyro.all]\nwhite_noise = \"0.005 deg/sqrt(h)\"\n"),
        ("gyro rate_random_walk", "[gyro.all]\nrate_random_walk = \"0.002 deg/h/sqrt(h)\"\n"),
        ("gyro flicker", "[gyro.all]\nbias_instability = { value = \"0.005 deg/h\", convention = \"ieee\" }\n"),
        ("gyro turn_on_bias", "[gyro.all]\nturn_on_bias = \"0.01 deg/h\"\n"),
        ("gyro gauss_markov", "[gyro.all]\ngauss_markov = { sigma = \"0.01 deg/h\", time_constant = \"600 s\" }\n"),
        ("gyro constant_bias x", "[gyro.x]\nconstant_bias = \"0.01 deg/h\"\n"),
        ("gyro rate_ramp z", "[gyro.z]\nrate_ramp = \"1e-6 deg/s^2\"\n"),
        // Large enough that its errors stand above the mechanisation's rounding of latitude (a
        // few 1e-7 m after thousands of steps).
        ("gyro scale_factor (Earth rate)", "[gyro.all]\nscale_factor = \"5000 ppm\"\n"),
        ("gyro sinusoid", "[gyro.all]\nsinusoidal = { amplitude = \"0.05 deg/h\", frequency = \"0.002 Hz\" }\n"),
        ("gyro warmup", "[gyro.all]\nwarmup_transient = { amplitude = \"0.02 deg/h\", time_constant = \"10 min\", per_run = true }\n"),
        ("accel white_noise", "[accel.all]\nwhite_noise = \"50 ug/sqrt(Hz)\"\n"),
        ("accel turn_on_bias", "[accel.all]\nturn_on_bias = \"50 ug\"\n"),
        ("accel flicker", "[accel.all]\nbias_instability = { value = \"20 ug\", convention = \"ieee\" }\n"),
        ("accel constant_bias", "[accel.x]\nconstant_bias = \"30 ug\"\n[accel.y]\nconstant_bias = \"-50 ug\"\n"),
        ("accel resonance", "[accel.all]\nresonance = { sigma = \"5 mg\", frequency = \"1 Hz\", bandwidth = \"0.2 Hz\" }\n"),
    ];
    for (name, toml) in cases {
        let r = simulate(&model(toml), HOUR, 300);
        let expect: &[NavQuantity] = if name.contains("constant_bias") || name.contains("ramp") {
            &[]
        } else {
            &horizontal
        };
        let n = check(name, &r, expect);
        assert!(n >= 8, "{name}: only {n} cells");
    }
}

#[test]
fn calibrated_bias_and_alignment_follow_their_round_earth_laws() {
    let gm = model(
        "[gyro.all]\ngauss_markov = { sigma = \"0.02 deg/h\", time_constant = \"1200 s\" }\n[accel.all]\ngauss_markov = { sigma = \"50 ug\", time_constant = \"900 s\" }\n",
    );
    for (name, terms) in [
        (
            "calibrated at start",
            "[terms]\nbias_calibrated_at_start = true\n",
        ),
        (
            "calibration window",
            "[terms]\nbias_calibration_window_s = 300.0\n",
        ),
    ] {
        check(name, &simulate(&gm, &format!("{HOUR}{terms}"), 300), &[]);
    }
    let perfect = model("");
    let r = simulate(
        &perfect,
        &format!(
            "{HOUR}[alignment]\nroll_std_deg = 0.005\npitch_deg = 0.003\nyaw_std_deg = 0.05\n"
        ),
        300,
    );
    check("alignment", &r, &[NavQuantity::PosHorizontal]);
    // Tilted and turned: the error model takes any static attitude.
    let r = simulate(
        &model("[gyro.all]\nwhite_noise = \"0.005 deg/sqrt(h)\"\n[accel.all]\nturn_on_bias = \"50 ug\"\n"),
        &format!("{HOUR}[trajectory]\nkind = \"static\"\nroll_deg = 10.0\npitch_deg = -5.0\nyaw_deg = 120.0\n"),
        300,
    );
    check("tilted and turned", &r, &[NavQuantity::PosHorizontal]);
}

/// The shipped sensors, static, 4 h on the round Earth (20 Hz: the drift of these models is set
/// by their slow terms; the white noise's law holds at any rate), checkpoints from 0.5 s (the
/// MEMS sensors' attitude errors leave the small-angle laws within seconds to minutes; the
/// cells beyond have no law and are not counted).
#[test]
fn shipped_sensors_follow_their_round_earth_laws_for_four_hours() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs/sensors");
    for name in ["mtx", "adis16405", "gg1320an", "gg5300"] {
        let path = root.join(format!("{name}.toml"));
        let text = std::fs::read_to_string(&path).unwrap();
        let m = SensorModel::from_toml_str(&text, &format!("{name}.toml"))
            .unwrap_or_else(|e| panic!("{e}"));
        let r = simulate(
            &m,
            "duration_s = 14400.0\nrate_hz = 20.0\n[checkpoints]\nlog_count = 16\nfirst_s = 0.5\n",
            200,
        );
        let n = check(name, &r, &[]);
        assert!(n >= 10, "{name}: only {n} cells have a law");
    }
}

/// Woodman's minute: the MTx static for 60 s (his scenario's sensor, rate and seed) on the round
/// Earth and on the flat one, the same random streams: every quantity's rms at 60 s differs by
/// less than the half-width of its own 99.9 % interval (the Earth is invisible at his horizon).
#[test]
fn woodmans_minute_is_the_same_on_both_earths() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs/sensors/mtx.toml");
    let m = SensorModel::from_toml_str(&std::fs::read_to_string(root).unwrap(), "mtx.toml")
        .unwrap_or_else(|e| panic!("{e}"));
    let run = |earth: &str| {
        simulate(
            &m,
            &format!("duration_s = 60.0\nrate_hz = 100.0\n[earth]\n{earth}\n[checkpoints]\ntimes_s = [60.0]\n"),
            500,
        )
    };
    let (round, flat) = (run("model = \"wgs84\""), run("model = \"flat\""));
    let (r, f) = (
        &round.checkpoints[0].quantities,
        &flat.checkpoints[0].quantities,
    );
    for (q, fc) in f.iter() {
        let rc = &r[q];
        let (Some(lo), Some(hi), Some(law)) = (fc.ratio_lo, fc.ratio_hi, fc.law_rms) else {
            continue;
        };
        let half = (hi - lo) / 2.0 * law;
        let diff = (rc.rms - fc.rms).abs();
        eprintln!(
            "{q}: round {:.6e}, flat {:.6e}, |diff| {diff:.3e}, interval half-width {half:.3e}",
            rc.rms, fc.rms
        );
        if q == "pos_down_m" || q == "vel_down_mps" {
            // The round Earth holds the height: its vertical error is zero by construction.
            continue;
        }
        assert!(
            diff < half,
            "{q}: {} against {} (half-width {half})",
            rc.rms,
            fc.rms
        );
    }
}

/// A tilted, otherwise perfect static IMU (`[alignment] roll_deg = 0.01`) on the rotating Earth
/// at 45 deg N, 4 h: its east velocity error crosses zero every half Schuler period,
/// 2 pi sqrt(R / g) = 84.4 min, each full period within 0.5 % (the Foucault turn of the
/// oscillation, 34 h, moves the crossings of one component by a few tenths of a percent).
#[test]
fn a_tilt_oscillates_at_the_schuler_period() {
    let times: Vec<String> = (1..=480).map(|k| format!("{}.0", 30 * k)).collect();
    let r = simulate(
        &model(""),
        &format!(
            "duration_s = 14400.0\nrate_hz = 10.0\n[alignment]\nroll_deg = 0.01\n[checkpoints]\ntimes_s = [{}]\n",
            times.join(", ")
        ),
        1,
    );
    let pts: Vec<(f64, f64)> = r
        .checkpoints
        .iter()
        .map(|c| (c.t_s, c.quantities["vel_east_mps"].mean))
        .collect();
    let crossings: Vec<f64> = pts
        .windows(2)
        .filter(|w| (w[0].1 < 0.0) != (w[1].1 < 0.0))
        .map(|w| w[0].0 + (w[1].0 - w[0].0) * w[0].1 / (w[0].1 - w[1].1))
        .collect();
    let place = strapdown::earth::Place::from_deg(45.0, 0.0, 0.0);
    let period = std::f64::consts::TAU / place.schuler_rad_s();
    assert!((period / 60.0 - 84.4).abs() < 0.1, "{period}");
    assert!(crossings.len() >= 5, "{crossings:?}");
    for w in crossings.windows(3) {
        let p = w[2] - w[0];
        eprintln!(
            "period {:.2} min (Schuler {:.2} min)",
            p / 60.0,
            period / 60.0
        );
        assert!((p / period - 1.0).abs() < 5e-3, "{p} s against {period} s");
    }
}

/// The unaided vertical channel (`vertical = "free"`): its divergence (time constant
/// sqrt(R / 2g), about 570 s) is in the laws and the Monte Carlo follows it, 30 min.
#[test]
fn the_free_vertical_channel_diverges_as_its_law() {
    use NavQuantity::*;
    let r = simulate(
        &model("[accel.all]\nwhite_noise = \"50 ug/sqrt(Hz)\"\nturn_on_bias = \"20 ug\"\n"),
        "duration_s = 1800.0\nrate_hz = 10.0\n[earth]\nvertical = \"free\"\n[checkpoints]\nlog_count = 8\nfirst_s = 60.0\n",
        300,
    );
    check("free vertical", &r, &[PosDown, VelDown, PosHorizontal]);
    // The turn-on bias alone gives (b / w^2)(cosh(w t) - 1), w = sqrt(2 g / R): at 30 min 2.2
    // times the flat Earth's b t^2 / 2; with the white noise the law is above that.
    let last = &r.checkpoints.last().unwrap().quantities;
    let flat = 20e-6 * 9.80665 * 1800.0f64.powi(2) / 2.0;
    let law = last["pos_down_m"].law_rms.unwrap();
    eprintln!("pos_down at 30 min: law rms {law:.1} m, flat b t^2/2 {flat:.1} m");
    assert!(law > 2.0 * flat, "{law} against {flat}");
}
