//! The full path of the readback: `imudrift generate` writes a 12 h, 100 Hz log from
//! configs/sensors/mtx.toml (601 MB of CSV), the CSV is read back and its gyro columns go through the
//! allan crate's overlapping Allan deviation (octave taus, Woodman's >= 9 bins), giving back
//! Woodman's Table 4: ADEV(1 s) within 5 % of the configured ARW and the minimum within 20 % of
//! 0.010 / 0.009 / 0.012 deg/s (reasons for the tolerances: crates/noise/tests/woodman_table4.rs,
//! which checks the same log in memory in the default test run).
//!
//! Writes 601 MB into a temporary directory (removed afterwards); about 4 s in release.

mod common;
use common::command;

use allan::{DataKind, Estimator, TauGrid};
use std::io::BufRead;

#[test]
fn twelve_hour_csv_reads_back_table_4() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("mtx12h.csv");
    let cfg = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/sensors/mtx.toml");
    let out = command()
        .args([
            "generate",
            cfg.to_str().unwrap(),
            "--duration",
            "12 h",
            "--rate",
            "100",
            "--seed",
            "1",
            "-o",
        ])
        .arg(&log)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );

    let reader = std::io::BufReader::with_capacity(1 << 20, std::fs::File::open(&log).unwrap());
    let mut gyro: [Vec<f64>; 3] = Default::default();
    for line in reader.lines() {
        let line = line.unwrap();
        if line.starts_with('#') || line.starts_with('t') {
            continue;
        }
        let mut fields = line.split(',').skip(1);
        for g in gyro.iter_mut() {
            g.push(fields.next().unwrap().parse().unwrap());
        }
    }
    assert_eq!(gyro[0].len(), 4_320_000);

    let arw = [0.075, 0.078, 0.079];
    let minimum = [0.010, 0.009, 0.012];
    let opts = allan::Options {
        edf: allan::EdfMethod::None,
        ..allan::Options::default()
    };
    for (axis, y) in gyro.iter().enumerate() {
        let at_1s = allan::deviation_with(
            y,
            DataKind::Rate,
            0.01,
            Estimator::Overlapping,
            &TauGrid::Explicit(vec![100]),
            &opts,
        )[0]
        .dev
        .to_degrees();
        let curve = allan::deviation_with(
            y,
            DataKind::Rate,
            0.01,
            Estimator::Overlapping,
            &TauGrid::Octave,
            &opts,
        );
        let min = curve
            .iter()
            .filter(|p| p.woodman_ok())
            .map(|p| p.dev.to_degrees())
            .fold(f64::INFINITY, f64::min);
        eprintln!("axis {axis}: ADEV(1 s) {at_1s:.5} deg/s, minimum {min:.5} deg/s");
        assert!((at_1s / arw[axis] - 1.0).abs() < 0.05);
        assert!((min / minimum[axis] - 1.0).abs() < 0.20);
    }
}
