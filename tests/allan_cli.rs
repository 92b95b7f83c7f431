//! End-to-end tests of `imudrift allan`: reading CSV and gzip CSV, units, column mapping,
//! outputs (table, JSON fields of docs/cli.md, CSV, SVG), errors with line numbers, and the
//! command on the real ADIS16405 log against allantools' curve.

mod common;
use common::command;

use std::io::Write;
use std::path::Path;

/// A static gyro log in deg/s with a time column: white noise of known level (SplitMix64 +
/// Box-Muller, deterministic).
fn write_log(path: &Path, n: usize, gz: bool) {
    let mut rng = testkit::SplitMix64::new(7);
    let mut text = String::from("# test log\n# gyro in deg/s\ntime_s,wx,temp\n");
    for k in 0..n {
        let g = rng.normal();
        text.push_str(&format!("{},{},{}\n", k as f64 * 0.01, 0.5 * g, 25.0));
    }
    let file = std::fs::File::create(path).unwrap();
    if gz {
        let mut e = flate2::write::GzEncoder::new(file, flate2::Compression::fast());
        e.write_all(text.as_bytes()).unwrap();
        e.finish().unwrap();
    } else {
        std::io::BufWriter::new(file)
            .write_all(text.as_bytes())
            .unwrap();
    }
}

#[test]
fn json_csv_svg_outputs_and_units() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("log.csv.gz");
    write_log(&log, 200_000, true);
    let out = dir.path().join("out");
    let o = command()
        .args([
            "allan",
            log.to_str().unwrap(),
            "--gyro-unit",
            "deg/s",
            "--col",
            "t=time_s,gx=wx",
        ])
        .args(["--json", "--out", out.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let doc: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!((doc["rate_hz"].as_f64().unwrap() - 100.0).abs() < 1e-6);
    let gx = &doc["channels"]["gx"];
    // temp is not analysed by default
    assert!(doc["channels"].get("temp").is_none());
    let col = |k: &str| -> Vec<f64> {
        gx[k]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect()
    };
    let (tau, adev, lo, hi) = (col("tau_s"), col("adev"), col("adev_lo"), col("adev_hi"));
    assert_eq!(tau.len(), adev.len());
    assert!(tau.len() >= 10);
    for i in 0..tau.len() {
        assert!(lo[i] < adev[i] && adev[i] < hi[i]);
    }
    // White noise of 0.5 deg/s per sample at 100 Hz: N = 0.5 deg/s * sqrt(0.01 s), in rad.
    // The fitted N must agree within 3 of its stated standard errors (plus 1 % for the
    // generator's finite sample, far below the fit's own uncertainty here).
    let n_true = 0.5f64.to_radians() * 0.1;
    let n = gx["fit"]["n"].as_f64().unwrap();
    let n_sigma = gx["fit_sigma"]["n"].as_f64().unwrap();
    assert!(
        (n - n_true).abs() < 3.0 * n_sigma + 0.01 * n_true,
        "{n} +- {n_sigma} vs {n_true}"
    );
    for f in ["allan.csv", "allan.json", "allan_gx.svg"] {
        assert!(out.join(f).exists(), "{f}");
    }
    let csv = std::fs::read_to_string(out.join("allan.csv")).unwrap();
    assert!(csv.starts_with("channel,tau_s,m,n_terms,bins,alpha,edf,adev_lo,adev,adev_hi"));
    assert_eq!(csv.lines().count(), 1 + tau.len());
    let svg = std::fs::read_to_string(out.join("allan_gx.svg")).unwrap();
    assert!(svg.contains("confidence interval") && svg.contains("IEEE 952 fit"));
}

#[test]
fn bad_row_is_reported_by_line_and_no_output_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("bad.csv");
    std::fs::write(&log, "# c\ngx,gy\n1,2\n3,4\n5,x7\n").unwrap();
    let out = dir.path().join("out");
    let o = command()
        .args([
            "allan",
            log.to_str().unwrap(),
            "--rate",
            "10",
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("bad.csv:5") && err.contains("\"gy\"") && err.contains("x7"),
        "{err}"
    );
    assert!(!out.join("allan.json").exists());
}

#[test]
fn thread_count_does_not_change_results() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("log.csv");
    write_log(&log, 100_000, false);
    let run = |threads: &str| {
        let o = command()
            .args([
                "allan",
                log.to_str().unwrap(),
                "--col",
                "t=time_s,gx=wx",
                "--json",
            ])
            .args(["--threads", threads, "--grid", "5/decade"])
            .output()
            .unwrap();
        assert!(o.status.success());
        o.stdout
    };
    assert_eq!(run("1"), run("2"));
}

#[test]
#[cfg_attr(
    imudrift_no_data,
    ignore = "needs the real IMU logs and reference tables: set IMUDRIFT_DATA"
)]
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

