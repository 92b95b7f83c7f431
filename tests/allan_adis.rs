//! The real ADIS16405 run 1 log through `imudrift allan`: against allantools' oadev of the same
//! data, and its readings, fit and noise file consistent with each other. Needs `IMUDRIFT_DATA` (see the testkit crate): without it the test shows as ignored.

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

/// Issue 45 items 3 and 4 on ADIS16405 run 1 (the README's command with `--kalibr`): one verdict
/// per quantity, points the readings leave out marked, the noise file's values the readings the
/// text prints, and the fit's misfit said with what it means for the numbers instead of an
/// always-on warning.
fn adis16405_readings_fit_and_noise_file_agree() {
    let data = testkit::data_dir().join("adis16405_imudata");
    let dir = tempfile::tempdir().unwrap();
    let yaml = dir.path().join("imu.yaml");
    let log = data.join("adis16405_imu1.csv.gz");
    let args = |json: bool| {
        let mut c = command();
        c.args(["allan", log.to_str().unwrap(), "--rate", "100"])
            .args(["--gyro-unit", "deg/s", "--accel-unit", "g"])
            .args([
                "--col",
                "gx=gyro_x_dps,gy=gyro_y_dps,gz=gyro_z_dps,ax=acc_x_g,ay=acc_y_g,az=acc_z_g",
            ]);
        if json {
            c.args(["--json", "--kalibr", yaml.to_str().unwrap()]);
        }
        c.output().unwrap()
    };
    let o = args(true);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let doc: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let text = String::from_utf8(common::ok(args(false)).stdout).unwrap();
    let gx_text = text
        .split("\nchannel ")
        .find(|c| c.starts_with("gx "))
        .expect("gx table");

    // Item 3a: the fit's B and the curve's minimum are named as two quantities; the minimum's
    // B-convention bound is not written as a second "IEEE B" verdict beside the fit's B.
    assert!(!gx_text.contains("IEEE B <"), "{gx_text}");
    assert!(
        gx_text.contains("fit B vs Allan minimum: different quantities"),
        "{gx_text}"
    );
    assert!(
        gx_text.contains("fit N vs ARW line: different quantities"),
        "{gx_text}"
    );
    // Item 3b: every point with fewer than 9 bins, which no reading uses, is marked in the table
    // (for oadev too), and the longest tau the readings use is in the JSON.
    let gx = &doc["channels"]["gx"];
    let bins = gx["bins"].as_array().unwrap();
    let taus = gx["tau_s"].as_array().unwrap();
    let marked = gx_text.lines().filter(|l| l.ends_with("<9 bins")).count();
    let few = bins.iter().filter(|b| b.as_u64().unwrap() < 9).count();
    assert!(
        few >= 1 && marked == few,
        "{few} points with < 9 bins, {marked} marked"
    );
    let usable_max = gx["readings_tau_max_s"].as_f64().unwrap();
    let last_usable = taus
        .iter()
        .zip(bins)
        .filter(|(_, b)| b.as_u64().unwrap() >= 9)
        .map(|(t, _)| t.as_f64().unwrap())
        .fold(0.0, f64::max);
    assert_eq!(usable_max, last_usable);
    assert!(gx_text.contains("its longest tau with 9 or more non-overlapping averages"));
    // Item 3c: the noise file's densities are the ARW readings the JSON and text give (5
    // significant digits in the file), and its header says so.
    let file = std::fs::read_to_string(&yaml).unwrap();
    assert!(file.contains("-1/2 line"), "{file}");
    let arw: Vec<f64> = ["gx", "gy", "gz"]
        .iter()
        .map(|c| {
            doc["channels"][c]["readings"]["arw_at_1s"]
                .as_f64()
                .unwrap()
        })
        .collect();
    let worst = arw.iter().copied().fold(0.0, f64::max);
    let written = file
        .lines()
        .find_map(|l| l.strip_prefix("gyroscope_noise_density: "))
        .and_then(|v| v.split_whitespace().next())
        .and_then(|v| v.parse::<f64>().ok())
        .unwrap();
    assert!((written / worst - 1.0).abs() < 1e-4, "{written} vs {worst}");
    // Item 4: the gyros' misfit does not change a printed coefficient (each refit without a
    // quarter of the taus stays within 2 sigma): a note with the ranges, no warning; the
    // accelerometers' does, and their warning says which term and its range.
    for ch in ["gx", "gy", "gz"] {
        let c = &doc["channels"][ch];
        assert_eq!(c["warnings"], serde_json::json!([]), "{ch}");
        let note = c["fit_note"].as_str().unwrap();
        assert!(
            note.contains("refitted without each quarter"),
            "{ch}: {note}"
        );
        let n = c["fit"]["n"].as_f64().unwrap();
        let range = c["fit_subrange"]["n"].as_array().unwrap();
        let (lo, hi) = (range[0].as_f64().unwrap(), range[1].as_f64().unwrap());
        assert!(lo <= n && n <= hi, "{ch}: {lo} {n} {hi}");
    }
    assert!(!gx_text.contains("warning: gx"), "{gx_text}");
    let ax = doc["channels"]["ax"]["warnings"].as_array().unwrap();
    assert!(
        ax.iter().any(|w| w.as_str().unwrap().contains("N 0.")),
        "{ax:?}"
    );
}

fn main() -> std::process::ExitCode {
    testkit::run_data_tests(&[
        (
            "adis16405_log_through_the_command",
            adis16405_log_through_the_command,
        ),
        (
            "adis16405_readings_fit_and_noise_file_agree",
            adis16405_readings_fit_and_noise_file_agree,
        ),
    ])
}
