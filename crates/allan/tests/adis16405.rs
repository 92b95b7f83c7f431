//! The published Allan curve of a real sensor: ADIS16405 run 1 ($IMUDRIFT_DATA/adis16405_imudata),
//! overlapping Allan deviation of all six axes at the 18 published taus (m = 2^1 .. 2^18 at
//! 100 Hz), against the textbook overlapping AVAR column `oavar_std` of
//! expected_avar_adis_av_imu1.csv, and against allantools 2024.06 `oadev` at m = 2^0 .. 2^18.

use allan::{DataKind, EdfMethod, Estimator, Options, TauGrid};
use std::io::Read;

/// The tolerance. The reference is an independent double-precision computation; ours
/// agrees with it to 1.9e-9 (printed), so 1e-6 leaves room only for a real error.
const REL_TOL: f64 = 1e-6;

fn read_gz_text(path: &std::path::Path) -> String {
    let mut s = String::new();
    flate2::read::GzDecoder::new(std::fs::File::open(path).unwrap())
        .read_to_string(&mut s)
        .unwrap();
    s
}

fn adis16405_run1_matches_published_curve() {
    let dir = testkit::data_dir();
    let dir = dir.join("adis16405_imudata");
    let text = read_gz_text(&dir.join("adis16405_imu1.csv.gz"));
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let mut cols: Vec<Vec<f64>> = vec![Vec::with_capacity(1_000_000); header.len()];
    for l in lines {
        for (c, v) in cols.iter_mut().zip(l.split(',')) {
            c.push(v.trim().parse().unwrap());
        }
    }
    assert_eq!(cols[0].len(), 1_000_000);
    let axis_col = |axis: &str| -> usize {
        let name = match axis {
            "Gyro_X" => "gyro_x_dps",
            "Gyro_Y" => "gyro_y_dps",
            "Gyro_Z" => "gyro_z_dps",
            "Accel_X" => "acc_x_g",
            "Accel_Y" => "acc_y_g",
            "Accel_Z" => "acc_z_g",
            other => panic!("unknown axis {other}"),
        };
        header.iter().position(|h| *h == name).unwrap()
    };
    let opts = Options {
        edf: EdfMethod::None,
        ..Options::default()
    };
    let ms: Vec<usize> = (1..=18).map(|j| 1usize << j).collect();
    let curves: Vec<Vec<f64>> = cols
        .iter()
        .map(|y| {
            let pts = allan::deviation_with(
                y,
                DataKind::Rate,
                0.01,
                Estimator::Overlapping,
                &TauGrid::Explicit(ms.clone()),
                &opts,
            );
            assert_eq!(pts.len(), 18);
            pts.iter().map(|p| p.dev).collect()
        })
        .collect();

    let reference = std::fs::read_to_string(dir.join("expected_avar_adis_av_imu1.csv")).unwrap();
    let mut rows = reference.lines().filter(|l| !l.starts_with('#'));
    let head: Vec<&str> = rows.next().unwrap().split(',').collect();
    let idx = |n: &str| head.iter().position(|h| *h == n).unwrap();
    let (i_axis, i_m, i_tau, i_std) = (idx("axis"), idx("m"), idx("tau_s"), idx("oadev_std"));
    let mut compared = 0;
    let mut worst = 0.0f64;
    for row in rows {
        let f: Vec<&str> = row.split(',').collect();
        let m: usize = f[i_m].parse().unwrap();
        let tau: f64 = f[i_tau].parse().unwrap();
        assert!((tau - m as f64 * 0.01).abs() < 1e-12);
        let want: f64 = f[i_std].parse().unwrap();
        let j = ms.iter().position(|&x| x == m).unwrap();
        let got = curves[axis_col(f[i_axis])][j];
        let e = (got / want - 1.0).abs();
        worst = worst.max(e);
        assert!(
            e < REL_TOL,
            "{} m={m}: {got} vs {want} ({e:.2e})",
            f[i_axis]
        );
        compared += 1;
    }
    assert_eq!(compared, 6 * 18);
    eprintln!("ADIS16405 run 1: 108 points, worst relative difference to oadev_std {worst:.2e}");

    // allantools 2024.06 oadev, same data, m = 2^0..2^18 (and its number of terms).
    let at = std::fs::read_to_string(dir.join("expected_allantools_oadev_imu1.csv")).unwrap();
    let mut rows = at.lines().filter(|l| !l.starts_with('#'));
    let head: Vec<&str> = rows.next().unwrap().split(',').collect();
    let idx = |n: &str| head.iter().position(|h| *h == n).unwrap();
    let (i_col, i_m, i_dev, i_n) = (idx("column"), idx("m"), idx("oadev"), idx("oadev_n"));
    let mut worst_at = 0.0f64;
    for row in rows {
        let f: Vec<&str> = row.split(',').collect();
        let c = header.iter().position(|h| *h == f[i_col]).unwrap();
        let m: usize = f[i_m].parse().unwrap();
        let p = allan::deviation_with(
            &cols[c],
            DataKind::Rate,
            0.01,
            Estimator::Overlapping,
            &TauGrid::Explicit(vec![m]),
            &opts,
        );
        let want: f64 = f[i_dev].parse().unwrap();
        assert_eq!(p[0].n_terms, f[i_n].parse::<usize>().unwrap());
        let e = (p[0].dev / want - 1.0).abs();
        worst_at = worst_at.max(e);
        // allantools sums the phase without compensation: agreement to 1e-8 is expected
        // (its own header reports 2e-9 against the textbook computation).
        assert!(e < 1e-8, "{} m={m}: {} vs {want}", f[i_col], p[0].dev);
    }
    eprintln!("ADIS16405 run 1: worst relative difference to allantools oadev {worst_at:.2e}");
}

fn main() -> std::process::ExitCode {
    testkit::run_data_tests(&[(
        "adis16405_run1_matches_published_curve",
        adis16405_run1_matches_published_curve,
    )])
}
