//! A 12 h, 100 Hz static log from configs/sensors/mtx.toml reads back Woodman's Table 4
//! (TR-696; docs/model.md §1.4) through the allan crate's overlapping Allan deviation:
//! - ADEV at tau = 1 s within 5 % of the configured ARW per axis. Reason: at m = 100 of 4.32e6
//!   samples the white-FM EDF is ~6.5e4, a 0.3 % standard error, and the other terms add 0.7 % at 1 s;
//! - the minimum over the octave grid within 20 % of 0.010 / 0.009 / 0.012 deg/s. Reason: near
//!   tau = 300-600 s the flicker-FM EDF is ~90, a standard error of ~7.5 % of the deviation, so 20 %
//!   is 2.7 standard errors for one tau, and the minimum over the grid is biased low by its scatter.
//!   The ignored seed sweep measured it: over 20 seeds x 3 axes the ADEV(1 s) miss was at most 1.4 %,
//!   the minimum missed by -18.7 % .. +9.5 % (median -3.0 %), none beyond 20 % (seed 1, axis y, is the
//!   -18.7 %). A raw minimum of one 12 h log is that noisy, so this test pins seed 1 rather than claiming
//!   a false-positive rate; with the previous realisation (2 flicker components per decade) 2 of 60
//!   axis-logs missed by more than 20 %, so expect a few per cent of seeds to.

mod common;

use allan::{DataKind, Estimator, TauGrid};
use nalgebra::Vector3;
use noise::{ImuErrors, SensorModel};

const ARW_DEG_PER_SQRT_S: [f64; 3] = [0.075, 0.078, 0.079];
const BI_MIN_DEG_PER_S: [f64; 3] = [0.010, 0.009, 0.012];
const ARW_TOLERANCE: f64 = 0.05;
const MIN_TOLERANCE: f64 = 0.20;

pub fn mtx() -> SensorModel {
    common::shipped_model("mtx.toml")
}

/// (ADEV at 1 s, minimum ADEV, tau of the minimum) per gyro axis, deg/s.
fn readback(seed: u64) -> [(f64, f64, f64); 3] {
    let model = mtx();
    let rate = 100.0;
    let n = 12 * 3600 * 100;
    let mut errors = ImuErrors::new(&model, 1.0 / rate, seed, 0);
    let mut out = [(0.0, 0.0, 0.0); 3];
    for (axis, o) in out.iter_mut().enumerate() {
        let mut y = vec![0.0; n];
        errors.channels_mut()[axis].fill_static(0, &Vector3::zeros(), &mut y);
        let opts = allan::Options {
            edf: allan::EdfMethod::None,
            ..allan::Options::default()
        };
        let curve = allan::deviation_with(
            &y,
            DataKind::Rate,
            1.0 / rate,
            Estimator::Overlapping,
            &TauGrid::Octave,
            &opts,
        );
        let one = allan::deviation_with(
            &y,
            DataKind::Rate,
            1.0 / rate,
            Estimator::Overlapping,
            &TauGrid::Explicit(vec![100]),
            &opts,
        )[0]
        .dev;
        let min = curve
            .iter()
            .filter(|p| p.woodman_ok())
            .min_by(|a, b| a.dev.total_cmp(&b.dev))
            .unwrap();
        *o = (one.to_degrees(), min.dev.to_degrees(), min.tau_s);
    }
    out
}

/// Relative misses (ADEV at 1 s vs ARW, minimum vs Table 4) per axis, printed.
fn misses(seed: u64) -> [(f64, f64); 3] {
    let mut out = [(0.0, 0.0); 3];
    for (axis, (one, min, at)) in readback(seed).into_iter().enumerate() {
        let arw_err = one / ARW_DEG_PER_SQRT_S[axis] - 1.0;
        let min_err = min / BI_MIN_DEG_PER_S[axis] - 1.0;
        eprintln!(
            "seed {seed} axis {axis}: ADEV(1 s) {one:.5} deg/s ({:+.2} %), min {min:.5} deg/s at {at} s ({:+.1} %)",
            100.0 * arw_err,
            100.0 * min_err
        );
        out[axis] = (arw_err, min_err);
    }
    out
}

#[test]
fn twelve_hour_log_reads_back_table_4() {
    for (axis, (arw_err, min_err)) in misses(1).into_iter().enumerate() {
        assert!(
            arw_err.abs() < ARW_TOLERANCE,
            "axis {axis}: ADEV(1 s) off by {arw_err}"
        );
        assert!(
            min_err.abs() < MIN_TOLERANCE,
            "axis {axis}: minimum off by {min_err}"
        );
    }
}

/// The seed sweep behind the stated miss rate (slow: `cargo test --release -- --ignored`).
#[test]
#[ignore]
fn twelve_hour_log_reads_back_table_4_over_20_seeds() {
    let all: Vec<(f64, f64)> = (1..=20).flat_map(misses).collect();
    let arw_worst = all.iter().map(|m| m.0.abs()).fold(0.0, f64::max);
    let min_misses = all.iter().filter(|m| m.1.abs() >= MIN_TOLERANCE).count();
    let mut min_errs: Vec<f64> = all.iter().map(|m| m.1).collect();
    min_errs.sort_by(f64::total_cmp);
    eprintln!(
        "60 axis-logs: worst ADEV(1 s) miss {:.2} %; minimum misses {:.1} % .. {:+.1} %, median {:+.1} %; {min_misses} of 60 beyond 20 %",
        100.0 * arw_worst,
        100.0 * min_errs[0],
        100.0 * min_errs[59],
        100.0 * min_errs[30]
    );
    assert!(arw_worst < ARW_TOLERANCE);
}
