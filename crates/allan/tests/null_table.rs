//! The null thresholds' shipped table (allan::null_table) against the simulation it replaces
//! (allan::null::simulated_thresholds, the whole analysis on null logs at the log's length).
//!
//! What the table assumes, checked exactly: the null statistics do not depend on the sample
//! interval or the confidence level. What it approximates, checked statistically: at lengths
//! between its nodes and beyond its top, the thresholds interpolated from 1000 null logs per node
//! against 200 null logs simulated at the length itself (the command's former way). The
//! tolerance is the sampling spread of the two: the standard error of each threshold is
//! estimated by a bootstrap of the simulated statistics (200 resamples, seeded), scaled by
//! sqrt(200/1000) for the table's, and a difference fails beyond 4 combined standard errors:
//! under a normal law a false failure per threshold has probability 6e-5, 2e-3 over the CI test's
//! 35 thresholds (Bonferroni). Beyond that, the test states the error: it prints each
//! threshold's difference and the false-claim probability per claim the table's threshold gives
//! under the simulated tail (the rule's budget is 1 % / 30 = 3.3e-4 per claim).

use allan::null::{null_statistics, simulated_thresholds, tabulated_thresholds, tail_of};
use allan::{Estimator, Options, TauGrid};
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

fn simulated_opts() -> Options {
    let mut o = Options::default();
    o.claims.table = false;
    o
}

/// The null statistics at 100 Hz, 1 Hz, and 200 Hz with 99.9 % intervals, replicate by
/// replicate. Not bitwise: the fit's basis columns scale by powers of tau0, so its solves round
/// differently (2e-8 relative seen), and where a coefficient is zero to rounding the fit's choice
/// of terms can tip (seen: a rate-ramp term of 1e-6 +- 413 kept at one interval and not at
/// another, in 1 of 24 totdev logs of 3000 samples), which moves that log's statistics. So: equal
/// to 1e-6 relative on at least 95 % of the logs of each analysis (measured: see the output).
#[test]
fn null_statistics_ignore_interval_and_confidence() {
    let o = simulated_opts();
    let wide = Options {
        confidence: 0.999,
        ..simulated_opts()
    };
    let logs = 60;
    for est in [
        Estimator::Overlapping,
        Estimator::NonOverlapping,
        Estimator::Total,
    ] {
        for grid in [TauGrid::Octave, TauGrid::Decade] {
            let a = null_statistics(3000, 0.01, est, &grid, &o, logs, &|_, _| {});
            let b = null_statistics(3000, 1.0, est, &grid, &o, logs, &|_, _| {});
            let c = null_statistics(3000, 0.005, est, &grid, &wide, logs, &|_, _| {});
            let same = |x: &[f64; 5], y: &[f64; 5]| {
                (0..5).all(|j| (x[j] - y[j]).abs() <= 1e-6 * (1.0 + x[j].abs()))
            };
            let differ = a
                .iter()
                .zip(&b)
                .zip(&c)
                .filter(|((x, y), z)| !(same(x, y) && same(x, z)))
                .count();
            eprintln!("{est:?} {grid:?}: {differ} of {logs} null logs differ across interval and confidence");
            assert!(
                differ * 20 <= logs,
                "{est:?} {grid:?}: {differ} of {logs} logs differ"
            );
        }
    }
}

/// The threshold's bootstrap standard error from `stats` (the simulation's own statistics).
fn bootstrap_se(stats: &[[f64; 5]], opts: &Options, seed: u64) -> [f64; 5] {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let r = stats.len();
    let share = (0.1 * r as f64).floor() / r as f64;
    let draws: Vec<[f64; 5]> = (0..200)
        .map(|_| {
            let s: Vec<[f64; 5]> = (0..r).map(|_| stats[rng.gen_range(0..r)]).collect();
            let (start, scale) = tail_of(&s).unwrap();
            allan::null::thresholds_of(start, scale, share, &opts.claims).threshold
        })
        .collect();
    std::array::from_fn(|j| {
        let m = draws.iter().map(|d| d[j]).sum::<f64>() / draws.len() as f64;
        (draws.iter().map(|d| (d[j] - m).powi(2)).sum::<f64>() / (draws.len() - 1) as f64).sqrt()
    })
}

/// Table against simulation at `n` samples: the differences within 4 combined standard errors.
/// `beyond_top`: N's threshold falls with the length (about a quarter per octave) and the table
/// holds its top period's value beyond its top, so there N's table threshold is only checked not
/// to lie below the simulated one (it may lie above: fewer N claims, never more false ones).
fn check(n: usize, est: Estimator, grid: TauGrid) {
    check_with(n, est, grid, false)
}

#[allow(clippy::needless_range_loop)] // j indexes five parallel arrays of one term each
fn check_with(n: usize, est: Estimator, grid: TauGrid, beyond_top: bool) {
    let mut opts = simulated_opts();
    opts.claims.family = 30;
    let sim = simulated_thresholds(n, 0.01, est, &grid, &opts);
    let stats = null_statistics(n, 0.01, est, &grid, &opts, 200, &|_, _| {});
    let se = bootstrap_se(&stats, &opts, n as u64);
    let mut tab_opts = opts.clone();
    tab_opts.claims.table = true;
    let tab = tabulated_thresholds(n, est, &grid, &tab_opts).expect("the table covers it");
    for j in 0..5 {
        let (a, b) = (tab.threshold[j], sim.threshold[j]);
        let tol = 4.0 * se[j] * (1.0f64 + 200.0 / 1000.0).sqrt();
        // The false-claim probability per claim of the table's threshold under the simulated
        // tail (exponential beyond its start).
        let p = if a > sim.tail_start[j] {
            0.1 * (-(a - sim.tail_start[j]) / sim.tail_scale[j]).exp()
        } else {
            f64::NAN
        };
        eprintln!(
            "{est:?} {grid:?} n {n} term {j}: table {a:.3}, simulated {b:.3} (se {:.3}); per-claim rate at the table's threshold {p:.2e}",
            se[j]
        );
        let off = if beyond_top && j == 1 {
            b - a
        } else {
            (a - b).abs()
        };
        assert!(
            off <= tol.max(1e-9),
            "{est:?} {grid:?} n {n} term {j}: table {a}, simulated {b}, tolerance {tol}"
        );
    }
}

#[test]
fn table_matches_simulation_between_nodes() {
    // 10 min at 100 Hz (the tests' white logs), 37 777 (no node nearby), and an hour at 50 Hz.
    check(60_000, Estimator::Overlapping, TauGrid::Octave);
    check(37_777, Estimator::Overlapping, TauGrid::Octave);
    check(180_000, Estimator::NonOverlapping, TauGrid::Octave);
    check(45_000, Estimator::Total, TauGrid::Octave);
    check(90_000, Estimator::Overlapping, TauGrid::Decade);
    check(70_000, Estimator::NonOverlapping, TauGrid::Decade);
    check(30_000, Estimator::Total, TauGrid::Decade);
}

#[test]
#[ignore = "full simulation at 4.32 M samples: about 20 s per estimator; run with --ignored --nocapture"]
fn table_matches_simulation_beyond_its_top() {
    check_with(4_320_000, Estimator::Overlapping, TauGrid::Octave, true);
    check_with(3_000_000, Estimator::NonOverlapping, TauGrid::Decade, true);
}
