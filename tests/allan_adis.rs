//! The real ADIS16405 run 1 log through `imudrift allan` against allantools' oadev of the same
//! data. Needs `IMUDRIFT_DATA` (see the testkit crate): without it the test shows as ignored.

mod common;
use common::command;

fn adis16405_log_through_the_command() {
    // The real log, read by the command (gz, # comments, columns mapped, deg/s and g), against
    // allantools 2024.06 oadev on the same data (expected_allantools_oadev_imu1.csv), converted
    // to SI. Tolerance 1e-9 relative: both are double-precision evaluations of SP 1065 eq (11).
    let data = testkit::data_dir();
    let dir = data.join("adis16405_imudata");
    let o = command()
        .args([
            "allan",
            dir.join("adis16405_imu1.csv.gz").to_str().unwrap(),
            "--rate",
            "100",
        ])
        .args([
            "--gyro-unit",
            "deg/s",
            "--accel-unit",
            "g",
            "--json",
            "--edf",
            "none",
        ])
        .args([
            "--col",
            "gx=gyro_x_dps,gy=gyro_y_dps,gz=gyro_z_dps,ax=acc_x_g,ay=acc_y_g,az=acc_z_g",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let doc: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let reference =
        std::fs::read_to_string(dir.join("expected_allantools_oadev_imu1.csv")).unwrap();
    let mut rows = reference.lines().filter(|l| !l.starts_with('#'));
    let head: Vec<&str> = rows.next().unwrap().split(',').collect();
    let idx = |n: &str| head.iter().position(|h| *h == n).unwrap();
    let mut compared = 0;
    for row in rows {
        let f: Vec<&str> = row.split(',').collect();
        let (name, scale) = match f[idx("column")] {
            "gyro_x_dps" => ("gx", 1f64.to_radians()),
            "gyro_y_dps" => ("gy", 1f64.to_radians()),
            "gyro_z_dps" => ("gz", 1f64.to_radians()),
            "acc_x_g" => ("ax", 9.806_65),
            "acc_y_g" => ("ay", 9.806_65),
            "acc_z_g" => ("az", 9.806_65),
            other => panic!("{other}"),
        };
        let m: u64 = f[idx("m")].parse().unwrap();
        let want: f64 = f[idx("oadev")].parse::<f64>().unwrap() * scale;
        let ch = &doc["channels"][name];
        let ms = ch["m"].as_array().unwrap();
        if let Some(i) = ms.iter().position(|v| v.as_u64() == Some(m)) {
            let got = ch["adev"][i].as_f64().unwrap();
            assert!(
                (got / want - 1.0).abs() < 1e-9,
                "{name} m={m}: {got} vs {want}"
            );
            compared += 1;
        }
    }
    // octave grid up to N/4 (Stable32 stop ratio): m = 1 .. 2^17 on 6 channels
    assert_eq!(compared, 6 * 18);
}

fn main() -> std::process::ExitCode {
    testkit::run_data_tests(&[(
        "adis16405_log_through_the_command",
        adis16405_log_through_the_command,
    )])
}