/// The issue-24 case through the commands: a white-noise-only sensor (N = 0.5833 deg/sqrt(h) on
/// every gyro, 0.12 m/s/sqrt(h) on every accelerometer), `imudrift generate` 10 min at 200 Hz,
/// then `imudrift allan --json`: every white-noise reading holds its truth within its stated
/// interval, and no bias-instability or random-walk value is claimed, only bounds (`null` with
/// `<name>_bound`), in the JSON and the text alike. Tolerance: the intervals are asked at the
/// level 1 - 0.01/6 for the 6 readings (Bonferroni: family-wise false-positive rate 1 %).
#[test]
fn white_noise_readings_are_right_and_claim_no_bias_instability() {
    let dir = tempfile::tempdir().unwrap();
    let sensor = dir.path().join("white.toml");
    std::fs::write(
        &sensor,
        "name = \"white\"\n[gyro.all]\nwhite_noise = \"0.5833 deg/sqrt(h)\"\n[accel.all]\nwhite_noise = \"0.12 m/s/sqrt(h)\"\n",
    )
    .unwrap();
    let log = dir.path().join("white.csv");
    let o = command()
        .args(["generate", sensor.to_str().unwrap()])
        .args(["--duration", "10min", "--rate", "200", "--seed", "5", "-o"])
        .arg(&log)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let confidence = format!("{}", 1.0 - 0.01 / 6.0);
    let o = command()
        .args(["allan", log.to_str().unwrap(), "--json", "--confidence"])
        .arg(&confidence)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let doc: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let truth = |ch: &str| {
        if ch.starts_with('g') {
            (0.5833f64 / 60.0).to_radians()
        } else {
            0.12 / 60.0
        }
    };
    for ch in ["gx", "gy", "gz", "ax", "ay", "az"] {
        let r = &doc["channels"][ch]["readings"];
        let (v, lo, hi) = (
            r["arw_at_1s"].as_f64().unwrap(),
            r["arw_at_1s_lo"].as_f64().unwrap(),
            r["arw_at_1s_hi"].as_f64().unwrap(),
        );
        assert!(
            lo <= truth(ch) && truth(ch) <= hi,
            "{ch}: {v} [{lo}, {hi}] vs {}",
            truth(ch)
        );
        for name in ["bi_min", "bi_ieee", "rrw_at_3s"] {
            assert!(r[name].is_null(), "{ch}: {name} = {} claimed", r[name]);
            assert!(
                r[format!("{name}_bound")].as_f64().unwrap() > 0.0,
                "{ch}: {r}"
            );
        }
        for term in ["b", "k", "r"] {
            let resolved = &doc["channels"][ch]["fit_resolved"][term];
            assert_eq!(
                resolved,
                &serde_json::json!(false),
                "{ch}: fitted {term} given as a value"
            );
        }
    }
    // The text (on stderr with --json) says the same: bounds, no minimum.
    let text = String::from_utf8_lossy(&o.stderr);
    assert!(
        text.matches("Allan minimum (bias inst.) not resolved: <")
            .count()
            == 6,
        "{text}"
    );
}

/// Unit plausibility (issue 24): a gyro logged in deg/s under the name `gx` (read as rad/s, the
/// canonical name's default) and an accelerometer logged in g read as m/s^2 each draw a warning
/// naming the flag that fixes it; the analysis still runs. The noise (0.5 deg/s per sample at
/// 100 Hz: 0.05 deg/s/sqrt(Hz), 2.9 "deg/s/sqrt(Hz)" when read as rad/s) and the magnitude (1 g
/// read as 1 m/s^2) are each far beyond the warning's thresholds (1 deg/s/sqrt(Hz); a factor
/// 1.25 around standard gravity), so no tolerance question arises.
#[test]
fn wrong_units_draw_a_plausibility_warning() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("units.csv");
    let mut rng = testkit::SplitMix64::new(3);
    let mut text = String::from("gx,ax,ay,az\n");
    for _ in 0..20_000 {
        let n = 0.002 * rng.normal();
        text.push_str(&format!("{},{n},{n},{}\n", 0.5 * rng.normal(), -1.0 + n));
    }
    std::fs::write(&path, text).unwrap();
    let o = command()
        .args(["allan", path.to_str().unwrap(), "--rate", "100"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("warning:")
            && err.contains("gx reads a white noise of")
            && err.contains("--gyro-unit deg/s"),
        "{err}"
    );
    assert!(
        err.contains("near 1, as a log in g reads") && err.contains("--accel-unit g"),
        "{err}"
    );
    // Stated right, no warning.
    let o = command()
        .args(["allan", path.to_str().unwrap(), "--rate", "100"])
        .args(["--gyro-unit", "deg/s", "--accel-unit", "g"])
        .output()
        .unwrap();
    assert!(o.status.success());
    assert!(!String::from_utf8_lossy(&o.stderr).contains("warning:"));
}

/// Issue 45 items 3 and 4 on ADIS16405 run 1 (the README's command with `--kalibr`): one verdict
/// per quantity, points the readings leave out marked, the noise file's values the readings the
/// text prints, and the fit's misfit said with what it means for the numbers instead of an
/// always-on warning.
#[test]
#[cfg_attr(
    imudrift_no_data,
    ignore = "needs the real IMU logs and reference tables: set IMUDRIFT_DATA"
)]
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
